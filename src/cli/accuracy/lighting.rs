//! `conetrace accuracy --mode lighting`: how close each light-transport algorithm comes to a
//! path-traced ground truth, and at what cost.
//!
//! Every scene (default: [`DEFAULT_SCENES`], the Cornell box lit by an area light and the
//! three scenes of docs/vct.md) is rendered with
//! - Whitted plus its constant ambient term, as Whitted renders these scenes;
//! - the path tracer at every `--lighting-path-spp` count (1, 4, 16, 64, 256);
//! - the voxel cone tracer at every `--lighting-vct-resolutions` grid (32, 64, 128, 256),
//!   once with the voxels holding direct light only (`--vct-bounces 1`) and once with the
//!   default bounces (`vct::build::DEFAULT_BOUNCES`, 3);
//!
//! and compared with the path tracer at `--lighting-reference-spp` samples (1024) drawn with
//! another seed ([`super::methods::ground_truth_seed`]): as its samples grow it converges to
//! the solution of the rendering equation for the scene's lights and materials, which
//! Whitted and vct approximate and the path-traced rows estimate with noise.
//! Whitted and vct are deterministic per sample: they render at `--lighting-spp` samples
//! (4), which only antialias edges. Errors are RMSE and FLIP of display values
//! ([`super::metrics::compare`]) over all pixels.
//!
//! Images are `--lighting-size` pixels (128) on their longer side, the other side following
//! the scene's own `[render]` aspect ratio (the `--width`/`--height` of the other modes do
//! not apply: the scenes here are square and 2:1).
//!
//! Cost: each row's render time is the median of `--runs` renders (the first of which gives
//! the image); a vct row adds the voxel scene's build (voxelisation, light injection,
//! mipmapping and the extra bounce, measured once), and the total is what the plot's time
//! axis shows. A row is on the Pareto front when no other row is at least as fast and at
//! least as accurate (RMSE) and strictly better in one of them.
//!
//! Outputs in `--out`/lighting (checked in: docs/accuracy/lighting), per scene: `<scene>.csv`,
//! `<scene>.md`, `<scene>_error_vs_time.png` (RMSE and FLIP against total seconds, log-log,
//! the front in red) and `<scene>_crop.png` (the window where the rows err most on average,
//! the reference first). Bad input stops the command before it renders anything.

use std::path::Path;
use std::time::Instant;

use plotters::style::RGBColor;

use crate::cli::CommandError;
use crate::film::PixelRect;
use crate::integrator::{PathTracer, Vct, Whitted};
use crate::render::{self, Integrator, RenderContext, RenderControl, RenderOptions, RenderResult};
use conetrace::vct::build::DEFAULT_BOUNCES;
use conetrace::vct::{build_voxel_scene, VctSettings, VoxelKind};

use super::metrics::{self, DisplayImage, ErrorMetrics};
use super::plot::{draw_two_panels, pareto_front, PanelText, PlotPoint};
use super::{crop, files, font, AccuracyArgs, SceneSetup};
use crate::cli::summary::median;

/// Scenes measured when none is named (run from the repository root).
pub const DEFAULT_SCENES: [&str; 4] = [
    "assets/scenes/cornell.toml",
    "assets/scenes/vct_cornell.toml",
    "assets/scenes/vct_corner.toml",
    "assets/scenes/vct_light_leak.toml",
];

/// The subdirectory of `--out` the lighting report is written to.
pub const OUTPUT_SUBDIR: &str = "lighting";

/// Largest grid resolution vct accepts for an explicit one.
const MAX_VCT_RESOLUTION: u32 = conetrace::vct::build::MAX_RESOLUTION;

/// How one row transports light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightingMethod {
    /// Whitted with its constant ambient term.
    Whitted,
    /// The path tracer at this many samples per pixel.
    Path { spp: u32 },
    /// The voxel cone tracer on a grid of `resolution` voxels across the scene, the voxels
    /// holding `bounces` bounces (1: direct light only), of kind `voxels`.
    Vct {
        resolution: u32,
        bounces: u32,
        voxels: VoxelKind,
    },
}

