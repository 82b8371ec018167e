//! `conetrace accuracy --mode fog`: fog's optical depth integrated in closed form against
//! ray marching at several steps per segment, and the exact transmittance against seed
//! 004's clamped-linear blend — image error, render time, fog segments and density samples.
//!
//! Every scene (default: [`DEFAULT_SCENES`]: height fog seen from inside and from outside,
//! and seed 004's edge-on view of constant box fog) is rendered with Whitted once per
//! [`FogRowKind`]: the analytic integral (`G(B) - G(A)`, seed 004 "Analytic Fog Density -
//! Integrals"), the midpoint-rule march at each count of [`MARCH_STEPS`]
//! (`crate::medium::integration`), and the clamped blend `min(1, tau)` of the same exact
//! depths (`fog_model = "linear-blend"`). The reference is the analytic row itself: its
//! depths are the exact integrals to rounding (docs/fog.md measures them against f64
//! quadrature to about 1e-13 and better; docs/fog.md), so no supersampled ground truth is needed, and all rows share the
//! camera samples (same seed, same spp): the only difference between two images is the fog.
//! Each row is compared with the analytic image (RMSE and FLIP of display values,
//! [`super::metrics::compare`]); the analytic row's error is 0 by definition and the plot
//! draws its time as a vertical line.
//!
//! Cost: the median of `--runs` timed renders (interleaved across rows, after an untimed
//! first render that gives the image and the counters), and the work counters that do not
//! depend on the machine: fog segments evaluated and density samples taken by marching.
//!
//! Outputs in `--out`, per scene: `<scene>_fog.csv`, `<scene>_fog.md`,
//! `<scene>_fog_error_vs_time.png` and `<scene>_fog_crop.png` (the window where the rows
//! differ most from the analytic image, each row weighted by its own mean error).

use std::path::Path;
use std::sync::Arc;

use plotters::style::BLUE;

use crate::cli::CommandError;
use crate::film::PixelRect;
use crate::integrator::Whitted;
use crate::render::{self, RenderControl, RenderOptions, RenderResult};
use crate::scene::SceneDescription;
use conetrace::medium::{FogIntegration, FogModel};

use super::metrics::{self, DisplayImage, ErrorMetrics};
use super::plot::{draw_two_panels, PanelText, PlotPoint};
use super::{crop, files, font, AccuracyArgs, SceneSetup};
use crate::cli::summary::median;

/// Scenes measured when none is named (run from the repository root).
pub const DEFAULT_SCENES: [&str; 3] = [
    "assets/scenes/fog_accuracy_inside.toml",
    "assets/scenes/fog_accuracy_outside.toml",
    "assets/scenes/fog_accuracy_edge.toml",
];

/// The subdirectory of `--out` the fog report is written to.
pub const OUTPUT_SUBDIR: &str = "fog";

/// Ray-march steps per segment compared (coarsest first).
pub const MARCH_STEPS: [u32; 4] = [4, 16, 64, 256];

/// How a row integrates and applies the fog.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FogRowKind {
    /// Closed-form depth, transmittance `exp(-tau)`: the reference.
    Analytic,
    /// Depth marched with this many midpoint steps per segment, transmittance `exp(-tau)`.
    March(u32),
    /// Closed-form depth, seed 004's clamped blend `min(1, tau)`.
    LinearBlend,
}

impl FogRowKind {
    /// Every row of a scene, the analytic one first.
    pub fn all() -> Vec<FogRowKind> {
        let mut kinds = vec![FogRowKind::Analytic];
        kinds.extend(MARCH_STEPS.iter().map(|&steps| FogRowKind::March(steps)));
        kinds.push(FogRowKind::LinearBlend);
        kinds
    }

