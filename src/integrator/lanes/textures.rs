//! Stage 4: the materials' textures read at the lanes' hits. The lanes are ordered by
//! material, so each texture binding is looked up for its material's range of lanes in one
//! batch (`Texture::sample_batch`), and the texels combined into albedo, metallic and roughness as
//! `shading::surface_inputs` combines them (glTF 2.0: the base colour's RGB, the
//! metallic-roughness texture's blue and green).

use glam::Vec4;

use super::WaveLanes;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::binding_query;
use crate::render::surface_textures::sample_binding_batch;
use crate::scene::{Material, TextureBinding};

/// Albedo, metallic and roughness of every lane (the lanes ordered by material).
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn shading_inputs(
    context: &RenderContext,
    lanes: &mut WaveLanes,
    worker: &mut WorkerState,
) {
    let len = lanes.len();
    lanes.albedo.resize(len);
    lanes.metallic.resize(len, 0.0);
    lanes.roughness.resize(len, 0.0);
    for run in 0..lanes.material_runs.len() {
        let (material, range) = lanes.material_run(run);
        let material = &context.scene.materials[material as usize];
        let model = material.model.metallic_roughness();
        let base = material.base_color;
        lanes.albedo.x[range.clone()].fill(base.x);
        lanes.albedo.y[range.clone()].fill(base.y);
        lanes.albedo.z[range.clone()].fill(base.z);
        lanes.metallic[range.clone()].fill(model.map_or(0.0, |model| model.metallic));
        lanes.roughness[range.clone()].fill(model.map_or(0.0, |model| model.roughness));
        for (binding, channel) in texture_reads(material) {
            let mut queries = std::mem::take(&mut lanes.texture_queries);
            let mut texels = std::mem::take(&mut lanes.texels);
            queries.clear();
            queries.extend(range.clone().map(|lane| {
                binding_query(
                    &binding.transform,
                    lanes.st.get(lane),
                    lanes.gradients[lane],
                )
            }));
            texels.clear();
            texels.resize(queries.len(), Vec4::ZERO);
            sample_binding_batch(context, binding, &queries, worker, &mut texels);
            for (lane, &texel) in range.clone().zip(&texels) {
                apply_texel(lanes, lane, channel, material, texel);
            }
            lanes.texture_queries = queries;
            lanes.texels = texels;
        }
    }
}

/// What a texel multiplies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Channel {
    /// The base colour (RGB).
    BaseColor,
    /// Roughness (green) and metallic (blue).
    MetallicRoughness,
    Roughness,
    Metallic,
}

/// The textures shading `material` reads, in the order `shading::surface_inputs` reads them
/// (emission and normal maps are not the lanes'; alpha is resolved while tracing).
fn texture_reads(material: &Material) -> impl Iterator<Item = (&TextureBinding, Channel)> {
    let model = material.model.metallic_roughness();
    let reads = [
        (material.base_color_texture.as_ref(), Channel::BaseColor),
        (
            model.and_then(|m| m.metallic_roughness_texture.as_ref()),
            Channel::MetallicRoughness,
        ),
        (
            model.and_then(|m| m.roughness_texture.as_ref()),
            Channel::Roughness,
        ),
        (
            model.and_then(|m| m.metallic_texture.as_ref()),
            Channel::Metallic,
        ),
    ];
    reads
        .into_iter()
        .filter_map(|(binding, channel)| binding.map(|b| (b, channel)))
}

#[inline]
fn apply_texel(
    lanes: &mut WaveLanes,
    lane: usize,
    channel: Channel,
    material: &Material,
    texel: Vec4,
) {
    match channel {
        Channel::BaseColor => lanes
            .albedo
            .set(lane, material.base_color * texel.truncate()),
        Channel::MetallicRoughness => {
            lanes.metallic[lane] *= texel.z;
            lanes.roughness[lane] *= texel.y;
        }
        Channel::Roughness => lanes.roughness[lane] *= texel.y,
        Channel::Metallic => lanes.metallic[lane] *= texel.z,
    }
}
