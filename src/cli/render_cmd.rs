//! `conetrace render`: load a scene, render it, write EXR (+ AOVs) and PNG atomically, print
//! a summary line and optionally the statistics as JSON.
//!
//! Outputs are decided and checked before any work (`cli::outputs`); the EXR, PNG and
//! statistics of a complete render replace earlier files together (`film::OutputSet`).
//!
//! Interruption: Ctrl-C or SIGTERM sets a flag the workers check before each tile; the tiles
//! in flight finish, and the finished part is written to the partial file beside the EXR
//! (`<name>.partial.exr`), never over the outputs. Its unfinished pixels have alpha 0, and its
//! header says `conetrace.incomplete = 1`, lists the finished tiles (`conetrace.tiles_done`)
//! and carries the render's signature (`cli::resume`); the command exits with status 3.
//! `--resume` reads the partial file, refuses it with the first difference when the scene,
//! a file it references or a pixel-changing option changed, and renders only the missing
//! tiles; rendering is deterministic per pixel, so the result equals an uninterrupted render.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

use clap::Args;

use crate::cli::outputs::OutputPlan;
use crate::cli::progress::RenderProgress;
use crate::cli::resume::{
    encoded_texture_digest, partial_stats_record, read_resume_state, tiled_texture_digest,
    RenderSignature, ResumeState, PARTIAL_STATS_ATTRIBUTE,
};
use crate::cli::{CommandError, EXIT_INTERRUPTED};
use crate::film::AovSelection;
use crate::film::{self, ExrAttributes, OutputSet};
use crate::footprint::LodStrategy;
use crate::integrator::selection::{self, IntegratorKind, SelectedIntegrator};
use crate::render::stats::PhaseSeconds;
use crate::render::{self, RenderControl, RenderOptions};
use crate::scene::load::{default_scene, frame_camera, load_scene};
use crate::scene::{FresnelMode, SceneDescription, ToneMap};
use crate::texture::{FilterMode, FilterOptions};

/// The EXR layers `--aov` can add, or `none` to drop the surface layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AovName {
    /// Colour and alpha only: not even Z, N, albedo and uv, which are then not computed.
    None,
    /// tex.s tex.t tex.dsdx tex.dtdx tex.dsdy tex.dtdy and texcolor.R/G/B/A of the first camera-path lookup.
    Footprint,
    /// `lod` (mip level of that lookup) and `footprint` (its world-space width).
    Lod,
    /// Both of the above.
    All,
}

/// The longest image side a render takes, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 65_536;

