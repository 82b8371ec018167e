//! Tracing one wave of rays, shared by the integrators: camera waves as coherent 16-wide
//! packets, later waves as incoherent ray streams (see `render::tracer`), each ray with its
//! footprint's cone for alpha cut-out callbacks and traced from its start distance.

use glam::Vec3;

use crate::footprint::Footprint;
use crate::render::stats::{RayKind, WorkCounters};
use crate::render::tracer::{TraceHit, TraceRay};
use crate::render::RenderContext;

/// What tracing needs of a ray in flight.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WaveRay<'a> {
    pub origin: Vec3,
    pub direction: Vec3,
    /// Where tracing starts along the ray (0 for rays leaving a surface).
    pub start: f32,
    pub footprint: &'a Footprint,
}

impl WaveRay<'_> {
    /// The ray as Embree traces it: from `start`, where its cone is as wide as it has grown
    /// by then.
    #[inline]
    pub(crate) fn traced(&self) -> TraceRay {
        let (cone_width, cone_spread) = self.footprint.cone_at_origin();
        TraceRay {
            origin: self.origin + self.direction * self.start,
            direction: self.direction,
            tfar: f32::INFINITY,
            cone_width: cone_width + cone_spread * self.start,
            cone_spread,
        }
    }
}

/// Closest hits of `rays` into `hits`, with distances counted from each ray's origin;
/// `trace_rays` is a reused buffer.
pub(crate) fn trace_wave<'a>(
    context: &RenderContext,
    rays: impl ExactSizeIterator<Item = WaveRay<'a>> + Clone,
    coherent: bool,
    trace_rays: &mut Vec<TraceRay>,
    hits: &mut Vec<TraceHit>,
    counters: &mut WorkCounters,
) {
    let trace_ray = |ray: WaveRay| ray.traced();
    if coherent {
        trace_rays.clear();
        trace_rays.extend(rays.clone().map(trace_ray));
        context.tracer.intersect(trace_rays, hits, true, counters);
    } else {
        // An incoherent wave fills Embree's stream straight from the rays.
        context
            .tracer
            .intersect_stream(rays.clone().map(trace_ray), hits, counters);
    }
    // Distances count from the ray's origin again.
    for (hit, ray) in hits.iter_mut().zip(rays) {
        if ray.start > 0.0 && hit.is_hit() {
            hit.t += ray.start;
        }
    }
}

/// A shadow ray an integrator queues: the segment an occlusion query tests, and what the
/// light delivers to the pixel if nothing blocks it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ShadowRay {
    pub origin: Vec3,
    pub direction: Vec3,
    /// Where the segment ends along `direction`, short of the light
    /// (`shading::shadow_ray_end`), or infinity.
    pub tfar: f32,
    /// The point light's position, where a shadow ray is continued past transmissive
    /// occluders (Whitted's), which measure their far end from it; `None` for directional
    /// lights and where no continuation is traced.
    pub light: Option<Vec3>,
    pub contribution: Vec3,
    /// The colour-buffer slot the contribution goes to.
    pub slot: u32,
}

/// The occlusion rays of a wave's shadow segments in `trace_rays` (a reused buffer),
/// counted as shadow rays; shadow rays carry no cone. Each ray is written field by field
/// into its place: a `TraceRay` built as a value and then copied went through the stack in
/// pieces the copy's wider loads straddled, which stalls store forwarding on every ray.
pub(crate) fn shadow_trace_rays(
    shadows: &[ShadowRay],
    trace_rays: &mut Vec<TraceRay>,
    counters: &mut WorkCounters,
) {
    counters.count_rays(RayKind::Shadow, shadows.len() as u64);
    trace_rays.resize(shadows.len(), shadow_ray(Vec3::ZERO, Vec3::Z, 0.0));
    for (ray, shadow) in trace_rays.iter_mut().zip(shadows) {
        ray.origin = shadow.origin;
        ray.direction = shadow.direction;
        ray.tfar = shadow.tfar;
        ray.cone_width = 0.0;
        ray.cone_spread = 0.0;
    }
}

/// The occlusion ray of one shadow segment: it carries no cone.
#[inline]
pub(crate) fn shadow_ray(origin: Vec3, direction: Vec3, tfar: f32) -> TraceRay {
    TraceRay {
        origin,
        direction,
        tfar,
        cone_width: 0.0,
        cone_spread: 0.0,
    }
}
