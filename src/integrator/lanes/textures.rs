//! Stage 4: the materials' textures read at the lanes' hits. The lanes are ordered by
//! material, so each texture binding is looked up for its material's range of lanes in one
//! batch (`Texture::sample_batch`), and the texels combined as `shading::surface_inputs`
//! combines them (glTF 2.0): the base colour's RGB into albedo, the metallic-roughness
//! texture's blue and green into metallic and roughness, the emission texture's RGB into
//! the emitted radiance, and the normal map's texel into the shading normal
//! (`shading::surface_inputs::perturb_normal`).

use std::ops::Range;

use glam::{Vec3, Vec4};

use super::{LaneArray, WaveLanes};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::binding_query;
use crate::render::surface_textures::sample_binding_batch;
use crate::scene::{Material, TextureBinding};
use crate::shading::surface_inputs::{perturb_normal, SurfaceInputs};

/// Albedo, metallic, roughness and the emission of emission-textured emitters of every
/// lane, and the shading normals bent by normal maps (the lanes ordered by material).
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn shading_inputs(
    context: &RenderContext,
    lanes: &mut WaveLanes,
    worker: &mut WorkerState,
) {
    let len = lanes.len();
    lanes.albedo.resize(len);
    lanes.metallic.resize_lanes(len, 0.0);
    lanes.roughness.resize_lanes(len, 0.0);
    lanes.emission.resize(len);
    if lanes.keeps_base_color_lookups {
        super::refill(&mut lanes.base_color_lookups, len, None);
    }
    for run in 0..lanes.material_runs.len() {
        let (material, range) = lanes.material_run(run);
        let material = &context.scene.materials[material as usize];
        fill_factors(lanes, material, range.clone());
        for read in texture_reads(material) {
            look_up(context, lanes, (material, read), range.clone(), worker);
        }
    }
}

/// The material's factors over its range of lanes, before the texels multiply them.
fn fill_factors(lanes: &mut WaveLanes, material: &Material, range: Range<usize>) {
    let model = material.model.metallic_roughness();
    let base = material.base_color;
    lanes.albedo.x[range.clone()].fill(base.x);
    lanes.albedo.y[range.clone()].fill(base.y);
    lanes.albedo.z[range.clone()].fill(base.z);
    lanes.metallic[range.clone()].fill(model.map_or(0.0, |model| model.metallic));
    lanes.roughness[range].fill(model.map_or(0.0, |model| model.roughness));
}

/// One texture binding of `material` looked up in one batch at the lanes `range` that read
/// it, and its texels applied to them.
fn look_up(
    context: &RenderContext,
    lanes: &mut WaveLanes,
    (material, (binding, channel)): (&Material, (&TextureBinding, Channel)),
    range: Range<usize>,
    worker: &mut WorkerState,
) {
    let mut at = std::mem::take(&mut lanes.texture_lanes);
    let mut queries = std::mem::take(&mut lanes.texture_queries);
    let mut texels = std::mem::take(&mut lanes.texels);
    at.clear();
    // A normal map is read only where the hit has a tangent frame, as the scalar path
    // reads it (the lookup counts, and marks the texture's tiles).
    at.extend(
        range
            .filter(|&lane| channel != Channel::Normal || has_tangent_frame(lanes, lane))
            .map(|lane| lane as u32),
    );
    queries.clear();
    queries.extend(at.iter().map(|&lane| {
        let lane = lane as usize;
        binding_query(
            &binding.transform,
            lanes.st.get(lane),
            lanes.gradients[lane],
        )
    }));
    texels.clear();
    texels.resize_lanes(queries.len(), Vec4::ZERO);
    sample_binding_batch(context, binding, &queries, worker, &mut texels);
    for (&lane, &texel) in at.iter().zip(&texels) {
        apply_texel(lanes, lane as usize, channel, material, texel);
    }
    if channel == Channel::BaseColor && lanes.keeps_base_color_lookups {
        for ((&lane, &query), &texel) in at.iter().zip(&queries).zip(&texels) {
            lanes.base_color_lookups[lane as usize] = Some((query, texel));
        }
    }
    lanes.texture_lanes = at;
    lanes.texture_queries = queries;
    lanes.texels = texels;
}

/// Whether lane `lane` has the dP/ds and dP/dt a normal map's tangent frame is made of
/// (`shading::surface_inputs`' test).
#[inline]
fn has_tangent_frame(lanes: &WaveLanes, lane: usize) -> bool {
    lanes.dpds.get(lane) != Vec3::ZERO && lanes.dpdt.get(lane) != Vec3::ZERO
}

/// What a texel gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Channel {
    /// The base colour (RGB).
    BaseColor,
    /// Roughness (green) and metallic (blue).
    MetallicRoughness,
    Roughness,
    Metallic,
    /// The emitted radiance (RGB).
    Emission,
    /// The tangent-space normal (RGB).
    Normal,
}

/// The textures shading `material` reads, in the order `shading::surface_inputs` reads them
/// (alpha is resolved while tracing; a black emission factor reads no emission texture).
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
        (
            material
                .emission_texture
                .as_ref()
                .filter(|_| reads_emission_texture(material)),
            Channel::Emission,
        ),
        (material.normal_texture.as_ref(), Channel::Normal),
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
        // Never negative, as `shading::surface_inputs` clamps it.
        Channel::Emission => lanes
            .emission
            .set(lane, (material.emission * texel.truncate()).max(Vec3::ZERO)),
        Channel::Normal => {
            let bent = perturb_normal(
                lanes.shading_normal.get(lane),
                lanes.dpds.get(lane),
                lanes.dpdt.get(lane),
                texel.truncate(),
                material.normal_scale,
            );
            lanes.shading_normal.set(lane, bent);
        }
    }
}

/// Whether `material`'s emission is read from its emission texture: it has one, and an
/// emission factor that is not black.
#[inline]
fn reads_emission_texture(material: &Material) -> bool {
    material.emission_texture.is_some() && material.emission != Vec3::ZERO
}

/// The radiance `material` emits at lane `lane`, as `shading::surface_inputs` gives it:
/// stage 4's texel-scaled emission for an emission-textured emitter, else the material's.
#[inline]
pub(crate) fn lane_emission(lanes: &WaveLanes, material: &Material, lane: usize) -> Vec3 {
    if reads_emission_texture(material) {
        lanes.emission.get(lane)
    } else {
        material.emission
    }
}

/// The material's shading inputs at lane `lane`, as `shading::surface_inputs` gives them
/// (the shading normal bent by the material's normal map, if any, in stage 4).
#[inline]
pub(crate) fn lane_inputs(material: &Material, lanes: &WaveLanes, lane: usize) -> SurfaceInputs {
    let model = material.model.metallic_roughness();
    SurfaceInputs {
        albedo: lanes.albedo.get(lane),
        alpha: material.alpha,
        // Zero for the classic model (`shading_inputs`).
        metallic: lanes.metallic[lane],
        roughness: model.map(|_| lanes.roughness[lane]),
        emission: lane_emission(lanes, material, lane),
        shading_normal: lanes.shading_normal.get(lane),
    }
}
