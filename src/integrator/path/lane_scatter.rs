//! The path tracer's stages 5 and 6 over a wave's lanes: light sampling
//! ([`super::lane_lights`]) and the BSDF, evaluated towards the light samples and sampled
//! for the continuation ([`super::lane_bsdf`]), for every lane at once, so that the wave's
//! walk only queues the rays they set up (`lane_waves::finish_lane`).
//!
//! [`scatter_lanes`] runs them in the order their data needs: each lane's path arrives at
//! its hit (absorption, footprint), the BSDF says which lanes sample a light, the lights
//! are sampled, and the BSDF values, weights and continuations follow. Every lane computes
//! what `vertex::scatter_at_surface` computes for its ray, operation for operation and from
//! the same uniform numbers, so the rays queued and the light they carry have the scalar
//! path's bits. Side effects (counters, texture-tile marks of emission lookups) are sums
//! and sets, which the order of the lanes does not change.

use glam::Vec3;

use super::lane_waves::PathLanes;
use super::{lane_bsdf, lane_lights, PathRay, PathTracer};
use crate::footprint::{Footprint, RayDifferential};
use crate::integrator::lanes::soa::Vec3Lanes;
use crate::integrator::lanes::{bsdf::incident_normals, refill, LaneArray};
use crate::integrator::trace_wave::ShadowRay;
use crate::render::context::{RenderContext, WorkerState};
use crate::shading::{self, BsdfSample, LightRef, SpawnPoint};

/// What stages 5 and 6 read of each lane's path and write for the walk, one entry per
/// lane, reused from wave to wave.
#[derive(Default)]
pub(super) struct ScatterLanes {
    // The path as it arrives (`arrive_at_hits`).
    /// Whether the path scatters here: its depth allows it (it takes its vertex numbers).
    pub(super) active: Vec<bool>,
    /// Whether a ray may continue at all, and along a non-delta lobe
    /// (`vertex::SurfaceVertex`).
    pub(super) continues: Vec<bool>,
    pub(super) rough_continues: Vec<bool>,
    /// Absorption coefficient of the medium the path arrives through.
    pub(super) sigma: Vec3Lanes,

    // Stage 6, before the lights.
    /// Whether the BSDF transmits with a density (light may come from the far side).
    pub(super) transmits: Vec<bool>,
    /// Whether light sampling runs: the BSDF has a part with a density that light from
    /// above the shading normal reaches.
    pub(super) samples_light: Vec<bool>,

    // Stage 5.
    /// Whether a light was chosen and sampled, and its sample admitted.
    pub(super) lit: Vec<bool>,
    pub(super) light: Vec<LightRef>,
    /// The probability of choosing the light, and whether it is a delta light.
    pub(super) pmf: Vec<f32>,
    pub(super) delta: Vec<bool>,
    /// The light sample (`shading::LiSample`): direction, distance, radiance, density.
    pub(super) light_wi: Vec3Lanes,
    pub(super) light_distance: Vec<f32>,
    pub(super) radiance: Vec3Lanes,
    pub(super) light_pdf: Vec<f32>,
    /// The shadow ray towards the sample, when it has a direction (`segment`).
    pub(super) segment: Vec<bool>,
    pub(super) shadow_origin: Vec3Lanes,
    pub(super) shadow_direction: Vec3Lanes,
    pub(super) shadow_tfar: Vec<f32>,

    // Stage 6, after the lights: what the walk queues, one record per lane, as the walk
    // reads them in the wave's order (a lane's record is one or two cache lines, where
    // the arrays it is made from would be a dozen).
    /// The shadow ray to queue, its slot left for the walk to set.
    pub(super) shadow: Vec<Option<ShadowRay>>,
    /// The BSDF sample the path continues along.
    pub(super) next: Vec<Option<LaneContinuation>>,

    // Stage 6's drawing of the classic lobe's directions (`lane_bsdf`): the concentric
    // disk's polar coordinates, the angle's cosine and sine, and the direction.
    pub(super) disk_radius: Vec<f32>,
    pub(super) disk_angle: Vec<f32>,
    pub(super) disk_cos: Vec<f32>,
    pub(super) disk_sin: Vec<f32>,
    pub(super) cosine_wi: Vec3Lanes,
}

/// What the walk needs of a lane whose path continues (`vertex::queue_continuation`).
#[derive(Clone, Copy, Debug)]
pub(super) struct LaneContinuation {
    pub(super) sample: BsdfSample,
    /// Whether the sample leaves below the geometric surface.
    pub(super) crosses: bool,
    /// The BSDF's value towards a non-delta sample, for the footprint's spread (only when
    /// footprints are on).
    pub(super) value: Vec3,
    /// The hit's point and its rounding-error bound, where the ray leaves from.
    pub(super) spawn: SpawnPoint,
    /// The geometric normal on the viewer's side, and whether that is the front.
    pub(super) ng: Vec3,
    pub(super) front: bool,
}

