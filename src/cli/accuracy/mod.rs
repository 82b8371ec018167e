//! `conetrace accuracy`: error against time, in four modes (`--mode`). This module is the
//! default mode, `footprints`; the others are [`patches`] (curved patches traced exactly
//! against their tessellations), [`lighting`] (Whitted, the path tracer and voxel cone
//! tracing against a path-traced ground truth) and [`fog`] (fog's closed-form optical depth
//! against ray marching). They share the metrics, the plots, the crops and the files.
//!
//! The footprint mode: how close each footprint strategy and texture filter comes to the
//! ground truth, and at what cost.
//!
//! Every scene (default: the built-in showcase and `assets/scenes/fp_*.toml`) is rendered
//! with the sixteen [`methods::compared_methods`] (nine strategy x filter pairs at one sample
//! per pixel, `mip0` + `bilinear` at 4, 16 and 64 samples, two footprint filters at 4 and 16)
//! and compared with a ground truth, `mip0` + `bilinear` supersampled at `--ground-truth-spp`
//! (1024) samples with another seed ([`methods::ground_truth_seed`]):
//! as the samples grow, the pixel value converges to the box-filtered integral of the
//! unfiltered (bilinearly magnified) texture over the pixel, the image every filter
//! approximates (docs/accuracy.md argues this).
//!
//! Textures whose files store mip levels other than level 0 reduced by maketx's box rule
//! (the footprint scenes' `miplevels.exr` tints each level to show which one a lookup used)
//! get their pyramid rebuilt from level 0, unless `--stored-mip-levels`: a filter is then
//! compared with supersampling of the very image it filters.
//!
//! Timing: a first, untimed pass renders every method once with texture-tile counting on
//! (it gives the image, the counters and the tiles touched, and warms the caches); then
//! `--runs` timed passes render every method again, interleaved (method 1..16, then again),
//! without counting; each row's time is the median of its timed renders. The ground truth is
//! rendered once.
//!
//! Outputs in `--out` (docs/accuracy): per scene `<scene>.csv`, `<scene>.md`,
//! `<scene>_error_vs_time.png` and `<scene>_crop.png`, and `README.md` indexing them with the
//! machine and the command. Every file is written atomically. Bad input (a scene that does
//! not load, an unusable output directory, a bad option) stops the command before it renders
//! anything, with one line naming the problem and exit status 2.

pub mod crop;
pub mod files;
pub mod fog;
pub mod font;
pub mod index;
pub mod lighting;
pub mod methods;
pub mod metrics;
pub mod patches;
pub mod plot;
pub mod report;

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::{Args, FromArgMatches};

use crate::cli::render_cmd::{self, RenderArgs};
use crate::cli::summary::median;
use crate::cli::CommandError;
use crate::film::AovSelection;
use crate::film::Film;
use crate::integrator::Whitted;
use crate::render::{self, RenderControl, RenderOptions, RenderResult};
use crate::scene::{SceneDescription, ToneMap};
use crate::texture::{FilterOptions, Texture};

use methods::Method;
use metrics::DisplayImage;
use report::{Row, SceneReport};

/// The name that selects the built-in showcase scene among the `SCENE` arguments.
pub const BUILT_IN_NAME: &str = "default";

/// Where the footprint scenes are looked for when no scene is named.
pub const FOOTPRINT_SCENE_DIR: &str = "assets/scenes";

