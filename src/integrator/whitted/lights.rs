//! Light at a hit: the environment seen by rays that leave the scene, and the shadow rays
//! that carry each delta light's direct contribution to the opaque part of a surface (the
//! delta subset of the scene's lights, `shading::light_interface`).

use glam::{Vec2, Vec3};

use super::{add_radiance, PathRay, Waves};
use crate::film::TileImage;
use crate::integrator::texturing::environment_lookup;
use crate::integrator::trace_wave::ShadowRay;
use crate::render::context::{RenderContext, WorkerState};
use crate::shading::{self, Bsdf, OpaqueLobe, OwnEmission, SpawnPoint};

pub(super) fn shade_miss(
    context: &RenderContext,
    ray: &PathRay,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let radiance = environment_lookup(context, ray.direction, &ray.footprint, worker);
    add_miss_light(context, ray, radiance, image, worker);
}

/// The environment's radiance `radiance` along the escaping `ray` (as [`shade_miss`] looks
/// it up) added to its pixel, with the fog on its way out.
pub(super) fn add_miss_light(
    context: &RenderContext,
    ray: &PathRay,
    radiance: Vec3,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if context.effects.fog {
        // Fogged up to the last volume's exit: an escaping ray's depth to infinity.
        let mut fogged = *ray;
        super::fog::fog_ray_segment(context, &mut fogged, f32::INFINITY, image, worker);
        add_radiance(image, ray.slot, fogged.throughput * radiance);
        return;
    }
    add_radiance(image, ray.slot, ray.throughput * radiance);
}

/// Queue one shadow ray per light that lights the opaque lobe `bsdf` (weight `opaque`) of a
/// hit seen along `ray`, carrying what the light delivers if nothing blocks it. `ng` is the
/// geometric normal on the incident side, as the lobe's shading normal is.
#[allow(clippy::too_many_arguments)]
pub(super) fn queue_shadow_rays(
    context: &RenderContext,
    ray: &PathRay,
    bsdf: &OpaqueLobe,
    opaque: f32,
    spawn: SpawnPoint,
    ng: Vec3,
    waves: &mut Waves,
) {
    let ns = bsdf.normal();
    let wo = -ray.direction;
    let origin = spawn.offset_origin(ng);
    let lights = &context.lights;
    for light in lights.delta_lights() {
        // The light as the surface point sees it; the shadow ray starts from the offset
        // origin and runs to the light (`shading::shadow_ray_towards`). A delta light
        // arrives from one direction whatever the uniform numbers, and has no emission to
        // look up.
        let Some(sample) = lights.sample_li(light, spawn.position, Vec2::ZERO, &mut OwnEmission)
        else {
            continue;
        };
        let wi = sample.wi;
        if wi.dot(ng) <= 0.0 || wi.dot(ns) <= 0.0 {
            continue;
        }
        // The opaque lobe times the cosine at the surface (seed 001's local illumination).
        let f = bsdf.eval(wo, wi) * ns.dot(wi);
        let contribution = ray.throughput * opaque * f * sample.radiance;
        if contribution.max_element() <= 0.0 {
            continue;
        }
        let Some((direction, tfar)) = shading::shadow_ray_towards(origin, sample.light_point, wi)
        else {
            continue;
        };
        waves.shadows.push(ShadowRay {
            origin,
            direction,
            tfar,
            light: sample.light_point.map(|(position, _)| position.as_vec3()),
            contribution,
            slot: ray.slot,
        });
    }
}

/// Shadow rays stop short of a point light robustly (`shading::shadow_ray_end`); towards a
/// directional light (no position) they are unbounded.
#[inline]
pub(super) fn shadow_tfar(distance: f32, light: Option<Vec3>) -> f32 {
    match light {
        Some(position) => shading::shadow_ray_end(distance, position, 0.0),
        None => f32::INFINITY,
    }
}