#[derive(Args, Debug, Clone)]
pub struct RenderArgs {
    /// Scene file (.toml, .obj, .gltf, .glb). Without it, the built-in default scene.
    pub scene: Option<PathBuf>,
    /// Output EXR (default: out/<scene name>.exr).
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Output PNG (default: next to the EXR, same name).
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Do not write a PNG.
    #[arg(long)]
    pub no_png: bool,
    /// Image width in pixels, 1 to 65536 [default: the scene's width, else 640].
    #[arg(long, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_IMAGE_SIDE)))]
    pub width: Option<u32>,
    /// Image height in pixels, 1 to 65536 [default: the scene's height, else 360].
    #[arg(long, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_IMAGE_SIDE)))]
    pub height: Option<u32>,
    /// Samples per pixel (Owen-scrambled Sobol; 1 = pixel centre) [default: the scene's,
    /// else 1].
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// Seed of the sample positions, 0 to 4294967295; the same seed gives the same image
    /// [default: the scene's, else 0].
    #[arg(long)]
    pub seed: Option<u32>,
    /// Integrator: whitted, path (Monte Carlo path tracing), vct (voxel cone tracing), or
    /// auto (path when the scene has emissive geometry, rough materials or `[render] gi =
    /// true`, else whitted) [default: the scene's, else auto].
    #[arg(long, value_parser = ["whitted", "path", "vct", "auto"])]
    pub integrator: Option<String>,
    /// Maximum number of reflection/refraction bounces, 0 or more [default: the scene's,
    /// else 8].
    #[arg(long, allow_negative_numbers = true)]
    pub max_depth: Option<u32>,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(long, allow_negative_numbers = true, value_parser = thread_count_parser())]
    pub threads: Option<usize>,
    /// Write the statistics as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Also count the 64x64 texture tiles the lookups touch, per texture and level, as a
    /// demand-loaded cache with a small per-thread ring would read them (`texture_tiles` in
    /// `--stats`, and the summary line). Off by default: it records every texel block a
    /// filter reads, which slows anisotropic filtering, so `--stats` alone times the render
    /// as it runs without it.
    #[arg(long)]
    pub count_texture_tiles: bool,
    /// Footprint strategy that drives texture level of detail.
    #[arg(long, default_value = "cone", value_parser = lod_parser())]
    pub lod: LodStrategy,
    /// Texture filter.
    #[arg(long, default_value = "aniso", value_parser = filter_parser())]
    pub filter: FilterMode,
    /// Maximum anisotropy of the aniso and ewa filters (a number >= 1).
    #[arg(long, default_value_t = 16.0, allow_negative_numbers = true)]
    pub max_aniso: f32,
    /// Extra EXR layers (Z, N, albedo and uv are written unless `--aov none`).
    #[arg(long, value_enum)]
    pub aov: Vec<AovName>,
    /// Clamp every camera sample so that no colour component exceeds VALUE (a finite
    /// number above 0), scaling the sample as a whole (its hue kept), as pbrt-v4's
    /// `maxcomponentvalue` does: removes fireflies, and darkens what it clamps (biased)
    /// [default: the scene's `[render] clamp`, else no clamp].
    #[arg(long, value_name = "VALUE", allow_negative_numbers = true)]
    pub clamp: Option<f64>,
    /// Fresnel equations at dielectric boundaries (default: the scene's, else exact).
    #[arg(long, value_parser = ["exact", "schlick"])]
    pub fresnel: Option<String>,
    /// PNG tone mapping (default: the scene's, else clamp).
    #[arg(long, value_parser = ["clamp", "reinhard"])]
    pub tonemap: Option<String>,
    /// Force every effect on (the general path), for comparisons.
    #[arg(long)]
    pub all_effects: bool,
    /// Refuse the render when its estimated memory (film, tiles, outputs, decoded textures)
    /// exceeds this size, e.g. 8G or 512M [default: the memory the system reports available].
    #[arg(long, value_parser = crate::render::memory::parse_memory_size)]
    pub max_memory: Option<u64>,
    /// Cap on the memory of texture tiles read on demand from tiled, mip-mapped `.tx`
    /// files, e.g. 256M or 1G; tiles beyond it are evicted and read again when touched,
    /// the image unchanged [default: 256M]. Textures decoded whole do not count.
    #[arg(long, value_name = "SIZE", value_parser = crate::render::memory::parse_memory_size)]
    pub texture_cache: Option<u64>,
    /// Do not show a progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Continue an interrupted render: read its partial file (<name>.partial.exr beside the
    /// EXR) and render only the tiles it lacks. Refused when the scene, a file it references
    /// or a pixel-changing option changed since.
    #[arg(long)]
    pub resume: bool,
    /// How curved patches are traced: `exact` (the polynomial surface itself, through an
    /// Embree user geometry) or `tessellate` (triangles within --tessellation-error of it).
    #[arg(long, value_enum, default_value = "exact")]
    pub patch_mode: PatchMode,
    /// With --patch-mode tessellate: the largest distance, in world units, between a patch
    /// and its triangles.
    #[arg(long, default_value_t = 1e-3, allow_negative_numbers = true)]
    pub tessellation_error: f32,
    /// Render only this region, X0,Y0,X1,Y1 (columns X0..X1, rows Y0..Y1; any rectangle
    /// inside the image). The EXR's data window is the region, its display window the whole
    /// image; a PNG (only with --png) holds the region alone; `conetrace merge` stitches
    /// regions.
    #[arg(long, value_name = "X0,Y0,X1,Y1", conflicts_with = "part")]
    pub region: Option<String>,
    /// Render only the sample indices START..END of every pixel (of --spp); the EXR keeps
    /// their exact sums for `conetrace merge`.
    #[arg(long, value_name = "START..END")]
    pub samples: Option<String>,
    /// Render part i of N (0-based) horizontal strips of about equal work, balanced by a
    /// quick low-resolution cost estimate.
    #[arg(long, value_name = "i/N")]
    pub part: Option<String>,
    /// Voxel cone tracing: voxels across the scene's longest side, 2 to 1024 [default: the
    /// scene's, else 128, halved until the voxel pyramid fits in 256 MiB].
    #[arg(long, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(2..=i64::from(conetrace::vct::build::MAX_RESOLUTION)))]
    pub vct_resolution: Option<u32>,
    /// Voxel cone tracing: light bounces held by the voxels, 1 (direct light) to 8
    /// [default: the scene's, else 3].
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=8))]
    pub vct_bounces: Option<u32>,
    /// Voxel cone tracing: what a voxel above the finest level holds: `directional` (six
    /// values, one per axis direction) or `isotropic` (one, thin surfaces diluted)
    /// [default: directional].
    #[arg(long, value_name = "KIND", value_parser = vct_voxels_parser())]
    pub vct_voxels: Option<conetrace::vct::VoxelKind>,
    /// Fog: integrate each segment's optical depth by ray marching with N steps (midpoint
    /// rule) instead of the closed form, for comparison [default: the scene's
    /// `fog_march_steps`, else the closed form].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub fog_march_steps: Option<i64>,
    /// Render progressively for this many seconds: passes of samples (1, 1, 2, 4, ...), the
    /// outputs rewritten after each; --spp is then an upper bound, and without it the render
    /// runs until the time is up (`cli::progressive`).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true,
          conflicts_with_all = ["resume", "region", "samples", "part"])]
    pub time_limit: Option<f64>,
}

