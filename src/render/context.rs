//! Everything a worker needs to render a tile, shared read-only across threads, and the
//! per-worker state it fills.

use std::sync::Arc;

use glam::Vec3;

use crate::camera::Camera;
use crate::film::AovSelection;
use crate::footprint::LodStrategy;
use crate::render::effects::EffectSet;
use crate::render::prepared::{MaterialTable, PrepareError, SurfaceLookup};
use crate::render::stats::{EffectReason, WorkCounters};
use crate::render::tracer::{AlphaTests, Tracer, TracerSettings};
use crate::scene::SceneDescription;
use crate::shading::SceneLights;
use crate::texture::{FilterOptions, Texture, TextureTileSet};

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
    pub count_texture_tiles: bool,
    /// Force every effect on (the general path), for benchmarks.
    pub all_effects: bool,
    /// The seed of every sample position (`crate::sampler::Sampler`): equal seeds give
    /// bit-identical images.
    pub seed: u32,
    /// No camera sample's colour component may exceed this (`--clamp`, `[render] clamp`):
    /// brighter samples are scaled down, keeping their hue (`film::tile_image::clamp_sample`).
    /// `None`: samples are kept as traced.
    pub sample_clamp: Option<f32>,
}

/// The sample clamp `value` (`--clamp`, `[render] clamp`) as a render uses it, or the
/// problem to report after the option's name: it must be a finite number above 0 that an
/// `f32` holds.
pub fn parse_sample_clamp(value: f64) -> Result<f32, String> {
    let single = value as f32;
    if value.is_finite() && single.is_finite() && single > 0.0 {
        Ok(single)
    } else if value.is_finite() && value > 0.0 && single.is_infinite() {
        Err(format!(
            "must be at most {:e}, the largest single-precision number, got {value:e}",
            f32::MAX
        ))
    } else {
        Err(format!(
            "must be a finite number above 0 (the largest colour component a sample keeps), \
             got {value}"
        ))
    }
}

impl RenderOptions {
    /// A scene's own settings (size, samples, depth, throughput cut-off, Fresnel mode, seed),
    /// with cone footprints, the default filter, no AOVs, and nothing counted or forced. A
    /// scene that gives no sample count gets one sample; renders that know their integrator
    /// use its default instead (`crate::integrator::selection::default_spp`).
    pub fn from_settings(settings: &crate::scene::RenderSettings) -> RenderOptions {
        RenderOptions {
            width: settings.width,
            height: settings.height,
            spp: settings.spp.unwrap_or(1),
            max_depth: settings.max_depth,
            min_throughput: settings.min_throughput,
            lod: LodStrategy::Cone,
            filter: FilterOptions::default(),
            fresnel: settings.fresnel,
            aovs: AovSelection::default(),
            count_texture_tiles: false,
            all_effects: false,
            seed: settings.seed,
            sample_clamp: settings.sample_clamp,
        }
    }
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
    /// The effects this render switches on: the scene's analysis, or a forced superset
    /// (`--all-effects`, [`RenderContext::force_effects`]).
    pub effects: EffectSet,
    /// The effects the scene needs, as [`EffectSet::analyse`] found them.
    pub needed_effects: EffectSet,
    /// Why each effect of [`Self::effects`] is on, as the statistics report it.
    pub effect_reasons: Vec<EffectReason>,
    pub options: RenderOptions,
    /// Filter options per texture: the render's filter with each texture's own wrap modes.
    pub texture_filters: Vec<FilterOptions>,
    /// The lights integrators sample: the environment (with its mean radiance) and the
    /// choice among the scene's lights.
    pub lights: SceneLights,
    /// When set, base-colour and environment lookups go to this texture system instead of
    /// [`Self::textures`] (see [`crate::render::external_textures`]).
    pub external_textures: Option<Arc<dyn crate::render::ExternalTextures>>,
}

/// Why [`RenderContext::force_effects`] refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum ForceEffectsError {
    /// The forced set lacks effects the scene needs (it holds them).
    #[error("the forced effects lack {} that the scene needs", .0.names().join(", "))]
    MissingNeeded(EffectSet),
    /// Rebuilding the Embree scene for the new alpha tests failed.
    #[error(transparent)]
    Rebuild(#[from] PrepareError),
}