impl LightingMethod {
    /// The vct grid resolution and bounces as table cells; empty for the other methods.
    fn vct_columns(&self) -> (String, String) {
        match self {
            LightingMethod::Vct {
                resolution,
                bounces,
                ..
            } => (resolution.to_string(), bounces.to_string()),
            _ => (String::new(), String::new()),
        }
    }

    /// `whitted`, `path`, `vct` (directional voxels), `vct_isotropic`.
    pub fn name(&self) -> &'static str {
        match self {
            LightingMethod::Whitted => "whitted",
            LightingMethod::Path { .. } => "path",
            LightingMethod::Vct {
                voxels: VoxelKind::Directional,
                ..
            } => "vct",
            LightingMethod::Vct { .. } => "vct_isotropic",
        }
    }

    /// A short label for plots and crops: `whitted+ambient`, `path 16`, `vct 64 b2`,
    /// `vct 64 b1 iso`.
    pub fn label(&self) -> String {
        match self {
            LightingMethod::Whitted => "whitted+ambient".to_string(),
            LightingMethod::Path { spp } => format!("path {spp}"),
            LightingMethod::Vct {
                resolution,
                bounces,
                voxels: VoxelKind::Directional,
            } => format!("vct {resolution} b{bounces}"),
            LightingMethod::Vct {
                resolution,
                bounces,
                voxels: VoxelKind::Isotropic,
            } => format!("vct {resolution} b{bounces} iso"),
        }
    }
}

/// One method's image error and cost.
#[derive(Clone, Debug, PartialEq)]
pub struct LightingRow {
    pub method: LightingMethod,
    /// Samples per pixel of the render.
    pub spp: u32,
    /// The voxel scene's build, seconds (0 for Whitted and path).
    pub build_seconds: f64,
    /// Median render time of the runs, seconds.
    pub render_seconds: f64,
    /// Every run's render seconds.
    pub run_seconds: Vec<f64>,
    /// Rays of every kind in the first render.
    pub rays: u64,
    /// Error against the reference over all pixels.
    pub error: ErrorMetrics,
    /// Whether the row is on the Pareto front of (total seconds, RMSE).
    pub pareto: bool,
}

impl LightingRow {
    /// Build plus render time: the plot's time axis.
    pub fn total_seconds(&self) -> f64 {
        self.build_seconds + self.render_seconds
    }
}

/// Everything measured for one scene.
#[derive(Clone, Debug)]
pub struct LightingReport {
    pub name: String,
    pub source: String,
    pub width: u32,
    pub height: u32,
    /// The path tracer's bounce limit (the scene's `max_depth`), for reference and rows.
    pub max_depth: u32,
    pub reference_spp: u32,
    pub reference_seconds: f64,
    pub runs: usize,
    pub threads: usize,
    pub crop: PixelRect,
    /// Whitted first, then path by samples, then vct by resolution and bounces.
    pub rows: Vec<LightingRow>,
}

/// The rows the options ask for, in report order.
pub fn methods(args: &AccuracyArgs) -> Vec<LightingMethod> {
    let mut methods = vec![LightingMethod::Whitted];
    methods.extend(
        args.lighting_path_spp
            .iter()
            .map(|&spp| LightingMethod::Path { spp }),
    );
    // The isotropic voxels are measured with direct light only: the reason for the
    // directional ones, not a setting to tune.
    for &resolution in &args.lighting_vct_resolutions {
        for bounces in [1, DEFAULT_BOUNCES] {
            methods.push(LightingMethod::Vct {
                resolution,
                bounces,
                voxels: VoxelKind::Directional,
            });
        }
        methods.push(LightingMethod::Vct {
            resolution,
            bounces: 1,
            voxels: VoxelKind::Isotropic,
        });
    }
    methods
}

