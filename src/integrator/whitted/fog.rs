//! Fog on Whitted's segments (seed 004, "Analytic Fog Density"): every camera, reflection
//! and refraction segment, from the ray's origin to its hit (or to infinity for a ray that
//! escapes), blends towards the fog colour by `1 - T` and passes `T` of what lies behind
//! it; every shadow segment passes `T` of the light. `T = exp(-tau)` with `tau` the exact
//! optical depth (`crate::medium`), or the seed's clamped `1 - min(1, tau)` under
//! `fog_model = "linear-blend"`. `tau` is integrated as `[render] fog_march_steps` says
//! (`crate::medium::integration`: the closed form unless a ray march is asked for).
//!
//! A ray carries its throughput from the camera, so the blend
//! `L = T * L_behind + (1 - T) * fog_color` is applied as: add `throughput * (1 - T) *
//! fog_color` to the pixel now, and multiply the throughput by `T` for what the ray meets.
//! Only called when the scene's effects include fog.

use glam::Vec3;

use super::{add_radiance, PathRay, Waves};
use crate::film::TileImage;
use crate::medium::{segment_fog_with, SegmentFog};
use crate::render::context::{RenderContext, WorkerState};

/// The fog of `[0, t_end]` along `ray`, counted.
#[inline]
fn evaluate(
    context: &RenderContext,
    origin: Vec3,
    direction: Vec3,
    t_end: f32,
    worker: &mut WorkerState,
) -> SegmentFog {
    let (fog, density_samples) = segment_fog_with(
        &context.scene.fog,
        origin,
        direction,
        t_end,
        context.scene.settings.fog_integration,
    );
    worker.counters.fog_segments += 1;
    worker.counters.fog_volume_crossings += u64::from(fog.crossed);
    worker.counters.fog_density_samples += density_samples;
    fog
}

/// Fog every hit ray of the wave up to its hit before any hit is shaded: each ray's
/// throughput keeps what passes, and the in-scattered fog colour it owes its pixel goes into
/// `waves.fog_light` (per ray, `None` for misses, which fog themselves to infinity, and for
/// rays the fog does not touch), added when the ray's turn comes in the wave's order
/// ([`add_fog_light`]). So the shading lanes light the hits with the fogged throughputs, and
/// the film's sums keep the scalar path's order. Left empty when the scene has no fog.
pub(super) fn fog_wave_segments(
    context: &RenderContext,
    waves: &mut Waves,
    worker: &mut WorkerState,
) {
    waves.fog_light.clear();
    if !context.effects.fog {
        return;
    }
    let rays = &mut waves.buffers.rays.current;
    for (ray, hit) in rays.iter_mut().zip(&waves.buffers.trace_hits) {
        let light = hit
            .is_hit()
            .then(|| fog_segment(context, ray, hit.t, worker))
            .flatten();
        waves.fog_light.push(light);
    }
}

/// The fog colour the wave's ray `index` owes its pixel ([`fog_wave_segments`]), added.
#[inline]
pub(super) fn add_fog_light(waves: &Waves, index: usize, image: &mut TileImage) {
    if let Some(Some(light)) = waves.fog_light.get(index) {
        let slot = waves.buffers.rays.current[index].slot;
        add_radiance(image, slot, *light);
    }
}

/// Fog the segment of `ray` up to `t_end` (its hit distance, or infinity when it escapes):
/// the in-scattered fog colour goes to the pixel, the throughput keeps what passes.
pub(super) fn fog_ray_segment(
    context: &RenderContext,
    ray: &mut PathRay,
    t_end: f32,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if let Some(light) = fog_segment(context, ray, t_end, worker) {
        add_radiance(image, ray.slot, light);
    }
}

/// The fog of `ray`'s segment up to `t_end`: the throughput keeps what passes, and the
/// in-scattered fog colour the pixel receives is returned (`None` where the segment holds
/// no fog).
#[inline]
fn fog_segment(
    context: &RenderContext,
    ray: &mut PathRay,
    t_end: f32,
    worker: &mut WorkerState,
) -> Option<Vec3> {
    let fog = evaluate(context, ray.origin, ray.direction, t_end, worker);
    if fog.optical_depth <= 0.0 {
        return None;
    }
    let transmittance = fog.transmittance(context.scene.settings.fog_model);
    let light = ray.throughput * (1.0 - transmittance) * fog.color;
    ray.throughput *= transmittance;
    Some(light)
}

/// The fraction of a light's contribution that passes the fog on a shadow segment from
/// `origin` along `direction` up to `t_end` (infinite towards a directional light).
pub(super) fn shadow_transmittance(
    context: &RenderContext,
    origin: Vec3,
    direction: Vec3,
    t_end: f32,
    worker: &mut WorkerState,
) -> f32 {
    let fog = evaluate(context, origin, direction, t_end, worker);
    if fog.optical_depth > 0.0 {
        fog.transmittance(context.scene.settings.fog_model)
    } else {
        1.0
    }
}
