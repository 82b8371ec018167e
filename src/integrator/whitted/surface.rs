//! Shading a hit: what the camera hit writes to the AOVs, absorption on the way in, the
//! material's albedo under the ray's footprint, emission and ambient light, and which
//! secondary rays the material spawns (direct light in `lights`, mirror and dielectric rays
//! in `spawn` and `dielectric`).

use glam::Vec3;

use super::dielectric::scatter_dielectric;
use super::lights::queue_shadow_rays;
use super::spawn::Spawner;
use super::{add_radiance, PathRay, Waves};
use crate::film::TileImage;
use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::{binding_query, SurfaceDetail};
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::scene::Material;
use crate::shading::{self, MaterialBsdf};

/// Texture coordinates are needed for textured materials and for the camera hit's AOVs.
#[inline]
pub(super) fn surface_detail(
    context: &RenderContext,
    ray: &PathRay,
    hit: &TraceHit,
) -> SurfaceDetail {
    let aov = ray.kind == RayKind::Camera && ray.first_sample && context.options.aovs.surface;
    if aov || context.surfaces.is_textured(hit) {
        SurfaceDetail::Texturing
    } else {
        SurfaceDetail::Geometry
    }
}

/// Shade the hit of `ray` at `surface`: its AOVs, emission and ambient light, the shadow
/// rays of its direct light, and the secondary rays of the next wave.
pub(super) fn shade_hit(
    context: &RenderContext,
    mut ray: PathRay,
    surface: &SurfaceHit,
    image: &mut TileImage,
    waves: &mut Waves,
    worker: &mut WorkerState,
) {
    let effects = &context.effects;
    let options = &context.options;
    let material: &Material = &context.scene.materials[surface.material as usize];
    let pixel = ray.pixel as usize;

    if ray.kind == RayKind::Camera {
        if ray.first_sample && !image.depth.is_empty() {
            image.depth[pixel] = surface.t * ray.direction.dot(context.camera_forward);
            image.normal[pixel] = surface.shading_normal.to_array();
            image.uv[pixel] = surface.st.to_array();
        }
    }

    // Fog between the ray's origin and the hit (seed 004, analytic fog density).
    if effects.fog {
        super::fog::fog_ray_segment(context, &mut ray, surface.t, image, worker);
    }
    // Beer's law over the distance travelled inside the medium (seed 004).
    if effects.absorption && ray.sigma != Vec3::ZERO {
        ray.throughput *= shading::transmittance(ray.sigma, surface.t);
        worker.counters.absorption_evaluations += 1;
    }
    if effects.footprints {
        ray.footprint.transfer(ray.direction, surface);
        worker.counters.footprint_updates += 1;
    }

    let albedo = surface_albedo(context, &ray, material, surface, image, worker);
    if ray.kind == RayKind::Camera && ray.first_sample && !image.albedo.is_empty() {
        image.albedo[pixel] = albedo.to_array();
    }

    let mut radiance = material.emission;
    let spawn = surface.spawn_point();
    // The index-matched case (the `fresnel` effect is off when every medium has ior 1)
    // reflects nothing but total internal reflection.
    let bsdf = MaterialBsdf::new(
        material,
        albedo,
        ray.direction,
        surface.geometric_normal,
        surface.shading_normal,
        effects.fresnel.then_some(options.fresnel),
    );

    // Local illumination of the opaque part: direct light with shadow rays, plus ambient
    // environment light.
    // The geometric normal on the incident side: rays leaving on that side start above it.
    let ng = bsdf.mirror.ng;
    let opaque = bsdf.opaque_weight;
    if opaque > 0.0 {
        if effects.shadows {
            queue_shadow_rays(context, &ray, &bsdf.opaque, opaque, spawn, ng, waves);
        }
        if effects.environment {
            radiance += opaque * albedo * context.lights.environment.mean_radiance;
        }
    }
    add_radiance(image, ray.pixel, ray.throughput * radiance);

    let can_spawn = ray.depth < options.max_depth;
    if !can_spawn {
        return;
    }
    let spawner = Spawner {
        parent: &ray,
        spawn,
        min_throughput: options.min_throughput,
    };
    if effects.mirror_reflection && bsdf.mirror_weight > 0.0 {
        let reflected = bsdf.mirror.direction(-ray.direction);
        let weight = bsdf.mirror_weight;
        spawner.spawn_reflection(context, surface, reflected, ng, weight, waves, worker);
    }

    if effects.refraction && bsdf.dielectric_weight > 0.0 {
        let dielectric = &bsdf.dielectric;
        scatter_dielectric(
            context, &ray, surface, material, dielectric, &spawner, waves, worker,
        );
    }
}

/// The material's albedo at the hit: base colour times its texture, filtered by the ray's
/// footprint. Fills the first-lookup AOVs of the pixel.
pub(super) fn surface_albedo(
    context: &RenderContext,
    ray: &PathRay,
    material: &Material,
    surface: &SurfaceHit,
    image: &mut TileImage,
    worker: &mut WorkerState,
) -> Vec3 {
    let Some(binding) = &material.base_color_texture else {
        return material.base_color;
    };
    let options = &context.options;
    let filter = &context.texture_filters[binding.texture];
    let gradients = if context.effects.footprints {
        let g = ray
            .footprint
            .texture_gradients(ray.direction, surface, options.filter.max_aniso);
        [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
    } else {
        [0.0; 4]
    };
    let query = binding_query(&binding.transform, surface.st, gradients);
    let texture = &context.textures[binding.texture];
    worker.counters.texture_lookups += 1;
    let texel = match (
        &context.external_textures,
        worker.texture_tiles.get_mut(binding.texture),
    ) {
        (Some(external), _) => crate::render::external_textures::sample_external(
            external.as_ref(),
            binding.texture,
            &query,
            filter,
        ),
        (None, Some(tiles)) => texture.sample_recording(&query, filter, tiles),
        (None, None) => texture.sample(&query, filter),
    };
    let pixel = ray.pixel as usize;
    if ray.first_sample && !image.lookup_done.is_empty() && !image.lookup_done[pixel] {
        image.lookup_done[pixel] = true;
        if !image.tex.is_empty() {
            image.tex[pixel] = [
                query.s, query.t, query.dsdx, query.dtdx, query.dsdy, query.dtdy,
            ];
            image.texcolor[pixel] = [texel.x, texel.y, texel.z, 1.0];
        }
        if !image.lod.is_empty() {
            image.lod[pixel] = texture.lod(&query, filter);
            image.footprint[pixel] = ray.footprint.width();
        }
    }
    material.base_color * texel.truncate()
}
