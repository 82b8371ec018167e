//! `conetrace accuracy --mode patches`: curved patches traced exactly against the same
//! patches tessellated at several error bounds, and height patches marched at several
//! steps — image error, time, triangles, memory.
//!
//! Every scene (default: [`DEFAULT_SCENES`], a mirror and a textured teapot and a height
//! patch) is rendered once with its patches traced exactly (`--patch-mode exact`; height
//! patches in their Bezier form), once per bound of [`TESSELLATION_BOUNDS`] with them
//! tessellated (`--patch-mode tessellate`) and, when it has height patches, once per step
//! of [`MARCH_STEPS`] with those marched; all at `--patch-spp` samples per pixel with the
//! same seed, so the camera rays are the same and the only difference is the surface: each
//! image is compared with the exact one (RMSE and FLIP of display values,
//! [`super::metrics::compare`], over all pixels and over the textured ones): the surface's
//! own error, with the sampling noise cancelled. The exact row's error is 0 by definition;
//! the plot draws its time as a vertical line. Every row is also compared with a high-sample
//! exact reference (`--patch-reference-spp`, another seed): the total error a user sees at
//! `--patch-spp`, geometry plus noise, where the exact row shows the noise alone.
//!
//! Cost: `build` is the tessellation plus the scene's preparation (Embree's BVH and the
//! render tables), `render` the median of `--runs` timed renders (interleaved across rows,
//! after an untimed first render that gives the image). Memory is the geometry the mode adds:
//! for tessellation the meshes' arrays (positions, normals, texture coordinates, indices);
//! for exact patches the control points and each patch's subdivision hierarchy
//! (`crate::scene::patch::hull_tree`). Embree's BVH is not counted in either.
//!
//! Outputs in `--out`, per scene: `<scene>_patches.csv`, `<scene>_patches.md`,
//! `<scene>_patches_error_vs_time.png` and `<scene>_patches_crop.png` (the window where
//! the tessellations differ most, at every bound).

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use plotters::style::BLUE;

use crate::cli::CommandError;
use crate::film::PixelRect;
use crate::integrator::Whitted;
use crate::render::{self, RenderControl, RenderOptions, RenderResult};
use crate::scene::patch::intersect::PatchIntersector;
use crate::scene::patch::tessellate::tessellate_all;
use crate::scene::SceneDescription;

use super::metrics::{self, DisplayImage, ErrorMetrics};
use super::plot::{draw_two_panels, PanelText, PlotPoint};
use super::{crop, files, font, AccuracyArgs, SceneSetup};
use crate::cli::summary::median;

/// Scenes measured when none is named (run from the repository root).
pub const DEFAULT_SCENES: [&str; 3] = [
    "assets/scenes/teapot_mirror.toml",
    "assets/scenes/teapot_textured.toml",
    "assets/scenes/height_patch.toml",
];

/// The subdirectory of `--out` the patch report is written to.
pub const OUTPUT_SUBDIR: &str = "patches";

/// Tessellation error bounds compared, in world units (coarsest first).
pub const TESSELLATION_BOUNDS: [f32; 5] = [1e-1, 3e-2, 1e-2, 1e-3, 1e-4];

/// March steps compared on height patches, in world units (coarsest first).
pub const MARCH_STEPS: [f32; 5] = [5e-1, 2e-1, 1e-1, 3e-2, 1e-2];

/// How a row renders the scene's curved surfaces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RowKind {
    /// Every patch (height patches in their Bezier form) traced exactly: the reference.
    Exact,
    /// Every patch tessellated within this distance.
    Tessellate(f32),
    /// Height patches marched at this step; other patches exact.
    March(f32),
}

impl RowKind {
    /// `exact`, `tessellate`, `march`.
    pub fn mode(&self) -> &'static str {
        match self {
            RowKind::Exact => "exact",
            RowKind::Tessellate(_) => "tessellate",
            RowKind::March(_) => "march",
        }
    }

    /// The error bound or step (`None` for exact).
    pub fn parameter(&self) -> Option<f32> {
        match *self {
            RowKind::Exact => None,
            RowKind::Tessellate(e) | RowKind::March(e) => Some(e),
        }
    }

    /// A short label: `exact`, `E=0.01`, `step=0.01`.
    pub fn short(&self) -> String {
        match self {
            RowKind::Exact => "exact".to_string(),
            RowKind::Tessellate(e) => format!("E={e}"),
            RowKind::March(h) => format!("step={h}"),
        }
    }
}

