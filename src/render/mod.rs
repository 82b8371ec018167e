//! The render stage: from a scene description to a filled film.
//!
//! Data flow: [`SceneDescription`] -> [`prepare`] (decode textures, build and commit the
//! Embree scene, analyse effects) -> tiles rendered in parallel by an
//! [`Integrator`] (e.g. Whitted's, from `crate::integrator`) on rayon workers (each with the
//! flush-to-zero/denormals-are-zero bits Embree asks for) -> a [`RenderResult`] holding
//! the film and the statistics. Writing files is the caller's business (`crate::film`).
//! A render may cover one part of the image and of the samples ([`part::RenderPart`], for
//! renders split across machines); its film then holds that region only.

pub mod context;
pub mod effects;
pub mod external_textures;
pub mod integrator;
pub mod memory;
pub mod part;
pub mod patch_geometry;
pub mod prepared;
pub mod sphere_geometry;
pub mod stats;
pub mod surface_textures;
pub mod tracer;

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;
use thread_local::ThreadLocal;

use crate::film::{AovSelection, Film, FilmRegion, Layer, PixelRect, TileImage};
use crate::scene::SceneDescription;

pub use context::{ForceEffectsError, RenderContext, RenderOptions, WorkerState};
pub use effects::EffectSet;
pub use external_textures::ExternalTextures;
pub use integrator::Integrator;
pub use prepared::PrepareError;
pub use stats::{RenderStats, TextureTileUsage, WorkCounters};

/// Side of the square work tiles handed to workers (a multiple of the 4x4 packet block).
///
/// A *work tile* is a rectangle of image pixels rendered by one worker; [`work_tiles`] is
/// the one enumeration of them. It is unrelated to the 64x64-texel *texture tiles* of
/// [`crate::texture::TextureTileSet`], a texture cache's unit.
pub const WORK_TILE_SIZE: u32 = 16;

/// Most worker threads a render accepts (command line and C API alike): far above any
/// machine's cores, and low enough that thread start-up stays brief and interruptible.
pub const MAX_WORKER_THREADS: usize = 1024;

/// A finished (or interrupted) render.
pub struct RenderResult {
    pub film: Film,
    pub stats: RenderStats,
    /// Which work tiles finished (all of them unless cancelled).
    pub finished_tiles: Vec<bool>,
    /// When the first work tile began tracing (its first ray); `None` when no tile was
    /// traced (all skipped or cancelled).
    pub first_ray_at: Option<Instant>,
}

/// Build everything a render needs from a scene description.
pub fn prepare(
    scene: Arc<SceneDescription>,
    options: RenderOptions,
) -> Result<RenderContext, PrepareError> {
    let textures = prepared::decode_textures(&scene)?;
    prepare_with_textures(scene, options, textures)
}

/// [`prepare`] with the tiles of the scene's `.tx` textures kept in `cache`, under its cap.
pub fn prepare_in(
    scene: Arc<SceneDescription>,
    options: RenderOptions,
    cache: &Arc<crate::texture::TileCache>,
) -> Result<RenderContext, PrepareError> {
    let textures = prepared::decode_textures_in(&scene, cache)?;
    prepare_with_textures(scene, options, textures)
}