/// Options of `conetrace accuracy`.
#[derive(Args, Debug, Clone)]
pub struct AccuracyArgs {
    /// Scenes (TOML, OBJ, glTF); `default` is the built-in showcase. Without any: the
    /// built-in showcase and every assets/scenes/fp_*.toml (run from the repository root).
    pub scenes: Vec<PathBuf>,
    /// Output directory.
    #[arg(long, default_value = "docs/accuracy")]
    pub out: PathBuf,
    /// Image width of every render.
    #[arg(long, default_value_t = 320)]
    pub width: u32,
    /// Image height of every render.
    #[arg(long, default_value_t = 180)]
    pub height: u32,
    /// Samples per pixel of the ground truth (mip0 + bilinear, drawn with another seed).
    /// Smaller values are accepted for quick checks; the checked-in results use 1024.
    #[arg(long, default_value_t = 1024)]
    pub ground_truth_spp: u32,
    /// Timed runs of every method (interleaved); each row reports their median.
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Maximum anisotropy of the aniso and ewa filters.
    #[arg(long, default_value_t = 16.0)]
    pub max_aniso: f32,
    /// Use the mip levels stored in texture files as they are. By default a texture whose
    /// file stores levels that are not its level 0 reduced by maketx's box rule (the
    /// footprint scenes' miplevels.exr tints each level to show which one a lookup used) is
    /// rebuilt from level 0, so filtering is compared with supersampling of the same image.
    #[arg(long)]
    pub stored_mip_levels: bool,
    /// Do not print progress lines.
    #[arg(long)]
    pub quiet: bool,
    /// What to measure: texture footprints and filters (the default), curved patches
    /// traced exactly against their tessellations ([`patches`]), light transport against
    /// a path-traced ground truth ([`lighting`]), or fog integrated exactly against ray
    /// marching ([`fog`]).
    #[arg(long, value_enum, default_value_t = AccuracyMode::Footprints)]
    pub mode: AccuracyMode,
    /// Samples per pixel of every render of `--mode patches` (exact and tessellated alike).
    #[arg(long, default_value_t = 4)]
    pub patch_spp: u32,
    /// Samples per pixel of `--mode patches`' high-sample exact reference (another seed),
    /// against which every row's total error (geometry plus noise) is also measured.
    #[arg(long, default_value_t = 64)]
    pub patch_reference_spp: u32,
    /// `--mode lighting`: pixels on the longer side of every render (the other side follows
    /// the scene's aspect ratio; `--width`/`--height` do not apply to this mode).
    #[arg(long, default_value_t = 128)]
    pub lighting_size: u32,
    /// `--mode lighting`: samples per pixel of the path-traced ground truth (another seed).
    #[arg(long, default_value_t = 1024)]
    pub lighting_reference_spp: u32,
    /// `--mode lighting`: the path tracer's rows, samples per pixel (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1, 4, 16, 64, 256])]
    pub lighting_path_spp: Vec<u32>,
    /// `--mode lighting`: the voxel cone tracer's rows, grid resolutions (comma-separated);
    /// each is measured with 1 and with 2 bounces held by the voxels.
    #[arg(long, value_delimiter = ',', default_values_t = [32, 64, 128, 256])]
    pub lighting_vct_resolutions: Vec<u32>,
    /// `--mode lighting`: samples per pixel of the Whitted and vct rows (they only
    /// antialias: both are deterministic per sample).
    #[arg(long, default_value_t = 4)]
    pub lighting_spp: u32,
}

/// The measurements `conetrace accuracy` can make.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccuracyMode {
    /// Footprint strategies and texture filters against supersampling.
    Footprints,
    /// Exact patch intersection against tessellation at several error bounds.
    Patches,
    /// Whitted, path tracing and voxel cone tracing against a path-traced ground truth.
    Lighting,
    /// Fog's closed-form optical depth against ray marching and the clamped blend ([`fog`]).
    Fog,
}

/// A scene to measure, loaded and checked, with the options every method starts from.
struct SceneSetup {
    /// Output file prefix: the file stem, or `default` for the built-in scene.
    name: String,
    scene: Arc<SceneDescription>,
    /// One sample, no AOVs, no tile counting; methods override spp, lod and filter.
    base: RenderOptions,
    tonemap: ToneMap,
    exposure: f32,
}

