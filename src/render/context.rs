//! Everything a worker needs to render a tile, shared read-only across threads, and the
//! per-worker state it fills.

use std::sync::Arc;

use glam::Vec3;

use crate::camera::Camera;
use crate::footprint::LodStrategy;
use crate::integrator::AovSelection;
use crate::render::effects::EffectSet;
use crate::render::prepared::{MaterialTable, SurfaceLookup};
use crate::render::stats::WorkCounters;
use crate::render::tracer::Tracer;
use crate::scene::SceneDescription;
use crate::texture::{FilterOptions, Texture, TileSet};

/// How to render: size, sampling, recursion and filtering choices.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub max_depth: u32,
    pub min_throughput: f32,
    pub lod: LodStrategy,
    pub filter: FilterOptions,
    pub fresnel: crate::scene::FresnelMode,
    pub aovs: AovSelection,
    /// Record the 64x64 texture tiles every lookup touches (for `--stats`).
    pub count_tiles: bool,
    /// Force every effect on (the general path), for benchmarks.
    pub all_effects: bool,
}

/// The shared, read-only state of one render.
pub struct RenderContext {
    pub scene: Arc<SceneDescription>,
    pub tracer: Tracer,
    pub surfaces: SurfaceLookup,
    pub textures: Vec<Arc<Texture>>,
    pub materials: MaterialTable,
    pub camera: Camera,
    /// Unit viewing direction, for camera-space depth.
    pub camera_forward: Vec3,
    pub effects: EffectSet,
    pub options: RenderOptions,
    /// Filter options per texture: the render's filter with each texture's own wrap modes.
    pub texture_filters: Vec<FilterOptions>,
    /// Mean environment radiance: the ambient light of diffuse surfaces.
    pub environment_mean: Vec3,
    /// When set, base-colour and environment lookups go to this texture system instead of
    /// [`Self::textures`] (see [`crate::render::external_textures`]).
    pub external_textures: Option<Arc<dyn crate::render::ExternalTextures>>,
}

impl RenderContext {
    /// Render with `effects` instead of the set [`EffectSet::analyse`] gave, e.g. with
    /// unneeded effects switched on to measure what they cost. Refused unless `effects`
    /// includes every effect the scene needs (an unneeded effect never changes the image; a
    /// missing needed one would): the error holds the needed effects `effects` lacks.
    pub fn force_effects(&mut self, effects: EffectSet) -> Result<(), EffectSet> {
        let (needed, _) = EffectSet::analyse(&self.scene, self.options.lod);
        if effects.includes(&needed) {
            self.effects = effects;
            Ok(())
        } else {
            Err(needed.without(effects))
        }
    }
}

/// What one worker accumulates while rendering tiles.
#[derive(Default)]
pub struct WorkerState {
    pub counters: WorkCounters,
    /// One tile record per texture, when tiles are counted.
    pub tiles: Vec<TileSet>,
}