/// One way of rendering a scene's patches and what it cost.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchRow {
    /// `exact`, `tessellate E` or `march h`.
    pub label: String,
    pub kind: RowKind,
    /// Triangles the patches became (0 when traced exactly).
    pub triangles: usize,
    /// Memory of the patch geometry this mode keeps, bytes (see the module docs).
    pub geometry_bytes: u64,
    /// Tessellation plus preparation, seconds.
    pub build_seconds: f64,
    /// Median render time of the timed runs, seconds.
    pub render_seconds: f64,
    /// Every timed render's seconds.
    pub run_seconds: Vec<f64>,
    /// Rays of every kind.
    pub rays: u64,
    /// Error against the exact render over all pixels.
    pub error: ErrorMetrics,
    /// The same over the textured pixels (`None` when no pixel is textured).
    pub textured_error: Option<ErrorMetrics>,
    /// Error against the high-sample exact reference over all pixels (geometry plus noise).
    pub reference_error: ErrorMetrics,
}

impl PatchRow {
    /// Build plus render time: what the plot's time axis shows.
    pub fn total_seconds(&self) -> f64 {
        self.build_seconds + self.render_seconds
    }
}

/// Everything measured for one scene.
#[derive(Clone, Debug)]
pub struct PatchReport {
    pub name: String,
    pub source: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Samples per pixel of the exact reference.
    pub reference_spp: u32,
    pub runs: usize,
    pub threads: usize,
    pub textured_pixels: usize,
    pub crop: PixelRect,
    /// The exact row first, then the bounds in [`TESSELLATION_BOUNDS`] order (scenes with
    /// patches), then the steps of [`MARCH_STEPS`] (scenes with height patches).
    pub rows: Vec<PatchRow>,
}

/// A scene made ready for one row: the scene itself (patches, or their tessellation) and
/// what making it cost.
struct Variant {
    label: String,
    kind: RowKind,
    scene: Arc<SceneDescription>,
    triangles: usize,
    geometry_bytes: u64,
    tessellation_seconds: f64,
}

/// Memory of the exact patches: f32 and f64 control points and the hierarchy.
fn exact_bytes(scene: &SceneDescription) -> u64 {
    scene
        .patches
        .iter()
        .map(|patch| {
            let hierarchy = PatchIntersector::new(&patch.control).hierarchy_bytes();
            (16 * (12 + 24) + hierarchy) as u64
        })
        .sum()
}

/// Memory of marched height patches: the rectangle, 16 heights and the step.
fn height_bytes(scene: &SceneDescription) -> u64 {
    (scene.height_patches.len() * std::mem::size_of::<crate::scene::patch::height::HeightPatch>())
        as u64
}

/// `scene` with its height patches replaced by the same surfaces as Bezier patches.
fn all_bezier(scene: &SceneDescription) -> SceneDescription {
    let mut converted = scene.clone();
    let heights = std::mem::take(&mut converted.height_patches);
    converted
        .patches
        .extend(heights.iter().map(|h| h.to_bezier()));
    converted
}