/// The scenes named on the command line, or the default set: `(name, path)`, `None` for the
/// built-in scene.
fn scene_inputs(args: &AccuracyArgs) -> Result<Vec<(String, Option<PathBuf>)>, CommandError> {
    let mut inputs = Vec::new();
    if args.scenes.is_empty() {
        inputs.push((BUILT_IN_NAME.to_string(), None));
        let dir = Path::new(FOOTPRINT_SCENE_DIR);
        let entries = std::fs::read_dir(dir).map_err(|e| {
            CommandError::bad_input(format!(
                "{}: cannot list the footprint scenes ({e}); run from the repository root or \
                 name the scenes",
                dir.display()
            ))
        })?;
        let mut found: Vec<PathBuf> = entries
            .filter_map(|entry| entry.ok().map(|e| e.path()))
            .filter(|path| {
                let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
                name.is_some_and(|n| n.starts_with("fp_") && n.ends_with(".toml"))
            })
            .collect();
        found.sort();
        for path in found {
            inputs.push((scene_name(&path), Some(path)));
        }
    } else {
        for path in &args.scenes {
            if path.as_os_str() == BUILT_IN_NAME && !path.exists() {
                inputs.push((BUILT_IN_NAME.to_string(), None));
            } else {
                inputs.push((scene_name(path), Some(path.clone())));
            }
        }
    }
    for (i, (name, path)) in inputs.iter().enumerate() {
        if inputs[..i].iter().any(|(other, _)| other == name) {
            let label = path
                .as_ref()
                .map_or(BUILT_IN_NAME.to_string(), |p| p.display().to_string());
            return Err(CommandError::bad_input(format!(
                "{label}: another scene has the same name '{name}' (the output files would clash)"
            )));
        }
    }
    Ok(inputs)
}

/// The scene files a mode measures: those named on the command line, or the mode's
/// `defaults`; an error when two of them share a file stem (their output files would clash).
fn mode_scene_paths(args: &AccuracyArgs, defaults: &[&str]) -> Result<Vec<PathBuf>, CommandError> {
    let paths: Vec<PathBuf> = if args.scenes.is_empty() {
        defaults.iter().map(PathBuf::from).collect()
    } else {
        args.scenes.clone()
    };
    for (i, path) in paths.iter().enumerate() {
        let name = scene_name(path);
        if paths[..i].iter().any(|other| scene_name(other) == name) {
            return Err(CommandError::bad_input(format!(
                "{}: another scene has the same name '{name}' (the output files would clash)",
                path.display()
            )));
        }
    }
    Ok(paths)
}

fn scene_name(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".to_string())
}

/// The `render` command's arguments for one scene at the accuracy size, so scenes load and
/// options are checked exactly as `conetrace render` does.
fn render_args(args: &AccuracyArgs, path: Option<&Path>) -> Result<RenderArgs, CommandError> {
    let mut argv: Vec<OsString> = vec![
        "accuracy".into(),
        "--quiet".into(),
        format!("--width={}", args.width).into(),
        format!("--height={}", args.height).into(),
        format!("--max-aniso={}", args.max_aniso).into(),
    ];
    if let Some(path) = path {
        argv.push("--".into());
        argv.push(path.as_os_str().to_owned());
    }
    let command = <RenderArgs as Args>::augment_args(clap::Command::new("accuracy"));
    let matches = command
        .try_get_matches_from(argv)
        .map_err(|e| CommandError::internal(format!("render options: {e}")))?;
    RenderArgs::from_arg_matches(&matches)
        .map_err(|e| CommandError::internal(format!("render options: {e}")))
}

fn load_scene(
    args: &AccuracyArgs,
    name: String,
    path: Option<&Path>,
) -> Result<SceneSetup, CommandError> {
    let render_args = render_args(args, path)?;
    let scene = render_cmd::load(&render_args)?;
    let mut base = render_cmd::options(&render_args, &scene)?;
    base.spp = 1;
    base.aovs = AovSelection::default();
    base.count_texture_tiles = false;
    Ok(SceneSetup {
        name,
        tonemap: scene.settings.tonemap,
        exposure: scene.settings.exposure,
        scene: Arc::new(scene),
        base,
    })
}

