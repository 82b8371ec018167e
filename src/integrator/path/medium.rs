//! Fog as a participating medium for the path tracer: free-flight sampling along every
//! path segment through the scene's `[[fog]]` volumes, and the medium vertex a collision
//! makes (next-event estimation with the phase function, a phase-sampled continuation, a
//! cone spread by the phase value). docs/fog.md, "The path tracer", derives the weights.
//!
//! Each volume has a grey extinction `sigma_t(p)` (its density), split per channel into
//! scattering `sigma_s = albedo sigma_t` and absorption `sigma_a = (1 - albedo) sigma_t`.
//! The collision distance is drawn with density `sigma_t(t) T(t)` (`T = exp(-tau)`) by
//! inverting each volume's closed-form depth (`crate::medium::free_flight`, exact, no
//! majorant); so a collision at `t` is weighted by `sigma_s T / (sigma_t T) = albedo` and a
//! segment passed without collision (probability `T(t_end)`) by `T / T = 1`: the surface or
//! environment behind the fog is reached with the throughput it had. This is the analog
//! ("albedo-weighted") estimator of the radiative transfer equation with a grey extinction.

use glam::Vec3;

use super::next_event::{sample_light, Scatterer, ShadingPoint};
use super::vertex::continuing_throughput;
use super::{PathRay, PathTracer, PathWaves};
use crate::footprint::bsdf_spread_angle;
use crate::medium::{free_flight, HenyeyGreenstein, Line};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::shading;

/// Where a path segment collides with fog.
#[derive(Clone, Copy, Debug)]
pub(super) struct Collision {
    /// The distance along the f32 ray (`origin + t * direction`).
    t: f32,
    /// The same distance in world units (the ray's direction need not be of unit length).
    distance: f32,
    /// The index of the volume the collision happened in.
    volume: usize,
}

/// The first collision with fog of each of the wave's rays (`hits` in the same order), or
/// `None` where it passes, into `collisions`; left empty when the scene has no fog. Every
/// ray's fog is sampled before any hit is shaded, so the shading lanes take the rays that
/// pass with their samplers already moved past the fog's dimensions.
pub(super) fn sample_wave_collisions(
    context: &RenderContext,
    rays: &mut [PathRay],
    hits: &[TraceHit],
    collisions: &mut Vec<Option<Collision>>,
    worker: &mut WorkerState,
) {
    collisions.clear();
    if !context.effects.fog {
        return;
    }
    for (ray, hit) in rays.iter_mut().zip(hits) {
        let t_end = if hit.is_hit() { hit.t } else { f32::INFINITY };
        collisions.push(sample_collision(context, ray, t_end, worker));
    }
}

/// Sample the first collision of `ray` with the scene's fog between its origin and `t_end`
/// (its hit, or infinity for a ray that escapes); `None` if it passes. Each volume the
/// segment crosses draws one exponential variate from the path's sampler; the segment
/// always moves the sampler on by one dimension per volume of the scene, crossed or not, so
/// that the dimensions of the vertices after it do not depend on which volumes it crossed.
fn sample_collision(
    context: &RenderContext,
    ray: &mut PathRay,
    t_end: f32,
    worker: &mut WorkerState,
) -> Option<Collision> {
    worker.counters.fog_segments += 1;
    let (line, scale) = Line::from_ray(ray.origin, ray.direction)?;
    // From the ray's origin, not from `ray.start`: a camera ray starts tracing just before
    // the geometry's bounds (`shading::entry_distance`), but fog fills the space in front.
    let t0 = 0.0;
    let t1 = if t_end.is_finite() {
        f64::from(t_end) * scale
    } else {
        f64::INFINITY
    };
    let mut crossed = 0u64;
    let sampler = &mut ray.sampler;
    let found = free_flight(&context.scene.fog, &line, t0, t1, || {
        crossed += 1;
        // -ln(1 - u), u in [0, 1): an exponential variate of mean 1, never infinite.
        -(1.0 - f64::from(sampler.next_1d())).ln()
    });
    worker.counters.fog_volume_crossings += crossed;
    let volumes = context.scene.fog.len() as u64;
    ray.sampler
        .skip_dimensions(volumes.saturating_sub(crossed) as u32);
    let (distance, volume) = found?;
    Some(Collision {
        t: (distance / scale) as f32,
        distance: distance as f32,
        volume,
    })
}