/// Like [`prepare`], with the scene's textures already decoded (one per
/// `scene.textures` entry, as [`prepared::decode_textures`] returns them): for callers that
/// render one scene many times, or with pyramids of their own.
pub fn prepare_with_textures(
    scene: Arc<SceneDescription>,
    options: RenderOptions,
    textures: Vec<Arc<crate::texture::Texture>>,
) -> Result<RenderContext, PrepareError> {
    let Some(camera_desc) = scene.camera.clone() else {
        return Err(PrepareError::Invalid {
            source_label: scene.source.clone(),
            message: "the scene has no camera".to_string(),
        });
    };
    let (needed_effects, needed_reasons) = EffectSet::analyse(&scene, options.lod);
    let (effects, effect_reasons) = if options.all_effects {
        let all = EffectSet::all();
        (
            all,
            context::forced_reasons(all, needed_effects, &needed_reasons),
        )
    } else {
        (needed_effects, needed_reasons)
    };
    let settings =
        tracer::TracerSettings::new(tracer::AlphaTests::for_effects(&effects, &needed_effects));
    let (tracer, geometries) = tracer::Tracer::build_with(&scene, &textures, &options, settings)?;
    let camera = crate::camera::Camera::new(&camera_desc, options.width, options.height);
    let camera_forward = (camera_desc.target - camera_desc.eye).normalize_or(glam::Vec3::NEG_Z);
    let environment_mean = prepared::environment_mean(&scene.environment, &textures);
    let texture_filters = prepared::texture_filters(&scene, &options.filter);
    let surfaces = prepared::SurfaceLookup::new(scene.clone(), geometries);
    let scene_radius = surfaces
        .bounds
        .map_or(0.0, |(lower, upper)| 0.5 * (upper - lower).length());
    // Emitted radiance is never negative either: an emission texture with a negative
    // texel would subtract light where it is seen (the factor `emission` is checked on
    // load).
    for material in scene
        .materials
        .iter()
        .filter(|m| m.emission != glam::Vec3::ZERO)
    {
        let Some(texture) = material
            .emission_texture
            .as_ref()
            .and_then(|binding| textures.get(binding.texture))
        else {
            continue;
        };
        let role = format!("emission texture of material '{}': texel", material.name);
        refuse_negative_radiance(texture, &role)?;
    }
    let mut lights = crate::shading::SceneLights::with_area_lights(
        &scene.lights,
        environment_mean,
        scene_radius,
        crate::shading::AreaLights::new(&scene, &textures),
    );
    // A lat-long environment is importance sampled (built once here; Whitted reads only the
    // mean).
    if let crate::scene::Environment::LatLong { texture, intensity } = scene.environment {
        // Radiance is never negative: a negative texel would subtract light wherever it is
        // seen, and the sampling distribution (built from luminance >= 0) could not reach it.
        refuse_negative_radiance(&textures[texture], "environment map texel")?;
        let map = crate::shading::EnvironmentMap::new(textures[texture].clone(), intensity);
        lights = lights.with_environment_map(std::sync::Arc::new(map));
    }
    Ok(RenderContext {
        materials: prepared::MaterialTable::new(&scene.materials),
        surfaces,
        scene,
        tracer,
        textures,
        camera,
        camera_forward,
        effects,
        needed_effects,
        effect_reasons,
        options,
        lights,
        texture_filters,
        external_textures: None,
    })
}

/// Refuses a texture read as radiance (an emission texture, an environment map) whose
/// level 0 holds a negative colour texel: `"{role} (x, y) has C = v; radiance must be >= 0"`.
fn refuse_negative_radiance(
    texture: &crate::texture::Texture,
    role: &str,
) -> Result<(), PrepareError> {
    let base = &texture.pyramid().levels[0];
    match base.find_texel(3, |v| v < 0.0) {
        Some((x, y, channel, value)) => Err(PrepareError::Invalid {
            source_label: texture.label().to_string(),
            message: format!(
                "{role} ({x}, {y}) has {} = {value}; radiance must be >= 0",
                crate::texture::CHANNEL_NAMES[channel]
            ),
        }),
        None => Ok(()),
    }
}

/// The film layers an AOV selection asks for (colour is always there).
pub fn film_layers(aovs: AovSelection) -> Vec<Layer> {
    let mut layers = vec![Layer::Color];
    if aovs.surface {
        layers.extend([Layer::Depth, Layer::Normal, Layer::Albedo, Layer::Uv]);
    }
    if aovs.texture_footprint {
        layers.extend([Layer::TexFootprint, Layer::TexColor]);
    }
    if aovs.lod {
        layers.extend([Layer::Lod, Layer::Footprint]);
    }
    layers
}

/// The work tiles of an image, in row-major order: every render, `--resume`'s list of
/// finished tiles and the benchmarks use this one enumeration, so a tile's index means the
/// same rectangle everywhere.
pub fn work_tiles(width: u32, height: u32) -> Vec<PixelRect> {
    let mut tiles = Vec::new();
    for y0 in (0..height).step_by(WORK_TILE_SIZE as usize) {
        for x0 in (0..width).step_by(WORK_TILE_SIZE as usize) {
            tiles.push(PixelRect {
                x0,
                y0,
                width: WORK_TILE_SIZE.min(width - x0),
                height: WORK_TILE_SIZE.min(height - y0),
            });
        }
    }
    tiles
}