fn options_for(base: &RenderOptions, method: &Method) -> RenderOptions {
    RenderOptions {
        spp: method.spp,
        lod: method.lod,
        filter: FilterOptions {
            filter: method.filter,
            ..base.filter
        },
        ..base.clone()
    }
}

/// Each texture's pyramid rebuilt from its level 0 by maketx's box rule; the texture itself
/// where the stored pyramid already is that (every PNG/JPEG, and maketx's own EXRs).
fn consistent_pyramids(textures: &[Arc<Texture>]) -> Result<Vec<Arc<Texture>>, CommandError> {
    textures
        .iter()
        .map(|texture| {
            let rebuilt = texture
                .with_rebuilt_pyramid()
                .map_err(|e| CommandError::internal(e.to_string()))?;
            Ok(if rebuilt.pyramid() == texture.pyramid() {
                texture.clone()
            } else {
                Arc::new(rebuilt)
            })
        })
        .collect()
}

fn tiles_touched(result: &RenderResult) -> u64 {
    result.stats.texture_tiles.as_ref().map_or(0, |t| t.total)
}

/// What one scene's measurement produced: the report and the images behind it.
struct SceneMeasurement {
    report: SceneReport,
    ground_truth: DisplayImage,
    images: Vec<DisplayImage>,
}

