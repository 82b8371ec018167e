//! The path tracer's hits reconstructed and textured in lanes (`integrator::lanes`, stages
//! 1-4), wave by wave, their lights and BSDFs then handled in lanes (`lane_scatter`), and
//! each lane's vertex finished in wave order by queueing the rays those stages set up,
//! without a `SurfaceHit` record or a per-ray texture lookup.
//!
//! A hit takes the lanes whatever it lies on (triangles, analytic spheres, curved and height
//! patches) and whatever its material (mirrors, glass, emitters, normal maps and emission
//! textures included); a ray differential is moved to the hit in the lanes
//! (`lanes::differentials`). In a render that writes the texture-lookup AOVs (`tex`,
//! `texcolor`, `lod`, `footprint`), stage 4 keeps the lanes' base-colour lookups, and each
//! first sample's records its pixel's first lookup in the wave's order ([`finish_lane`]).
//! Misses are looked up together too (`lanes::misses`). A ray that fog stops before its
//! hit, or before it escapes, makes a medium vertex there instead (`medium`).
//!
//! What a lane adds is computed as `vertex::shade` computes it, operation for operation:
//! the stages give the bits of `SurfaceLookup::surface_hit` and `shading::surface_inputs`,
//! `lane_scatter` runs the same steps (absorption, the footprint at the hit, light
//! sampling, the BSDF's continuation), and [`finish_lane`] adds the emission the ray sees
//! (`vertex::add_seen_emission`) and queues the rays in the wave's order, so images are bit
//! for bit those of the scalar path.

use crate::film::TileImage;
use crate::integrator::lanes::differentials::{differentials_at_hits, LaneDifferential};
use crate::integrator::lanes::footprints::{lane_footprint, texture_gradients, LaneFootprint};
use crate::integrator::lanes::gather::{gather_spheres, gather_triangles};
use crate::integrator::lanes::interpolate::interpolate;
use crate::integrator::lanes::patches::evaluate_patches;
use crate::integrator::lanes::picks::{LaneHit, LanePicks, LaneSurface};
use crate::integrator::lanes::textures::{lane_emission, lane_inputs, shading_inputs};
use crate::integrator::lanes::{LaneArray, WaveLanes};
use crate::integrator::texturing::{record_first_lookup, records_first_lookup};
use crate::integrator::wave_integrator::{write_geometry_values, write_material_aovs};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::sampler::PixelSampler;
use crate::scene::Material;
use crate::shading::{self, LightHit, MaterialBsdf};
use crate::simd;

use super::lane_scatter::ScatterLanes;
use super::medium::Collision;
use super::vertex::{
    add_seen_emission, queue_continuation, FootprintSpread, HitRecord, SeenEmission, SurfaceSite,
    VertexSamples,
};
use super::{PathRay, PathTracer, PathWaves};

/// `PathLanes::lane_of_ray` for a ray shaded by the scalar path.
const SCALAR: u32 = u32::MAX;

/// The lanes of the wave being shaded, reused from wave to wave.
#[derive(Default)]
pub(crate) struct PathLanes {
    pub(super) lanes: WaveLanes,
    /// Per ray of the wave: its lane, or [`SCALAR`].
    lane_of_ray: Vec<u32>,
    /// The hits the lanes take, in the wave's order.
    picks: LanePicks,
    /// Per lane: the uniform numbers of its vertex, drawn for all lanes together.
    pub(super) vertex_samples: Vec<VertexSamples>,
    /// Stages 5 and 6: what they read of the paths and set up for the walk.
    pub(super) scatter: ScatterLanes,
}

impl PathLanes {
    /// The lane of the wave's ray `index`, if the lanes shade it.
    #[inline]
    pub(super) fn lane_of(&self, index: usize) -> Option<usize> {
        let lane = self.lane_of_ray[index];
        (lane != SCALAR).then_some(lane as usize)
    }
}