/// `conetrace render`'s options alone, for commands that render scenes as `render` would.
#[derive(clap::Parser, Debug)]
struct RenderArgsOnly {
    #[command(flatten)]
    render: RenderArgs,
}

impl RenderArgs {
    /// The options `conetrace render` would take from `argv` (its first element the program
    /// name).
    pub(crate) fn from_argv(argv: Vec<std::ffi::OsString>) -> Result<RenderArgs, clap::Error> {
        use clap::Parser;
        RenderArgsOnly::try_parse_from(argv).map(|parsed| parsed.render)
    }
}

/// `--patch-mode`'s values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum PatchMode {
    Exact,
    Tessellate,
}

use crate::cli::resume::{encode_tiles, TILES_DONE_ATTRIBUTE};

/// `--lod`'s values, listed in `--help` and in errors.
pub fn lod_parser() -> impl clap::builder::TypedValueParser<Value = LodStrategy> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(LodStrategy::ALL.map(LodStrategy::name))
        .try_map(|name| name.parse::<LodStrategy>())
}

/// `--vct-voxels`' values, listed in `--help` and in errors.
pub fn vct_voxels_parser() -> impl clap::builder::TypedValueParser<Value = conetrace::vct::VoxelKind>
{
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(["directional", "isotropic"])
        .try_map(|name| name.parse::<conetrace::vct::VoxelKind>())
}

/// `--threads`' values, 1 to [`render::MAX_WORKER_THREADS`], the range errors name.
pub fn thread_count_parser() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::new().range(1..=render::MAX_WORKER_THREADS as u64)
}

/// `--filter`'s values, listed in `--help` and in errors.
pub fn filter_parser() -> impl clap::builder::TypedValueParser<Value = FilterMode> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(["closest", "bilinear", "trilinear", "aniso", "ewa"])
        .try_map(|name| name.parse::<FilterMode>())
}

/// `--integrator`, `--vct-resolution`, `--vct-bounces`, `--vct-voxels` and `--fog-march-steps` over the
/// scene's `[render]` settings (kept there, so a resumed or merged render is checked against
/// them too: the signature covers the settings).
pub(crate) fn apply_integrator_options(
    args: &RenderArgs,
    scene: &mut SceneDescription,
) -> Result<(), CommandError> {
    let settings = &mut scene.settings;
    if let Some(name) = args.integrator.as_deref() {
        settings.integrator = name
            .parse()
            .map_err(|e: selection::UnknownIntegrator| CommandError::bad_input(e.to_string()))?;
    }
    if let Some(resolution) = args.vct_resolution {
        settings.vct_resolution = Some(resolution);
    }
    if let Some(bounces) = args.vct_bounces {
        settings.vct_bounces = bounces;
    }
    if let Some(voxels) = args.vct_voxels {
        settings.vct_voxels = voxels;
    }
    if let Some(steps) = args.fog_march_steps {
        // Read as a signed number, so that a negative count gets this message rather than
        // the parser's "not in 0..=4294967295".
        settings.fog_integration = u32::try_from(steps)
            .ok()
            .and_then(conetrace::medium::FogIntegration::march)
            .ok_or_else(|| {
                CommandError::bad_input(format!(
                    "--fog-march-steps must be at least 1 and at most {}, got {steps}",
                    u32::MAX
                ))
            })?;
    }
    Ok(())
}

/// The integrator the scene's settings select (after [`apply_integrator_options`]), built
/// for `context` (the voxel scene of vct; nothing for Whitted).
pub(crate) fn select_integrator(
    context: &render::RenderContext,
    kind: IntegratorKind,
) -> Result<SelectedIntegrator, CommandError> {
    selection::select(kind, context)
        .map_err(|e| CommandError::bad_input(format!("{}: {e}", context.scene.source)))
}

/// The memory estimate of rendering `scene` with `options` and the integrator its settings
/// select (the voxel pyramid of vct included).
pub(crate) fn memory_estimate(
    scene: &SceneDescription,
    options: &render::RenderOptions,
    texture_cache: u64,
) -> Result<render::memory::MemoryEstimate, CommandError> {
    let mut estimate = render::memory::estimate(scene, options, texture_cache)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    estimate.voxels = selection::integrator_memory(scene.settings.integrator, scene)
        .map_err(|e| CommandError::bad_input(format!("{}: {e}", scene.source)))?;
    Ok(estimate)
}

/// Set by the Ctrl-C / SIGTERM handler; render workers stop taking new tiles.
pub(crate) static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// While a render command loads (scene, textures, memory check: nothing is on disk yet and
/// no Embree thread runs), the line a signal ends it with at once; `None` once rendering
/// begins, when a signal only sets [`INTERRUPTED`].
static LOADING: Mutex<Option<String>> = Mutex::new(None);