/// Renders the ground truth, the textured-pixel mask and every method of one scene, and
/// compares them.
fn measure_scene(
    setup: &SceneSetup,
    args: &AccuracyArgs,
) -> Result<SceneMeasurement, CommandError> {
    let say = |text: String| {
        if !args.quiet {
            eprintln!("accuracy: {}: {text}", setup.name);
        }
    };
    // Textures decoded once for every render of the scene (surfaces, environment and alpha
    // cut-outs alike); their pyramids made consistent unless --stored-mip-levels.
    let textures = render::prepared::decode_textures(&setup.scene)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let textures = if args.stored_mip_levels {
        textures
    } else {
        consistent_pyramids(&textures)?
    };
    let prepare = |options: RenderOptions| {
        render::prepare_with_textures(setup.scene.clone(), options, textures.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))
    };
    let display = |film: &Film| {
        DisplayImage::from_film(film, setup.tonemap, setup.exposure)
            .ok_or_else(|| CommandError::internal("a render produced no colour layer"))
    };
    let control = RenderControl::default();

    // The ground truth: one render, counting tiles.
    let truth_method = methods::ground_truth(args.ground_truth_spp);
    let mut truth_options = options_for(&setup.base, &truth_method);
    truth_options.count_texture_tiles = true;
    truth_options.seed = methods::ground_truth_seed(setup.base.seed);
    let truth = render::render(&prepare(truth_options)?, &Whitted, &control)
        .map_err(crate::cli::render_failed)?;
    say(format!(
        "ground truth ({} spp) in {:.2} s",
        truth_method.spp, truth.stats.seconds
    ));
    let ground_truth = display(&truth.film)?;

    // Textured pixels: the pixel centre's camera path looked up a surface texture
    // (texcolor.A = 1 at one sample per pixel).
    let mut mask_options = options_for(&setup.base, &methods::ground_truth(1));
    mask_options.aovs.texture_footprint = true;
    let mask_render = render::render(&prepare(mask_options)?, &Whitted, &control)
        .map_err(crate::cli::render_failed)?;
    let mask: Vec<bool> = mask_render
        .film
        .channel("texcolor.A")
        .map(|a| a.iter().map(|&v| v > 0.5).collect())
        .unwrap_or_else(|| vec![false; ground_truth.pixels.len()]);

    // The compared methods: an untimed counting pass, then interleaved timed passes.
    let compared = methods::compared_methods();
    let mut contexts = Vec::with_capacity(compared.len());
    for method in &compared {
        let mut options = options_for(&setup.base, method);
        options.count_texture_tiles = true;
        contexts.push(prepare(options)?);
    }
    let mut first: Vec<RenderResult> = Vec::with_capacity(compared.len());
    for context in &mut contexts {
        first.push(render::render(context, &Whitted, &control).map_err(crate::cli::render_failed)?);
        context.options.count_texture_tiles = false;
    }
    let runs = args.runs;
    let mut times = vec![Vec::with_capacity(runs); compared.len()];
    for run in 0..runs {
        for (index, context) in contexts.iter().enumerate() {
            let result =
                render::render(context, &Whitted, &control).map_err(crate::cli::render_failed)?;
            times[index].push(result.stats.seconds);
        }
        say(format!("timed run {}/{runs} done", run + 1));
    }

    let mut rows = vec![Row {
        method: truth_method,
        seconds: truth.stats.seconds,
        run_seconds: vec![truth.stats.seconds],
        rays: truth.stats.counters.total_rays(),
        texture_lookups: truth.stats.counters.texture_lookups,
        tiles_touched: tiles_touched(&truth),
        error: None,
        textured_error: None,
        relative_time: f64::NAN,
    }];
    let mut images = Vec::with_capacity(compared.len());
    for ((method, result), run_seconds) in compared.iter().zip(&first).zip(times) {
        let image = display(&result.film)?;
        let comparison = metrics::compare(&ground_truth, &image, &mask);
        rows.push(Row {
            method: *method,
            seconds: median(&run_seconds),
            run_seconds,
            rays: result.stats.counters.total_rays(),
            texture_lookups: result.stats.counters.texture_lookups,
            tiles_touched: tiles_touched(result),
            error: Some(comparison.all),
            textured_error: comparison.masked,
            relative_time: f64::NAN,
        });
        images.push(image);
    }
    let fastest = rows
        .iter()
        .map(|r| r.seconds)
        .filter(|s| s.is_finite() && *s > 0.0)
        .fold(f64::INFINITY, f64::min);
    for row in &mut rows {
        row.relative_time = row.seconds / fastest;
    }

    // The crop window: where the one-sample methods err most on average.
    let (width, height) = (setup.base.width, setup.base.height);
    let mut error = vec![0.0f64; ground_truth.pixels.len()];
    let single: Vec<&DisplayImage> = compared
        .iter()
        .zip(&images)
        .filter(|(m, _)| m.is_single_sample())
        .map(|(_, image)| image)
        .collect();
    for image in &single {
        for (sum, e) in error
            .iter_mut()
            .zip(metrics::squared_errors(&ground_truth, image))
        {
            *sum += e / single.len() as f64;
        }
    }
    let crop = crop::hardest_window(&error, width, height, crop::window_side(width, height));

    Ok(SceneMeasurement {
        report: SceneReport {
            name: setup.name.clone(),
            source: setup.scene.source.clone(),
            width,
            height,
            runs,
            threads: rayon::current_num_threads(),
            textured_pixels: mask.iter().filter(|&&m| m).count(),
            crop,
            rows,
        },
        ground_truth,
        images,
    })
}

