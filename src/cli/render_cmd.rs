//! `conetrace render`: load a scene, render it, write EXR (+ AOVs) and PNG atomically, print
//! a summary line and optionally the statistics as JSON.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Args;

use crate::cli::CommandError;
use crate::film::{self, ExrAttributes};
use crate::footprint::LodStrategy;
use crate::integrator::{AovSelection, Whitted};
use crate::render::{self, RenderControl, RenderOptions};
use crate::scene::load::{default_scene, frame_camera, load_scene};
use crate::scene::{FresnelMode, SceneDescription, ToneMap};
use crate::texture::{FilterMode, FilterOptions};

/// Extra EXR layers `--aov` can add.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum AovName {
    /// tex.s tex.t tex.dsdx tex.dtdx tex.dsdy tex.dtdy and texcolor.R/G/B/A of the first camera-path lookup.
    Footprint,
    /// `lod` (mip level of that lookup) and `footprint` (its world-space width).
    Lod,
    /// Both of the above.
    All,
}

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
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Samples per pixel (stratified; 1 = pixel centre).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Maximum number of reflection/refraction bounces.
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Write the statistics as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Footprint strategy that drives texture level of detail.
    #[arg(long, default_value = "cone")]
    pub lod: LodStrategy,
    /// Texture filter.
    #[arg(long, default_value = "aniso")]
    pub filter: FilterMode,
    /// Maximum anisotropy of the aniso and ewa filters.
    #[arg(long, default_value_t = 16.0)]
    pub max_aniso: f32,
    /// Extra EXR layers (Z, N, albedo and uv are always written).
    #[arg(long, value_enum)]
    pub aov: Vec<AovName>,
    /// Fresnel equations at dielectric boundaries (default: the scene's, else exact).
    #[arg(long)]
    pub fresnel: Option<String>,
    /// PNG tone mapping: clamp or reinhard (default: the scene's, else clamp).
    #[arg(long)]
    pub tonemap: Option<String>,
    /// Force every effect on (the general path), for comparisons.
    #[arg(long)]
    pub all_effects: bool,
    /// Do not show a progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Load the scene named by `args` (or the default one), with a camera.
pub fn load(args: &RenderArgs) -> Result<SceneDescription, CommandError> {
    let mut scene = match &args.scene {
        Some(path) => load_scene(path).map_err(|e| CommandError::bad_input(e.to_string()))?,
        None => default_scene(),
    };
    let width = args.width.unwrap_or(scene.settings.width);
    let height = args.height.unwrap_or(scene.settings.height);
    if scene.camera.is_none() {
        let aspect = width.max(1) as f32 / height.max(1) as f32;
        scene.camera = Some(frame_camera(&scene, aspect));
        if !scene.notes.iter().any(|n| n.contains("camera")) {
            scene
                .notes
                .push("no camera: placed one to frame the bounds".to_string());
        }
    }
    Ok(scene)
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
    if width > 65_536 || height > 65_536 {
        return Err(CommandError::bad_input(format!(
            "{label}: image size {width}x{height} is larger than 65536 on a side"
        )));
    }
    let spp = args.spp.unwrap_or(scene.settings.spp);
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
    let extra = |name: AovName| args.aov.contains(&name) || args.aov.contains(&AovName::All);
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
            surface: true,
            texture_footprint: extra(AovName::Footprint),
            lod: extra(AovName::Lod),
        },
        count_tiles: args.stats.is_some(),
        all_effects: args.all_effects,
    })
}

fn tonemap(args: &RenderArgs, scene: &SceneDescription) -> Result<ToneMap, CommandError> {
    match args.tonemap.as_deref() {
        None => Ok(scene.settings.tonemap),
        Some("clamp") => Ok(ToneMap::Clamp),
        Some("reinhard") => Ok(ToneMap::Reinhard),
        Some(other) => Err(CommandError::bad_input(format!(
            "--tonemap: unknown value '{other}' (clamp, reinhard)"
        ))),
    }
}

/// Where the EXR and PNG go.
pub fn output_paths(args: &RenderArgs) -> (PathBuf, Option<PathBuf>) {
    let stem = args
        .scene
        .as_deref()
        .and_then(Path::file_stem)
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "default".to_string());
    let exr = args
        .output
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{stem}.exr")));
    let png = if args.no_png {
        None
    } else {
        Some(
            args.png
                .clone()
                .unwrap_or_else(|| exr.with_extension("png")),
        )
    };
    (exr, png)
}

pub fn run(args: &RenderArgs) -> Result<(), CommandError> {
    let scene = load(args)?;
    let options = options(args, &scene)?;
    let tonemap = tonemap(args, &scene)?;
    let (exr_path, png_path) = output_paths(args);
    let exposure = scene.settings.exposure;

    let mut pool =
        rayon::ThreadPoolBuilder::new().start_handler(|_| crate::embree::enable_flush_denormals());
    if let Some(threads) = args.threads {
        if threads == 0 {
            return Err(CommandError::bad_input("--threads must be at least 1"));
        }
        pool = pool.num_threads(threads);
    }
    let pool = pool
        .build()
        .map_err(|e| CommandError::internal(format!("cannot start worker threads: {e}")))?;

    let scene = Arc::new(scene);
    let result = pool.install(|| -> Result<render::RenderResult, CommandError> {
        let context = render::prepare(scene.clone(), options.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        let bar = progress_bar(
            args.quiet,
            render::work_tiles(options.width, options.height).len(),
        );
        let progress = |done: usize, _total: usize| bar.set_position(done as u64);
        let control = RenderControl {
            progress: Some(&progress),
            ..RenderControl::default()
        };
        let result = render::render(&context, &Whitted, &control);
        bar.finish_and_clear();
        Ok(result)
    })?;

    let attributes = ExrAttributes {
        incomplete: !result.stats.complete,
        ..ExrAttributes::default()
    };
    film::write_exr(&result.film, &exr_path, &attributes)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    if let Some(png_path) = &png_path {
        film::write_png(&result.film, png_path, tonemap, exposure)
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
    }
    if let Some(stats_path) = &args.stats {
        let json = serde_json::to_string_pretty(&result.stats)
            .map_err(|e| CommandError::internal(format!("statistics: {e}")))?;
        film::atomic_file::write_atomically(stats_path, |w| {
            use std::io::Write;
            w.write_all(json.as_bytes())
                .map_err(|e| film::OutputError::io(stats_path, "write", e))
        })
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    }
    let mut line = result.stats.summary_line();
    line.push_str(&format!("; wrote {}", exr_path.display()));
    if let Some(png_path) = &png_path {
        line.push_str(&format!(" and {}", png_path.display()));
    }
    println!("{line}");
    Ok(())
}

fn progress_bar(quiet: bool, tiles: usize) -> indicatif::ProgressBar {
    if quiet {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(tiles as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {pos}/{len} tiles")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar
}
