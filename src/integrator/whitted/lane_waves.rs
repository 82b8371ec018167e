//! Whitted's waves shaded in lanes (`integrator::lanes`): which hits take the lanes, the
//! stages run over them, and what each lane adds to the film and the shadow queue.
//!
//! A hit takes the lanes, whatever surface it lies on (triangles, analytic spheres, curved
//! and height patches), when its material is one the lanes cover (`lanes::LaneMaterial::of`:
//! opaque and not emissive, normal-mapped or not), and the light beyond the shadow rays is
//! Whitted's ambient term. These take the scalar path (`surface::shade_hit`), hit by hit:
//! mirrors, dielectrics and emitters; rays inside an absorbing medium; every hit when the
//! indirect light is voxel cone tracing's. Ray differentials are transferred to their hits
//! in the lanes (`lanes::differentials`); misses are looked up together (`lanes::misses`),
//! and fogged on their way out as their light is added. A render that writes the texture-lookup AOVs (`tex`, `texcolor`,
//! `lod`, `footprint`) records each pixel's first lookup from the lanes' base-colour
//! lookups, in the wave's order. Fog on the way to a hit is the wave's
//! (`fog::fog_wave_segments`), before either path shades it.

use glam::Vec3;

use super::surface::{AmbientEnvironment, IndirectLight};
use super::{add_radiance, Waves};
use crate::film::TileImage;
use crate::footprint::Footprint;
use crate::integrator::lanes::bsdf::{eval_lights, incident_normals};
use crate::integrator::lanes::differentials::differentials_at_hits;
use crate::integrator::lanes::footprints::{lane_footprint, texture_gradients, LaneFootprint};
use crate::integrator::lanes::gather::{gather_spheres, gather_triangles};
use crate::integrator::lanes::interpolate::interpolate;
use crate::integrator::lanes::lights::{sample_lights, shadow_rays};
use crate::integrator::lanes::patches::evaluate_patches;
use crate::integrator::lanes::picks::{LaneHit, LaneSurface};
use crate::integrator::lanes::textures::shading_inputs;
use crate::integrator::texturing::{record_first_lookup, records_first_lookup};
use crate::integrator::trace_wave::ShadowRay;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::shading;

/// `Waves::lane_of_ray` for a ray shaded by the scalar path.
pub(super) const SCALAR: u32 = u32::MAX;

/// Pick the wave's rays the lanes shade into `waves.lanes`, and each ray's lane (or
/// [`SCALAR`]) into `waves.lane_of_ray`. Counts the lanes' footprint updates.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(super) fn pick_lanes(
    context: &RenderContext,
    waves: &mut Waves,
    image: &TileImage,
    worker: &mut WorkerState,
    indirect: &dyn IndirectLight,
) {
    let rays = waves.buffers.rays.current.len();
    waves.lane_of_ray.clear();
    waves.lane_of_ray.resize(rays, SCALAR);
    waves.lanes.clear();
    waves.picks.clear();
    let effects = &context.effects;
    if waves.scalar_only || !indirect.is_ambient_environment() {
        return;
    }
    waves.lanes.prepare(context);
    waves.lanes.keeps_base_color_lookups = !image.lookup_done.is_empty();
    for index in 0..rays {
        let ray = &waves.buffers.rays.current[index];
        let hit = &waves.buffers.trace_hits[index];
        if !hit.is_hit() || (effects.absorption && ray.sigma != Vec3::ZERO) {
            continue;
        }
        let (surface, material) = LaneSurface::at(&context.surfaces, hit);
        let lane_material = waves.lanes.materials[material];
        if !lane_material.covers {
            continue;
        }
        let footprint = if effects.footprints && lane_material.textured {
            lane_footprint(&ray.footprint, hit.t)
        } else {
            LaneFootprint::Point
        };
        waves.picks.push(index, material, surface, footprint);
    }
    let uv_aov = context.options.aovs.surface;
    let (rays, hits) = (&waves.buffers.rays.current, &waves.buffers.trace_hits);
    waves.picks.place(
        &mut waves.lanes,
        &mut waves.lane_of_ray,
        |index, material| {
            let (ray, hit) = (&rays[index], &hits[index]);
            let camera_first = ray.kind == RayKind::Camera && ray.first_sample;
            let wants_st = material.textured || (camera_first && uv_aov);
            LaneHit::new(hit, (ray.origin, ray.direction), ray.throughput, wants_st)
        },
    );
    worker.counters.lane_hits += waves.lanes.len() as u64;
    if effects.footprints {
        worker.counters.footprint_updates += waves.picks.len() as u64;
    }
}

