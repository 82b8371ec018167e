//! Unidirectional Monte Carlo path tracing with next-event estimation and multiple
//! importance sampling, traced in waves (docs/path-tracing.md).
//!
//! The estimator (pbrt-v4, section 13.4): at every hit, one light is chosen by power
//! ([`crate::shading::SceneLights`]) and a point on it sampled (next-event estimation, one
//! shadow ray); then the material's BSDF ([`crate::shading::MaterialBsdf`], only through
//! its `Bsdf` interface) samples the direction the path continues in. Light reaching the
//! path by both strategies (area lights, the environment) is weighted by the power
//! heuristic ([`mis`]); delta lights (point, spot, directional) are reached only by light
//! sampling and delta lobes (mirror, smooth glass) only by BSDF sampling, so neither is
//! weighted. Emission seen by the camera or through delta lobes is taken whole.
//!
//! After three bounces, Russian roulette ends a path with probability
//! `max(0.05, 1 - max(throughput))` when its throughput has fallen below 1, and divides the
//! survivors' throughput by the survival probability. `max_depth` bounds the number of
//! bounces; light sampling still runs at the last hit, unweighted, as no BSDF ray
//! continues from it along a non-delta lobe to compete, and a delta lobe's ray continues
//! only to collect the emission it reaches. Beer's law attenuates paths inside absorbing
//! dielectrics as in Whitted.
//!
//! Every random number comes from the pixel's [`crate::sampler::PixelSampler`], which the
//! path carries: after the camera's four dimensions, each hit draws seven in a fixed order
//! (light choice, point on the light, BSDF lobe, BSDF direction, roulette), so an image is a
//! pure function of the seed.
//!
//! Like Whitted, a tile is rendered breadth first by the wave layer
//! (`integrator::wave_integrator`, `integrator::wave_order`), but one sample at a time: the camera rays of a sample form 16-wide packets of 4x4 pixels, the shadow
//! rays of a wave one occlusion stream (packets for the camera wave), and the continuing
//! paths the next wave, traced as an incoherent stream.
//!
//! Footprints follow every bounce: mirror and refraction bounces reflect or refract the
//! ray's cone (or differential) as Whitted does; a non-delta bounce widens the cone by the
//! BSDF spread heuristic of seed 000 ([`crate::footprint::bsdf_spread_angle`]), and
//! differentials are replaced at the next hit by the camera's footprint there
//! ([`crate::camera::Camera::approximate_dp_dxy`]). Every texture lookup is filtered by the
//! footprint at its hit.
//!
//! Fog (`[[fog]]`) is a participating medium: every segment samples a free-flight distance
//! through the volumes, and a collision is a medium vertex (light sampling with the
//! Henyey–Greenstein phase function, phase-sampled continuation, the albedo as weight);
//! shadow rays pass the exact transmittance (`medium`, docs/fog.md).
//!
//! The hits the shading lanes cover (`crate::integrator::lanes`) are reconstructed and
//! textured together, wave by wave (`lane_waves`), their lights sampled and their BSDFs
//! evaluated and sampled over the lane arrays, one lobe's code per material
//! (`lane_scatter`), before the wave's vertices are finished in its order; the same bits
//! as the scalar path's. The wave's misses read the environment together
//! (`lanes::misses`, `look_up_wave_misses`) and add it in the same order.
//!
//! Files: `vertex` (what a hit adds and where the path goes next), `lane_waves` (the hits
//! reconstructed and textured in lanes, and the walk that queues their rays),
//! `lane_scatter`, `lane_lights` and `lane_bsdf` (stages 5 and 6 in lanes), `medium` (free flights
//! through fog and the medium vertex), `next_event` (light sampling and its shadow rays),
//! `mis` (the power heuristic).

mod lane_bsdf;
mod lane_lights;
mod lane_scatter;
mod lane_waves;
mod medium;
mod mis;
mod next_event;
mod vertex;

use std::sync::atomic::AtomicBool;

use glam::Vec3;

use crate::film::{PixelRect, TileImage};
use crate::footprint::Footprint;
use crate::integrator::camera_sample::CameraRay;
use crate::integrator::lanes::misses::{look_up_misses, Escape, MissLanes};
use crate::integrator::trace_wave::WaveRay;
use crate::integrator::wave_integrator::{add_radiance, render_waves, WaveBuffers, WaveIntegrator};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::render::Integrator;
use crate::sampler::PixelSampler;

use crate::integrator::trace_wave::ShadowRay;
pub use mis::power_heuristic;
use next_event::trace_shadow_rays;

