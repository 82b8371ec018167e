//! Whitted's waves shaded in lanes (`integrator::lanes`): which hits take the lanes, the
//! stages run over them, and what each lane adds to the film, the shadow queue and the next
//! wave.
//!
//! A hit takes the lanes, whatever surface it lies on (triangles, analytic spheres, curved
//! and height patches) and whatever its material (emitters, mirrors and dielectric
//! boundaries included, and inside an absorbing medium: Beer's law on the lane's throughput
//! before stage 6 reads it), when the light beyond the shadow rays is Whitted's ambient
//! term; with voxel cone tracing's indirect light every hit takes the scalar path
//! (`surface::shade_hit`). Ray differentials are transferred to their hits in the lanes
//! (`lanes::differentials`); misses are looked up together (`lanes::misses`), and fogged on
//! their way out as their light is added. A render that writes the texture-lookup AOVs
//! (`tex`, `texcolor`, `lod`, `footprint`) records each pixel's first lookup from the
//! lanes' base-colour lookups, in the wave's order. Fog on the way to a hit is the wave's
//! (`fog::fog_wave_segments`), before either path shades it.
//!
//! A lane's mirror and boundary rays are spawned in [`finish_lane`] with the scalar path's
//! functions (`spawn`, `dielectric`), from the lanes' spawn point and shading inputs; the
//! hit record their footprints read (a cone's curvature, a differential's normal
//! derivatives) is made only when one asks (`spawn::HitSurface`).

use glam::Vec3;

use std::cell::OnceCell;

use super::dielectric::scatter_dielectric;
use super::spawn::{HitSurface, Spawner};
use super::surface::{AmbientEnvironment, IndirectLight};
use super::{add_radiance, PathRay, Waves};
use crate::film::TileImage;
use crate::footprint::{sphere_curvature, triangle_curvature, Footprint};
use crate::hit::SurfaceHit;
use crate::integrator::lanes::bsdf::{eval_lights, incident_normals};
use crate::integrator::lanes::differentials::differentials_at_hits;
use crate::integrator::lanes::footprints::{lane_footprint, texture_gradients, LaneFootprint};
use crate::integrator::lanes::gather::{gather_spheres, gather_triangles};
use crate::integrator::lanes::interpolate::interpolate;
use crate::integrator::lanes::lights::{sample_lights, shadow_rays};
use crate::integrator::lanes::patches::evaluate_patches;
use crate::integrator::lanes::picks::{LaneHit, LaneSurface};
use crate::integrator::lanes::textures::{lane_emission, lane_inputs, shading_inputs};
use crate::integrator::lanes::{LaneArray, LaneSections, WaveLanes};
use crate::integrator::texturing::{record_first_lookup, records_first_lookup};
use crate::integrator::trace_wave::ShadowRay;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::shading::{self, MaterialBsdf, SpawnPoint};

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
    waves.lane_of_ray.resize_lanes(rays, SCALAR);
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
        if !hit.is_hit() {
            continue;
        }
        let (surface, material) = LaneSurface::at(&context.surfaces, hit);
        let lane_material = waves.lanes.materials[material];
        if absorbs(context, ray) {
            worker.counters.absorption_evaluations += 1;
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
            let throughput = throughput_at_hit(context, ray, hit.t);
            LaneHit::new(hit, (ray.origin, ray.direction), throughput, wants_st)
        },
    );
    worker.counters.lane_hits += waves.lanes.len() as u64;
    if effects.footprints {
        worker.counters.footprint_updates += waves.picks.len() as u64;
    }
}

/// Whether `ray` travels inside a medium that absorbs (`surface::shade_hit`'s test).
#[inline]
fn absorbs(context: &RenderContext, ray: &PathRay) -> bool {
    context.effects.absorption && ray.sigma != Vec3::ZERO
}