impl RenderContext {
    /// Render with `effects` instead of the set [`EffectSet::analyse`] gave, e.g. with
    /// unneeded effects switched on to measure what they cost. Refused unless `effects`
    /// includes every effect the scene needs (an unneeded effect never changes the image; a
    /// missing needed one would). When the alpha tests change (see
    /// [`AlphaTests::for_effects`]), the Embree scene is rebuilt with the new filters, so a
    /// forced alpha cut-out costs what it would in a renderer that runs it.
    pub fn force_effects(&mut self, effects: EffectSet) -> Result<(), ForceEffectsError> {
        let needed = self.needed_effects;
        if !effects.includes(&needed) {
            return Err(ForceEffectsError::MissingNeeded(needed.without(effects)));
        }
        let alpha_tests = AlphaTests::for_effects(&effects, &needed);
        if alpha_tests != self.tracer.settings().alpha_tests {
            self.rebuild_tracer(TracerSettings {
                alpha_tests,
                ..self.tracer.settings()
            })?;
        }
        self.effect_reasons = forced_reasons(effects, needed, &self.effect_reasons_of_needed());
        self.effects = effects;
        Ok(())
    }

    /// Switches Embree's robust (watertight) mode on or off by rebuilding the Embree scene;
    /// off only to measure what watertight traversal costs (`conetrace bench render`).
    pub fn set_robust_traversal(&mut self, robust: bool) -> Result<(), PrepareError> {
        self.set_tracer_settings(TracerSettings {
            robust,
            ..self.tracer.settings()
        })
    }

    /// Rebuilds the Embree scene with `settings` (if they differ from the current ones):
    /// how `conetrace bench render` pairs the default traversal with a variant of it.
    pub fn set_tracer_settings(&mut self, settings: TracerSettings) -> Result<(), PrepareError> {
        if self.tracer.settings() != settings {
            self.rebuild_tracer(settings)?;
        }
        Ok(())
    }

    fn rebuild_tracer(&mut self, settings: TracerSettings) -> Result<(), PrepareError> {
        let (tracer, geometries) =
            Tracer::build_with(&self.scene, &self.textures, &self.options, settings)?;
        // The same meshes are added in the same order whatever the filters, so the surface
        // lookup built for the first tracer stays valid.
        if self.surfaces.geometries != geometries {
            return Err(PrepareError::Invalid {
                source_label: self.scene.source.clone(),
                message: "the rebuilt Embree scene has different geometry ids".to_string(),
            });
        }
        self.tracer = tracer;
        Ok(())
    }

    /// The analysis' reasons for the needed effects.
    fn effect_reasons_of_needed(&self) -> Vec<EffectReason> {
        EffectSet::analyse(&self.scene, self.options.lod).1
    }
}

/// The reasons reported for a forced effect set: the analysis' reason for each needed
/// effect, "forced" for each one switched on beyond the scene's needs.
pub fn forced_reasons(
    effects: EffectSet,
    needed: EffectSet,
    needed_reasons: &[EffectReason],
) -> Vec<EffectReason> {
    let forced = effects.without(needed);
    let mut reasons: Vec<EffectReason> = needed_reasons
        .iter()
        .filter(|r| effects.names().contains(&r.effect.as_str()))
        .cloned()
        .collect();
    reasons.extend(forced.names().into_iter().map(|name| EffectReason {
        effect: name.to_string(),
        because: "forced on (general path), not needed by the scene".to_string(),
    }));
    reasons
}

/// What one worker accumulates while rendering tiles, whatever the integrator: the
/// render merges these into its statistics.
#[derive(Default)]
pub struct WorkerState {
    pub counters: WorkCounters,
    /// One record of touched 64x64 texture tiles per texture, when they are counted.
    pub texture_tiles: Vec<TextureTileSet>,
}

impl WorkerState {
    /// Adds `other`'s work to this one: counters are summed, texture tiles united. Both are
    /// independent of the order workers are merged in, so the totals do not depend on the
    /// thread count.
    pub fn merge(&mut self, other: WorkerState) {
        self.counters.add(&other.counters);
        if self.texture_tiles.is_empty() {
            self.texture_tiles = other.texture_tiles;
        } else {
            for (sum, part) in self.texture_tiles.iter_mut().zip(other.texture_tiles) {
                sum.merge(part);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_clamp_is_a_positive_single_precision_number() {
        assert_eq!(parse_sample_clamp(2.5), Ok(2.5));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, -1e40, 1e-50] {
            let message = parse_sample_clamp(bad).unwrap_err();
            assert!(
                message.contains("finite number above 0"),
                "{bad}: {message}"
            );
        }
        // Finite, but beyond what a single-precision film holds: the message says so.
        let message = parse_sample_clamp(1e40).unwrap_err();
        assert!(message.contains("at most 3.4028235e38"), "{message}");
    }
}