/// What one worker thread keeps for the whole render: its counters, its integrator's state,
/// the image its tiles are rendered into, and which tiles it finished.
struct TileWorker<S> {
    counters: WorkerState,
    integrator: S,
    image: TileImage,
    finished: Vec<usize>,
}

/// Hooks a render reports to: progress after each tile and a cancellation flag.
#[derive(Default)]
pub struct RenderControl<'a> {
    /// Called with (finished tiles, total tiles) from worker threads.
    pub progress: Option<&'a (dyn Fn(usize, usize) + Sync)>,
    /// Set to stop the render: tiles in flight stop within their current run of samples
    /// and are left out with those never started.
    pub cancel: Option<&'a AtomicBool>,
    /// Tiles already finished by an earlier run (`--resume`): skipped.
    pub skip: Option<&'a [bool]>,
    /// Render only this region and range of samples (`--region`, `--samples`, `--part`);
    /// the film then covers the region only (see [`part::RenderPart`]).
    pub part: Option<&'a part::RenderPart>,
}

/// A render that could not be trusted.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// Embree reported an error during ray traversal, or an alpha-test filter panicked: rays
    /// may have been taken for misses, so no image is returned. The render stopped handing
    /// out tiles once the failure was seen.
    #[error("{scene}: ray traversal failed: {source}")]
    Traversal {
        scene: String,
        source: crate::embree::EmbreeError,
    },
    /// The film's memory could not be allocated.
    #[error("{scene}: {message}")]
    OutOfMemory { scene: String, message: String },
    /// A tile of a demand-loaded texture could not be read: lookups that needed it saw
    /// zeros, so no image is returned. The message names the file, the level and the tile.
    #[error("{message}")]
    TextureTile { message: String },
}

