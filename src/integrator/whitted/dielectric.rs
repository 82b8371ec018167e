//! A dielectric boundary: how a ray hitting a transmissive surface splits into a refracted
//! ray (Snell's law, seed 001) and a reflected one (the Fresnel share, seed 004, all of it
//! under total internal reflection), with the medium each one travels in.

use glam::Vec3;

use super::spawn::Spawner;
use super::{PathRay, Waves};
use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::scene::Material;
use crate::shading::{self, DielectricBoundary};

/// Spawn the refracted and reflected rays of `ray` at a transmissive `surface`, weighted by
/// the material's transmission. `ns` and `ng` are the shading and geometric normals on the
/// incident side.
#[allow(clippy::too_many_arguments)]
pub(super) fn scatter_dielectric(
    context: &RenderContext,
    ray: &PathRay,
    surface: &SurfaceHit,
    material: &Material,
    ns: Vec3,
    ng: Vec3,
    spawner: &Spawner,
    waves: &mut Waves,
    worker: &mut WorkerState,
) {
    let effects = &context.effects;
    let options = &context.options;
    let front = ray.direction.dot(surface.geometric_normal) < 0.0;
    // Which side the ray comes from, eta = n_incident / n_transmitted (outside = 1): the
    // geometric normal decides, as it decides `front` and the medium below.
    let boundary = DielectricBoundary::with_shading_normal(
        ray.direction,
        surface.geometric_normal,
        surface.shading_normal,
        material.ior,
    );
    let refracted =
        shading::refract(ray.direction, boundary.normal, boundary.eta).filter(|d| d.dot(ng) < 0.0);
    // Total internal reflection (or a refracted ray that would stay on the incident side)
    // reflects everything; otherwise the Fresnel share (seed 004), which is zero for
    // index-matched media (the `fresnel` effect is off when every medium has ior 1).
    let reflectance = if refracted.is_none() {
        1.0
    } else if effects.fresnel {
        shading::fresnel(options.fresnel, boundary.cos_i, boundary.eta)
    } else {
        0.0
    };
    if let Some(refracted) = refracted {
        let footprint = if effects.footprints {
            worker.counters.footprint_updates += 1;
            ray.footprint
                .refract(ray.direction, surface, boundary.eta, refracted)
        } else {
            ray.footprint
        };
        // Entering the material: its medium; leaving: back outside.
        let sigma = if front {
            context.materials.sigma[surface.material as usize]
        } else {
            Vec3::ZERO
        };
        spawner.spawn(
            waves,
            worker,
            refracted,
            -ng,
            Vec3::splat(material.transmission * (1.0 - reflectance)),
            RayKind::Refraction,
            footprint,
            sigma,
        );
    }
    if reflectance > 0.0 {
        let weight = material.transmission * reflectance;
        spawner.spawn_reflection(context, surface, ns, ng, weight, waves, worker);
    }
}
