//! The wave-integrator layer: what every integrator that renders a tile in waves does the
//! same way, written once.
//!
//! [`render_waves`] owns the tile loop: the runs of samples (`camera_sample::sample_runs`),
//! their camera rays, the waves in their order (`wave_order::run_waves`), the tracing of each
//! wave, and the radiance of each run joining the exact sums of the film. [`WaveBuffers`] is
//! the wave state every such integrator keeps, and traces a wave's shadow rays
//! ([`WaveBuffers::trace_shadow_segments`]); [`add_radiance`] and the AOV writers are how
//! shading reaches the film. An integrator ([`WaveIntegrator`]) supplies only what differs:
//! the ray it carries, how a camera ray starts one, and how a traced wave is shaded (which
//! queues the next wave's rays and delivers its shadow rays).
//!
//! ```text
//! for run in sample_runs:
//!     for wave in run_waves:              camera wave: its rays -> buffers.rays.current
//!                                         trace (packets / stream) -> buffers.trace_hits
//!         integrator.shade_wave           film += radiance; next wave; shadow rays
//!     film.add_samples_in_flight
//! ```

use std::sync::atomic::AtomicBool;

use glam::Vec3;

use crate::film::{PixelRect, TileImage};
use crate::hit::SurfaceHit;
use crate::integrator::camera_sample::{camera_rays, sample_runs, slot_place, CameraRay};
use crate::integrator::trace_wave::{shadow_trace_rays, ShadowRay, WaveRay};
use crate::integrator::wave_order::{run_waves, trace_current, Wave, WaveQueues, CAMERA_WAVE_RAYS};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::integrator::stop_requested;
use crate::render::stats::{RayKind, WorkCounters};
use crate::render::tracer::{TraceHit, TraceRay};
use crate::shading::surface_inputs::SurfaceInputs;

/// An integrator that renders a tile in waves: what it carries along a ray, and how it
/// shades a traced wave. The rest is [`render_waves`].
pub(crate) trait WaveIntegrator {
    /// A ray in flight, with what the integrator carries from the camera.
    type Ray: Copy;
    /// The integrator's per-thread state; it holds the [`WaveBuffers`].
    type State;

    /// How many samples of a pixel are traced together (`camera_sample::SampleRun`).
    const SAMPLES_IN_FLIGHT: u32;
    /// Whether every kept camera ray counts as a path in the render's statistics.
    const COUNTS_PATHS: bool;
    /// Whether a sample whose radiance is not finite is dropped (and counted) rather than
    /// summed.
    const DROPS_NONFINITE_SAMPLES: bool;

    fn buffers(state: &mut Self::State) -> &mut WaveBuffers<Self::Ray>;

    /// The ray a camera ray starts.
    fn camera_ray(ray: CameraRay) -> Self::Ray;

    /// What tracing needs of `ray`.
    fn wave_ray(ray: &Self::Ray) -> WaveRay<'_>;

    /// The colour-buffer slot of `ray` (`camera_sample::sample_slot`).
    fn slot(ray: &Self::Ray) -> u32;

    /// Shade the traced wave (`buffers.rays.current`, hits in `buffers.trace_hits`): add
    /// its light to `image`, push the rays that continue onto `buffers.rays.next`, and trace
    /// and deliver its shadow rays.
    fn shade_wave(
        &self,
        context: &RenderContext,
        state: &mut Self::State,
        image: &mut TileImage,
        worker: &mut WorkerState,
    );
}

/// The wave state of a wave integrator's thread, reused from tile to tile.
pub(crate) struct WaveBuffers<R> {
    /// The camera rays of a run of samples and the waves they lead to.
    pub rays: WaveQueues<R>,
    /// The current wave as traced, and its closest hits.
    pub trace_rays: Vec<TraceRay>,
    pub trace_hits: Vec<TraceHit>,
    /// The current wave's shadow rays as traced, and which of them are blocked.
    pub shadow_rays: Vec<TraceRay>,
    pub shadow_blocked: Vec<bool>,
    /// Pixels of the tile being rendered, and samples of each in flight.
    pub tile_pixels: u32,
    pub in_flight: usize,
    /// Whether the current wave is a camera wave.
    pub camera_wave: bool,
}

impl<R> WaveBuffers<R> {
    /// Which of `shadows` (the current wave's) are blocked, into `shadow_blocked`: a camera
    /// wave's are coherent and go as 16-wide packets, a later wave's as one occlusion
    /// stream. Counted as shadow rays.
    pub fn trace_shadow_segments(
        &mut self,
        context: &RenderContext,
        shadows: &[ShadowRay],
        counters: &mut WorkCounters,
    ) {
        shadow_trace_rays(shadows, &mut self.shadow_rays, counters);
        if self.camera_wave {
            context.tracer.occluded_wave(
                &self.shadow_rays,
                &mut self.shadow_blocked,
                true,
                counters,
            );
        } else {
            context.tracer.occluded_stream(
                self.shadow_rays.iter().copied(),
                &mut self.shadow_blocked,
                counters,
            );
        }
    }
}

impl<R> Default for WaveBuffers<R> {
    fn default() -> Self {
        WaveBuffers {
            rays: WaveQueues::default(),
            trace_rays: Vec::new(),
            trace_hits: Vec::new(),
            shadow_rays: Vec::new(),
            shadow_blocked: Vec::new(),
            tile_pixels: 0,
            in_flight: 0,
            camera_wave: false,
        }
    }
}

