//! Whitted ray tracing (seed 001's recursion, seed 004's Fresnel and Beer's law), traced in
//! waves.
//!
//! Instead of recursing ray by ray, a tile is rendered breadth first, up to 16 samples of
//! every pixel at a time (`integrator::wave_order`): the camera rays form 16-wide packets,
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
//! The files follow the stages of a wave: `camera_rays` (the first wave), `surface` (shading
//! a hit), `lights` (the environment and the shadow rays of punctual lights), `spawn` and
//! `dielectric` (the secondary rays of mirrors and dielectric boundaries) and `shadow_walk`
//! (tracing the shadow rays, through transmissive occluders too); `fog` attenuates and
//! blends every segment through the scene's fog volumes.

mod camera_rays;
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
use crate::integrator::camera_sample::{sample_runs, slot_place, MAX_SAMPLES_IN_FLIGHT};
use crate::integrator::lanes::WaveLanes;
use crate::integrator::trace_wave::WaveRay;
use crate::integrator::wave_order::{run_waves, trace_current, Wave, WaveQueues};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::integrator::stop_requested;
use crate::render::stats::RayKind;
use crate::render::tracer::{TraceHit, TraceRay};
use crate::render::Integrator;

pub(crate) use surface::{AmbientEnvironment, IndirectLight, IndirectQuery};

use camera_rays::generate_camera_rays;
use lights::{shade_miss, ShadowRay};
use shadow_walk::{trace_shadows, ShadowWalk};
use surface::{shade_hit, surface_detail};

/// The Whitted integrator.
#[derive(Clone, Copy, Debug, Default)]
pub struct Whitted;

/// A ray in flight, with what it carries from the camera.
#[derive(Clone, Copy, Debug)]
struct PathRay {
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
    /// The camera rays of a run of samples and the waves they lead to.
    rays: WaveQueues<PathRay>,
    trace_rays: Vec<TraceRay>,
    trace_hits: Vec<TraceHit>,
    shadows: Vec<ShadowRay>,
    shadow_rays: Vec<TraceRay>,
    shadow_blocked: Vec<bool>,
    /// Reordering a camera wave's shadow rays by sample (`wave_order::group_by_place`).
    shadow_scratch: Vec<ShadowRay>,
    shadow_order: Vec<u32>,
    group_ends: Vec<usize>,
    /// Pixels of the tile being rendered, and samples of each in flight.
    tile_pixels: u32,
    in_flight: usize,
    /// Whether the current wave is a camera wave.
    camera_wave: bool,
    /// Walks of shadow rays through transmissive occluders.
    walk: ShadowWalk,
    /// The current wave's hits shaded in lanes (`lane_waves`), each ray's lane
    /// (`lane_waves::SCALAR` for the scalar path), and each lane's footprint width at its hit
    /// (`None`: a point sample). Boxed: the lanes' many arrays would make `Waves` the
    /// largest of the integrators' states by far.
    lanes: Box<WaveLanes>,
    lane_of_ray: Vec<u32>,
    cone_width: Vec<Option<f32>>,
}

impl Integrator for Whitted {
    type ThreadState = Waves;

    fn thread_state(&self, _context: &RenderContext) -> Waves {
        Waves::default()
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
    let options = &context.options;
    let spp = options.spp.max(1);
    let image_width = options.width;
    let samples = image.samples.clone().unwrap_or(0..spp);
    let sample_count = samples.len() as u32;
    // Up to 16 samples of every pixel are traced together (`camera_sample`).
    waves.tile_pixels = tile.area() as u32;
    for run in sample_runs(samples, spp, MAX_SAMPLES_IN_FLIGHT) {
        if stop_requested(stop) {
            return false;
        }
        image.begin_samples(run.len());
        waves.in_flight = run.len();
        generate_camera_rays(context, tile, &run, image_width, waves);
        let kept = waves.rays.kept.iter().filter(|&&k| k).count();
        worker.counters.count_rays(RayKind::Camera, kept as u64);
        let tile_pixels = waves.tile_pixels;
        run_waves(
            waves,
            |waves| &mut waves.rays,
            run.len(),
            |ray| slot_place(ray.slot, tile_pixels) as usize,
            |waves, wave| {
                trace_wave(context, waves, &wave, worker);
                shade_wave(context, waves, image, worker, indirect);
                trace_shadows(context, waves, image, worker);
            },
        );
        // These samples' radiance joins the exact sums (`film::sample_sum`): any split of
        // the samples into ranges then adds up to the same bits.
        image.add_samples_in_flight(run.kept_places(), false, options.sample_clamp);
    }
    image.finish_mean(sample_count);
    // The background is rendered too: a finished pixel is opaque. (Alpha 0 marks pixels
    // an interrupted render did not reach.)
    image.alpha.fill(1.0);
    true
}

/// Trace the current wave (`wave_order::trace_current`).
fn trace_wave(context: &RenderContext, waves: &mut Waves, wave: &Wave, worker: &mut WorkerState) {
    waves.camera_wave = matches!(wave, Wave::Camera(_));
    trace_current(
        context,
        &mut waves.rays,
        wave,
        |ray| WaveRay {
            origin: ray.origin,
            direction: ray.direction,
            start: ray.start,
            footprint: &ray.footprint,
        },
        &mut waves.trace_rays,
        &mut waves.trace_hits,
        &mut worker.counters,
    );
}

/// Shade the wave's hits: those the lanes cover together, stage by stage
/// (`lane_waves`), the others one by one; then, in the wave's order, each ray's light joins
/// the film and its shadow rays the queue, so the sums are the same whichever path shaded it.
fn shade_wave(
    context: &RenderContext,
    waves: &mut Waves,
    image: &mut TileImage,
    worker: &mut WorkerState,
    indirect: &dyn IndirectLight,
) {
    waves.shadows.clear();
    lane_waves::pick_lanes(context, waves, image, worker, indirect);
    lane_waves::shade_lanes(context, waves, worker);
    for index in 0..waves.rays.current.len() {
        let lane = waves.lane_of_ray[index];
        if lane != lane_waves::SCALAR {
            lane_waves::finish_lane(context, waves, index, lane as usize, image);
            continue;
        }
        let ray = waves.rays.current[index];
        let hit = &waves.trace_hits[index];
        if !hit.is_hit() {
            shade_miss(context, &ray, image, worker);
            continue;
        }
        let detail = surface_detail(context, &ray, hit);
        let surface = context
            .surfaces
            .surface_hit(ray.origin, ray.direction, hit, detail);
        shade_hit(context, ray, &surface, image, waves, worker, indirect);
    }
}

#[inline]
fn add_radiance(image: &mut TileImage, slot: u32, radiance: Vec3) {
    let c = &mut image.color[slot as usize];
    c[0] += radiance.x;
    c[1] += radiance.y;
    c[2] += radiance.z;
}