/// The medium vertex at `collision`: light sampling weighted by the phase function (MIS
/// against phase sampling), then the path continues in a direction the phase function
/// samples. Moves the sampler on by the seven dimensions of a surface vertex (light choice,
/// point on the light, lobe, direction, roulette; the lobe's is unused here), so that later
/// vertices draw the same dimensions whether this one was in fog or on a surface.
pub(super) fn scatter(
    tracer: &PathTracer,
    context: &RenderContext,
    mut ray: PathRay,
    collision: Collision,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    let volume = &context.scene.fog[collision.volume];
    worker.counters.fog_scatter_events += 1;
    // Beer's law inside an absorbing dielectric still applies up to the collision.
    if context.effects.absorption && ray.sigma != Vec3::ZERO {
        ray.throughput *= shading::transmittance(ray.sigma, collision.t);
        worker.counters.absorption_evaluations += 1;
    }
    // sigma_s T / (sigma_t T): the collision's weight under exact free-flight sampling.
    let throughput = ray.throughput * volume.albedo;
    let travel = ray.direction.normalize();
    let position = ray.origin + ray.direction * collision.t;
    let phase = HenyeyGreenstein::new(volume.g);

    let u_light = ray.sampler.next_1d();
    let u_light_point = ray.sampler.next_2d();
    ray.sampler.skip_dimensions(1);
    let u_direction = ray.sampler.next_2d();
    let u_roulette = ray.sampler.next_1d();

    let footprint = if context.effects.footprints {
        worker.counters.footprint_updates += 1;
        ray.footprint.advance(collision.distance)
    } else {
        ray.footprint
    };
    // A scattering event is a non-delta bounce: it counts against both bounce limits.
    let continues =
        ray.depth < context.options.max_depth && ray.diffuse_depth < tracer.diffuse_bounces;
    if throughput.max_element() > 0.0 {
        let point = ShadingPoint {
            position,
            origin: position,
            origin_through: position,
            sigma: ray.sigma,
            sigma_through: ray.sigma,
            wo: -travel,
            scatterer: Scatterer::Medium(phase),
            throughput,
            slot: ray.slot,
            last: !continues,
        };
        sample_light(
            tracer,
            context,
            &point,
            u_light,
            u_light_point,
            waves,
            worker,
        );
    }
    if !continues {
        return;
    }
    // The phase function is sampled exactly: p / pdf = 1, the throughput is unchanged.
    let sample = phase.sample(travel, u_direction);
    let depth = ray.depth + 1;
    let Some(throughput) = continuing_throughput(throughput, depth, u_roulette, worker) else {
        return;
    };
    // Seed 000's BSDF spread with the phase function's value in the sampled direction.
    let footprint = if context.effects.footprints {
        worker.counters.footprint_updates += 1;
        footprint.scatter(bsdf_spread_angle(sample.pdf))
    } else {
        footprint
    };
    // Scattered rays are counted with the reflection rays (rays a vertex scattered).
    worker.counters.count_rays(RayKind::Reflection, 1);
    worker.counters.path_bounces += 1;
    waves.buffers.rays.next.push(PathRay {
        origin: position,
        direction: sample.wi,
        start: 0.0,
        throughput,
        footprint,
        approximate_footprint: true,
        slot: ray.slot,
        depth,
        diffuse_depth: ray.diffuse_depth + 1,
        bsdf_pdf: Some(sample.pdf),
        from: position,
        kind: RayKind::Reflection,
        sigma: ray.sigma,
        first_sample: ray.first_sample,
        sampler: ray.sampler,
    });
}