/// Routes Ctrl-C and SIGTERM to this render command, which has planned its outputs and is
/// about to load. Until [`loading_done`] a signal ends the process at once with status 3 and
/// one line saying nothing was written to `target`: reading a scene (even from a pipe no one
/// writes to) or decoding a large texture is not waited for. After it, the signal sets
/// [`INTERRUPTED`], which workers check before each tile.
pub(crate) fn catch_interrupts(target: &Path) {
    INTERRUPTED.store(false, Ordering::SeqCst);
    *LOADING.lock().unwrap_or_else(PoisonError::into_inner) =
        Some(nothing_written("rendering started", target).message);
    // A second handler cannot be installed (e.g. when `run` is called twice in one
    // process); the first one does the same.
    let _ = ctrlc::set_handler(|| {
        INTERRUPTED.store(true, Ordering::SeqCst);
        // Held while exiting, so the main thread cannot leave loading meanwhile.
        let loading = LOADING.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(message) = loading.as_ref() {
            crate::cli::print_error(message);
            std::process::exit(EXIT_INTERRUPTED);
        }
    });
}

/// Loading is over (the scene is about to be prepared for Embree): from now on a signal sets
/// [`INTERRUPTED`] and the command ends in its own time, writing what it finished.
pub(crate) fn loading_done() {
    *LOADING.lock().unwrap_or_else(PoisonError::into_inner) = None;
}

/// The error of a render interrupted before it produced anything: status 3, nothing written.
pub(crate) fn nothing_written(before: &str, target: &Path) -> CommandError {
    CommandError {
        message: format!(
            "interrupted before {before}; nothing written to {}",
            target.display()
        ),
        status: EXIT_INTERRUPTED,
    }
}

/// Load the scene named by `args` (or the default one), with a camera.
pub fn load(args: &RenderArgs) -> Result<SceneDescription, CommandError> {
    let mut scene = match &args.scene {
        Some(path) => load_scene(path).map_err(|e| CommandError::bad_input(e.to_string()))?,
        None => default_scene(),
    };
    crate::cli::patch_mode::apply(&mut scene, args.patch_mode, args.tessellation_error)?;
    let width = args.width.unwrap_or(scene.settings.width);
    let height = args.height.unwrap_or(scene.settings.height);
    // A camera the loader placed to frame the bounds is re-placed for the aspect ratio the
    // command line asks for.
    let framed = scene.notes.iter().any(|n| n.contains("no camera"));
    if scene.camera.is_none() || (framed && (args.width.is_some() || args.height.is_some())) {
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        scene.camera = Some(frame_camera(&scene, aspect));
        if !framed {
            scene
                .notes
                .push("no camera: placed one to frame the bounds".to_string());
        }
    }
    Ok(scene)
}

/// Samples per pixel: `--spp`, else the scene's `[render] spp`, else the default of the
/// integrator the scene resolves to, with a note for the summary line when that default is
/// more than one sample.
pub(crate) fn samples_per_pixel(
    args: &RenderArgs,
    scene: &SceneDescription,
) -> (u32, Option<String>) {
    if let Some(spp) = args.spp.or(scene.settings.spp) {
        return (spp, None);
    }
    let kind = selection::resolve(scene.settings.integrator, scene).kind;
    let spp = selection::default_spp(kind);
    let note = (spp > 1).then(|| {
        format!(
            "{spp} spp: the {} integrator's default, as neither --spp nor [render] spp \
             gave a count",
            kind.name()
        )
    });
    (spp, note)
}

/// Render options from the command line over the scene's settings.
pub fn options(args: &RenderArgs, scene: &SceneDescription) -> Result<RenderOptions, CommandError> {
    let label = &scene.source;
    let width = args.width.unwrap_or(scene.settings.width);
    let height = args.height.unwrap_or(scene.settings.height);
    if width == 0 || height == 0 {
        return Err(CommandError::bad_input(format!(
            "{label}: image size {width}x{height} has zero area"
        )));
    }
    if width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
        return Err(CommandError::bad_input(format!(
            "{label}: image size {width}x{height} is larger than {MAX_IMAGE_SIDE} on a side"
        )));
    }
    let (spp, _) = samples_per_pixel(args, scene);
    if spp == 0 {
        return Err(CommandError::bad_input(format!(
            "{label}: --spp must be at least 1"
        )));
    }
    if !(args.max_aniso.is_finite() && args.max_aniso >= 1.0) {
        return Err(CommandError::bad_input(format!(
            "--max-aniso must be a finite number >= 1, got {}",
            args.max_aniso
        )));
    }
    let fresnel = match args.fresnel.as_deref() {
        None => scene.settings.fresnel,
        Some("exact") => FresnelMode::Exact,
        Some("schlick") => FresnelMode::Schlick,
        Some(other) => {
            return Err(CommandError::bad_input(format!(
                "--fresnel: unknown value '{other}' (exact, schlick)"
            )))
        }
    };
    let colour_only = args.aov.contains(&AovName::None);
    if colour_only && args.aov.len() > 1 {
        return Err(CommandError::bad_input(
            "--aov none (colour and alpha only) cannot be combined with other --aov layers",
        ));
    }
    let extra = |name: AovName| args.aov.contains(&name) || args.aov.contains(&AovName::All);
    let sample_clamp = match args.clamp {
        Some(value) => Some(
            render::context::parse_sample_clamp(value)
                .map_err(|problem| CommandError::bad_input(format!("--clamp {problem}")))?,
        ),
        None => scene.settings.sample_clamp,
    };
    Ok(RenderOptions {
        width,
        height,
        spp,
        max_depth: args.max_depth.unwrap_or(scene.settings.max_depth),
        min_throughput: scene.settings.min_throughput,
        lod: args.lod,
        filter: FilterOptions {
            filter: args.filter,
            max_aniso: args.max_aniso,
            ..FilterOptions::default()
        },
        fresnel,
        aovs: AovSelection {
            surface: !colour_only,
            texture_footprint: extra(AovName::Footprint),
            lod: extra(AovName::Lod),
        },
        count_texture_tiles: args.count_texture_tiles,
        all_effects: args.all_effects,
        seed: args.seed.unwrap_or(scene.settings.seed),
        sample_clamp,
    })
}

