//! Whitted ray tracing (seed 001's recursion, seed 004's Fresnel and Beer's law), traced in
//! waves.
//!
//! Instead of recursing ray by ray, a tile is rendered breadth first, up to 16 samples of
//! every pixel at a time (`integrator::wave_integrator`, `integrator::wave_order`): the camera rays form 16-wide packets,
//! each one pixel's samples; every hit is shaded, its shadow rays are batched and traced
//! (the camera wave's as packets, later ones as one occlusion stream), and the reflection
//! and refraction rays it spawns form the next wave, traced, one sample at a time, as an
//! incoherent ray stream. A ray carries its
//! throughput (the product of the coefficients on its way from the camera), so the sum over
//! all waves equals the
//! recursive formulation `local + k_r * trace(reflected) + k_t * trace(refracted)`.
//!
//! Recursion stops at the maximum depth or when a ray's throughput falls below the
//! threshold (seed 001's termination rules).
//!
//! Every ray that leaves a surface (shadow rays, reflections, refractions, and shadow rays
//! continuing past a transmissive occluder) starts from the hit's spawn point: the point
//! recomputed from the surface, moved along the geometric normal just past the bound on its
//! rounding error (`shading::ray_offset`), so no ray meets the surface it leaves, whatever
//! the scene's scale or the camera's distance. The geometric normal is also the one rule for
//! which side of a dielectric a ray is on (`shading::DielectricBoundary`).
//!
//! The tile loop, the camera rays and the tracing of each wave are the wave layer's
//! (`integrator::wave_integrator`). The files follow the stages of shading a wave:
//! `surface` (shading a hit), `lane_waves` (the hits shaded together in lanes), `lights`
//! (the environment and the shadow rays of punctual lights), `spawn` and `dielectric` (the
//! secondary rays of mirrors and dielectric boundaries) and `shadow_walk` (tracing the
//! shadow rays, through transmissive occluders too); `fog` attenuates and blends every
//! segment through the scene's fog volumes.

mod dielectric;
mod fog;
mod lane_waves;
mod lights;
mod shadow_walk;
mod spawn;
mod surface;

use std::sync::atomic::AtomicBool;

use glam::Vec3;

use crate::film::{PixelRect, TileImage};
use crate::footprint::Footprint;
use crate::integrator::camera_sample::{CameraRay, MAX_SAMPLES_IN_FLIGHT};
use crate::integrator::lanes::misses::{look_up_misses, Escape, MissLanes};
use crate::integrator::lanes::picks::LanePicks;
use crate::integrator::lanes::WaveLanes;
use crate::integrator::trace_wave::WaveRay;
use crate::integrator::wave_integrator::{add_radiance, render_waves, WaveBuffers, WaveIntegrator};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::render::Integrator;

pub(crate) use surface::{AmbientEnvironment, IndirectLight, IndirectQuery};

use crate::integrator::trace_wave::ShadowRay;
use lights::{add_miss_light, shade_miss};
use shadow_walk::{trace_shadows, ShadowWalk};
use surface::{shade_hit, surface_detail};

/// The Whitted integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Whitted {
    /// Whether the hits the lanes cover are shaded over a wave's lane arrays (`lane_waves`,
    /// the default) rather than each by the scalar path. Both give the same bits; the
    /// choice exists to show it and to time the two.
    pub shade_in_lanes: bool,
}

impl Default for Whitted {
    fn default() -> Self {
        Whitted {
            shade_in_lanes: true,
        }
    }
}

/// A ray in flight, with what it carries from the camera.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PathRay {
    origin: Vec3,
    direction: Vec3,
    /// Where tracing starts along the ray: just before the scene's bounds for camera rays
    /// from far away (`shading::entry_distance`), 0 for rays leaving a surface.
    start: f32,
    throughput: Vec3,
    footprint: Footprint,
    /// The slot of the ray's pixel and sample in the tile's colour buffer
    /// (`integrator::camera_sample::sample_slot`); the pixel's index for its first sample.
    slot: u32,
    depth: u32,
    kind: RayKind,
    /// Absorption coefficient of the medium the ray travels in (zero outside media).
    sigma: Vec3,
    /// Whether this ray belongs to the pixel's first sample (which writes the AOVs).
    first_sample: bool,
}

/// Whitted's per-thread state: the buffers of a tile's waves, reused for every tile a
/// worker renders.
#[derive(Default)]
pub struct Waves {
    buffers: WaveBuffers<PathRay>,
    shadows: Vec<ShadowRay>,
    /// Reordering a camera wave's shadow rays by sample (`wave_order::group_by_place`).
    shadow_scratch: Vec<ShadowRay>,
    shadow_order: Vec<u32>,
    group_ends: Vec<usize>,
    /// Walks of shadow rays through transmissive occluders.
    walk: ShadowWalk,
    /// The current wave's hits shaded in lanes (`lane_waves`), each ray's lane
    /// (`lane_waves::SCALAR` for the scalar path), and the hits the lanes take in the wave's
    /// order (`lane_waves::pick_lanes`). Boxed: the lanes' many arrays would make `Waves` the
    /// largest of the integrators' states by far.
    lanes: Box<WaveLanes>,
    lane_of_ray: Vec<u32>,
    picks: LanePicks,
    /// Every hit by the scalar path (`Whitted::shade_in_lanes` off).
    scalar_only: bool,
    /// Per ray of the wave being shaded, the fog colour its segment adds to its pixel
    /// (`fog::fog_wave_segments`); empty without fog.
    fog_light: Vec<Option<Vec3>>,
    /// The current wave's misses, their environment radiance looked up together
    /// (`lanes::misses`).
    misses: MissLanes,
}

