//! A dielectric boundary: how a ray hitting a transmissive surface splits into a refracted
//! ray (Snell's law, seed 001) and a reflected one (the Fresnel share, seed 004, all of it
//! under total internal reflection), with the medium each one travels in.

use glam::Vec3;

use super::spawn::{HitSurface, Spawner};
use super::{PathRay, Waves};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::shading::material_bsdf::Weighted;
use crate::shading::{self, SmoothDielectric};

/// Spawn the refracted and reflected rays of `ray` at a transmissive `surface` of the
/// material `material` (the material's smooth boundary, with its weight: the material's
/// transmission).
pub(super) fn scatter_dielectric(
    context: &RenderContext,
    ray: &PathRay,
    (surface, material): (&HitSurface, u32),
    boundary: Weighted<SmoothDielectric>,
    spawner: &Spawner,
    waves: &mut Waves,
    worker: &mut WorkerState,
) {
    let effects = &context.effects;
    let transmission = boundary.weight;
    let split = boundary.lobe.split(ray.direction);
    let (boundary, reflectance) = (split.boundary, split.reflectance);
    let (ng, ns) = (split.incident_normal, split.incident_shading_normal);
    if let Some(refracted) = split.refracted {
        let footprint = if effects.footprints {
            worker.counters.footprint_updates += 1;
            ray.footprint.refract_with(
                ray.direction,
                boundary.eta,
                refracted,
                || surface.curvature(context, ray.direction),
                || surface.record(context),
            )
        } else {
            ray.footprint
        };
        // Entering the material: its medium; leaving: back outside.
        let sigma = if boundary.entering {
            context.materials.sigma[material as usize]
        } else {
            Vec3::ZERO
        };
        spawner.spawn(
            waves,
            worker,
            refracted,
            -ng,
            Vec3::splat(transmission * (1.0 - reflectance)),
            RayKind::Refraction,
            footprint,
            sigma,
        );
    }
    if reflectance > 0.0 {
        let weight = transmission * reflectance;
        let reflected = shading::reflect_above(ray.direction, ns, ng);
        spawner.spawn_reflection(context, surface, reflected, ng, weight, waves, worker);
    }
}