    /// `analytic`, `march`, `linear-blend`.
    pub fn mode(&self) -> &'static str {
        match self {
            FogRowKind::Analytic => "analytic",
            FogRowKind::March(_) => "march",
            FogRowKind::LinearBlend => "linear-blend",
        }
    }

    /// Steps per segment of a march row.
    pub fn steps(&self) -> Option<u32> {
        match *self {
            FogRowKind::March(steps) => Some(steps),
            _ => None,
        }
    }

    /// `analytic`, `march 16`, `linear-blend`.
    pub fn label(&self) -> String {
        match self {
            FogRowKind::March(steps) => format!("march {steps}"),
            other => other.mode().to_string(),
        }
    }

    /// The fog settings of this row.
    fn integration_and_model(&self) -> (FogIntegration, FogModel) {
        match *self {
            FogRowKind::Analytic => (FogIntegration::Exact, FogModel::Exact),
            FogRowKind::March(steps) => (
                FogIntegration::March {
                    steps_per_segment: steps,
                },
                FogModel::Exact,
            ),
            FogRowKind::LinearBlend => (FogIntegration::Exact, FogModel::LinearBlend),
        }
    }

    /// `scene` with this row's fog settings.
    pub fn scene(&self, scene: &SceneDescription) -> SceneDescription {
        let mut variant = scene.clone();
        let (integration, model) = self.integration_and_model();
        variant.settings.fog_integration = integration;
        variant.settings.fog_model = model;
        variant
    }
}

/// One row: what it cost and how far its image is from the analytic one.
#[derive(Clone, Debug, PartialEq)]
pub struct FogRow {
    pub kind: FogRowKind,
    /// Median render time of the timed runs, seconds.
    pub render_seconds: f64,
    /// Every timed render's seconds.
    pub run_seconds: Vec<f64>,
    /// Rays of every kind.
    pub rays: u64,
    /// Segments whose fog was evaluated (camera, secondary, shadow, escaping).
    pub fog_segments: u64,
    /// (segment, volume) pairs whose box the segment crossed.
    pub fog_volume_crossings: u64,
    /// Density samples taken by the march (0 for the closed form).
    pub fog_density_samples: u64,
    /// Error against the analytic render over all pixels.
    pub error: ErrorMetrics,
}

/// Everything measured for one scene.
#[derive(Clone, Debug)]
pub struct FogReport {
    pub name: String,
    pub source: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub runs: usize,
    pub threads: usize,
    /// The fog volumes, as `kind sigma` pairs, for the caption.
    pub volumes: Vec<String>,
    pub crop: PixelRect,
    /// In [`FogRowKind::all`] order.
    pub rows: Vec<FogRow>,
}