/// The four files of one scene.
fn write_scene_outputs(out: &Path, measurement: &SceneMeasurement) -> Result<(), CommandError> {
    let report = &measurement.report;
    let labels = font::labels_available();
    files::write_text(
        &out.join(format!("{}.csv", report.name)),
        &report::csv(report),
    )?;
    files::write_text(
        &out.join(format!("{}.md", report.name)),
        &report::markdown(report),
    )?;

    let plot = plot::draw_error_vs_time(report, labels).map_err(CommandError::internal)?;
    let (plot_width, plot_height) = plot::PLOT_SIZE;
    files::write_rgb_png(
        &out.join(format!("{}_error_vs_time.png", report.name)),
        plot_width,
        plot_height,
        &plot,
    )?;

    let truth_row = &report.rows[0];
    let mut panels = vec![crop::Panel {
        title: "ground truth".to_string(),
        subtitle: format!(
            "{} {} spp",
            truth_row.method.pair_name(),
            truth_row.method.spp
        ),
        image: &measurement.ground_truth,
    }];
    for (row, image) in report.rows[1..].iter().zip(&measurement.images) {
        let (rmse, flip) = row.error.map_or((f64::NAN, f64::NAN), |e| (e.rmse, e.flip));
        panels.push(crop::Panel {
            title: row.method.label(),
            subtitle: format!("RMSE {rmse:.4}, FLIP {flip:.3}"),
            image,
        });
    }
    let (crop_width, crop_height, crop_rgb) =
        crop::compose(&panels, report.crop, labels).map_err(CommandError::internal)?;
    files::write_rgb_png(
        &out.join(format!("{}_crop.png", report.name)),
        crop_width,
        crop_height,
        &crop_rgb,
    )
}

/// Measures every scene and writes its files, then the index; see the module docs.
pub fn run(args: &AccuracyArgs) -> Result<(), CommandError> {
    if args.mode == AccuracyMode::Patches {
        return patches::run(args);
    }
    if args.mode == AccuracyMode::Lighting {
        return lighting::run(args);
    }
    if args.mode == AccuracyMode::Fog {
        return fog::run(args);
    }
    if args.runs == 0 {
        return Err(CommandError::bad_input("--runs must be at least 1"));
    }
    if args.ground_truth_spp == 0 {
        return Err(CommandError::bad_input(
            "--ground-truth-spp must be at least 1",
        ));
    }
    // Load and check every scene before writing or rendering anything.
    let mut setups = Vec::new();
    for (name, path) in scene_inputs(args)? {
        setups.push(load_scene(args, name, path.as_deref())?);
    }
    files::check_output_dir(&args.out)?;

    let pool = crate::cli::worker_pool(args.threads)?;

    let mut reports = Vec::with_capacity(setups.len());
    for setup in &setups {
        let measurement = pool.install(|| measure_scene(setup, args))?;
        write_scene_outputs(&args.out, &measurement)?;
        println!(
            "{}: wrote {}/{}.csv, .md, _error_vs_time.png, _crop.png",
            setup.name,
            args.out.display(),
            setup.name
        );
        reports.push(measurement.report);
    }
    let index_path = args.out.join("README.md");
    files::write_text(&index_path, &index::index_markdown(&reports, args))?;
    println!("wrote {}", index_path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_inconsistent_pyramids_are_rebuilt() {
        // A pyramid built from level 0 is kept as it is.
        let texels: Vec<[f32; 4]> = (0..64).map(|i| [i as f32 / 64.0, 0.5, 0.25, 1.0]).collect();
        let built = Arc::new(Texture::from_rgba_f32(8, 8, texels).unwrap());
        let kept = consistent_pyramids(std::slice::from_ref(&built)).unwrap();
        assert!(Arc::ptr_eq(&kept[0], &built));
        // miplevels.exr stores tinted levels: level 0 stays, the others become its box
        // reductions.
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/miplevels.exr");
        let tinted =
            Arc::new(Texture::from_file(&path, crate::texture::ColorSpace::Linear).unwrap());
        let rebuilt = consistent_pyramids(std::slice::from_ref(&tinted)).unwrap();
        assert!(!Arc::ptr_eq(&rebuilt[0], &tinted));
        let (old, new) = (tinted.pyramid(), rebuilt[0].pyramid());
        assert_eq!(old.levels[0], new.levels[0]);
        assert_eq!(old.levels.len(), new.levels.len());
        assert_ne!(old.levels[1], new.levels[1]);
        let reference =
            crate::texture::MipPyramid::build(old.levels[0].clone(), "miplevels.exr").unwrap();
        assert_eq!(new, &reference);
    }
}