pub(crate) fn tonemap(
    args: &RenderArgs,
    scene: &SceneDescription,
) -> Result<ToneMap, CommandError> {
    match args.tonemap.as_deref() {
        None => Ok(scene.settings.tonemap),
        Some("clamp") => Ok(ToneMap::Clamp),
        Some("reinhard") => Ok(ToneMap::Reinhard),
        Some(other) => Err(CommandError::bad_input(format!(
            "--tonemap: unknown value '{other}' (clamp, reinhard)"
        ))),
    }
}

pub fn run(args: &RenderArgs) -> Result<(), CommandError> {
    if let Some(seconds) = args.time_limit {
        return crate::cli::progressive::run(args, seconds);
    }
    // Outputs are checked before anything is loaded or rendered: a bad path costs nothing.
    let mut outputs = OutputPlan::from_args(args)?;
    // --quiet shows no progress, so the interval's setting is not read.
    let progress_interval = if args.quiet {
        std::time::Duration::ZERO
    } else {
        crate::cli::progress::plain_interval()?
    };
    catch_interrupts(&outputs.exr);
    let started = Instant::now();
    let mut scene = load(args)?;
    // The integrator options join the scene's settings, so the resume signature covers them.
    apply_integrator_options(args, &mut scene)?;
    let mut phases = PhaseSeconds {
        load: started.elapsed().as_secs_f64(),
        ..PhaseSeconds::default()
    };
    let options = options(args, &scene)?;
    scene.notes.extend(samples_per_pixel(args, &scene).1);
    let tonemap = tonemap(args, &scene)?;
    let exposure = scene.settings.exposure;
    let split = requested_split(args, &options)?;
    // A part of the image or of its samples writes no PNG unless --png names one.
    if split.samples_partial(&options) || split.is_partial(&options) {
        outputs.without_default_png();
    }
    outputs.check_inputs(scene.input_files.iter().map(PathBuf::as_path))?;

    // Refused before anything large is allocated: an image or texture set that cannot fit
    // gets the estimate, not an allocation failure halfway.
    let mut estimate = memory_estimate(&scene, &options, texture_cache_cap(args))?;
    if split.samples_partial(&options) {
        // A part holding a sample range also carries its exact sums.
        let pixels = u64::from(options.width) * u64::from(options.height);
        let sum_channels = film::Layer::SampleSum.channel_count() as u64;
        estimate.add_film_channels(pixels, sum_channels);
    }
    render::memory::check(&estimate, args.max_memory, &scene.source)
        .map_err(CommandError::bad_input)?;

    let pool = crate::cli::worker_pool(args.threads)?;

    let decoding = Instant::now();
    let (textures, texture_digests) = decode_textures(&scene, &texture_cache(args), args.quiet)?;
    phases.textures = decoding.elapsed().as_secs_f64();

    let signature =
        RenderSignature::new(&scene, args.scene.as_deref(), &options, &texture_digests)?;
    let earlier = match (&split, args.resume) {
        (RequestedSplit::Fixed(part), true) => Some(read_resume_state(
            &outputs.partial_exr,
            &signature,
            &scene,
            &options,
            part,
        )?),
        _ => None,
    };
    let scene = Arc::new(scene);
    let (mut result, camera, part, tiles) = pool.install(|| -> Result<_, CommandError> {
        loading_done();
        let preparing = Instant::now();
        let context = render::prepare_with_textures(scene.clone(), options.clone(), textures)
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        phases.prepare = preparing.elapsed().as_secs_f64();
        let resolution = selection::resolve(context.scene.settings.integrator, &context.scene);
        let integrator = select_integrator(&context, resolution.kind)?;
        let part = split.resolve(&context, &integrator)?;
        let tiles = part.tiles(options.width, options.height);
        let already = earlier.as_ref().map_or(0, |state| {
            state.finished.iter().filter(|&&done| done).count()
        });
        let bar = RenderProgress::new(args.quiet, tiles.len(), already, progress_interval);
        let progress = |done: usize, _total: usize| bar.update(done);
        let control = RenderControl {
            progress: Some(&progress),
            cancel: Some(&INTERRUPTED),
            skip: earlier.as_ref().map(|state| state.finished.as_slice()),
            part: Some(&part),
        };
        let result = render::render(&context, &integrator, &control);
        bar.finish();
        let mut result = result.map_err(crate::cli::render_failed)?;
        result.stats.integrator = Some(resolution.to_string());
        let unsupported = selection::unsupported_effects(resolution.kind, &context.scene);
        result.stats.notes.extend(unsupported);
        if let Some(vct) = integrator.vct_stats() {
            result.stats.counters.vct_voxels_built = vct.occupied_voxels;
            result.stats.vct = Some(vct.clone());
            let [x, y, z] = vct.dims;
            result.stats.notes.push(format!(
                "vct: {x}x{y}x{z} voxels ({} filled), built in {:.3} s, pyramid {:.1} MiB",
                vct.occupied_voxels,
                vct.seconds,
                vct.pyramid_bytes as f64 / (1 << 20) as f64
            ));
        }
        Ok((result, context.camera, part, tiles))
    })?;

    // Tiles an earlier run finished come from its file, a film of the part's region.
    if let Some(state) = &earlier {
        copy_resumed_tiles(state, &tiles, &part, &mut result, &outputs.partial_exr);
    }
    let earlier_stats = earlier
        .as_ref()
        .and_then(|state| superseded_partial_stats(state, &outputs));
    let finished_count = result.finished_tiles.iter().filter(|&&d| d).count();
    let complete = finished_count == tiles.len();
    result.stats.complete = complete;
    phases.render = result.stats.seconds;
    phases.first_ray = crate::cli::seconds_since_start(result.first_ray_at);
    result.stats.phases = Some(phases);
    if !complete && finished_count == 0 {
        return Err(nothing_written("any tile finished", &outputs.partial_exr));
    }
    let mut attributes = ExrAttributes {
        software: Some(format!("conetrace {}", env!("CARGO_PKG_VERSION"))),
        incomplete: !complete,
        finished_tiles: Some(finished_count as u32),
        world_to_camera: Some(camera.world_to_camera_matrix()),
        world_to_ndc: Some(camera.world_to_ndc_matrix()),
        ..ExrAttributes::default()
    };
    attributes.strings.insert(
        TILES_DONE_ATTRIBUTE.to_string(),
        encode_tiles(&result.finished_tiles),
    );
    if part.region != render::part::RenderPart::whole(&options).region {
        attributes.window = Some(film::partial::ImageWindow {
            x0: part.region.x0,
            y0: part.region.y0,
            full_width: options.width,
            full_height: options.height,
        });
    }
    attributes.strings.insert(
        film::partial::SAMPLES_ATTRIBUTE.to_string(),
        film::partial::format_sample_range(&part.samples),
    );
    attributes.strings.insert(
        film::partial::SAMPLE_WEIGHT_ATTRIBUTE.to_string(),
        part.samples.len().to_string(),
    );
    for (name, value) in signature.attributes() {
        attributes
            .strings
            .insert(name.to_string(), value.to_string());
    }
    let stats_json = |stats: &crate::render::RenderStats| {
        serde_json::to_string_pretty(stats)
            .map_err(|e| CommandError::internal(format!("statistics: {e}")))
    };
    let written = |e: film::OutputError| CommandError::bad_input(e.to_string());

    let mut set = OutputSet::default();
    if !complete {
        // The finished part goes to the partial files only: the outputs of an earlier,
        // complete run stay as they were.
        record_partial_stats(&mut set, &mut attributes, &outputs, earlier_stats);
        film::stage_exr(&mut set, &result.film, &outputs.partial_exr, &attributes)
            .map_err(written)?;
        if let Some(partial_stats) = &outputs.partial_stats {
            stage_text(&mut set, partial_stats, &stats_json(&result.stats)?).map_err(written)?;
        }
        set.commit().map_err(written)?;
        return Err(CommandError {
            message: format!(
                "interrupted: wrote the {finished_count} finished of {} tiles to {} \
                 (unfinished pixels have alpha 0; the outputs were not touched); continue \
                 with --resume",
                tiles.len(),
                outputs.partial_exr.display()
            ),
            status: EXIT_INTERRUPTED,
        });
    }
    let writing = Instant::now();
    film::stage_exr(&mut set, &result.film, &outputs.exr, &attributes).map_err(written)?;
    // A part's PNG is written only when asked for (farm parts need none), and never for a
    // sample range, whose colour is not final.
    let png = if split.samples_partial(&options) {
        None
    } else {
        outputs.png.as_ref()
    };
    if let Some(png_path) = png {
        film::stage_png(&mut set, &result.film, png_path, tonemap, exposure).map_err(written)?;
    }
    // The statistics file cannot time its own writing: "write" is the images'.
    phases.write = writing.elapsed().as_secs_f64();
    phases.total = started.elapsed().as_secs_f64();
    result.stats.phases = Some(phases);
    if let Some(stats_path) = &outputs.stats {
        stage_text(&mut set, stats_path, &stats_json(&result.stats)?).map_err(written)?;
    }
    // The render is complete: its partial files are superseded, and removed in the same
    // locked commit, so the outputs and the partial files change together.
    set.remove_on_commit(&outputs.partial_exr);
    if let Some(partial_stats) = &outputs.partial_stats {
        set.remove_on_commit(partial_stats);
    }
    if let Some(earlier_stats) = earlier_stats {
        set.remove_on_commit(earlier_stats);
    }
    set.commit().map_err(written)?;

    let mut line = result.stats.summary_line();
    line.push_str(&format!("; wrote {}", outputs.exr.display()));
    if let Some(png_path) = png {
        line.push_str(&format!(" and {}", png_path.display()));
    }
    println!("{line}");
    Ok(())
}

