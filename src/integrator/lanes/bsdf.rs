//! Stage 6: the opaque lobe at every lane, evaluated towards every light. The lanes are
//! ordered by material, so each material's lanes are one range and each range runs one
//! lobe's code (Lambert plus Blinn-Phong for classic materials, glTF metallic-roughness
//! otherwise), as `shading::MaterialBsdf`'s opaque lobe and Whitted's `queue_shadow_rays`
//! compute it.
//!
//! The loops read and write one array per coordinate and run at the level
//! `simd::dispatch` picks, with the scalar functions' operations in their order.

use std::ops::Range;

use glam::Vec3;

use super::soa::{Vec3Slices, Vec3SlicesMut};
use super::{LaneArray, WaveLanes};
use crate::scene::{Material, MaterialModel};
use crate::shading::{Bsdf, MetallicRoughnessBsdf, OpaqueBsdf};
use crate::simd;

/// The normals on the viewer's side (`incident_geometric`, `incident_shading`): the
/// geometric normal's side decides, as for `shading::MaterialBsdf`.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn incident_normals(lanes: &mut WaveLanes) {
    let len = lanes.len();
    lanes.incident_geometric.resize(len);
    lanes.incident_shading.resize(len);
    simd::run_at(
        lanes.level(),
        #[inline(always)]
        || {
            let geometric = lanes.geometric_normal.lanes(len);
            let shading = lanes.shading_normal.lanes(len);
            let direction = lanes.direction.lanes(len);
            let mut incident_geometric = lanes.incident_geometric.lanes_mut(len);
            let mut incident_shading = lanes.incident_shading.lanes_mut(len);
            for lane in 0..len {
                let (g, s) = (geometric.get(lane), shading.get(lane));
                let front = direction.get(lane).dot(g) < 0.0;
                incident_geometric.set(lane, if front { g } else { -g });
                incident_shading.set(lane, if front { s } else { -s });
            }
        },
    );
}

/// What each light delivers through each lane's opaque lobe if nothing blocks it,
/// `throughput * weight * f(wo, wi) * cos * irradiance`, into `contribution`, and whether it
/// is positive into `lit` (light-major, as `sample_lights` wrote the samples). The lanes of
/// a material without an opaque lobe are unlit, their contribution left as it was.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn eval_lights(lanes: &mut WaveLanes, materials: &[Material], lights: usize) {
    let len = lanes.len();
    lanes.contribution.resize(len * lights);
    lanes.lit.resize_lanes(len * lights, false);
    simd::run_at(
        lanes.level(),
        #[inline(always)]
        || {
            for run in 0..lanes.material_runs.len() {
                let (material, range) = lanes.material_run(run);
                let weight = lanes.materials[material as usize].opaque_weight;
                for light in 0..lights {
                    if weight > 0.0 {
                        let model = &materials[material as usize].model;
                        eval_run(lanes, model, range.clone(), weight, light);
                    } else {
                        // No opaque lobe: no light reflected, nothing sampled to evaluate.
                        let in_light = light * len + range.start..light * len + range.end;
                        lanes.lit[in_light].fill(false);
                    }
                }
            }
        },
    );
}

/// The lanes `range` (of one material, `model`, of opaque weight `weight`) towards light
/// `light`: one loop per lobe. A classic material without a highlight runs the Lambert
/// lobe alone (the highlight's exponentiation keeps the other lobes' loops scalar).
#[inline(always)]
fn eval_run(
    lanes: &mut WaveLanes,
    model: &MaterialModel,
    range: Range<usize>,
    weight: f32,
    light: usize,
) {
    let len = lanes.len();
    let shading = lanes.incident_shading.range(range.clone());
    let albedo = lanes.albedo.range(range.clone());
    let metallic = &lanes.metallic[range.clone()];
    let roughness = &lanes.roughness[range.clone()];
    let first = light * len;
    let in_light = first + range.start..first + range.end;
    let inputs = RunInputs {
        geometric: lanes.incident_geometric.range(range.clone()),
        shading,
        direction: lanes.direction.range(range.clone()),
        throughput: lanes.throughput.range(range.clone()),
        light_direction: lanes.light_direction.range(in_light.clone()),
        light_scale: lanes.light_scale.range(in_light.clone()),
        weight,
    };
    let outputs = RunOutputs {
        contribution: Vec3SlicesMut {
            x: &mut lanes.contribution.x[in_light.clone()],
            y: &mut lanes.contribution.y[in_light.clone()],
            z: &mut lanes.contribution.z[in_light.clone()],
        },
        lit: &mut lanes.lit[in_light],
    };
    match model {
        MaterialModel::Classic(classic) if classic.specular > 0.0 => inputs.eval(
            outputs,
            #[inline(always)]
            |lane| OpaqueBsdf {
                n: shading.get(lane),
                albedo: albedo.get(lane),
                specular: classic.specular,
                shininess: classic.shininess,
            },
        ),
        // `OpaqueBsdf::eval` adds the highlight only for a positive `specular`: the same
        // lobe with a constant 0 compiles to Lambert alone.
        MaterialModel::Classic(classic) => inputs.eval(
            outputs,
            #[inline(always)]
            |lane| OpaqueBsdf {
                n: shading.get(lane),
                albedo: albedo.get(lane),
                specular: 0.0,
                shininess: classic.shininess,
            },
        ),
        MaterialModel::MetallicRoughness(_) => inputs.eval(
            outputs,
            #[inline(always)]
            |lane| {
                let (n, base) = (shading.get(lane), albedo.get(lane));
                MetallicRoughnessBsdf::new(n, base, roughness[lane], metallic[lane])
            },
        ),
    }
}

/// What stage 6 reads for one light and one material's lanes, every slice one entry per
/// lane.
struct RunInputs<'a> {
    geometric: Vec3Slices<'a>,
    shading: Vec3Slices<'a>,
    direction: Vec3Slices<'a>,
    throughput: Vec3Slices<'a>,
    light_direction: Vec3Slices<'a>,
    light_scale: Vec3Slices<'a>,
    weight: f32,
}

/// What stage 6 writes for one light and one material's lanes.
struct RunOutputs<'a> {
    contribution: Vec3SlicesMut<'a>,
    lit: &'a mut [bool],
}

impl RunInputs<'_> {
    /// Every lane through the lobe `lobe(lane)` gives: zero and unlit where the light is
    /// below either normal.
    #[inline(always)]
    fn eval<B: Bsdf>(&self, mut out: RunOutputs, lobe: impl Fn(usize) -> B) {
        for lane in 0..out.lit.len() {
            let ng = self.geometric.get(lane);
            let ns = self.shading.get(lane);
            let wo = -self.direction.get(lane);
            let wi = self.light_direction.get(lane);
            // Written as the scalar path's test, so a NaN cosine counts as above.
            let above = !(wi.dot(ng) <= 0.0 || wi.dot(ns) <= 0.0);
            let f = lobe(lane).eval(wo, wi) * ns.dot(wi);
            let contribution =
                self.throughput.get(lane) * self.weight * f * self.light_scale.get(lane);
            let contribution = if above { contribution } else { Vec3::ZERO };
            out.contribution.set(lane, contribution);
            out.lit[lane] = above && contribution.max_element() > 0.0;
        }
    }
}