impl Integrator for Whitted {
    type ThreadState = Waves;

    fn thread_state(&self, _context: &RenderContext) -> Waves {
        Waves {
            scalar_only: !self.shade_in_lanes,
            ..Waves::default()
        }
    }

    fn render_tile(
        &self,
        context: &RenderContext,
        tile: PixelRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
        waves: &mut Waves,
        stop: Option<&AtomicBool>,
    ) -> bool {
        render_tile_with(
            context,
            tile,
            image,
            worker,
            waves,
            &AmbientEnvironment,
            stop,
        )
    }
}

/// Render `tile` with Whitted's waves, the opaque lobe of every hit lit by the punctual
/// lights' shadow rays plus `indirect` (Whitted's constant ambient, or cones through the
/// voxels for `crate::integrator::vct`); `stop` and the result as for
/// [`Integrator::render_tile`].
pub(crate) fn render_tile_with(
    context: &RenderContext,
    tile: PixelRect,
    image: &mut TileImage,
    worker: &mut WorkerState,
    waves: &mut Waves,
    indirect: &dyn IndirectLight,
    stop: Option<&AtomicBool>,
) -> bool {
    let shading = WhittedShading { indirect };
    render_waves(&shading, context, tile, image, worker, waves, stop)
}

/// Whitted's waves with the light `indirect` adds to every opaque lobe.
/// Samples of a pixel traced together: a packet's worth (`camera_sample`).
pub(crate) const SAMPLES_IN_FLIGHT: u32 = MAX_SAMPLES_IN_FLIGHT;

struct WhittedShading<'a> {
    indirect: &'a dyn IndirectLight,
}

impl WaveIntegrator for WhittedShading<'_> {
    type Ray = PathRay;
    type State = Waves;

    const SAMPLES_IN_FLIGHT: u32 = SAMPLES_IN_FLIGHT;
    const COUNTS_PATHS: bool = false;
    const DROPS_NONFINITE_SAMPLES: bool = false;

    fn buffers(state: &mut Waves) -> &mut WaveBuffers<PathRay> {
        &mut state.buffers
    }

    fn camera_ray(ray: CameraRay) -> PathRay {
        PathRay {
            origin: ray.origin,
            direction: ray.direction,
            start: ray.start,
            throughput: Vec3::ONE,
            footprint: ray.footprint,
            slot: ray.slot,
            depth: 0,
            kind: RayKind::Camera,
            sigma: Vec3::ZERO,
            first_sample: ray.sample == 0,
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

    /// Shades the wave's hits, then walks their shadow rays.
    fn shade_wave(
        &self,
        context: &RenderContext,
        waves: &mut Waves,
        image: &mut TileImage,
        worker: &mut WorkerState,
    ) {
        shade_hits(context, waves, image, worker, self.indirect);
        trace_shadows(context, waves, image, worker);
    }
}

/// Shade the wave's hits: those the lanes cover together, stage by stage
/// (`lane_waves`), the others one by one; then, in the wave's order, each ray's light joins
/// the film and its shadow rays the queue, so the sums are the same whichever path shaded it.
fn shade_hits(
    context: &RenderContext,
    waves: &mut Waves,
    image: &mut TileImage,
    worker: &mut WorkerState,
    indirect: &dyn IndirectLight,
) {
    waves.shadows.clear();
    fog::fog_wave_segments(context, waves, worker);
    lane_waves::pick_lanes(context, waves, image, worker, indirect);
    lane_waves::shade_lanes(context, waves, worker);
    look_up_wave_misses(context, waves, worker);
    for index in 0..waves.buffers.rays.current.len() {
        fog::add_fog_light(waves, index, image);
        let lane = waves.lane_of_ray[index];
        if lane != lane_waves::SCALAR {
            lane_waves::finish_lane(context, waves, (index, lane as usize), image, worker);
            continue;
        }
        let ray = waves.buffers.rays.current[index];
        let hit = &waves.buffers.trace_hits[index];
        if !hit.is_hit() {
            match waves.misses.radiance_of(index) {
                Some(radiance) => add_miss_light(context, &ray, radiance, image, worker),
                None => shade_miss(context, &ray, image, worker),
            }
            continue;
        }
        let detail = surface_detail(context, &ray, hit);
        let surface = context
            .surfaces
            .surface_hit(ray.origin, ray.direction, hit, detail);
        shade_hit(context, ray, &surface, image, waves, worker, indirect);
    }
}

/// The environment along the wave's misses, looked up together (`lanes::misses`); fog
/// on a miss's way out is added ray by ray as the walk adds its light
/// (`lights::add_miss_light`).
fn look_up_wave_misses<'a>(
    context: &RenderContext,
    waves: &'a mut Waves,
    worker: &mut WorkerState,
) {
    let (rays, hits) = (&waves.buffers.rays.current, &waves.buffers.trace_hits);
    let takes = !waves.scalar_only;
    let miss = |_, ray: &'a PathRay| {
        Some(Escape {
            direction: ray.direction,
            footprint: &ray.footprint,
            as_light: false,
        })
    };
    look_up_misses(
        context,
        &mut waves.misses,
        (rays, hits),
        takes,
        miss,
        worker,
    );
}