/// The image size: `longer` pixels on the longer side, the other side in the scene's
/// aspect ratio (at least 1).
pub fn image_size(scene_width: u32, scene_height: u32, longer: u32) -> (u32, u32) {
    let (w, h) = (scene_width.max(1) as f64, scene_height.max(1) as f64);
    if w >= h {
        (longer, ((longer as f64 * h / w).round() as u32).max(1))
    } else {
        (((longer as f64 * w / h).round() as u32).max(1), longer)
    }
}

/// Checks the mode's options; a bad one is a one-line error.
fn check_options(args: &AccuracyArgs) -> Result<(), CommandError> {
    if args.runs == 0 {
        return Err(CommandError::bad_input("--runs must be at least 1"));
    }
    if args.lighting_size == 0 || args.lighting_size > 65_536 {
        return Err(CommandError::bad_input(
            "--lighting-size must be between 1 and 65536",
        ));
    }
    if args.lighting_reference_spp == 0 || args.lighting_spp == 0 {
        return Err(CommandError::bad_input(
            "--lighting-reference-spp and --lighting-spp must be at least 1",
        ));
    }
    if args.lighting_path_spp.contains(&0) {
        return Err(CommandError::bad_input(
            "--lighting-path-spp: every count must be at least 1",
        ));
    }
    if let Some(bad) = args
        .lighting_vct_resolutions
        .iter()
        .find(|&&r| !(2..=MAX_VCT_RESOLUTION).contains(&r))
    {
        return Err(CommandError::bad_input(format!(
            "--lighting-vct-resolutions: {bad} is outside 2..{MAX_VCT_RESOLUTION}"
        )));
    }
    Ok(())
}

/// Renders `context` `runs` times with `integrator`: the first result and every run's
/// seconds.
fn timed_renders<I: Integrator>(
    context: &RenderContext,
    integrator: &I,
    runs: usize,
) -> Result<(RenderResult, Vec<f64>), CommandError> {
    let control = RenderControl::default();
    let first = render::render(context, integrator, &control).map_err(crate::cli::render_failed)?;
    let mut seconds = vec![first.stats.seconds];
    for _ in 1..runs {
        let result =
            render::render(context, integrator, &control).map_err(crate::cli::render_failed)?;
        seconds.push(result.stats.seconds);
    }
    Ok((first, seconds))
}

