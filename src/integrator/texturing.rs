//! Filtered texture lookups at a hit or towards the environment, shared by the integrators:
//! the material's albedo under a ray's footprint (filling the first-lookup AOVs of its
//! pixel) and the environment's radiance in a direction.

use glam::Vec3;

use crate::film::TileImage;
use crate::footprint::Footprint;
use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::{binding_query, environment_radiance, SurfaceDetail};
use crate::render::tracer::TraceHit;
use crate::scene::Material;

/// The ray a lookup is made for: its direction and footprint (already at the hit), its
/// pixel in the tile, and whether it belongs to the pixel's first sample (which writes
/// the AOVs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct LookupRay<'a> {
    pub direction: Vec3,
    pub footprint: &'a Footprint,
    pub pixel: u32,
    pub first_sample: bool,
}

/// Texture coordinates are needed for textured materials and for the camera hit's AOVs.
#[inline]
pub(crate) fn surface_detail(
    context: &RenderContext,
    camera_ray_of_first_sample: bool,
    hit: &TraceHit,
) -> SurfaceDetail {
    let aov = camera_ray_of_first_sample && context.options.aovs.surface;
    if aov || context.surfaces.is_textured(hit) {
        SurfaceDetail::Texturing
    } else {
        SurfaceDetail::Geometry
    }
}

/// The material's albedo at the hit: base colour times its texture, filtered by the ray's
/// footprint. Fills the first-lookup AOVs of the pixel.
pub(crate) fn surface_albedo(
    context: &RenderContext,
    ray: LookupRay,
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

/// The environment's radiance in `direction`, filtered by `footprint`'s spread.
pub(crate) fn environment_lookup(
    context: &RenderContext,
    direction: Vec3,
    footprint: &Footprint,
    worker: &mut WorkerState,
) -> Vec3 {
    let gradients = if context.effects.footprints {
        let g = footprint.environment_gradients(direction);
        [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
    } else {
        [0.0; 4]
    };
    if matches!(
        context.scene.environment,
        crate::scene::Environment::LatLong { .. }
    ) {
        worker.counters.texture_lookups += 1;
    }
    environment_radiance(
        &context.scene.environment,
        &context.textures,
        direction,
        gradients,
        &context.texture_filters,
        context.external_textures.as_deref(),
    )
}
