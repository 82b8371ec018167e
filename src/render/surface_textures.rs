//! A material's textures read at a hit, filtered over the ray's footprint: the one lookup
//! every integrator uses for the base colour, metallic-roughness, emission and normal
//! textures, combined into shading inputs by `crate::shading::surface_inputs`.
//!
//! Each binding is looked up with the same texture gradients (the footprint's at the hit,
//! mapped through the binding's transform) and the same filter options as the base colour,
//! from the render's own textures or from an external texture system when one serves them.

use glam::{Vec2, Vec4};

use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::binding_query;
use crate::scene::{Material, TextureBinding};
use crate::shading::surface_inputs::{surface_inputs, SurfaceInputs, TextureSlot};
use crate::texture::TextureQuery;

/// The filtered texel of `binding` at texture coordinates `st` with the footprint's
/// gradients `[ds/dx, dt/dx, ds/dy, dt/dy]` (zero for a point sample of level 0), with the
/// query it used. Counts the lookup and records its texture tiles when they are counted.
pub fn sample_binding(
    context: &RenderContext,
    binding: &TextureBinding,
    st: Vec2,
    gradients: [f32; 4],
    worker: &mut WorkerState,
) -> (TextureQuery, Vec4) {
    let filter = &context.texture_filters[binding.texture];
    let query = binding_query(&binding.transform, st, gradients);
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
    (query, texel)
}

/// [`sample_binding`]'s texels for many queries of one binding (made by
/// `binding_query`), into `out`: the lookups of the shading lanes, one batch per material
/// run and texture.
pub fn sample_binding_batch(
    context: &RenderContext,
    binding: &TextureBinding,
    queries: &[TextureQuery],
    worker: &mut WorkerState,
    out: &mut [Vec4],
) {
    let filter = &context.texture_filters[binding.texture];
    worker.counters.texture_lookups += queries.len() as u64;
    match &context.external_textures {
        Some(external) => {
            for (query, texel) in queries.iter().zip(out) {
                *texel = crate::render::external_textures::sample_external(
                    external.as_ref(),
                    binding.texture,
                    query,
                    filter,
                );
            }
        }
        None => context.textures[binding.texture].sample_batch(
            queries,
            filter,
            worker.texture_tiles.get_mut(binding.texture),
            out,
        ),
    }
}

/// The radiance an area light emits at texture coordinates `st` (from its front side): its
/// emission factor, times its material's emission texture read at level 0 with the render's
/// filter and zero gradients (a point lookup: bilinear for the filtering modes, the nearest
/// texel for `closest`) when it has one.
///
/// Next-event estimation reads it at the sampled point and a BSDF-sampled ray that hits the
/// light at the hit, so the two halves of multiple importance sampling weigh the same
/// radiance. Level 0 rather than a footprint: a light sample has no ray cone of its own, and
/// the cone that would reach the point (the shading point's, widened by the BSDF spread
/// there, out to the light) differs from the BSDF-sampled ray's, so filtered values would
/// make the two strategies estimate two different blurs of the texture. Emission seen by
/// the camera or through mirrors and glass, which light sampling cannot reach, stays
/// filtered by the ray's footprint.
pub fn area_light_radiance(
    context: &RenderContext,
    light: &crate::shading::AreaLight,
    st: Vec2,
    worker: &mut WorkerState,
) -> glam::Vec3 {
    let binding = light
        .textured
        .and_then(|t| context.scene.materials.get(t.material as usize))
        .and_then(|material| material.emission_texture.as_ref());
    match binding {
        Some(binding) => {
            let (_, texel) = sample_binding(context, binding, st, [0.0; 4], worker);
            light.radiance * texel.truncate()
        }
        None => light.radiance,
    }
}

/// The shading inputs of `material` at `surface`, every texture filtered with the
/// footprint's `gradients` (see [`sample_binding`]). `observe` sees each lookup (slot, query,
/// texel), e.g. to fill the texture AOVs; `with_alpha` as in
/// [`surface_inputs`](crate::shading::surface_inputs::surface_inputs).
pub fn shading_inputs(
    context: &RenderContext,
    material: &Material,
    surface: &SurfaceHit,
    gradients: [f32; 4],
    with_alpha: bool,
    worker: &mut WorkerState,
    mut observe: impl FnMut(TextureSlot, &TextureQuery, Vec4),
) -> SurfaceInputs {
    surface_inputs(material, surface, with_alpha, |slot, binding| {
        let (query, texel) = sample_binding(context, binding, surface.st, gradients, worker);
        observe(slot, &query, texel);
        texel
    })
}

pub use crate::shading::material_features::reads_textures;