/// Renders the reference and every row of one scene and compares them.
fn measure(
    setup: &SceneSetup,
    args: &AccuracyArgs,
) -> Result<(LightingReport, DisplayImage, Vec<DisplayImage>), CommandError> {
    let say = |text: String| {
        if !args.quiet {
            eprintln!("accuracy: {}: {text}", setup.name);
        }
    };
    let textures = render::prepared::decode_textures(&setup.scene)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let prepare = |options: RenderOptions| {
        render::prepare_with_textures(setup.scene.clone(), options, textures.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))
    };
    let display = |result: &RenderResult| {
        DisplayImage::from_film(&result.film, setup.tonemap, setup.exposure)
            .ok_or_else(|| CommandError::internal("a render produced no colour layer"))
    };
    let control = RenderControl::default();
    let path_tracer = PathTracer::for_settings(&setup.scene.settings);

    // The ground truth: the path tracer at many samples with another seed.
    let reference_context = prepare(RenderOptions {
        spp: args.lighting_reference_spp,
        seed: super::methods::ground_truth_seed(setup.base.seed),
        ..setup.base.clone()
    })?;
    let reference = render::render(&reference_context, &path_tracer, &control)
        .map_err(crate::cli::render_failed)?;
    drop(reference_context);
    say(format!(
        "reference (path, {} spp) in {:.2} s",
        args.lighting_reference_spp, reference.stats.seconds
    ));
    let reference_seconds = reference.stats.seconds;
    let reference = display(&reference)?;
    let no_mask = vec![false; reference.pixels.len()];

    let mut rows = Vec::new();
    let mut images = Vec::new();
    for method in methods(args) {
        let spp = match method {
            LightingMethod::Path { spp } => spp,
            _ => args.lighting_spp,
        };
        let context = prepare(RenderOptions {
            spp,
            ..setup.base.clone()
        })?;
        let (build_seconds, (first, run_seconds)) = match method {
            LightingMethod::Whitted => (
                0.0,
                timed_renders(&context, &Whitted::default(), args.runs)?,
            ),
            LightingMethod::Path { .. } => (0.0, timed_renders(&context, &path_tracer, args.runs)?),
            LightingMethod::Vct {
                resolution,
                bounces,
                voxels,
            } => {
                let started = Instant::now();
                let voxels = build_voxel_scene(
                    &context,
                    &VctSettings {
                        resolution: Some(resolution),
                        bounces,
                        voxels,
                    },
                )
                .map_err(|e| CommandError::bad_input(format!("{}: {e}", setup.scene.source)))?;
                let build_seconds = started.elapsed().as_secs_f64();
                let vct = Vct::new(voxels);
                (build_seconds, timed_renders(&context, &vct, args.runs)?)
            }
        };
        let image = display(&first)?;
        let error = metrics::compare(&reference, &image, &no_mask).all;
        let row = LightingRow {
            method,
            spp,
            build_seconds,
            render_seconds: median(&run_seconds),
            run_seconds,
            rays: first.stats.counters.total_rays(),
            error,
            pareto: false,
        };
        say(format!(
            "{}: RMSE {:.5}, FLIP {:.4}, build {:.3} s, render {:.3} s",
            method.label(),
            error.rmse,
            error.flip,
            build_seconds,
            row.render_seconds
        ));
        rows.push(row);
        images.push(image);
    }
    mark_pareto_front(&mut rows);

    // The crop: where the rows err most on average.
    let (width, height) = (setup.base.width, setup.base.height);
    let mut error = vec![0.0f64; reference.pixels.len()];
    for image in &images {
        for (sum, e) in error
            .iter_mut()
            .zip(metrics::squared_errors(&reference, image))
        {
            *sum += e / images.len() as f64;
        }
    }
    let crop = crop::hardest_window(&error, width, height, crop::window_side(width, height));
    Ok((
        LightingReport {
            name: setup.name.clone(),
            source: setup.scene.source.clone(),
            width,
            height,
            max_depth: setup.base.max_depth,
            reference_spp: args.lighting_reference_spp,
            reference_seconds,
            runs: args.runs,
            threads: rayon::current_num_threads(),
            crop,
            rows,
        },
        reference,
        images,
    ))
}

/// Sets `pareto` on the rows no other row beats in both total seconds and RMSE.
pub fn mark_pareto_front(rows: &mut [LightingRow]) {
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.total_seconds(), r.error.rmse))
        .collect();
    let front = pareto_front(&points);
    for (index, row) in rows.iter_mut().enumerate() {
        row.pareto = front.contains(&index);
    }
}

/// The CSV header; one line per [`LightingRow`] follows.
pub const CSV_HEADER: &str = "scene,method,spp,vct_resolution,vct_bounces,build_seconds,\
render_seconds,total_seconds,rays,rmse,psnr_db,flip,pareto";

/// The report as CSV.
pub fn csv(report: &LightingReport) -> String {
    let mut text = format!("{CSV_HEADER}\n");
    for row in &report.rows {
        let (resolution, bounces) = row.method.vct_columns();
        text.push_str(&format!(
            "{},{},{},{},{},{:.6},{:.6},{:.6},{},{:.6},{:.2},{:.6},{}\n",
            report.name,
            row.method.name(),
            row.spp,
            resolution,
            bounces,
            row.build_seconds,
            row.render_seconds,
            row.total_seconds(),
            row.rays,
            row.error.rmse,
            row.error.psnr,
            row.error.flip,
            row.pareto,
        ));
    }
    text
}