/// Pick the wave's rays the lanes shade (none unless `enabled`), order them by surface and
/// material, and run stages 1-4 over them: the triangles' vertex data and the spheres'
/// centres and radii, the point, normals and texture coordinates (the patches evaluated),
/// the footprints' texture gradients, and the texture lookups (albedo, metallic, roughness,
/// emission, normal maps).
pub(super) fn shade_lanes(
    context: &RenderContext,
    path: &mut PathLanes,
    (rays, hits, collisions): (&[PathRay], &[TraceHit], &[Option<Collision>]),
    image: &TileImage,
    worker: &mut WorkerState,
    enabled: bool,
) {
    path.lane_of_ray.clear();
    path.lane_of_ray.resize_lanes(rays.len(), SCALAR);
    path.lanes.clear();
    path.picks.clear();
    if !enabled {
        return;
    }
    pick_lanes(context, path, (rays, hits, collisions), image);
    let lanes = &mut path.lanes;
    if lanes.len() == 0 {
        return;
    }
    worker.counters.lane_hits += lanes.len() as u64;
    let scene = &context.surfaces.scene;
    gather_triangles(lanes, &scene.meshes);
    gather_spheres(lanes, &scene.spheres);
    interpolate(lanes);
    evaluate_patches(lanes, &scene.patches, &scene.height_patches);
    differentials_at_hits(lanes, &context.camera, context.options.spp);
    texture_gradients(lanes, context.options.filter.max_aniso);
    shading_inputs(context, lanes, worker);
    draw_vertex_samples(path, rays);
}

/// Lanes whose samplers are hashed side by side: one AVX-512 register of 32-bit lanes.
const DRAW_WIDTH: usize = 16;

/// Every lane's vertex numbers (light choice and point, BSDF lobe and direction, roulette),
/// [`DRAW_WIDTH`] lanes at a time at the lanes' vector level. The samplers are moved on as
/// each path arrives at its hit (`lane_scatter`); a path that ends before then leaves its
/// numbers unread.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
fn draw_vertex_samples(path: &mut PathLanes, rays: &[PathRay]) {
    let PathLanes {
        lanes,
        vertex_samples,
        ..
    } = path;
    vertex_samples.clear();
    simd::run_at(
        lanes.level(),
        #[inline(always)]
        || {
            for chunk in lanes.wave_index.chunks(DRAW_WIDTH) {
                // A short last chunk repeats its last lane; the copies are dropped.
                let samplers: [PixelSampler; DRAW_WIDTH] =
                    std::array::from_fn(|k| rays[chunk[k.min(chunk.len() - 1)] as usize].sampler);
                let drawn = VertexSamples::draw_lanes(&samplers);
                vertex_samples.extend_from_slice(&drawn[..chunk.len()]);
            }
        },
    );
}

/// The rays whose hits the lanes cover, each with its footprint's width at the hit, placed
/// in lanes ordered by material.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
fn pick_lanes(
    context: &RenderContext,
    path: &mut PathLanes,
    (rays, hits, collisions): (&[PathRay], &[TraceHit], &[Option<Collision>]),
    image: &TileImage,
) {
    let effects = &context.effects;
    path.lanes.prepare(context);
    path.lanes.keeps_base_color_lookups = !image.lookup_done.is_empty();
    let uv_aov = context.options.aovs.surface;
    for (index, (ray, hit)) in rays.iter().zip(hits).enumerate() {
        if !hit.is_hit() {
            continue;
        }
        if matches!(collisions.get(index), Some(Some(_))) {
            // Fog stopped the ray before its hit: a medium vertex (`medium`).
            continue;
        }
        let (surface, material) = LaneSurface::at(&context.surfaces, hit);
        let lane_material = path.lanes.materials[material];
        let footprint = if effects.footprints {
            lane_footprint(&ray.footprint, hit.t)
        } else {
            LaneFootprint::Point
        };
        let footprint = match footprint {
            // Every differential moves to its hit in the lanes, textured or not: the path
            // carries it on (`lane_scatter::arrive_at_hits`).
            LaneFootprint::Differential(_) if ray.approximate_footprint => {
                LaneFootprint::Differential(LaneDifferential::FromCamera)
            }
            LaneFootprint::Cone(_) if !lane_material.textured => LaneFootprint::Point,
            footprint => footprint,
        };
        path.picks.push(index, material, surface, footprint);
    }
    path.picks
        .place(&mut path.lanes, &mut path.lane_of_ray, |index, material| {
            let (ray, hit) = (&rays[index], &hits[index]);
            let camera_first = ray.kind == RayKind::Camera && ray.first_sample;
            let wants_st = material.textured || (camera_first && uv_aov);
            LaneHit::new(hit, (ray.origin, ray.direction), ray.throughput, wants_st)
        });
}