fn variants(scene: &SceneDescription) -> Vec<Variant> {
    let exact = Arc::new(all_bezier(scene));
    let mut variants = vec![Variant {
        label: "exact".to_string(),
        kind: RowKind::Exact,
        geometry_bytes: exact_bytes(&exact),
        scene: exact.clone(),
        triangles: 0,
        tessellation_seconds: 0.0,
    }];
    if !scene.patches.is_empty() {
        for bound in TESSELLATION_BOUNDS {
            let mut tessellated = (*exact).clone();
            let first_new_mesh = tessellated.meshes.len();
            let report = tessellate_all(&mut tessellated.patches, &mut tessellated.meshes, bound);
            let geometry_bytes = tessellated.meshes[first_new_mesh..]
                .iter()
                .map(|mesh| {
                    (mesh.positions.len() * 12
                        + mesh.normals.len() * 12
                        + mesh.st.len() * 8
                        + mesh.triangles.len() * 12) as u64
                })
                .sum();
            variants.push(Variant {
                label: format!("tessellate {bound}"),
                kind: RowKind::Tessellate(bound),
                scene: Arc::new(tessellated),
                triangles: report.triangles,
                geometry_bytes,
                tessellation_seconds: report.seconds,
            });
        }
    }
    if !scene.height_patches.is_empty() {
        for step in MARCH_STEPS {
            let mut marched = scene.clone();
            for patch in &mut marched.height_patches {
                patch.march_step = step;
            }
            variants.push(Variant {
                label: format!("march {step}"),
                kind: RowKind::March(step),
                geometry_bytes: exact_bytes(&marched) + height_bytes(&marched),
                scene: Arc::new(marched),
                triangles: 0,
                tessellation_seconds: 0.0,
            });
        }
    }
    variants
}