/// The report as a markdown table with a one-line caption.
pub fn markdown(report: &LightingReport) -> String {
    let mut text = format!(
        "`{}` ({}), {}x{}, {} threads; error against the path tracer at {} spp (another seed, \
         max depth {}, rendered in {:.2} s); render time the median of {} runs; vct's total \
         adds the voxel build. Rows marked * are on the Pareto front of total time and RMSE.\n\n\
         | method | spp | vct grid | vct bounces | build s | render s | total s | rays | RMSE | PSNR dB | FLIP | front |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
        report.name,
        report.source,
        report.width,
        report.height,
        report.threads,
        report.reference_spp,
        report.max_depth,
        report.reference_seconds,
        report.runs,
    );
    for row in &report.rows {
        let (resolution, bounces) = row.method.vct_columns();
        text.push_str(&format!(
            "| {} | {} | {} | {} | {:.3} | {:.3} | {:.3} | {} | {:.5} | {:.2} | {:.4} | {} |\n",
            row.method.label(),
            row.spp,
            resolution,
            bounces,
            row.build_seconds,
            row.render_seconds,
            row.total_seconds(),
            row.rays,
            row.error.rmse,
            row.error.psnr,
            row.error.flip,
            if row.pareto { "*" } else { "" },
        ));
    }
    text
}

/// A colour per family of rows: Whitted, path, isotropic vct, vct direct only, vct with a
/// bounce.
fn family_colour(method: &LightingMethod) -> RGBColor {
    match method {
        LightingMethod::Whitted => RGBColor(20, 20, 20),
        LightingMethod::Path { .. } => RGBColor(0, 114, 178),
        LightingMethod::Vct {
            voxels: VoxelKind::Isotropic,
            ..
        } => RGBColor(204, 121, 167),
        LightingMethod::Vct { bounces: 1, .. } => RGBColor(230, 159, 0),
        LightingMethod::Vct { .. } => RGBColor(0, 158, 115),
    }
}

/// The error-against-time plot of one scene as RGB8 pixels of [`super::plot::PLOT_SIZE`]: RMSE on the
/// left, FLIP on the right, each with its own Pareto front; a marker per row at its total
/// seconds, coloured by family and labelled.
pub fn draw_plot(report: &LightingReport, labels: bool) -> Result<Vec<u8>, String> {
    let points = |error: fn(&LightingRow) -> f64| -> Vec<PlotPoint> {
        report
            .rows
            .iter()
            .map(|r| PlotPoint {
                seconds: r.total_seconds(),
                error: error(r),
                label: r.method.label(),
                colour: family_colour(&r.method),
            })
            .collect()
    };
    let text = |title: String, error_name: &str| PanelText {
        title,
        x_desc: "seconds (vct build + median render), log scale",
        y_desc: format!("{error_name} against path reference, log scale"),
        empty_note: "no positive values to plot",
        zero_error: None,
    };
    let rmse_title = format!("{}: RMSE", report.name);
    let flip_title = format!("{}: FLIP", report.name);
    draw_two_panels(
        (&text(rmse_title, "RMSE"), &points(|r| r.error.rmse)),
        (&text(flip_title, "FLIP"), &points(|r| r.error.flip)),
        labels,
    )
}

/// Writes the four files of one scene.
fn write_outputs(
    out: &Path,
    report: &LightingReport,
    reference: &DisplayImage,
    images: &[DisplayImage],
) -> Result<(), CommandError> {
    let mut panels = vec![crop::Panel {
        title: "reference".to_string(),
        subtitle: format!("path {} spp", report.reference_spp),
        image: reference,
    }];
    for (row, image) in report.rows.iter().zip(images) {
        panels.push(crop::Panel {
            title: row.method.label(),
            subtitle: format!("RMSE {:.4}, FLIP {:.3}", row.error.rmse, row.error.flip),
            image,
        });
    }
    files::write_scene_report(
        out,
        &report.name,
        (&csv(report), &markdown(report)),
        draw_plot(report, font::labels_available()),
        &panels,
        report.crop,
    )
}

