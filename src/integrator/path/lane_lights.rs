//! Stage 5 of the path tracer's lanes: next-event estimation's light sample for every lane
//! that samples a light, over the whole wave. Each lane chooses a light by power with its
//! vertex's first number, samples a direction towards it with the next two
//! (`shading::SceneLights::sample_li`), and sets up the shadow ray towards the sample from
//! its point moved off the surface on the side the light arrives from; what the light
//! delivers through the BSDF is stage 6's (`lane_bsdf`). The steps and their order are
//! `next_event::sample_light`'s and `queue_shadow_ray`'s.

use glam::Vec3;

use super::lane_waves::PathLanes;
use super::next_event::{shadow_segment, surface_admits, AdmittedEmission, ContextEmission};
use super::{LightStrategy, PathTracer};
use crate::render::context::{RenderContext, WorkerState};
use crate::shading::SpawnPoint;

/// The light samples and shadow segments of the lanes that sample a light
/// (`ScatterLanes::samples_light`), into `ScatterLanes`'s stage-5 arrays.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(super) fn sample_lights(
    tracer: &PathTracer,
    context: &RenderContext,
    path: &mut PathLanes,
    worker: &mut WorkerState,
) {
    let PathLanes {
        lanes,
        scatter,
        vertex_samples,
        ..
    } = path;
    let lights = &context.lights;
    let area_only_by_bsdf = tracer.strategy == LightStrategy::BsdfSampling;
    // One set of vertex numbers per lane.
    for (lane, u) in vertex_samples.iter().enumerate() {
        if !scatter.samples_light[lane] {
            continue;
        }
        let Some((light, pmf)) = lights.choose(u.light) else {
            continue;
        };
        let delta = lights.is_delta(light);
        // Delta lights always; lights with an area only when light sampling takes part.
        if !delta && area_only_by_bsdf {
            continue;
        }
        let (ng, transmits) = (lanes.incident_geometric.get(lane), scatter.transmits[lane]);
        let admits = |wi: Vec3| surface_admits(ng, transmits, wi);
        let mut emission = AdmittedEmission {
            admits,
            lookup: ContextEmission { context, worker },
        };
        let position = lanes.position.get(lane);
        let Some(sample) = lights.sample_li(light, position, u.light_point, &mut emission) else {
            continue;
        };
        let (wi, pdf) = (sample.wi, sample.pdf);
        if !admits(wi) || sample.radiance.max_element() <= 0.0 || pdf.is_nan() || pdf <= 0.0 {
            continue;
        }
        scatter.lit[lane] = true;
        scatter.light[lane] = light;
        scatter.pmf[lane] = pmf;
        scatter.delta[lane] = delta;
        scatter.light_wi.set(lane, wi);
        scatter.light_distance[lane] = sample.distance;
        scatter.radiance.set(lane, sample.radiance);
        scatter.light_pdf[lane] = pdf;
        // The light was seen from the surface point; the shadow ray asks only whether the
        // segment from the offset origin to the light's point is clear.
        let spawn = SpawnPoint {
            position,
            error: lanes.error.get(lane),
        };
        let crosses = wi.dot(ng) < 0.0;
        let origin = spawn.offset_origin(if crosses { -ng } else { ng });
        if let Some((direction, tfar)) = shadow_segment(context, light, origin, &sample) {
            scatter.segment[lane] = true;
            scatter.shadow_origin.set(lane, origin);
            scatter.shadow_direction.set(lane, direction);
            scatter.shadow_tfar[lane] = tfar;
        }
    }
}
