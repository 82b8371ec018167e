//! `conetrace render`: load a scene, render it, write EXR (+ AOVs) and PNG atomically, print
//! a summary line and optionally the statistics as JSON.
//!
//! Interruption: Ctrl-C or SIGTERM sets a flag the workers check before each tile; the tiles
//! in flight finish, the finished part is written as an EXR whose unfinished pixels have
//! alpha 0 and whose header says `conetrace.incomplete = 1`, lists the finished tiles
//! (`conetrace.tiles_done`) and the settings (`conetrace.settings`), and the command exits
//! with status 3 (no PNG is written for an incomplete render). `--resume` reads that EXR,
//! refuses it when the settings differ, and renders only the missing tiles; rendering is
//! deterministic per pixel, so the result equals an uninterrupted render.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::Args;

use crate::cli::{CommandError, EXIT_INTERRUPTED};
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
    /// Continue an interrupted render: read the incomplete output EXR and render only the
    /// tiles it lacks (the settings must be the same).
    #[arg(long)]
    pub resume: bool,
}

/// Header attribute listing the finished work tiles (see [`encode_tiles`]).
pub const TILES_DONE_ATTRIBUTE: &str = "conetrace.tiles_done";
/// Header attribute holding the settings a `--resume` must match.
pub const SETTINGS_ATTRIBUTE: &str = "conetrace.settings";

/// Set by the Ctrl-C / SIGTERM handler; render workers stop taking new tiles.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Finished tiles as hexadecimal digits, four tiles per digit (tile `4k + b` is bit `b` of
/// digit `k`), so a 4K image's 32,400 tiles take 8,100 characters.
pub fn encode_tiles(finished: &[bool]) -> String {
    finished
        .chunks(4)
        .map(|bits| {
            let value = bits
                .iter()
                .enumerate()
                .fold(0u32, |acc, (b, &done)| acc | ((done as u32) << b));
            char::from_digit(value, 16).unwrap_or('0')
        })
        .collect()
}

/// The inverse of [`encode_tiles`] for `count` tiles; `None` when the text does not fit.
pub fn decode_tiles(text: &str, count: usize) -> Option<Vec<bool>> {
    if text.len() != count.div_ceil(4) {
        return None;
    }
    let mut finished = Vec::with_capacity(count);
    for c in text.chars() {
        let value = c.to_digit(16)?;
        for b in 0..4 {
            if finished.len() < count {
                finished.push(value & (1 << b) != 0);
            } else if value & (1 << b) != 0 {
                return None;
            }
        }
    }
    Some(finished)
}

/// Everything that changes the pixels, as one line: a resume must match it exactly.
pub fn settings_signature(scene: &SceneDescription, options: &RenderOptions) -> String {
    let text = format!(
        "scene={}; size={}x{}; spp={}; max_depth={}; min_throughput={}; lod={}; filter={:?}; \
         fresnel={:?}; aovs={:?}; all_effects={}",
        scene.source,
        options.width,
        options.height,
        options.spp,
        options.max_depth,
        options.min_throughput,
        options.lod,
        options.filter,
        options.fresnel,
        options.aovs,
        options.all_effects
    );
    // EXR text attributes are Latin-1.
    text.chars()
        .map(|c| if (c as u32) < 256 { c } else { '?' })
        .collect()
}

/// The earlier, incomplete render `--resume` continues: its film and finished tiles.
fn read_resume_state(
    exr_path: &Path,
    signature: &str,
    tile_count: usize,
) -> Result<(film::Film, Vec<bool>), CommandError> {
    let label = exr_path.display();
    let (earlier, attributes) =
        film::read_exr(exr_path).map_err(|e| CommandError::bad_input(format!("--resume: {e}")))?;
    let stored = attributes.strings.get(SETTINGS_ATTRIBUTE).ok_or_else(|| {
        CommandError::bad_input(format!(
            "{label}: --resume: not a conetrace render (no {SETTINGS_ATTRIBUTE} attribute)"
        ))
    })?;
    if stored != signature {
        return Err(CommandError::bad_input(format!(
            "{label}: --resume: the file was rendered with different settings ({stored}) than \
             now ({signature})"
        )));
    }
    let finished = attributes
        .strings
        .get(TILES_DONE_ATTRIBUTE)
        .and_then(|text| decode_tiles(text, tile_count))
        .ok_or_else(|| {
            CommandError::bad_input(format!(
                "{label}: --resume: missing or malformed {TILES_DONE_ATTRIBUTE} attribute"
            ))
        })?;
    Ok((earlier, finished))
}