/// How direct light from area lights and the environment is estimated. Only
/// [`LightStrategy::MultipleImportance`] is a renderer's choice; the other two exist to test
/// that the three agree (each is unbiased on its own).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightStrategy {
    /// Light sampling and BSDF sampling, weighted by the power heuristic.
    #[default]
    MultipleImportance,
    /// Light sampling only: BSDF-sampled rays that reach a light it can sample add nothing.
    LightSampling,
    /// BSDF sampling only: light sampling is kept for delta lights alone, which no ray can
    /// hit.
    BsdfSampling,
}

/// The path tracer and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathTracer {
    /// How many non-delta (diffuse or glossy) bounces a path may take (`[render]
    /// diffuse_bounces`); `u32::MAX` for no limit. With 0, paths follow only mirrors and
    /// glass after the camera, and light reaches diffuse surfaces by light sampling alone:
    /// Whitted's image in expectation.
    pub diffuse_bounces: u32,
    pub strategy: LightStrategy,
    /// Whether the hits the lanes cover are reconstructed and textured over a wave's lane
    /// arrays (`lane_waves`, the default) rather than each by the scalar path. Both give
    /// the same bits; the choice exists to show it and to time the two.
    pub shade_in_lanes: bool,
}

impl Default for PathTracer {
    fn default() -> Self {
        PathTracer {
            diffuse_bounces: u32::MAX,
            strategy: LightStrategy::MultipleImportance,
            shade_in_lanes: true,
        }
    }
}

impl PathTracer {
    /// The path tracer with a scene's own settings (`[render] diffuse_bounces`).
    pub fn for_settings(settings: &crate::scene::RenderSettings) -> PathTracer {
        PathTracer {
            diffuse_bounces: settings.diffuse_bounces.unwrap_or(u32::MAX),
            ..PathTracer::default()
        }
    }
}

/// A path in flight: the ray it continues along and what it carries from the camera.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PathRay {
    origin: Vec3,
    direction: Vec3,
    /// Where tracing starts along the ray (`shading::entry_distance` for camera rays).
    start: f32,
    throughput: Vec3,
    footprint: Footprint,
    /// Differentials only: the footprint is to be replaced at the next hit by the camera's
    /// footprint there (after a non-delta bounce).
    approximate_footprint: bool,
    /// The slot of the ray's pixel and sample in the tile's colour buffer
    /// (`integrator::camera_sample::sample_slot`); the pixel's index for its first sample.
    slot: u32,
    /// Bounces so far (0 for camera rays), and how many of them were non-delta.
    depth: u32,
    diffuse_depth: u32,
    /// The density with which the BSDF (or, at a fog vertex, the phase function) chose this
    /// ray, for weighting the light it finds; `None` for camera rays and delta bounces,
    /// whose light is taken whole.
    bsdf_pdf: Option<f32>,
    /// The hit or fog scattering point this ray left (for the density of light sampling at
    /// the light it finds).
    from: Vec3,
    kind: RayKind,
    /// Absorption coefficient of the medium the ray travels in (zero outside media).
    sigma: Vec3,
    first_sample: bool,
    sampler: PixelSampler,
}

/// The path tracer's per-thread state: the buffers of a tile's waves, reused.
#[derive(Default)]
pub struct PathWaves {
    buffers: WaveBuffers<PathRay>,
    shadows: Vec<ShadowRay>,
    lanes: lane_waves::PathLanes,
    /// Per ray of the wave being shaded, where fog stopped it (`medium`); empty without fog.
    collisions: Vec<Option<medium::Collision>>,
    /// The current wave's misses, their environment radiance looked up together
    /// (`lanes::misses`).
    misses: MissLanes,
}

/// One sample of every pixel at a time: camera rays are a small share of a path tracer's
/// rays, and 16 samples in flight cost more in memory traffic than their coherent packets
/// save (docs/benchmarks.md).
pub(crate) const SAMPLES_IN_FLIGHT: u32 = 1;

impl WaveIntegrator for PathTracer {
    type Ray = PathRay;
    type State = PathWaves;

    const SAMPLES_IN_FLIGHT: u32 = SAMPLES_IN_FLIGHT;
    const COUNTS_PATHS: bool = true;
    const DROPS_NONFINITE_SAMPLES: bool = true;

    fn buffers(state: &mut PathWaves) -> &mut WaveBuffers<PathRay> {
        &mut state.buffers
    }

