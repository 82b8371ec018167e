//! Direct-light injection: the radiance each fragment's surface sends out, stored in its
//! voxel (seed 003, illumination components 1 and 2 as the voxels hold them).
//!
//! A fragment's outgoing radiance is its emission plus the diffuse reflection of every
//! delta light (the scene's punctual lights, through `shading::light_interface`), `opaque * albedo / pi * sum_l E_l |n . w_l| V_l`, with the visibility
//! `V_l` from a shadow ray through Embree (the same rays, origins and far ends as
//! Whitted's). Voxels are isotropic, so a fragment is lit on whichever side faces each
//! light; the side that received the light orients the fragment's normal (used by the
//! extra bounce). Occluders block shadow rays whatever their transmission. A textured
//! material contributes its texture's mean colour (the pyramid's top level): a voxel is far
//! larger than a texel.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::voxelise::Fragment;
use crate::render::context::RenderContext;
use crate::render::stats::WorkCounters;
use crate::render::tracer::TraceRay;
use crate::shading::{self, OwnEmission};

/// Fragments lit per batch of shadow rays.
const BATCH: usize = 4096;

/// What a fragment contributes to its voxel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LitFragment {
    pub voxel: u32,
    /// Emitted radiance, the same in every direction.
    pub emission: Vec3,
    /// Reflected direct light, the same in every direction.
    pub radiance: Vec3,
    /// Opacity: the opaque share of the material, `1 - transmission`.
    pub opacity: f32,
    /// Diffuse reflectance `opaque * albedo` (what the extra bounce reflects).
    pub reflectance: Vec3,
    /// Unit normal on the side the light came from (towards the grid's centre when unlit).
    pub normal: Vec3,
}

/// A material's albedo as voxels see it: base colour times its texture's mean.
fn mean_albedo(context: &RenderContext, material: &crate::scene::Material) -> Vec3 {
    let Some(binding) = &material.base_color_texture else {
        return material.base_color;
    };
    let Some(texture) = context.textures.get(binding.texture) else {
        return material.base_color;
    };
    let Some(top) = texture.pyramid().levels.last() else {
        return material.base_color;
    };
    let t = top.texel(0, 0);
    material.base_color * Vec3::new(t[0], t[1], t[2])
}

/// Light every fragment, in parallel batches (one occlusion stream per batch). Returns the
/// lit fragments and the number of shadow rays traced.
pub fn light_fragments(
    context: &RenderContext,
    fragments: &[Fragment],
    grid_center: Vec3,
) -> (Vec<LitFragment>, u64) {
    let albedos: Vec<Vec3> = context
        .scene
        .materials
        .iter()
        .map(|m| mean_albedo(context, m))
        .collect();
    let batches: Vec<(Vec<LitFragment>, u64)> = fragments
        .par_chunks(BATCH)
        .map(|batch| light_batch(context, batch, &albedos, grid_center))
        .collect();
    let rays = batches.iter().map(|(_, r)| r).sum();
    (batches.into_iter().flat_map(|(f, _)| f).collect(), rays)
}

/// A shadow ray queued for one fragment.
struct Pending {
    fragment: usize,
    /// Irradiance delivered if unblocked, times the diffuse reflectance over pi.
    radiance: Vec3,
    /// +1 when the light is on the side of the fragment's normal, -1 otherwise.
    side: f32,
}

fn light_batch(
    context: &RenderContext,
    batch: &[Fragment],
    albedos: &[Vec3],
    grid_center: Vec3,
) -> (Vec<LitFragment>, u64) {
    let scene = &context.scene;
    let lights = &context.lights;
    let mut out = Vec::with_capacity(batch.len());
    let mut rays = Vec::new();
    let mut pending = Vec::new();
    for (index, fragment) in batch.iter().enumerate() {
        let material = &scene.materials[fragment.material as usize];
        let opaque = (1.0 - material.mirror) * (1.0 - material.transmission);
        let reflectance = opaque * albedos[fragment.material as usize];
        let n = fragment.normal;
        for light in lights.delta_lights() {
            // A delta light arrives from one direction, whatever the uniform numbers.
            let towards = |p: Vec3| lights.sample_li(light, p, Vec2::ZERO, &mut OwnEmission);
            let Some(seen) = towards(fragment.point.position) else {
                continue;
            };
            let side = if seen.wi.dot(n) >= 0.0 { 1.0 } else { -1.0 };
            let origin = fragment.point.offset_origin(n * side);
            let Some(sample) = towards(origin) else {
                continue;
            };
            let cos = (sample.wi.dot(n) * side).max(0.0);
            let radiance = shading::brdf::lambert(reflectance) * sample.radiance * cos;
            if radiance.max_element() <= 0.0 {
                continue;
            }
            let tfar = match sample.light_point {
                Some((position, _)) => {
                    shading::shadow_ray_end(sample.distance, position.as_vec3(), 0.0)
                }
                None => f32::INFINITY,
            };
            rays.push(TraceRay {
                origin,
                direction: sample.wi,
                tfar,
                cone_width: 0.0,
                cone_spread: 0.0,
            });
            pending.push(Pending {
                fragment: index,
                radiance,
                side,
            });
        }
        let toward_center = if (grid_center - fragment.point.position).dot(n) >= 0.0 {
            n
        } else {
            -n
        };
        out.push(LitFragment {
            voxel: fragment.voxel,
            emission: material.emission,
            radiance: Vec3::ZERO,
            opacity: (1.0 - material.transmission).clamp(0.0, 1.0),
            reflectance,
            normal: toward_center,
        });
    }
    let mut blocked = Vec::new();
    let mut counters = WorkCounters::default();
    context.tracer.occluded(&rays, &mut blocked, &mut counters);
    // Which side received more light orients the normal.
    let mut side_light = vec![0.0f32; batch.len()];
    for (p, blocked) in pending.iter().zip(&blocked) {
        if *blocked {
            continue;
        }
        out[p.fragment].radiance += p.radiance;
        side_light[p.fragment] += p.side * p.radiance.max_element();
    }
    for ((lit, fragment), s) in out.iter_mut().zip(batch).zip(side_light) {
        if s != 0.0 {
            lit.normal = fragment.normal * s.signum();
        }
    }
    (out, rays.len() as u64)
}