/// Render `tile` with `integrator`'s waves; the arguments and the result are
/// [`crate::render::Integrator::render_tile`]'s.
pub(crate) fn render_waves<I: WaveIntegrator>(
    integrator: &I,
    context: &RenderContext,
    tile: PixelRect,
    image: &mut TileImage,
    worker: &mut WorkerState,
    state: &mut I::State,
    stop: Option<&AtomicBool>,
) -> bool {
    let options = &context.options;
    let spp = options.spp.max(1);
    let samples = image.samples.clone().unwrap_or(0..spp);
    let sample_count = samples.len() as u32;
    let tile_pixels = tile.area() as u32;
    I::buffers(state).tile_pixels = tile_pixels;
    for run in sample_runs(samples, spp, I::SAMPLES_IN_FLIGHT) {
        if stop_requested(stop) {
            return false;
        }
        image.begin_samples(run.len());
        I::buffers(state).in_flight = run.len();
        count_camera_rays::<I>(tile_pixels, run.kept.len(), worker);
        let mut camera = camera_rays(context, tile, &run, options.width);
        // Camera waves, then each sample's rays on their own (`wave_order`).
        run_waves(
            state,
            |state| &mut I::buffers(state).rays,
            run.len(),
            |ray| slot_place(I::slot(ray), tile_pixels) as usize,
            |state| {
                let rays = &mut I::buffers(state).rays;
                let (current, kept) = (&mut rays.current, &mut rays.kept);
                current.clear();
                kept.clear();
                let made = camera.emit_packets(CAMERA_WAVE_RAYS, |ray| {
                    kept.push(ray.kept);
                    current.push(I::camera_ray(ray));
                });
                made > 0
            },
            |state, wave| {
                trace_wave::<I>(context, I::buffers(state), &wave, worker);
                integrator.shade_wave(context, state, image, worker);
            },
        );
        // These samples' radiance joins the exact sums (`film::sample_sum`): any split of
        // the samples into ranges then adds up to the same bits.
        worker.counters.nonfinite_samples += image.add_samples_in_flight(
            run.kept_places(),
            I::DROPS_NONFINITE_SAMPLES,
            options.sample_clamp,
        );
    }
    image.finish_mean(sample_count);
    // The background is rendered too: a finished pixel is opaque. (Alpha 0 marks pixels
    // an interrupted render did not reach.)
    image.alpha.fill(1.0);
    true
}

/// Counts the camera rays the render keeps of a run for a tile (`kept_samples` of each
/// of its `tile_pixels` pixels), and with them the paths of an integrator that counts them.
fn count_camera_rays<I: WaveIntegrator>(
    tile_pixels: u32,
    kept_samples: usize,
    worker: &mut WorkerState,
) {
    let camera_rays = u64::from(tile_pixels) * kept_samples as u64;
    worker.counters.count_rays(RayKind::Camera, camera_rays);
    if I::COUNTS_PATHS {
        worker.counters.paths += camera_rays;
    }
}

/// Trace the current wave (`wave_order::trace_current`): its hits into
/// `buffers.trace_hits`.
fn trace_wave<I: WaveIntegrator>(
    context: &RenderContext,
    buffers: &mut WaveBuffers<I::Ray>,
    wave: &Wave,
    worker: &mut WorkerState,
) {
    buffers.camera_wave = *wave == Wave::Camera;
    trace_current(
        context,
        &mut buffers.rays,
        wave,
        I::wave_ray,
        &mut buffers.trace_rays,
        &mut buffers.trace_hits,
        &mut worker.counters,
    );
}

/// Adds `radiance` to the colour-buffer slot `slot` (`camera_sample::sample_slot`).
#[inline]
pub(crate) fn add_radiance(image: &mut TileImage, slot: u32, radiance: Vec3) {
    let c = &mut image.color[slot as usize];
    c[0] += radiance.x;
    c[1] += radiance.y;
    c[2] += radiance.z;
}

/// The depth, shading normal and texture coordinates of a pixel's first camera hit, seen
/// along `direction`, if the render keeps surface AOVs. A first sample's slot is its pixel.
pub(crate) fn write_geometry_aovs(
    context: &RenderContext,
    image: &mut TileImage,
    pixel: u32,
    direction: Vec3,
    surface: &SurfaceHit,
) {
    let (t, normal, st) = (surface.t, surface.shading_normal, surface.st);
    write_geometry_values(context, image, pixel, direction, t, normal, st);
}

/// [`write_geometry_aovs`] of a hit at distance `t` with shading normal `normal` and texture
/// coordinates `st`, for shading that keeps no hit record (the lanes).
#[inline]
pub(crate) fn write_geometry_values(
    context: &RenderContext,
    image: &mut TileImage,
    pixel: u32,
    direction: Vec3,
    t: f32,
    normal: Vec3,
    st: glam::Vec2,
) {
    if image.depth.is_empty() {
        return;
    }
    let pixel = pixel as usize;
    image.depth[pixel] = t * direction.dot(context.camera_forward);
    image.normal[pixel] = normal.to_array();
    image.uv[pixel] = st.to_array();
}

/// The albedo and the (normal-mapped) shading normal of a pixel's first camera hit, if the
/// render keeps them.
pub(crate) fn write_material_aovs(image: &mut TileImage, pixel: u32, inputs: &SurfaceInputs) {
    if image.albedo.is_empty() {
        return;
    }
    let pixel = pixel as usize;
    image.albedo[pixel] = inputs.albedo.to_array();
    if !image.normal.is_empty() {
        image.normal[pixel] = inputs.shading_normal.to_array();
    }
}