    fn camera_ray(ray: CameraRay) -> PathRay {
        PathRay {
            origin: ray.origin,
            direction: ray.direction,
            start: ray.start,
            throughput: Vec3::ONE,
            footprint: ray.footprint,
            approximate_footprint: false,
            slot: ray.slot,
            depth: 0,
            diffuse_depth: 0,
            bsdf_pdf: None,
            from: ray.origin,
            kind: RayKind::Camera,
            sigma: Vec3::ZERO,
            first_sample: ray.sample == 0,
            sampler: ray.sampler,
        }
    }

    fn wave_ray(ray: &PathRay) -> WaveRay<'_> {
        WaveRay {
            origin: ray.origin,
            direction: ray.direction,
            start: ray.start,
            footprint: &ray.footprint,
        }
    }

    fn slot(ray: &PathRay) -> u32 {
        ray.slot
    }

    /// Shades the wave's hits (those the lanes cover reconstructed and textured together
    /// first, `lane_waves`), each path's vertex then finished in wave order, and traces
    /// their shadow rays.
    fn shade_wave(
        &self,
        context: &RenderContext,
        waves: &mut PathWaves,
        image: &mut TileImage,
        worker: &mut WorkerState,
    ) {
        waves.shadows.clear();
        // Each path is shaded where it lies in the wave, not copied out of it: a `PathRay`
        // is 152 bytes, and a copy read back in other widths stalls on store forwarding.
        let mut current = std::mem::take(&mut waves.buffers.rays.current);
        let hits = std::mem::take(&mut waves.buffers.trace_hits);
        let mut lanes = std::mem::take(&mut waves.lanes);
        let mut collisions = std::mem::take(&mut waves.collisions);
        medium::sample_wave_collisions(context, &mut current, &hits, &mut collisions, worker);
        let wave = (current.as_slice(), hits.as_slice(), collisions.as_slice());
        lane_waves::shade_lanes(
            context,
            &mut lanes,
            wave,
            image,
            worker,
            self.shade_in_lanes,
        );
        lane_scatter::scatter_lanes(self, context, &mut lanes, &mut current, worker);
        let enabled = self.shade_in_lanes;
        let wave = (current.as_slice(), hits.as_slice(), collisions.as_slice());
        look_up_wave_misses(context, &mut waves.misses, wave, worker, enabled);
        for (index, (ray, hit)) in current.iter_mut().zip(&hits).enumerate() {
            if let Some(Some(collision)) = collisions.get(index) {
                vertex::scatter_in_fog(self, context, ray, hit, *collision, image, waves, worker);
            } else if let Some(lane) = lanes.lane_of(index) {
                lane_waves::finish_lane(
                    self, context, ray, hit, &lanes, lane, image, waves, worker,
                );
            } else if let Some(radiance) = waves.misses.radiance_of(index) {
                vertex::add_escaped_radiance(self, context, ray, radiance, image);
            } else {
                vertex::shade(self, context, ray, hit, image, waves, worker);
            }
        }
        waves.lanes = lanes;
        waves.collisions = collisions;
        waves.buffers.rays.current = current;
        waves.buffers.trace_hits = hits;
        trace_shadow_rays(context, waves, image, worker);
    }
}

impl Integrator for PathTracer {
    type ThreadState = PathWaves;

    fn thread_state(&self, _context: &RenderContext) -> PathWaves {
        PathWaves::default()
    }

    fn render_tile(
        &self,
        context: &RenderContext,
        tile: PixelRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
        waves: &mut PathWaves,
        stop: Option<&AtomicBool>,
    ) -> bool {
        render_waves(self, context, tile, image, worker, waves, stop)
    }
}

/// The environment along the wave's misses, looked up together (`lanes::misses`), unless
/// the lanes are off; a ray that fog stopped before it could escape (`collisions`, from
/// `medium::sample_wave_collisions`) scatters in the fog instead. A miss reads what
/// `vertex::add_escaped_light` reads: through its footprint when it sees the environment
/// whole (from the camera, or through a delta lobe), as a light when a non-delta lobe
/// sampled it.
fn look_up_wave_misses<'a>(
    context: &RenderContext,
    misses: &mut MissLanes,
    (rays, hits, collisions): (&'a [PathRay], &[TraceHit], &[Option<medium::Collision>]),
    worker: &mut WorkerState,
    enabled: bool,
) {
    let escape = |index: usize, ray: &'a PathRay| {
        let stopped = matches!(collisions.get(index), Some(Some(_)));
        (!stopped).then_some(Escape {
            direction: ray.direction,
            footprint: &ray.footprint,
            as_light: ray.bsdf_pdf.is_some(),
        })
    };
    look_up_misses(context, misses, (rays, hits), enabled, escape, worker);
}