/// Renders every row of one scene and compares it with the analytic render.
fn measure(
    setup: &SceneSetup,
    args: &AccuracyArgs,
) -> Result<(FogReport, Vec<DisplayImage>), CommandError> {
    let say = |text: String| {
        if !args.quiet {
            eprintln!("accuracy: {}: {text}", setup.name);
        }
    };
    let textures = render::prepared::decode_textures(&setup.scene)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let options = RenderOptions {
        spp: setup.scene.settings.spp.unwrap_or(1).max(1),
        ..setup.base.clone()
    };
    let display = |result: &RenderResult| {
        DisplayImage::from_film(&result.film, setup.tonemap, setup.exposure)
            .ok_or_else(|| CommandError::internal("a render produced no colour layer"))
    };
    let control = RenderControl::default();

    let kinds = FogRowKind::all();
    let mut contexts = Vec::with_capacity(kinds.len());
    for kind in &kinds {
        let scene = Arc::new(kind.scene(&setup.scene));
        contexts.push(
            render::prepare_with_textures(scene, options.clone(), textures.clone())
                .map_err(|e| CommandError::bad_input(e.to_string()))?,
        );
    }
    let mut first = Vec::with_capacity(contexts.len());
    for context in &contexts {
        first.push(
            render::render(context, &Whitted::default(), &control)
                .map_err(crate::cli::render_failed)?,
        );
    }
    let images: Vec<DisplayImage> = first.iter().map(display).collect::<Result<_, _>>()?;
    let mut times = vec![Vec::with_capacity(args.runs); contexts.len()];
    for run in 0..args.runs {
        for (index, context) in contexts.iter().enumerate() {
            let result = render::render(context, &Whitted::default(), &control)
                .map_err(crate::cli::render_failed)?;
            times[index].push(result.stats.seconds);
        }
        say(format!("timed run {}/{} done", run + 1, args.runs));
    }

    let no_mask = vec![false; images[0].pixels.len()];
    let mut rows = Vec::with_capacity(kinds.len());
    for (index, kind) in kinds.iter().enumerate() {
        let counters = &first[index].stats.counters;
        let error = metrics::compare(&images[0], &images[index], &no_mask).all;
        rows.push(FogRow {
            kind: *kind,
            render_seconds: median(&times[index]),
            run_seconds: times[index].clone(),
            rays: counters.total_rays(),
            fog_segments: counters.fog_segments,
            fog_volume_crossings: counters.fog_volume_crossings,
            fog_density_samples: counters.fog_density_samples,
            error,
        });
        say(format!(
            "{}: RMSE {:.3e}, FLIP {:.3e}, render {:.3} s, {} fog segments, {} density samples",
            kind.label(),
            error.rmse,
            error.flip,
            median(&times[index]),
            counters.fog_segments,
            counters.fog_density_samples
        ));
    }

    // The crop: where the rows differ from the analytic image most, each row's squared error
    // divided by its own mean so that the march rows are not drowned by the blend's.
    let (width, height) = (options.width, options.height);
    let mut error = vec![0.0f64; images[0].pixels.len()];
    for (image, row) in images[1..].iter().zip(&rows[1..]) {
        let mean = row.error.rmse * row.error.rmse;
        if mean > 0.0 {
            for (sum, e) in error
                .iter_mut()
                .zip(metrics::squared_errors(&images[0], image))
            {
                *sum += e / mean;
            }
        }
    }
    let crop = crop::hardest_window(&error, width, height, crop::window_side(width, height));
    let volumes = setup
        .scene
        .fog
        .iter()
        .map(|v| {
            let bounded = match v.bounds {
                None => "",
                Some(conetrace::medium::FogBounds::Box(_)) => ", boxed",
                Some(conetrace::medium::FogBounds::Mesh(_)) => ", in a mesh",
            };
            format!("{} sigma {}{bounded}", v.density.kind(), v.density.sigma())
        })
        .collect();
    Ok((
        FogReport {
            name: setup.name.clone(),
            source: setup.scene.source.clone(),
            width,
            height,
            spp: options.spp,
            runs: args.runs,
            threads: rayon::current_num_threads(),
            volumes,
            crop,
            rows,
        },
        images,
    ))
}

/// The CSV header; one line per [`FogRow`] follows.
pub const CSV_HEADER: &str = "scene,mode,steps,render_seconds,rays,fog_segments,\
fog_volume_crossings,fog_density_samples,rmse,psnr_db,flip";

/// The report as CSV.
pub fn csv(report: &FogReport) -> String {
    let mut text = format!("{CSV_HEADER}\n");
    for row in &report.rows {
        text.push_str(&format!(
            "{},{},{},{:.6},{},{},{},{},{:.8},{:.2},{:.8}\n",
            report.name,
            row.kind.mode(),
            row.kind.steps().map_or(String::new(), |s| s.to_string()),
            row.render_seconds,
            row.rays,
            row.fog_segments,
            row.fog_volume_crossings,
            row.fog_density_samples,
            row.error.rmse,
            row.error.psnr,
            row.error.flip,
        ));
    }
    text
}

/// The report as a markdown table with a caption.
pub fn markdown(report: &FogReport) -> String {
    let mut text = format!(
        "`{}` ({}), {}x{}, {} spp, {} threads, fog: {}. Error against the analytic render \
         (the exact integral, same camera samples); render time the median of {} runs.\n\n\
         | mode | render s | fog segments | density samples | rays | RMSE | PSNR dB | FLIP |\n\
         |---|---|---|---|---|---|---|---|\n",
        report.name,
        report.source,
        report.width,
        report.height,
        report.spp,
        report.threads,
        report.volumes.join("; "),
        report.runs,
    );
    for row in &report.rows {
        text.push_str(&format!(
            "| {} | {:.3} | {} | {} | {} | {:.2e} | {:.1} | {:.2e} |\n",
            row.kind.label(),
            row.render_seconds,
            row.fog_segments,
            row.fog_density_samples,
            row.rays,
            row.error.rmse,
            row.error.psnr,
            row.error.flip,
        ));
    }
    text
}