/// Stages 1-6 over the picked lanes.
pub(super) fn shade_lanes(context: &RenderContext, waves: &mut Waves, worker: &mut WorkerState) {
    let lanes = &mut waves.lanes;
    if lanes.len() == 0 {
        return;
    }
    let scene = &context.scene;
    let surfaces = &context.surfaces.scene;
    gather_triangles(lanes, &surfaces.meshes);
    gather_spheres(lanes, &surfaces.spheres);
    interpolate(lanes);
    evaluate_patches(lanes, &surfaces.patches, &surfaces.height_patches);
    differentials_at_hits(lanes, &context.camera, context.options.spp);
    texture_gradients(lanes, context.options.filter.max_aniso);
    shading_inputs(context, lanes, worker);
    if context.effects.shadows {
        incident_normals(lanes);
        sample_lights(lanes, &scene.lights);
        eval_lights(lanes, &scene.materials, scene.lights.len());
        shadow_rays(lanes, &scene.lights);
    }
}

/// Stage 7 for the lane `lane` of the wave's ray `index`: its shadow rays join the queue and
/// its ambient light the film, as `surface::shade_hit` adds them.
pub(super) fn finish_lane(
    context: &RenderContext,
    waves: &mut Waves,
    index: usize,
    lane: usize,
    image: &mut TileImage,
) {
    let ray = &waves.buffers.rays.current[index];
    let lanes = &waves.lanes;
    let lights = &context.scene.lights;
    if context.effects.shadows {
        for (light_index, light) in lights.iter().enumerate() {
            let at = light_index * lanes.len() + lane;
            if !lanes.lit[at] {
                continue;
            }
            waves.shadows.push(ShadowRay {
                origin: lanes.shadow_origin.get(lane),
                direction: lanes.shadow_direction.get(at),
                tfar: lanes.shadow_tfar[at],
                light: shading::light_position(light),
                contribution: lanes.contribution.get(at),
                slot: ray.slot,
            });
        }
    }
    if ray.kind == RayKind::Camera && ray.first_sample {
        write_surface_aovs(context, waves, index, lane, image);
    }
    record_lane_lookup(context, waves, index, lane, image);
    let lanes = &waves.lanes;
    let ray = &waves.buffers.rays.current[index];
    let material = lanes.materials[lanes.material[lane] as usize];
    let ambient =
        AmbientEnvironment::radiance(context, material.opaque_weight, lanes.albedo.get(lane));
    add_radiance(image, ray.slot, ray.throughput * (Vec3::ZERO + ambient));
}

/// The pixel's first lookup, from the base-colour lookup of lane `lane` (of the wave's ray
/// `index`) if its ray records it (`texturing::records_first_lookup`), under the ray's
/// footprint moved to the hit, as `surface::shade_hit` records it.
fn record_lane_lookup(
    context: &RenderContext,
    waves: &Waves,
    index: usize,
    lane: usize,
    image: &mut TileImage,
) {
    let ray = &waves.buffers.rays.current[index];
    if !records_first_lookup(image, ray.first_sample, ray.slot) {
        return;
    }
    let lanes = &waves.lanes;
    let material = &context.scene.materials[lanes.material[lane] as usize];
    let (Some(binding), Some(lookup)) =
        (&material.base_color_texture, lanes.base_color_lookups[lane])
    else {
        return;
    };
    let footprint = if context.effects.footprints {
        // A lane of a textured material carries its footprint: a cone's moves along the
        // ray, a differential's is the lane's at the hit.
        ray.footprint
            .propagated(lanes.t[lane])
            .unwrap_or_else(|| Footprint::Differential(lanes.differential_at_hit[lane]))
    } else {
        ray.footprint
    };
    record_first_lookup(context, image, ray.slot, binding, lookup, &footprint);
}

/// The camera hit's depth, normal, uv and albedo AOVs of a pixel's first sample (whose slot
/// is its pixel), as `surface::shade_hit` writes them.
fn write_surface_aovs(
    context: &RenderContext,
    waves: &Waves,
    index: usize,
    lane: usize,
    image: &mut TileImage,
) {
    let ray = &waves.buffers.rays.current[index];
    let lanes = &waves.lanes;
    let pixel = ray.slot as usize;
    if !image.depth.is_empty() {
        image.depth[pixel] = lanes.t[lane] * ray.direction.dot(context.camera_forward);
        image.normal[pixel] = lanes.shading_normal.get(lane).to_array();
        image.uv[pixel] = lanes.st.get(lane).to_array();
    }
    if !image.albedo.is_empty() {
        image.albedo[pixel] = lanes.albedo.get(lane).to_array();
        if !image.normal.is_empty() {
            image.normal[pixel] = lanes.shading_normal.get(lane).to_array();
        }
    }
}
