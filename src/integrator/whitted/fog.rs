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

use super::{add_radiance, PathRay};
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

/// Fog the segment of `ray` up to `t_end` (its hit distance, or infinity when it escapes):
/// the in-scattered fog colour goes to the pixel, the throughput keeps what passes.
pub(super) fn fog_ray_segment(
    context: &RenderContext,
    ray: &mut PathRay,
    t_end: f32,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let fog = evaluate(context, ray.origin, ray.direction, t_end, worker);
    if fog.optical_depth > 0.0 {
        let transmittance = fog.transmittance(context.scene.settings.fog_model);
        add_radiance(
            image,
            ray.slot,
            ray.throughput * (1.0 - transmittance) * fog.color,
        );
        ray.throughput *= transmittance;
    }
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