/// Render `context` with `integrator` into a new film; `Err` if any ray traversal failed
/// (see [`RenderError`]).
pub fn render<I: Integrator>(
    context: &RenderContext,
    integrator: &I,
    control: &RenderControl,
) -> Result<RenderResult, RenderError> {
    // A failure left over from an earlier render of this context is not this render's.
    let _ = context.tracer.take_failure();
    let options = &context.options;
    let whole = part::RenderPart::whole(options);
    let part = control.part.unwrap_or(&whole);
    // Whole work tiles are traced, so that every pixel is traced with the same packets as in
    // the whole render; the film is cut to the region at the end.
    let tiles = part.traced_tiles(options.width, options.height);
    let covering = part.covering_region(options.width, options.height);
    let sample_range = part.is_sample_range(options).then(|| part.samples.clone());
    let out_of_memory = |message| RenderError::OutOfMemory {
        scene: context.scene.source.clone(),
        message,
    };
    let mut film = Film::try_new(covering.width, covering.height, &part.film_layers(options))
        .map_err(out_of_memory)?;
    let finished_count = AtomicUsize::new(0);
    let count_texture_tiles = options.count_texture_tiles;
    let start = Instant::now();
    let first_ray_at = std::sync::OnceLock::new();
    let texture_count = context.textures.len();
    let new_worker = || WorkerState {
        counters: WorkCounters::default(),
        texture_tiles: if count_texture_tiles {
            context
                .textures
                .iter()
                .map(|_| crate::texture::TextureTileSet::new())
                .collect()
        } else {
            Vec::new()
        },
    };
    // The film covers whole work tiles: its bands and columns are the part's work tiles,
    // moved to the covering region's origin.
    let origin = (covering.x0, covering.y0);
    let tiles_per_row = covering.width.div_ceil(WORK_TILE_SIZE) as usize;
    // Each worker writes its finished tiles straight into its own region of the film and
    // keeps its counters, its integrator state and its tile image to itself, one of each per
    // thread for the whole render (a thread-local slot, not rayon's per-split fold state, so
    // buffers are reused across tiles and nothing is allocated per tile); the workers'
    // states are merged once at the end. Bands are cut into regions only when a worker
    // reaches them.
    let workers: ThreadLocal<RefCell<TileWorker<I::ThreadState>>> = ThreadLocal::new();
    let render_region = |index: usize, mut region: FilmRegion| {
        let tile = tiles[index];
        debug_assert_eq!(
            (region.rect().x0 + origin.0, region.rect().y0 + origin.1),
            (tile.x0, tile.y0)
        );
        let skipped = control
            .skip
            .is_some_and(|skip| skip.get(index) == Some(&true));
        let stopped =
            control.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) || context.tracer.failed();
        if skipped || stopped {
            return;
        }
        first_ray_at.get_or_init(Instant::now);
        let cell = workers.get_or(|| {
            crate::embree::enable_flush_denormals();
            RefCell::new(TileWorker {
                counters: new_worker(),
                integrator: integrator.thread_state(context),
                image: TileImage::default(),
                finished: Vec::new(),
            })
        });
        let mut worker = cell.borrow_mut();
        let TileWorker {
            counters,
            integrator: state,
            image,
            finished,
        } = &mut *worker;
        image.reset(tile, options.aovs);
        image.samples = sample_range.clone();
        // A cancelled tile stops within a run of samples and is left out, as a tile never
        // started is.
        if !integrator.render_tile(context, tile, image, counters, state, control.cancel) {
            return;
        }
        copy_tile_to_film(image, &mut region);
        finished.push(index);
        let done = finished_count.fetch_add(1, Ordering::Relaxed) + 1;
        if let Some(progress) = control.progress {
            progress(done, tiles.len());
        }
    };
    film.bands_mut(WORK_TILE_SIZE)
        .into_par_iter()
        .enumerate()
        .for_each(|(row, band)| {
            let mut regions = band.split_columns(WORK_TILE_SIZE);
            regions
                .par_regions()
                .enumerate()
                .for_each(|(column, region)| render_region(row * tiles_per_row + column, region));
        });
    let (total, finished) = workers.into_iter().map(RefCell::into_inner).fold(
        (new_worker(), Vec::new()),
        |(mut total, mut finished), worker| {
            total.merge(worker.counters);
            finished.extend(worker.finished);
            (total, finished)
        },
    );
    let seconds = start.elapsed().as_secs_f64();
    if let Some(source) = context.tracer.take_failure() {
        return Err(RenderError::Traversal {
            scene: context.scene.source.clone(),
            source,
        });
    }
    // Every worker's micro-cache hits reach the textures' counters, and no tile evicted
    // during the render stays alive in a micro-cache after it.
    crate::texture::flush_micro_caches();
    if let Some(message) = context.textures.iter().find_map(|t| t.tile_failure()) {
        return Err(RenderError::TextureTile {
            message: message.to_string(),
        });
    }

    if covering != part.region {
        let kept = PixelRect {
            x0: part.region.x0 - covering.x0,
            y0: part.region.y0 - covering.y0,
            ..part.region
        };
        film = film.try_cropped(kept).map_err(out_of_memory)?;
    }

    let mut finished_tiles = vec![false; tiles.len()];
    for index in finished {
        finished_tiles[index] = true;
    }
    let counters = total.counters;
    let texture_tiles = count_texture_tiles.then(|| TextureTileUsage {
        total: total.texture_tiles.iter().map(|t| t.count()).sum(),
        touches: total.texture_tiles.iter().map(|t| t.touches()).sum(),
        per_texture: (0..texture_count)
            .map(|i| {
                (
                    context.scene.textures[i].name.clone(),
                    total
                        .texture_tiles
                        .get(i)
                        .map(|t| t.count_per_level())
                        .unwrap_or_default(),
                )
            })
            .collect(),
    });
    // The effects this render ran with, forced or analysed, as prepared (no re-analysis).
    let effects = context.effect_reasons.clone();
    let stats = RenderStats {
        scene: context.scene.source.clone(),
        width: options.width,
        height: options.height,
        spp: options.spp,
        threads: rayon::current_num_threads(),
        lod: options.lod.to_string(),
        filter: options.filter.filter.to_string(),
        seconds,
        mrays_per_second: counters.total_rays() as f64 / seconds.max(1e-9) / 1e6,
        counters,
        texture_memory_bytes: context
            .textures
            .iter()
            .map(|t| t.memory_bytes() as u64)
            .sum(),
        texture_tiles,
        effects,
        notes: context
            .scene
            .notes
            .iter()
            .cloned()
            .chain(film_clamp_notes(&context.scene))
            .collect(),
        complete: finished_tiles.iter().all(|&f| f),
        simd: crate::simd::active().name().to_string(),
        phases: None,
        texture_memory: context
            .scene
            .textures
            .iter()
            .zip(&context.textures)
            .map(|(desc, texture)| stats::TextureMemory {
                texture: desc.source.label(),
                bytes: texture.memory_bytes() as u64,
                demand_loaded: texture.is_demand_loaded(),
                tiles_read: texture.is_demand_loaded().then(|| texture.tiles_read()),
                tiles_in_file: texture.is_demand_loaded().then(|| texture.tiles_in_file()),
                cache: texture.cache_stats().map(Into::into),
            })
            .collect(),
        texture_cache: stats::texture_cache_totals(&context.textures),
        vct: None,
        integrator: None,
    };
    Ok(RenderResult {
        film,
        stats,
        finished_tiles,
        first_ray_at: first_ray_at.into_inner(),
    })
}

