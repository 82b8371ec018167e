//! Stage 6: the opaque lobe at every lane, evaluated towards every light, lanes grouped by
//! material so that each group runs one lobe's code (Lambert plus Blinn-Phong for classic
//! materials, glTF metallic-roughness otherwise), as `shading::MaterialBsdf`'s opaque lobe
//! and Whitted's `queue_shadow_rays` compute it.

use glam::Vec3;

use super::{refill, WaveLanes};
use crate::scene::{Material, MaterialModel};
use crate::shading::{Bsdf, MetallicRoughnessBsdf, OpaqueBsdf};

/// The normals on the viewer's side (`incident_geometric`, `incident_shading`): the
/// geometric normal's side decides, as for `shading::MaterialBsdf`.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn incident_normals(lanes: &mut WaveLanes) {
    let len = lanes.len();
    refill(&mut lanes.incident_geometric, len, Vec3::ZERO);
    refill(&mut lanes.incident_shading, len, Vec3::ZERO);
    for lane in 0..len {
        let (g, s) = (lanes.geometric_normal[lane], lanes.shading_normal[lane]);
        let front = lanes.direction[lane].dot(g) < 0.0;
        lanes.incident_geometric[lane] = if front { g } else { -g };
        lanes.incident_shading[lane] = if front { s } else { -s };
    }
}

/// What each light delivers through each lane's opaque lobe if nothing blocks it,
/// `throughput * weight * f(wo, wi) * cos * irradiance`, into `contribution`, and whether it
/// is positive into `lit` (light-major, as `sample_lights` wrote the samples).
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn eval_lights(lanes: &mut WaveLanes, materials: &[Material], lights: usize) {
    let len = lanes.len();
    refill(&mut lanes.contribution, len * lights, Vec3::ZERO);
    refill(&mut lanes.lit, len * lights, false);
    for run in 0..lanes.material_runs.len() {
        let (material_index, range) = lanes.material_run(run);
        let material = &materials[material_index as usize];
        let weight = lanes.materials[material_index as usize].opaque_weight;
        match &material.model {
            MaterialModel::Classic(classic) => {
                for index in range {
                    let lane = lanes.by_material[index] as usize;
                    let lobe = OpaqueBsdf {
                        n: lanes.incident_shading[lane],
                        albedo: lanes.albedo[lane],
                        specular: classic.specular,
                        shininess: classic.shininess,
                    };
                    eval_lane(lanes, lane, &lobe, weight, lights);
                }
            }
            MaterialModel::MetallicRoughness(_) => {
                for index in range {
                    let lane = lanes.by_material[index] as usize;
                    let lobe = MetallicRoughnessBsdf::new(
                        lanes.incident_shading[lane],
                        lanes.albedo[lane],
                        lanes.roughness[lane],
                        lanes.metallic[lane],
                    );
                    eval_lane(lanes, lane, &lobe, weight, lights);
                }
            }
        }
    }
}

/// One lane's contributions from every light through `lobe` (of weight `weight`).
#[inline]
fn eval_lane(lanes: &mut WaveLanes, lane: usize, lobe: &impl Bsdf, weight: f32, lights: usize) {
    let len = lanes.len();
    let ng = lanes.incident_geometric[lane];
    let ns = lanes.incident_shading[lane];
    let wo = -lanes.direction[lane];
    let throughput = lanes.throughput[lane];
    for light in 0..lights {
        let at = light * len + lane;
        let wi = lanes.light_direction[at];
        if wi.dot(ng) <= 0.0 || wi.dot(ns) <= 0.0 {
            continue;
        }
        let f = lobe.eval(wo, wi) * ns.dot(wi);
        let contribution = throughput * weight * f * lanes.light_scale[at];
        lanes.contribution[at] = contribution;
        lanes.lit[at] = contribution.max_element() > 0.0;
    }
}