/// The error-against-time plot of one scene as RGB8 pixels of [`super::plot::PLOT_SIZE`]: RMSE on the
/// left, FLIP on the right, both over all pixels, the analytic render's time as a vertical
/// line (its error is 0).
pub fn draw_plot(report: &FogReport, labels: bool) -> Result<Vec<u8>, String> {
    let compared: Vec<&FogRow> = report
        .rows
        .iter()
        .filter(|r| r.kind != FogRowKind::Analytic)
        .collect();
    let analytic_seconds = report
        .rows
        .iter()
        .find(|r| r.kind == FogRowKind::Analytic)
        .map_or(f64::NAN, |r| r.render_seconds);
    let points = |error: fn(&FogRow) -> f64| -> Vec<PlotPoint> {
        compared
            .iter()
            .map(|r| PlotPoint {
                seconds: r.render_seconds,
                error: error(r),
                label: r.kind.label(),
                colour: BLUE,
            })
            .collect()
    };
    let text = |title: String, error_name: &str| PanelText {
        title,
        x_desc: "seconds (median render), log scale",
        y_desc: format!("{error_name} against analytic, log scale"),
        empty_note: "every row equals the analytic image",
        zero_error: Some((analytic_seconds, "analytic")),
    };
    let rmse_title = format!("{}: fog RMSE", report.name);
    let flip_title = format!("{}: fog FLIP", report.name);
    draw_two_panels(
        (&text(rmse_title, "RMSE"), &points(|r| r.error.rmse)),
        (&text(flip_title, "FLIP"), &points(|r| r.error.flip)),
        labels,
    )
}

/// Writes the four files of one scene.
fn write_outputs(
    out: &Path,
    report: &FogReport,
    images: &[DisplayImage],
) -> Result<(), CommandError> {
    let panels: Vec<crop::Panel> = report
        .rows
        .iter()
        .zip(images)
        .map(|(row, image)| crop::Panel {
            title: row.kind.label(),
            subtitle: format!("RMSE {:.2e}, FLIP {:.2e}", row.error.rmse, row.error.flip),
            image,
        })
        .collect();
    files::write_scene_report(
        out,
        &format!("{}_fog", report.name),
        (&csv(report), &markdown(report)),
        draw_plot(report, font::labels_available()),
        &panels,
        report.crop,
    )
}

/// Measures every scene and writes its files; see the module docs.
pub fn run(args: &AccuracyArgs) -> Result<(), CommandError> {
    if args.runs == 0 {
        return Err(CommandError::bad_input("--runs must be at least 1"));
    }
    let mut setups = Vec::new();
    for path in super::mode_scene_paths(args, &DEFAULT_SCENES)? {
        let setup = super::load_scene(args, super::scene_name(&path), Some(&path))?;
        if !setup.scene.fog.iter().any(|v| v.density.sigma() > 0.0) {
            return Err(CommandError::bad_input(format!(
                "{}: the scene has no fog to compare",
                path.display()
            )));
        }
        setups.push(setup);
    }
    let out = args.out.join(OUTPUT_SUBDIR);
    files::check_output_dir(&out)?;
    let pool = crate::cli::worker_pool(args.threads)?;
    for setup in &setups {
        let (report, images) = pool.install(|| measure(setup, args))?;
        write_outputs(&out, &report, &images)?;
        println!(
            "{}: wrote {}/{}_fog.csv, .md, _error_vs_time.png, _crop.png",
            setup.name,
            out.display(),
            setup.name
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_set_the_fog_settings_they_name() {
        let scene = SceneDescription::default();
        let kinds = FogRowKind::all();
        assert_eq!(kinds.len(), 2 + MARCH_STEPS.len());
        assert_eq!(kinds[0], FogRowKind::Analytic);
        let marched = FogRowKind::March(64).scene(&scene);
        assert_eq!(
            marched.settings.fog_integration,
            FogIntegration::March {
                steps_per_segment: 64
            }
        );
        assert_eq!(marched.settings.fog_model, FogModel::Exact);
        let blend = FogRowKind::LinearBlend.scene(&scene);
        assert_eq!(blend.settings.fog_integration, FogIntegration::Exact);
        assert_eq!(blend.settings.fog_model, FogModel::LinearBlend);
        assert_eq!(FogRowKind::March(4).label(), "march 4");
        assert_eq!(FogRowKind::LinearBlend.steps(), None);
    }
}