/// Copy an integrator's tile into its region of the film, layer by layer (the tile covers
/// the region).
fn copy_tile_to_film(image: &TileImage, region: &mut FilmRegion) {
    let rect = region.rect();
    if region.has(Layer::SampleSum) {
        use crate::film::sample_sum::{encode, DIGITS};
        for y in 0..rect.height {
            for x in 0..rect.width {
                let i = (y * rect.width + x) as usize;
                let mut digits = [0.0f32; 3 * DIGITS];
                for (chunk, &sum) in digits.chunks_exact_mut(DIGITS).zip(&image.color_sum[i]) {
                    chunk.copy_from_slice(&encode(sum));
                }
                region.set(Layer::SampleSum, rect.x0 + x, rect.y0 + y, &digits);
            }
        }
    }
    region.set_all(Layer::Color, |i| {
        let c = image.color[i];
        [c[0], c[1], c[2], image.alpha[i]]
    });
    if !image.depth.is_empty() {
        region.set_all(Layer::Depth, |i| [image.depth[i]]);
        region.set_all(Layer::Normal, |i| image.normal[i]);
        region.set_all(Layer::Albedo, |i| image.albedo[i]);
        region.set_all(Layer::Uv, |i| image.uv[i]);
    }
    if !image.tex.is_empty() {
        region.set_all(Layer::TexFootprint, |i| image.tex[i]);
        region.set_all(Layer::TexColor, |i| image.texcolor[i]);
    }
    if !image.lod.is_empty() {
        region.set_all(Layer::Lod, |i| [image.lod[i]]);
        region.set_all(Layer::Footprint, |i| [image.footprint[i]]);
    }
}

/// Notes for radiance the film cannot hold: an emission or environment colour brighter than
/// the largest sample value (`film::sample_sum::MAX_SAMPLE_MAGNITUDE`, 2^31) is clamped to
/// it wherever a camera path meets it.
fn film_clamp_notes(scene: &crate::scene::SceneDescription) -> Vec<String> {
    let limit = crate::film::sample_sum::MAX_SAMPLE_MAGNITUDE as f32;
    let mut notes: Vec<String> = scene
        .materials
        .iter()
        .filter(|m| m.emission.max_element() > limit)
        .map(|m| {
            format!(
                "material '{}': emission {} is above the film's largest sample value 2^31 and \
                 is clamped to it",
                m.name,
                m.emission.max_element()
            )
        })
        .collect();
    match scene.environment {
        crate::scene::Environment::Color(c) if c.max_element() > limit => {
            notes.push(format!(
                "environment color {} is above the film's largest sample value 2^31 and is \
                 clamped to it",
                c.max_element()
            ));
        }
        crate::scene::Environment::LatLong { intensity, .. } if intensity > limit => {
            notes.push(format!(
                "environment intensity {intensity} is above the film's largest sample value \
                 2^31: texels of 1 and brighter are clamped to it"
            ));
        }
        _ => {}
    }
    notes
}