impl ScatterLanes {
    /// Every array sized for `len` lanes, the flags cleared.
    fn reset(&mut self, len: usize) {
        for flags in [
            &mut self.active,
            &mut self.continues,
            &mut self.rough_continues,
            &mut self.transmits,
            &mut self.samples_light,
            &mut self.lit,
            &mut self.delta,
            &mut self.segment,
        ] {
            refill(flags, len, false);
        }
        for values in [
            &mut self.pmf,
            &mut self.light_distance,
            &mut self.light_pdf,
            &mut self.shadow_tfar,
            &mut self.disk_radius,
            &mut self.disk_angle,
            &mut self.disk_cos,
            &mut self.disk_sin,
        ] {
            values.resize_lanes(len, 0.0);
        }
        for vectors in [
            &mut self.sigma,
            &mut self.light_wi,
            &mut self.radiance,
            &mut self.shadow_origin,
            &mut self.shadow_direction,
            &mut self.cosine_wi,
        ] {
            vectors.resize(len);
        }
        self.light.resize_lanes(len, LightRef::Environment);
        refill(&mut self.shadow, len, None);
        refill(&mut self.next, len, None);
    }
}

/// Stages 5 and 6 of the path lanes, after stages 1-4 and the vertex numbers
/// (`lane_waves::shade_lanes`): the paths arrive at their hits, then the BSDF's test for
/// light sampling, the lights, and the BSDF's values and samples.
pub(super) fn scatter_lanes(
    tracer: &PathTracer,
    context: &RenderContext,
    path: &mut PathLanes,
    rays: &mut [PathRay],
    worker: &mut WorkerState,
) {
    let len = path.lanes.len();
    if len == 0 {
        return;
    }
    path.scatter.reset(len);
    arrive_at_hits(tracer, context, path, rays, worker);
    incident_normals(&mut path.lanes);
    lane_bsdf::test_smooth_parts(context, &path.lanes, &mut path.scatter);
    lane_lights::sample_lights(tracer, context, path, worker);
    lane_bsdf::scatter(tracer, context, path, worker);
}

/// Each lane's path at its hit, as `vertex::shade` takes it there: Beer's law inside its
/// medium and its footprint moved to the hit (on the ray), the throughput then into the
/// lanes, and the path's depths into whether it scatters and continues. A path that
/// scatters moves its sampler past its vertex numbers.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
fn arrive_at_hits(
    tracer: &PathTracer,
    context: &RenderContext,
    path: &mut PathLanes,
    rays: &mut [PathRay],
    worker: &mut WorkerState,
) {
    let PathLanes { lanes, scatter, .. } = path;
    let max_depth = context.options.max_depth;
    for lane in 0..lanes.len() {
        let ray = &mut rays[lanes.wave_index[lane] as usize];
        let differential = lanes.differential_at_hit.get(lane).copied();
        arrive_at_hit(context, ray, (lanes.t[lane], differential), worker);
        lanes.throughput.set(lane, ray.throughput);
        scatter.sigma.set(lane, ray.sigma);
        let active = ray.depth <= max_depth;
        scatter.active[lane] = active;
        if active {
            ray.sampler
                .skip_dimensions(super::vertex::VertexSamples::DIMENSIONS);
        }
        let continues = ray.depth < max_depth;
        scatter.continues[lane] = continues;
        scatter.rough_continues[lane] = continues && ray.diffuse_depth < tracer.diffuse_bounces;
    }
}

/// Beer's law over the distance `t` travelled inside the ray's medium, and the ray's
/// footprint moved to its hit (`vertex::shade`'s absorption and footprint steps): a ray
/// differential is the lane's at the hit (`lanes::differentials`).
#[inline]
fn arrive_at_hit(
    context: &RenderContext,
    ray: &mut PathRay,
    (t, differential): (f32, Option<RayDifferential>),
    worker: &mut WorkerState,
) {
    let effects = &context.effects;
    if effects.absorption && ray.sigma != Vec3::ZERO {
        ray.throughput *= shading::transmittance(ray.sigma, t);
        worker.counters.absorption_evaluations += 1;
    }
    if effects.footprints {
        worker.counters.footprint_updates += 1;
        // `pick_lanes` gives every differential its lane's.
        let at_hit = (ray.footprint.propagated(t)).or(differential.map(Footprint::Differential));
        if let Some(at_hit) = at_hit {
            ray.footprint = at_hit;
        }
    }
}