/// Load the scene named by `args` (or the default one), with a camera.
pub fn load(args: &RenderArgs) -> Result<SceneDescription, CommandError> {
    let mut scene = match &args.scene {
        Some(path) => load_scene(path).map_err(|e| CommandError::bad_input(e.to_string()))?,
        None => default_scene(),
    };
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

    let pool = crate::cli::worker_pool(args.threads)?;

    let tiles = render::work_tiles(options.width, options.height);
    let signature = settings_signature(&scene, &options);
    let earlier = if args.resume {
        Some(read_resume_state(&exr_path, &signature, tiles.len())?)
    } else {
        None
    };
    // A second handler cannot be installed (e.g. when `run` is called twice in one
    // process); the first one sets the same flag.
    INTERRUPTED.store(false, Ordering::SeqCst);
    let _ = ctrlc::set_handler(|| INTERRUPTED.store(true, Ordering::SeqCst));

    let scene = Arc::new(scene);
    let mut result = pool.install(|| -> Result<render::RenderResult, CommandError> {
        let context = render::prepare(scene.clone(), options.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        let bar = progress_bar(
            args.quiet,
            render::work_tiles(options.width, options.height).len(),
        );
        let progress = |done: usize, _total: usize| bar.set_position(done as u64);
        let control = RenderControl {
            progress: Some(&progress),
            cancel: Some(&INTERRUPTED),
            skip: earlier.as_ref().map(|(_, finished)| finished.as_slice()),
        };
        let result = render::render(&context, &Whitted, &control);
        bar.finish_and_clear();
        result.map_err(crate::cli::render_failed)
    })?;

    // Tiles an earlier run finished come from its file.
    if let Some((earlier_film, earlier_finished)) = &earlier {
        for ((tile, done), &done_before) in tiles
            .iter()
            .zip(result.finished_tiles.iter_mut())
            .zip(earlier_finished)
        {
            if done_before && !*done {
                result.film.copy_region_from(earlier_film, *tile);
                *done = true;
            }
        }
    }
    let finished_count = result.finished_tiles.iter().filter(|&&d| d).count();
    let complete = finished_count == tiles.len();
    result.stats.complete = complete;
    if !complete && finished_count == 0 {
        return Err(CommandError {
            message: format!(
                "interrupted before any tile finished; nothing written to {}",
                exr_path.display()
            ),
            status: EXIT_INTERRUPTED,
        });
    }
    let mut attributes = ExrAttributes {
        software: Some(format!("conetrace {}", env!("CARGO_PKG_VERSION"))),
        incomplete: !complete,
        finished_tiles: Some(finished_count as u32),
        ..ExrAttributes::default()
    };
    attributes.strings.insert(
        TILES_DONE_ATTRIBUTE.to_string(),
        encode_tiles(&result.finished_tiles),
    );
    attributes
        .strings
        .insert(SETTINGS_ATTRIBUTE.to_string(), signature);
    film::write_exr(&result.film, &exr_path, &attributes)
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    if !complete {
        return Err(CommandError {
            message: format!(
                "interrupted: wrote the {finished_count} finished of {} tiles to {} \
                 (unfinished pixels have alpha 0; no PNG); continue with --resume",
                tiles.len(),
                exr_path.display()
            ),
            status: EXIT_INTERRUPTED,
        });
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tile_lists_round_trip_through_their_text() {
        for count in [1usize, 3, 4, 5, 17, 64] {
            let finished: Vec<bool> = (0..count).map(|i| (i * 7) % 3 == 0).collect();
            let text = encode_tiles(&finished);
            assert_eq!(text.len(), count.div_ceil(4));
            assert_eq!(decode_tiles(&text, count), Some(finished));
        }
        assert_eq!(encode_tiles(&[true, false, false, true, true]), "91");
        // Wrong length, non-hex digits and bits past the end are refused.
        assert_eq!(decode_tiles("9", 5), None);
        assert_eq!(decode_tiles("9g", 5), None);
        assert_eq!(decode_tiles("93", 5), None);
    }
}