/// Measures every scene and writes its files; see the module docs.
pub fn run(args: &AccuracyArgs) -> Result<(), CommandError> {
    check_options(args)?;
    // Load and check every scene before writing or rendering anything.
    let mut setups = Vec::new();
    for path in super::mode_scene_paths(args, &DEFAULT_SCENES)? {
        let mut setup = super::load_scene(args, super::scene_name(&path), Some(&path))?;
        let (width, height) = image_size(
            setup.scene.settings.width,
            setup.scene.settings.height,
            args.lighting_size,
        );
        setup.base.width = width;
        setup.base.height = height;
        // A grid vct would refuse (its pyramid over the memory limit) is refused now, not
        // after the reference has rendered.
        let (lo, hi) = setup.scene.bounds().unwrap_or_default();
        for &resolution in &args.lighting_vct_resolutions {
            let bytes = conetrace::vct::GridFrame::for_bounds(lo, hi, resolution)
                .pyramid_bytes(VoxelKind::Directional);
            if bytes > conetrace::vct::build::MAX_PYRAMID_BYTES {
                return Err(CommandError::bad_input(format!(
                    "{}: --lighting-vct-resolutions {resolution} needs a {bytes}-byte voxel \
                     pyramid, over the {}-byte limit",
                    path.display(),
                    conetrace::vct::build::MAX_PYRAMID_BYTES
                )));
            }
        }
        setups.push(setup);
    }
    let out = args.out.join(OUTPUT_SUBDIR);
    files::check_output_dir(&out)?;
    let pool = crate::cli::worker_pool(args.threads)?;
    for setup in &setups {
        let (report, reference, images) = pool.install(|| measure(setup, args))?;
        write_outputs(&out, &report, &reference, &images)?;
        println!(
            "{}: wrote {}/{}.csv, .md, _error_vs_time.png, _crop.png",
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

    fn row(method: LightingMethod, seconds: f64, rmse: f64) -> LightingRow {
        LightingRow {
            method,
            spp: 1,
            build_seconds: 0.0,
            render_seconds: seconds,
            run_seconds: vec![seconds],
            rays: 0,
            error: ErrorMetrics {
                rmse,
                psnr: 0.0,
                flip: 0.0,
            },
            pareto: false,
        }
    }

    #[test]
    fn image_size_keeps_the_scene_aspect() {
        assert_eq!(image_size(256, 256, 64), (64, 64));
        assert_eq!(image_size(320, 160, 128), (128, 64));
        assert_eq!(image_size(160, 320, 128), (64, 128));
        assert_eq!(image_size(1000, 1, 10), (10, 1));
    }

    #[test]
    fn the_front_holds_the_rows_nothing_beats() {
        let mut rows = vec![
            row(LightingMethod::Whitted, 0.1, 0.30),
            row(LightingMethod::Path { spp: 1 }, 0.2, 0.40),
            row(LightingMethod::Path { spp: 16 }, 2.0, 0.10),
            row(
                LightingMethod::Vct {
                    resolution: 64,
                    bounces: 1,
                    voxels: VoxelKind::Directional,
                },
                0.5,
                0.20,
            ),
        ];
        rows[3].build_seconds = 2.0; // total 2.5 s: beaten by path 16 in time and error
        mark_pareto_front(&mut rows);
        let front: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(front, vec![true, false, true, false]);
    }

    #[test]
    fn methods_cover_every_count_both_bounce_settings_and_isotropic_voxels() {
        use clap::Parser;
        #[derive(Parser)]
        struct Wrapper {
            #[command(flatten)]
            args: AccuracyArgs,
        }
        let parsed = Wrapper::parse_from([
            "accuracy",
            "--lighting-path-spp",
            "1,16",
            "--lighting-vct-resolutions",
            "32",
        ]);
        assert_eq!(
            methods(&parsed.args),
            vec![
                LightingMethod::Whitted,
                LightingMethod::Path { spp: 1 },
                LightingMethod::Path { spp: 16 },
                LightingMethod::Vct {
                    resolution: 32,
                    bounces: 1,
                    voxels: VoxelKind::Directional,
                },
                LightingMethod::Vct {
                    resolution: 32,
                    bounces: DEFAULT_BOUNCES,
                    voxels: VoxelKind::Directional,
                },
                LightingMethod::Vct {
                    resolution: 32,
                    bounces: 1,
                    voxels: VoxelKind::Isotropic,
                },
            ]
        );
    }
}