/// The throughput `ray` brings to its hit at distance `t`: Beer's law over the distance
/// travelled inside its medium, as `surface::shade_hit` applies it before shading.
#[inline]
fn throughput_at_hit(context: &RenderContext, ray: &PathRay, t: f32) -> Vec3 {
    if absorbs(context, ray) {
        ray.throughput * shading::transmittance(ray.sigma, t)
    } else {
        ray.throughput
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

/// Stage 7 for the lane `lane` of the wave's ray `index`, in `surface::shade_hit`'s order:
/// its shadow rays join the queue, its emission and ambient light the film, and its mirror
/// and boundary rays the next wave.
pub(super) fn finish_lane(
    context: &RenderContext,
    waves: &mut Waves,
    (index, lane): (usize, usize),
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let ray = &waves.buffers.rays.current[index];
    let lanes = &waves.lanes;
    let material = lanes.materials[lanes.material[lane] as usize];
    // `MaterialBsdf::whitted_lobes` keeps an opaque lobe of positive weight only.
    let opaque = material.opaque_weight > 0.0;
    let lights = &context.scene.lights;
    if context.effects.shadows && opaque {
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
    add_lane_radiance(context, waves, (index, lane), image);
    if material.spawns && ray_continues(context, &waves.buffers.rays.current[index]) {
        spawn_lane_rays(context, waves, (index, lane), worker);
    }
}

/// Whether a ray's hit may spawn rays: the maximum depth is not reached.
#[inline]
fn ray_continues(context: &RenderContext, ray: &PathRay) -> bool {
    ray.depth < context.options.max_depth
}

/// What lane `lane` (of the wave's ray `index`) adds to its pixel: the emission leaving
/// towards the ray, plus the ambient light on its opaque lobe, times the throughput at the
/// hit, summed as `surface::shade_hit` sums them.
fn add_lane_radiance(
    context: &RenderContext,
    waves: &Waves,
    (index, lane): (usize, usize),
    image: &mut TileImage,
) {
    let ray = &waves.buffers.rays.current[index];
    let lanes = &waves.lanes;
    let material_index = lanes.material[lane] as usize;
    let lane_material = lanes.materials[material_index];
    let mut radiance = Vec3::ZERO;
    if lane_material.emits {
        let material = &context.scene.materials[material_index];
        let normal = lanes.geometric_normal.get(lane);
        if shading::area_lights::emits_towards(material, normal, ray.direction) {
            radiance = lane_emission(lanes, material, lane);
        }
    }
    let weight = lane_material.opaque_weight;
    if weight > 0.0 {
        radiance += AmbientEnvironment::radiance(context, weight, lanes.albedo.get(lane));
    }
    add_radiance(image, ray.slot, lanes.throughput.get(lane) * radiance);
}

/// The mirror reflection and the dielectric boundary's rays of lane `lane` (of the wave's
/// ray `index`), queued for the next wave as `surface::shade_hit` queues them: the
/// material's BSDF built from the lanes' inputs, the rays leaving the lanes' spawn point
/// with the ray's footprint moved to the hit.
fn spawn_lane_rays(
    context: &RenderContext,
    waves: &mut Waves,
    (index, lane): (usize, usize),
    worker: &mut WorkerState,
) {
    let effects = &context.effects;
    let lanes = &waves.lanes;
    let material_index = lanes.material[lane];
    let material = &context.scene.materials[material_index as usize];
    let traced = waves.buffers.rays.current[index];
    let hit = waves.buffers.trace_hits[index];
    // Only cones read the curvature (`Footprint::reflect_with`): no other footprint pays
    // for it.
    let cone = matches!(traced.footprint, Footprint::Cone1(_) | Footprint::Cone(_));
    let record = OnceCell::new();
    let surface = HitSurface::Deferred {
        hit: &hit,
        ray: &traced,
        curvature: (effects.footprints && cone)
            .then(|| lane_curvature(lanes, lane))
            .flatten(),
        geometric_normal: lanes.geometric_normal.get(lane),
        record: &record,
    };
    let mut ray = traced;
    ray.throughput = lanes.throughput.get(lane);
    ray.footprint = footprint_at_hit(context, &traced, (lanes, lane), || surface.record(context));
    let inputs = lane_inputs(material, lanes, lane);
    let fresnel = effects.fresnel.then_some(context.options.fresnel);
    let outward = lanes.geometric_normal.get(lane);
    let bsdf =
        MaterialBsdf::from_surface_inputs(material, &inputs, ray.direction, outward, fresnel);
    let spawner = Spawner {
        parent: &ray,
        spawn: SpawnPoint {
            position: lanes.position.get(lane),
            error: lanes.error.get(lane),
        },
        min_throughput: context.options.min_throughput,
    };
    let lobes = bsdf.whitted_lobes();
    let ng = bsdf.mirror.ng;
    if let Some(mirror) = lobes.mirror.filter(|_| effects.mirror_reflection) {
        let reflected = mirror.lobe.direction(-ray.direction);
        let weight = mirror.weight;
        spawner.spawn_reflection(context, &surface, reflected, ng, weight, waves, worker);
    }
    if let Some(boundary) = lobes.boundary.filter(|_| effects.refraction) {
        let surface = (&surface, material_index);
        scatter_dielectric(context, &ray, surface, boundary, &spawner, waves, worker);
    }
}

/// The curvature of lane `lane`'s surface from its stage-1 arrays, as
/// `footprint::curvature_at` computes it before signing it for the arriving side: a
/// triangle's from its vertex normals (zero where the mesh has none, which
/// `triangle_curvature` takes as flat, as `curvature_at` takes a missing normal), a
/// sphere's from its radius. A patch's comes from its hit record (`None`).
fn lane_curvature(lanes: &WaveLanes, lane: usize) -> Option<f32> {
    let LaneSections {
        triangles, spheres, ..
    } = lanes.sections();
    if triangles.contains(&lane) {
        let p = [
            lanes.p[0].get(lane),
            lanes.p[1].get(lane),
            lanes.p[2].get(lane),
        ];
        let n = [
            lanes.n[0].get(lane),
            lanes.n[1].get(lane),
            lanes.n[2].get(lane),
        ];
        Some(triangle_curvature(p, n))
    } else if spheres.contains(&lane) {
        Some(sphere_curvature(lanes.radius[lane]))
    } else {
        None
    }
}

/// The footprint of `ray` moved to its hit at lane `lane` (`Footprint::transfer`): a
/// cone-like footprint by its distance alone; a differential as the lanes transferred it
/// (`lanes::differentials`, for the lanes that carry one), else onto the hit `record`.
fn footprint_at_hit<'a>(
    context: &RenderContext,
    ray: &PathRay,
    (lanes, lane): (&WaveLanes, usize),
    record: impl FnOnce() -> &'a SurfaceHit,
) -> Footprint {
    if !context.effects.footprints {
        return ray.footprint;
    }
    if let Some(at_hit) = ray.footprint.propagated(lanes.t[lane]) {
        return at_hit;
    }
    if lanes.differential.get(lane).is_some_and(Option::is_some) {
        return Footprint::Differential(lanes.differential_at_hit[lane]);
    }
    let mut footprint = ray.footprint;
    footprint.transfer(ray.direction, record());
    footprint
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
    // A lane of a textured material carries its differential: the record is not made.
    let record = OnceCell::new();
    let surface = HitSurface::Deferred {
        hit: &waves.buffers.trace_hits[index],
        ray,
        curvature: None,
        geometric_normal: lanes.geometric_normal.get(lane),
        record: &record,
    };
    let footprint = footprint_at_hit(context, ray, (lanes, lane), || surface.record(context));
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