/// Copies the tiles an earlier, interrupted run finished from its partial file into
/// `result`, and notes how many on the summary line.
fn copy_resumed_tiles(
    state: &ResumeState,
    tiles: &[film::PixelRect],
    part: &render::part::RenderPart,
    result: &mut render::RenderResult,
    partial_exr: &Path,
) {
    let mut resumed = 0;
    for ((tile, done), &done_before) in tiles
        .iter()
        .zip(result.finished_tiles.iter_mut())
        .zip(&state.finished)
    {
        if done_before && !*done {
            let in_film = film::PixelRect {
                x0: tile.x0 - part.region.x0,
                y0: tile.y0 - part.region.y0,
                ..*tile
            };
            result.film.copy_region_from(&state.film, in_film);
            *done = true;
            resumed += 1;
        }
    }
    result.stats.notes.push(format!(
        "resumed: {resumed} of {} tiles from {}",
        tiles.len(),
        partial_exr.display()
    ));
}

/// The statistics file an earlier interrupted run wrote beside its partial EXR, unless this
/// run writes the same one: this run's partial or final statistics supersede it.
fn superseded_partial_stats<'a>(state: &'a ResumeState, outputs: &OutputPlan) -> Option<&'a Path> {
    let earlier = state.partial_stats.as_deref()?;
    let current = outputs.partial_stats.as_deref().map(partial_stats_record);
    (current != Some(partial_stats_record(earlier))).then_some(earlier)
}