/// Renders every variant of one scene and compares it with the exact render.
fn measure(
    setup: &SceneSetup,
    args: &AccuracyArgs,
) -> Result<(PatchReport, Vec<DisplayImage>), CommandError> {
    let say = |text: String| {
        if !args.quiet {
            eprintln!("accuracy: {}: {text}", setup.name);
        }
    };
    let textures = render::prepared::decode_textures(&setup.scene)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let options = RenderOptions {
        spp: args.patch_spp,
        ..setup.base.clone()
    };
    let display = |result: &RenderResult| {
        DisplayImage::from_film(&result.film, setup.tonemap, setup.exposure)
            .ok_or_else(|| CommandError::internal("a render produced no colour layer"))
    };
    let control = RenderControl::default();

    let variants = variants(&setup.scene);
    let mut contexts = Vec::with_capacity(variants.len());
    let mut build_seconds = Vec::with_capacity(variants.len());
    for variant in &variants {
        let started = Instant::now();
        let context =
            render::prepare_with_textures(variant.scene.clone(), options.clone(), textures.clone())
                .map_err(|e| CommandError::bad_input(e.to_string()))?;
        build_seconds.push(variant.tessellation_seconds + started.elapsed().as_secs_f64());
        contexts.push(context);
    }

    // Textured pixels: the exact render's pixel-centre camera path looked up a texture.
    let mut mask_options = RenderOptions {
        spp: 1,
        ..options.clone()
    };
    mask_options.aovs.texture_footprint = true;
    let mask_context =
        render::prepare_with_textures(setup.scene.clone(), mask_options, textures.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let mask_render = render::render(&mask_context, &Whitted::default(), &control)
        .map_err(crate::cli::render_failed)?;

    // The high-sample exact reference, drawn with another seed.
    let reference_options = RenderOptions {
        spp: args.patch_reference_spp,
        seed: super::methods::ground_truth_seed(options.seed),
        ..options.clone()
    };
    let reference_context = render::prepare_with_textures(
        variants[0].scene.clone(),
        reference_options,
        textures.clone(),
    )
    .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let reference = render::render(&reference_context, &Whitted::default(), &control)
        .map_err(crate::cli::render_failed)?;
    let reference = display(&reference)?;
    drop(reference_context);

    let mut first = Vec::with_capacity(contexts.len());
    for context in &contexts {
        first.push(
            render::render(context, &Whitted::default(), &control)
                .map_err(crate::cli::render_failed)?,
        );
    }
    let images: Vec<DisplayImage> = first.iter().map(display).collect::<Result<_, _>>()?;
    let mask: Vec<bool> = mask_render
        .film
        .channel("texcolor.A")
        .map(|a| a.iter().map(|&v| v > 0.5).collect())
        .unwrap_or_else(|| vec![false; images[0].pixels.len()]);
    let mut times = vec![Vec::with_capacity(args.runs); contexts.len()];
    for run in 0..args.runs {
        for (index, context) in contexts.iter().enumerate() {
            let result = render::render(context, &Whitted::default(), &control)
                .map_err(crate::cli::render_failed)?;
            times[index].push(result.stats.seconds);
        }
        say(format!("timed run {}/{} done", run + 1, args.runs));
    }

    let mut rows = Vec::with_capacity(variants.len());
    for (index, variant) in variants.iter().enumerate() {
        let comparison = metrics::compare(&images[0], &images[index], &mask);
        let against_reference = metrics::compare(&reference, &images[index], &mask);
        rows.push(PatchRow {
            label: variant.label.clone(),
            kind: variant.kind,
            triangles: variant.triangles,
            geometry_bytes: variant.geometry_bytes,
            build_seconds: build_seconds[index],
            render_seconds: median(&times[index]),
            run_seconds: times[index].clone(),
            rays: first[index].stats.counters.total_rays(),
            error: comparison.all,
            textured_error: comparison.masked,
            reference_error: against_reference.all,
        });
        say(format!(
            "{}: RMSE {:.5}, {} triangles, build {:.3} s, render {:.3} s",
            variant.label,
            comparison.all.rmse,
            variant.triangles,
            build_seconds[index],
            median(&times[index])
        ));
    }

    // The crop: where the tessellations differ from the exact image most, on average.
    let (width, height) = (options.width, options.height);
    let mut error = vec![0.0f64; images[0].pixels.len()];
    for image in &images[1..] {
        for (sum, e) in error
            .iter_mut()
            .zip(metrics::squared_errors(&images[0], image))
        {
            *sum += e;
        }
    }
    let crop = crop::hardest_window(&error, width, height, crop::window_side(width, height));
    Ok((
        PatchReport {
            name: setup.name.clone(),
            source: setup.scene.source.clone(),
            width,
            height,
            spp: options.spp,
            reference_spp: args.patch_reference_spp,
            runs: args.runs,
            threads: rayon::current_num_threads(),
            textured_pixels: mask.iter().filter(|&&m| m).count(),
            crop,
            rows,
        },
        images,
    ))
}

/// The CSV header; one line per [`PatchRow`] follows.
pub const CSV_HEADER: &str = "scene,mode,bound_or_step,triangles,geometry_bytes,build_seconds,\
render_seconds,rays,rmse,psnr_db,flip,rmse_textured,flip_textured,rmse_reference,flip_reference";

fn optional(value: Option<f64>, decimals: usize) -> String {
    match value {
        Some(v) if v.is_finite() => format!("{v:.decimals$}"),
        Some(v) => format!("{v}"),
        None => String::new(),
    }
}

/// The report as CSV.
pub fn csv(report: &PatchReport) -> String {
    let mut text = format!("{CSV_HEADER}\n");
    for row in &report.rows {
        text.push_str(&format!(
            "{},{},{},{},{},{:.6},{:.6},{},{:.6},{},{:.6},{},{},{:.6},{:.6}\n",
            report.name,
            row.kind.mode(),
            row.kind
                .parameter()
                .map_or(String::new(), |b| b.to_string()),
            row.triangles,
            row.geometry_bytes,
            row.build_seconds,
            row.render_seconds,
            row.rays,
            row.error.rmse,
            optional(Some(row.error.psnr), 2),
            row.error.flip,
            optional(row.textured_error.map(|e| e.rmse), 6),
            optional(row.textured_error.map(|e| e.flip), 6),
            row.reference_error.rmse,
            row.reference_error.flip,
        ));
    }
    text
}

/// The report as a markdown table with a one-line caption.
pub fn markdown(report: &PatchReport) -> String {
    let mut text = format!(
        "`{}` ({}), {}x{}, {} spp, {} threads; error against the exact render (same samples; \
         {} textured pixels) and against an exact reference of {} spp (another seed: geometry \
         plus noise); render time the median of {} runs.\n\n\
         | mode | triangles | geometry memory | build s | render s | RMSE | FLIP | RMSE textured | FLIP textured | RMSE vs reference | FLIP vs reference |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
        report.name,
        report.source,
        report.width,
        report.height,
        report.spp,
        report.threads,
        report.textured_pixels,
        report.reference_spp,
        report.runs,
    );
    for row in &report.rows {
        text.push_str(&format!(
            "| {} | {} | {:.1} KB | {:.3} | {:.3} | {:.5} | {:.4} | {} | {} | {:.5} | {:.4} |\n",
            row.label,
            row.triangles,
            row.geometry_bytes as f64 / 1024.0,
            row.build_seconds,
            row.render_seconds,
            row.error.rmse,
            row.error.flip,
            optional(row.textured_error.map(|e| e.rmse), 5),
            optional(row.textured_error.map(|e| e.flip), 4),
            row.reference_error.rmse,
            row.reference_error.flip,
        ));
    }
    text
}

/// The error-against-time plot of one scene as RGB8 pixels of [`super::plot::PLOT_SIZE`]: RMSE over all
/// pixels on the left, FLIP on the right (over the textured pixels when there are some), the
/// exact render's time as a vertical line (its error is 0).
pub fn draw_plot(report: &PatchReport, labels: bool) -> Result<Vec<u8>, String> {
    let tessellated: Vec<&PatchRow> = report
        .rows
        .iter()
        .filter(|r| r.kind != RowKind::Exact)
        .collect();
    let exact_seconds = report
        .rows
        .iter()
        .find(|r| r.kind == RowKind::Exact)
        .map_or(f64::NAN, PatchRow::total_seconds);
    let textured = tessellated.iter().all(|r| r.textured_error.is_some());
    let points = |error: &dyn Fn(&PatchRow) -> f64| -> Vec<PlotPoint> {
        tessellated
            .iter()
            .map(|r| PlotPoint {
                seconds: r.total_seconds(),
                error: error(r),
                label: r.kind.short(),
                colour: BLUE,
            })
            .collect()
    };
    let rmse = points(&|r| r.error.rmse);
    let flip = points(&|r| {
        if textured {
            r.textured_error.unwrap_or(r.error).flip
        } else {
            r.error.flip
        }
    });
    let text = |title: String, error_name: &str| PanelText {
        title,
        x_desc: "seconds (build + median render), log scale",
        y_desc: format!("{error_name} against exact, log scale"),
        empty_note: "no positive values to plot",
        zero_error: Some((exact_seconds, "exact")),
    };
    let rmse_title = format!("{}: RMSE, all pixels", report.name);
    let flip_title = if textured {
        format!("{}: FLIP, textured pixels", report.name)
    } else {
        format!("{}: FLIP, all pixels", report.name)
    };
    draw_two_panels(
        (&text(rmse_title, "RMSE"), &rmse),
        (&text(flip_title, "FLIP"), &flip),
        labels,
    )
}

/// Writes the four files of one scene.
fn write_outputs(
    out: &Path,
    report: &PatchReport,
    images: &[DisplayImage],
) -> Result<(), CommandError> {
    let panels: Vec<crop::Panel> = report
        .rows
        .iter()
        .zip(images)
        .map(|(row, image)| crop::Panel {
            title: row.label.clone(),
            subtitle: format!("RMSE {:.4}, FLIP {:.3}", row.error.rmse, row.error.flip),
            image,
        })
        .collect();
    files::write_scene_report(
        out,
        &format!("{}_patches", report.name),
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
    if args.patch_spp == 0 {
        return Err(CommandError::bad_input("--patch-spp must be at least 1"));
    }
    if args.patch_reference_spp == 0 {
        return Err(CommandError::bad_input(
            "--patch-reference-spp must be at least 1",
        ));
    }
    let mut setups = Vec::new();
    for path in super::mode_scene_paths(args, &DEFAULT_SCENES)? {
        let setup = super::load_scene(args, super::scene_name(&path), Some(&path))?;
        if setup.scene.patches.is_empty() && setup.scene.height_patches.is_empty() {
            return Err(CommandError::bad_input(format!(
                "{}: the scene has no curved patches to compare",
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
            "{}: wrote {}/{}_patches.csv, .md, _error_vs_time.png, _crop.png",
            setup.name,
            out.display(),
            setup.name
        );
    }
    Ok(())
}