/// The vertex of the wave's ray `ray` (which hit `hit`) at its lane `lane`, in the steps
/// and order of `vertex::shade`, once stages 5 and 6 have run (`lane_scatter`): the camera
/// hit's AOVs, the emission the ray sees, then the shadow ray and the continuing ray those
/// stages set up, queued in the wave's order.
#[allow(clippy::too_many_arguments)]
pub(super) fn finish_lane(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    hit: &TraceHit,
    path: &PathLanes,
    lane: usize,
    image: &mut TileImage,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    let (lanes, scatter) = (&path.lanes, &path.scatter);
    let material_index = lanes.material[lane];
    let material = &context.scene.materials[material_index as usize];
    let camera_first = ray.kind == RayKind::Camera && ray.first_sample;
    if camera_first {
        let st = lanes.st.get(lane);
        let (t, normal) = (lanes.t[lane], lanes.shading_normal.get(lane));
        write_geometry_values(context, image, ray.slot, ray.direction, t, normal, st);
        write_material_aovs(image, ray.slot, &lane_inputs(material, lanes, lane));
    }
    if records_first_lookup(image, ray.first_sample, ray.slot) {
        let lookup = lanes.base_color_lookups[lane];
        if let (Some(binding), Some(lookup)) = (&material.base_color_texture, lookup) {
            // `lane_scatter::arrive_at_hits` moved the ray's footprint to the hit.
            record_first_lookup(context, image, ray.slot, binding, lookup, &ray.footprint);
        }
    }
    if shading::material_features::emits(material) {
        add_lane_emission(tracer, context, ray, (lanes, lane), material, image, worker);
    }
    if let Some(shadow) = &scatter.shadow[lane] {
        // Copied where it lies and then given its slot: built as a new value, the ray went
        // through the stack in pieces that the copy's wider loads straddled.
        waves.shadows.push(*shadow);
        if let Some(queued) = waves.shadows.last_mut() {
            queued.slot = ray.slot;
        }
    }
    let Some(next) = &scatter.next[lane] else {
        return;
    };
    let site = SurfaceSite {
        material: material_index,
        position: lanes.surface_point(lane),
        spawn: next.spawn,
        geometric_normal: if next.front { next.ng } else { -next.ng },
        record: HitRecord::Deferred {
            hit,
            origin: &ray.origin,
            camera_first,
        },
    };
    let spread = FootprintSpread {
        site: &site,
        sample: &next.sample,
        crosses: next.crosses,
        value: || next.value,
        // Only a delta reflection below the geometric surface asks: rare enough to build
        // the mixture again, as `vertex::SurfaceVertex` builds it.
        boundary_eta: || {
            let fresnel = context.effects.fresnel.then_some(context.options.fresnel);
            let inputs = lane_inputs(material, lanes, lane);
            let outward = lanes.geometric_normal.get(lane);
            let bsdf = MaterialBsdf::from_surface_inputs(
                material,
                &inputs,
                ray.direction,
                outward,
                fresnel,
            );
            bsdf.dielectric.split(ray.direction).boundary.eta
        },
    };
    let side = (next.ng, next.front);
    let u_roulette = path.vertex_samples[lane].roulette;
    queue_continuation(context, ray, spread, side, u_roulette, waves, worker);
}

/// The emission of `material` that the ray of lane `lane` sees (filtered by the ray's
/// footprint where an emission texture scales it), added as `vertex::shade` adds it.
fn add_lane_emission(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    (lanes, lane): (&WaveLanes, usize),
    material: &Material,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let area = &context.lights.area;
    let primitive = lanes.primitive[lane];
    let sections = lanes.sections();
    // Patches are not sampled as lights: their emission is seen, never aimed at.
    let light = if sections.triangles.contains(&lane) {
        area.mesh_light(lanes.mesh[lane] as usize, primitive)
    } else if sections.spheres.contains(&lane) {
        area.sphere_light(primitive as usize)
    } else {
        None
    };
    let normal = lanes.geometric_normal.get(lane);
    let seen = SeenEmission {
        light,
        light_hit: LightHit {
            direction: ray.direction,
            point: lanes.surface_point(lane),
            normal,
            st: lanes.st.get(lane),
        },
        emission: lane_emission(lanes, material, lane),
        facing: shading::area_lights::emits_towards(material, normal, ray.direction),
    };
    add_seen_emission(tracer, context, ray, &seen, image, worker);
}