/// Records in a partial EXR's `attributes` the partial statistics that belong to it: this
/// run's, replacing (removing in `set`'s commit) an earlier run's; else the earlier run's,
/// which stay.
fn record_partial_stats(
    set: &mut OutputSet,
    attributes: &mut ExrAttributes,
    outputs: &OutputPlan,
    earlier_stats: Option<&Path>,
) {
    let recorded = match (&outputs.partial_stats, earlier_stats) {
        (Some(current), superseded) => {
            if let Some(superseded) = superseded {
                set.remove_on_commit(superseded);
            }
            current.as_path()
        }
        (None, Some(kept)) => kept,
        (None, None) => return,
    };
    attributes.strings.insert(
        PARTIAL_STATS_ATTRIBUTE.to_string(),
        partial_stats_record(recorded),
    );
}

/// The part of the image and samples the command line asks for, before the scene is
/// prepared (`--part` needs the prepared scene for its cost estimate).
pub enum RequestedSplit {
    /// `--region` and/or `--samples` (each defaulting to the whole).
    Fixed(render::part::RenderPart),
    /// `--part i/N`, with `--samples` (or all samples).
    Balanced {
        index: u32,
        count: u32,
        samples: std::ops::Range<u32>,
    },
}

impl RequestedSplit {
    /// True unless the whole image and every sample are rendered.
    pub fn is_partial(&self, options: &RenderOptions) -> bool {
        match self {
            RequestedSplit::Fixed(part) => *part != render::part::RenderPart::whole(options),
            RequestedSplit::Balanced { count, .. } => *count > 1 || self.samples_partial(options),
        }
    }

    /// True when only some of the samples are rendered.
    pub fn samples_partial(&self, options: &RenderOptions) -> bool {
        let samples = match self {
            RequestedSplit::Fixed(part) => &part.samples,
            RequestedSplit::Balanced { samples, .. } => samples,
        };
        *samples != (0..options.spp.max(1))
    }

    /// The part to render, estimating the cost of the image for `--part`.
    pub fn resolve(
        &self,
        context: &render::RenderContext,
        integrator: &impl render::Integrator,
    ) -> Result<render::part::RenderPart, CommandError> {
        match self {
            RequestedSplit::Fixed(part) => Ok(part.clone()),
            RequestedSplit::Balanced {
                index,
                count,
                samples,
            } => {
                let options = &context.options;
                let costs = render::part::estimate_tile_row_costs(context, integrator);
                let region = render::part::balanced_strip(
                    &costs,
                    *index,
                    *count,
                    options.width,
                    options.height,
                )
                .map_err(|e| CommandError::bad_input(e.to_string()))?;
                Ok(render::part::RenderPart {
                    region,
                    samples: samples.clone(),
                })
            }
        }
    }
}

