//! Filtered texture lookups at a hit or towards the environment, shared by the integrators:
//! the material's shading inputs under a ray's footprint (filling the first-lookup AOVs of its
//! pixel) and the environment's radiance in a direction.

use glam::{Vec3, Vec4};

use crate::film::TileImage;
use crate::footprint::Footprint;
use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::{environment_light_radiance, environment_radiance, SurfaceDetail};
use crate::render::surface_textures;
use crate::render::tracer::TraceHit;
use crate::scene::{Material, TextureBinding};
use crate::shading::surface_inputs::{SurfaceInputs, TextureSlot};
use crate::texture::TextureQuery;

/// The ray a lookup is made for: its direction and footprint (already at the hit), its
/// pixel in the tile, and whether it belongs to the pixel's first sample (which writes
/// the AOVs).
#[derive(Clone, Copy, Debug)]
pub(crate) struct LookupRay<'a> {
    pub direction: Vec3,
    pub footprint: &'a Footprint,
    /// The slot of the ray's pixel and sample in the tile's colour buffer
    /// (`integrator::camera_sample::sample_slot`); the pixel's index for its first sample.
    pub slot: u32,
    pub first_sample: bool,
}

/// Texture coordinates are needed for textured materials and for the camera hit's AOVs;
/// dP/ds and dP/dt only where footprints are filtered or a normal map bends the normal.
#[inline]
pub(crate) fn surface_detail(
    context: &RenderContext,
    camera_ray_of_first_sample: bool,
    hit: &TraceHit,
) -> SurfaceDetail {
    let aov = camera_ray_of_first_sample && context.options.aovs.surface;
    context
        .surfaces
        .detail_needed(hit, aov, context.effects.footprints)
}

/// The material's shading inputs at the hit (`crate::shading::surface_inputs`): albedo,
/// metallic, roughness, emission and the normal-mapped shading normal, every texture
/// filtered by the ray's footprint. The base-colour lookup fills the first-lookup AOVs of
/// the pixel.
pub(crate) fn surface_inputs(
    context: &RenderContext,
    ray: LookupRay,
    material: &Material,
    surface: &SurfaceHit,
    image: &mut TileImage,
    worker: &mut WorkerState,
) -> SurfaceInputs {
    if !surface_textures::reads_textures(material) {
        // No texture is read: no footprint gradients either.
        return crate::shading::surface_inputs::surface_inputs(material, surface, false, |_, _| {
            glam::Vec4::ONE
        });
    }
    let options = &context.options;
    let gradients = if context.effects.footprints {
        let g = ray
            .footprint
            .texture_gradients(ray.direction, surface, options.filter.max_aniso);
        [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
    } else {
        [0.0; 4]
    };
    let record = records_first_lookup(image, ray.first_sample, ray.slot);
    let mut base_color_lookup = None;
    let inputs = surface_textures::shading_inputs(
        context,
        material,
        surface,
        gradients,
        false,
        worker,
        |slot, query, texel| {
            if slot == TextureSlot::BaseColor {
                base_color_lookup = Some((*query, texel));
            }
        },
    );
    if let (true, Some(lookup), Some(binding)) =
        (record, base_color_lookup, &material.base_color_texture)
    {
        record_first_lookup(context, image, ray.slot, binding, lookup, ray.footprint);
    }
    inputs
}

/// Whether a hit of a ray of sample slot `slot` records its pixel's first lookup: the render
/// writes the texture-lookup AOVs (`tex`, `texcolor`, `lod`, `footprint`), the ray belongs
/// to its pixel's first sample (whose slot is its pixel), and no earlier hit of that sample
/// recorded one.
#[inline]
pub(crate) fn records_first_lookup(image: &TileImage, first_sample: bool, slot: u32) -> bool {
    first_sample && !image.lookup_done.is_empty() && !image.lookup_done[slot as usize]
}

/// The texture-lookup AOVs of the pixel `pixel` from its first sample's base-colour lookup
/// `(query, texel)` through `binding`, made under `footprint` (at the hit).
pub(crate) fn record_first_lookup(
    context: &RenderContext,
    image: &mut TileImage,
    pixel: u32,
    binding: &TextureBinding,
    (query, texel): (TextureQuery, Vec4),
    footprint: &Footprint,
) {
    let pixel = pixel as usize;
    image.lookup_done[pixel] = true;
    if !image.tex.is_empty() {
        image.tex[pixel] = [
            query.s, query.t, query.dsdx, query.dtdx, query.dsdy, query.dtdy,
        ];
        image.texcolor[pixel] = [texel.x, texel.y, texel.z, 1.0];
    }
    if !image.lod.is_empty() {
        let filter = &context.texture_filters[binding.texture];
        image.lod[pixel] = context.textures[binding.texture].lod(&query, filter);
        image.footprint[pixel] = footprint.width();
    }
}

/// The environment's radiance in `direction`, filtered by `footprint`'s spread.
pub(crate) fn environment_lookup(
    context: &RenderContext,
    direction: Vec3,
    footprint: &Footprint,
    worker: &mut WorkerState,
) -> Vec3 {
    // A constant colour reads no texture: no footprint gradients either.
    let textured = matches!(
        context.scene.environment,
        crate::scene::Environment::LatLong { .. }
    );
    let gradients = if context.effects.footprints && textured {
        let g = footprint.environment_gradients(direction);
        [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
    } else {
        [0.0; 4]
    };
    count_environment_lookup(context, worker);
    environment_radiance(
        &context.scene.environment,
        &context.textures,
        direction,
        gradients,
        &context.texture_filters,
        context.external_textures.as_deref(),
    )
}

/// The environment as a light in `direction` (`environment_light_radiance`): what light
/// sampling reads and what a ray the power heuristic weights against it reads when it
/// escapes.
pub(crate) fn environment_light_lookup(
    context: &RenderContext,
    direction: Vec3,
    worker: &mut WorkerState,
) -> Vec3 {
    count_environment_lookup(context, worker);
    environment_light_radiance(
        &context.scene.environment,
        &context.textures,
        direction,
        &context.texture_filters,
        context.external_textures.as_deref(),
    )
}

/// Counts a lookup of the environment's texture, when it has one.
#[inline]
fn count_environment_lookup(context: &RenderContext, worker: &mut WorkerState) {
    if matches!(
        context.scene.environment,
        crate::scene::Environment::LatLong { .. }
    ) {
        worker.counters.texture_lookups += 1;
    }
}