/// `--region`, `--samples` and `--part` checked against the image size and samples.
fn requested_split(
    args: &RenderArgs,
    options: &RenderOptions,
) -> Result<RequestedSplit, CommandError> {
    let whole = render::part::RenderPart::whole(options);
    let samples = match &args.samples {
        Some(text) => film::partial::parse_sample_range(text, options.spp.max(1))
            .map_err(CommandError::bad_input)?,
        None => whole.samples.clone(),
    };
    let split = if let Some(text) = &args.part {
        let (index, count) =
            render::part::parse_part(text).map_err(|e| CommandError::bad_input(e.to_string()))?;
        RequestedSplit::Balanced {
            index,
            count,
            samples,
        }
    } else {
        let region = match &args.region {
            Some(text) => film::partial::parse_region(text, options.width, options.height)
                .map_err(CommandError::bad_input)?,
            None => whole.region,
        };
        RequestedSplit::Fixed(render::part::RenderPart { region, samples })
    };
    if let RequestedSplit::Balanced { .. } = split {
        if args.resume {
            return Err(CommandError::bad_input(
                "--resume continues whole renders, --region and --samples; rerun a failed \
                 --part from the start",
            ));
        }
    }
    if split.samples_partial(options) && args.png.is_some() {
        return Err(CommandError::bad_input(
            "--png: a render of a sample range (--samples) writes only its EXR (its colour is \
             not the final image)",
        ));
    }
    Ok(split)
}

/// Decodes the scene's textures one by one, showing which one while large files load, and
/// returns each with its digest (for the render's signature): of its encoded bytes, each
/// file read once, or for a demand-loaded `.tx`, of its headers alone.
pub(crate) fn decode_textures(
    scene: &SceneDescription,
    cache: &Arc<crate::texture::TileCache>,
    quiet: bool,
) -> Result<(Vec<Arc<crate::texture::Texture>>, Vec<String>), CommandError> {
    let bar = if quiet || scene.textures.is_empty() {
        indicatif::ProgressBar::hidden()
    } else {
        let bar = indicatif::ProgressBar::new(scene.textures.len() as u64);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{elapsed_precise} decoding textures {pos}/{len}: {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(250));
        bar
    };
    let mut textures = Vec::with_capacity(scene.textures.len());
    let mut digests = Vec::with_capacity(scene.textures.len());
    for desc in &scene.textures {
        let label = desc.source.label();
        bar.set_message(label.clone());
        let bad_texture = |e: crate::texture::TextureError| CommandError::bad_input(e.to_string());
        let texture = match &desc.source {
            crate::scene::TextureSource::File(path) => {
                // A tiled `.tx` is read tile by tile on demand and digested from its headers;
                // any other file is read once, digested and decoded whole.
                match crate::texture::Texture::from_file_on_demand(path, desc.color_space, cache)
                    .map_err(bad_texture)?
                {
                    Some(texture) => {
                        let identity = texture.file_identity().unwrap_or_default();
                        digests.push(tiled_texture_digest(identity));
                        texture
                    }
                    None => {
                        let bytes = std::fs::read(path).map_err(|e| {
                            CommandError::bad_input(format!("{label}: cannot read file: {e}"))
                        })?;
                        digests.push(encoded_texture_digest(&bytes));
                        crate::texture::Texture::from_encoded(&bytes, &label, desc.color_space)
                            .map_err(bad_texture)?
                    }
                }
            }
            crate::scene::TextureSource::Encoded { bytes, .. } => {
                digests.push(encoded_texture_digest(bytes));
                crate::texture::Texture::from_encoded(bytes, &label, desc.color_space)
                    .map_err(bad_texture)?
            }
        };
        textures.push(Arc::new(texture));
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok((textures, digests))
}

/// The cache of the render's demand-loaded textures, with the cap of `--texture-cache`.
pub(crate) fn texture_cache(args: &RenderArgs) -> Arc<crate::texture::TileCache> {
    Arc::new(crate::texture::TileCache::new(texture_cache_cap(args)))
}

/// The cap of `--texture-cache`, in bytes (the default when not given).
fn texture_cache_cap(args: &RenderArgs) -> u64 {
    args.texture_cache
        .unwrap_or(crate::texture::DEFAULT_TEXTURE_CACHE_BYTES)
}

/// Stages a text file (the statistics) into `set`.
pub(crate) fn stage_text(
    set: &mut OutputSet,
    path: &Path,
    text: &str,
) -> Result<(), film::OutputError> {
    set.stage(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes())
            .map_err(|e| film::OutputError::io(path, "write", e))
    })
}
