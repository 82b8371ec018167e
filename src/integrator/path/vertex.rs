//! One vertex of a path: what a ray finds where it ends (a surface or the environment), the
//! light it adds there (emission, weighted against light sampling; light sampling itself),
//! and the ray the BSDF continues the path with, or why the path ends.
//!
//! [`shade`] reads as the steps of a vertex, in the order they run: fog on the way in, the
//! environment for a miss; at a surface its AOVs, absorption, the footprint there, the
//! material's inputs, emission; then the vertex's uniform numbers, next-event estimation and
//! the BSDF-sampled continuation (footprint spread, medium, Russian roulette).

use std::borrow::Cow;

use glam::{Vec2, Vec3};

use super::medium;
use super::mis::power_heuristic;
use super::next_event::{sample_light, ContextEmission, Scatterer, ShadingPoint};
use super::{add_radiance, LightStrategy, PathRay, PathTracer, PathWaves};
use crate::film::TileImage;
use crate::footprint::{bsdf_spread_angle, Footprint, LodStrategy, RayDifferential};
use crate::hit::SurfaceHit;
use crate::integrator::texturing::{self, environment_lookup, LookupRay};
use crate::integrator::wave_integrator::{write_geometry_aovs, write_material_aovs};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::{GeometryRef, SurfaceDetail};
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::sampler::{PixelSampler, SamplerLanes};
use crate::scene::Material;
use crate::shading::surface_inputs::SurfaceInputs;
use crate::shading::{
    self, area_lights::luminance, Bsdf, BsdfSample, LightHit, LightRef, LobeFlags, MaterialBsdf,
    SpawnPoint,
};

/// Bounces after which Russian roulette may end a path.
const ROULETTE_AFTER: u32 = 3;
/// Smallest probability with which roulette ends a path it applies to.
const ROULETTE_MIN_END: f32 = 0.05;

/// Shade where `ray` ends, once fog on its way has let it pass
/// (`medium::sample_wave_collisions`): the environment for a miss, else the hit surface.
pub(super) fn shade(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &mut PathRay,
    hit: &TraceHit,
    image: &mut TileImage,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    if !hit.is_hit() {
        add_escaped_light(tracer, context, ray, image, worker);
        return;
    }
    let camera_first = ray.kind == RayKind::Camera && ray.first_sample;
    let detail = texturing::surface_detail(context, camera_first, hit);
    let surface = context
        .surfaces
        .surface_hit(ray.origin, ray.direction, hit, detail);
    let material = &context.scene.materials[surface.material as usize];
    if camera_first {
        write_geometry_aovs(context, image, ray.slot, ray.direction, &surface);
    }
    absorb_inside_medium(context, ray, &surface, worker);
    carry_footprint_to_hit(context, ray, &surface, worker);
    let lookup = LookupRay {
        direction: ray.direction,
        footprint: &ray.footprint,
        slot: ray.slot,
        first_sample: ray.first_sample,
    };
    let inputs = texturing::surface_inputs(context, lookup, material, &surface, image, worker);
    if camera_first {
        write_material_aovs(image, ray.slot, &inputs);
    }
    if shading::material_features::emits(material) {
        let emitter = Emitter {
            hit,
            surface: &surface,
            material,
            emission: inputs.emission,
        };
        add_emission(tracer, context, ray, &emitter, image, worker);
    }
    let site = SurfaceSite::of_record(&surface);
    scatter_at_surface(
        tracer, context, ray, &site, material, &inputs, waves, worker,
    );
}

/// What a surface vertex reads of its hit once the material's inputs are known: from the
/// scalar path's hit record, or from the shading lanes' arrays (`lane_waves`), which make
/// the record only if a delta bounce's footprint needs the surface's curvature.
pub(super) struct SurfaceSite<'a> {
    /// Index into `SceneDescription::materials`.
    pub(super) material: u32,
    /// The point on the surface (`SurfaceHit::position`), and where rays leaving it start.
    pub(super) position: Vec3,
    pub(super) spawn: SpawnPoint,
    /// Unit geometric normal, facing outward.
    pub(super) geometric_normal: Vec3,
    pub(super) record: HitRecord<'a>,
}

/// The hit record of a [`SurfaceSite`].
pub(super) enum HitRecord<'a> {
    /// Made by the scalar path.
    Made(&'a SurfaceHit),
    /// Not made: `hit` of the ray from `origin`, the first camera sample's when
    /// `camera_first` (which wants texture coordinates for its AOVs).
    Deferred {
        hit: &'a TraceHit,
        // A reference, not a copy: a `Vec3` copied into the record straddled the 8-byte
        // loads that then moved the record, a store-forwarding stall per lane.
        origin: &'a Vec3,
        camera_first: bool,
    },
}

impl SurfaceSite<'_> {
    fn of_record(surface: &SurfaceHit) -> SurfaceSite<'_> {
        SurfaceSite {
            material: surface.material,
            position: surface.position,
            spawn: surface.spawn_point(),
            geometric_normal: surface.geometric_normal,
            record: HitRecord::Made(surface),
        }
    }

    /// The hit record of a ray along `direction`, made as the scalar path makes it.
    fn record(&self, context: &RenderContext, direction: Vec3) -> Cow<'_, SurfaceHit> {
        match self.record {
            HitRecord::Made(surface) => Cow::Borrowed(surface),
            HitRecord::Deferred {
                hit,
                origin,
                camera_first,
            } => {
                let detail = texturing::surface_detail(context, camera_first, hit);
                let surface = context
                    .surfaces
                    .surface_hit(*origin, direction, hit, detail);
                Cow::Owned(surface)
            }
        }
    }
}

/// Where the path goes from a surface vertex whose emission has been added: the vertex's
/// uniform numbers, next-event estimation and the BSDF-sampled continuation.
#[allow(clippy::too_many_arguments)]
fn scatter_at_surface(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &mut PathRay,
    site: &SurfaceSite,
    material: &Material,
    inputs: &SurfaceInputs,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    if ray.depth > context.options.max_depth {
        // Past the last bounce a delta lobe's ray only collects emission (added before).
        return;
    }
    let u = VertexSamples::draw(ray);
    let vertex = SurfaceVertex::new(tracer, context, ray, site, material, inputs);
    if vertex.lobes.has_density() && bsdf_has_smooth_part(&vertex.bsdf, vertex.wo, vertex.ns) {
        sample_direct_light(tracer, context, ray, &vertex, &u, waves, worker);
    }
    continue_by_bsdf(context, ray, &vertex, &u, waves, worker);
}

/// The vertex of a ray that fog stopped at `collision` before what it meets
/// (`medium::sample_wave_collisions`): a medium vertex instead (`medium`), unless the ray is
/// past the last bounce and looked only for emission, which the fog stops here.
#[allow(clippy::too_many_arguments)]
pub(super) fn scatter_in_fog(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    hit: &TraceHit,
    collision: medium::Collision,
    image: &mut TileImage,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    if ray.depth > context.options.max_depth {
        return;
    }
    if ray.kind == RayKind::Camera && ray.first_sample && hit.is_hit() {
        record_hidden_surface_aovs(context, ray, hit, image, worker);
    }
    medium::scatter(tracer, context, *ray, collision, waves, worker);
}

/// The environment a ray that left the scene sees. A ray that sees it whole (from the camera
/// or a delta lobe) reads it through its footprint. One a non-delta lobe sampled finds the
/// environment as a light, weighted against light sampling, and reads what light sampling
/// reads: the map's nearest level-0 texel. A filtered lookup there would count a sharp sun's
/// blurred glow under both strategies, and shift it to coarse texel centres.
fn add_escaped_light(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let escape = LightHit::escaping(ray.direction);
    let radiance = if ray.bsdf_pdf.is_some() {
        context.lights.le(
            LightRef::Environment,
            &escape,
            &mut ContextEmission { context, worker },
        )
    } else {
        environment_lookup(context, ray.direction, &ray.footprint, worker)
    };
    add_escaped_radiance(tracer, context, ray, radiance, image);
}

/// The environment's radiance `radiance` along an escaping ray (as
/// [`add_escaped_light`] reads it) added to the ray's pixel, weighted against light
/// sampling for a ray a non-delta lobe sampled. The scalar path's step and the misses
/// looked up together (`lanes::misses`).
pub(super) fn add_escaped_radiance(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    radiance: Vec3,
    image: &mut TileImage,
) {
    let lights = &context.lights;
    let environment = LightRef::Environment;
    let escape = LightHit::escaping(ray.direction);
    let weight = found_light_weight(tracer, ray, lights.pmf(environment), || {
        lights.pdf_li(environment, ray.from, &escape)
    });
    add_radiance(image, ray.slot, ray.throughput * radiance * weight);
}

/// Beer's law over the distance travelled inside the medium.
#[inline]
fn absorb_inside_medium(
    context: &RenderContext,
    ray: &mut PathRay,
    surface: &SurfaceHit,
    worker: &mut WorkerState,
) {
    if context.effects.absorption && ray.sigma != Vec3::ZERO {
        ray.throughput *= shading::transmittance(ray.sigma, surface.t);
        worker.counters.absorption_evaluations += 1;
    }
}

/// The ray's footprint at its hit: carried there, or, for differentials after a non-delta
/// bounce, replaced by the camera's footprint at the hit.
fn carry_footprint_to_hit(
    context: &RenderContext,
    ray: &mut PathRay,
    surface: &SurfaceHit,
    worker: &mut WorkerState,
) {
    if !context.effects.footprints {
        return;
    }
    worker.counters.footprint_updates += 1;
    if ray.approximate_footprint && ray.footprint.strategy() == LodStrategy::Differential {
        let spp = context.options.spp;
        let (dpdx, dpdy) =
            context
                .camera
                .approximate_dp_dxy(surface.position, surface.geometric_normal, spp);
        ray.footprint = Footprint::Differential(RayDifferential::parallel(dpdx, dpdy));
    } else {
        ray.footprint.transfer(ray.direction, surface);
    }
}

/// An emitting surface a ray hit.
struct Emitter<'a> {
    hit: &'a TraceHit,
    surface: &'a SurfaceHit,
    material: &'a Material,
    /// The material's emission at the hit, filtered by the ray's footprint.
    emission: Vec3,
}

/// Emission, from the front side unless the material is two-sided
/// (`shading::area_lights`).
fn add_emission(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    emitter: &Emitter,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let area = &context.lights.area;
    let light = match context.surfaces.geometries[emitter.hit.geometry as usize] {
        GeometryRef::Mesh(mesh) => area.mesh_light(mesh, emitter.hit.primitive),
        GeometryRef::Spheres => area.sphere_light(emitter.hit.primitive as usize),
        GeometryRef::Patches | GeometryRef::HeightPatches => None,
    };
    let surface = emitter.surface;
    let light_hit = LightHit {
        direction: ray.direction,
        point: surface.position,
        normal: surface.geometric_normal,
        st: surface.st,
    };
    let emission = emitter.emission;
    let facing = shading::area_lights::emits_towards(
        emitter.material,
        surface.geometric_normal,
        ray.direction,
    );
    let seen = SeenEmission {
        light,
        light_hit,
        emission,
        facing,
    };
    add_seen_emission(tracer, context, ray, &seen, image, worker);
}

/// What a ray sees of an emitting surface: the area light it is (if the surface is one),
/// the ray's hit as the light sees it, the material's emission there, and whether the
/// surface emits towards the ray (`shading::area_lights::emits_towards`).
pub(super) struct SeenEmission {
    pub(super) light: Option<usize>,
    pub(super) light_hit: LightHit,
    pub(super) emission: Vec3,
    pub(super) facing: bool,
}

/// The emission `seen` adds to the ray's pixel: read as light sampling reads it and weighted
/// against it for a BSDF-sampled ray that found an area light, else taken whole (from the
/// front side unless the material is two-sided). The scalar path's step and the lanes'.
pub(super) fn add_seen_emission(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    seen: &SeenEmission,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let found = match seen.light {
        // A BSDF-sampled ray reads the light's emission as light sampling does, so both
        // strategies estimate the same radiance.
        Some(index) if ray.bsdf_pdf.is_some() => found_area_light(
            tracer,
            context,
            ray,
            &seen.light_hit,
            LightRef::Area(index),
            worker,
        ),
        // Seen by the camera or through a delta lobe: taken whole, filtered by the ray's
        // footprint. Emitters that are not lights are found by BSDF rays alone.
        _ => seen.facing.then_some((seen.emission, 1.0)),
    };
    if let Some((emission, weight)) = found {
        add_radiance(image, ray.slot, ray.throughput * emission * weight);
    }
}

/// The uniform numbers of one vertex: the same seven dimensions at every vertex, drawn in
/// this order whichever are used, so an image is a pure function of the seed.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct VertexSamples {
    pub(super) light: f32,
    pub(super) light_point: Vec2,
    pub(super) lobe: f32,
    pub(super) direction: Vec2,
    pub(super) roulette: f32,
}

impl VertexSamples {
    /// The dimensions a surface vertex takes.
    pub(super) const DIMENSIONS: u32 = 7;

    fn draw(ray: &mut PathRay) -> VertexSamples {
        VertexSamples {
            light: ray.sampler.next_1d(),
            light_point: ray.sampler.next_2d(),
            lobe: ray.sampler.next_1d(),
            direction: ray.sampler.next_2d(),
            roulette: ray.sampler.next_1d(),
        }
    }

    /// [`VertexSamples::draw`] of every sampler of `samplers` at once, without moving them
    /// on: the same values, the hashing of all lanes done side by side
    /// ([`SamplerLanes`]).
    #[inline(always)]
    pub(super) fn draw_lanes<const N: usize>(samplers: &[PixelSampler; N]) -> [VertexSamples; N] {
        let lanes = SamplerLanes::new(samplers);
        let light = lanes.draw_1d(0);
        let light_point = lanes.draw_2d(1);
        let lobe = lanes.draw_1d(3);
        let direction = lanes.draw_2d(4);
        let roulette = lanes.draw_1d(6);
        std::array::from_fn(|lane| VertexSamples {
            light: light[lane],
            light_point: Vec2::new(light_point[0][lane], light_point[1][lane]),
            lobe: lobe[lane],
            direction: Vec2::new(direction[0][lane], direction[1][lane]),
            roulette: roulette[lane],
        })
    }
}

/// A surface hit where the path scatters, as the arriving ray sees it.
struct SurfaceVertex<'a> {
    site: &'a SurfaceSite<'a>,
    bsdf: MaterialBsdf,
    lobes: LobeFlags,
    /// Whether the ray arrived on the front side.
    front: bool,
    /// Geometric and shading normals on the viewer's side.
    ng: Vec3,
    ns: Vec3,
    /// Towards the viewer.
    wo: Vec3,
    /// Whether a ray may continue from here at all (the depth allows a bounce).
    continues: bool,
    /// Whether a non-delta (diffuse or glossy) bounce may continue from here: the depth
    /// and the diffuse-bounce limit both allow it.
    rough_continues: bool,
}

impl<'a> SurfaceVertex<'a> {
    fn new(
        tracer: &PathTracer,
        context: &RenderContext,
        ray: &PathRay,
        site: &'a SurfaceSite<'a>,
        material: &Material,
        inputs: &SurfaceInputs,
    ) -> SurfaceVertex<'a> {
        let geometric_normal = site.geometric_normal;
        let bsdf = MaterialBsdf::from_surface_inputs(
            material,
            inputs,
            ray.direction,
            geometric_normal,
            context.effects.fresnel.then_some(context.options.fresnel),
        );
        // `SurfaceHit::is_front_face`.
        let front = ray.direction.dot(geometric_normal) < 0.0;
        let (ng, ns) = if front {
            (geometric_normal, inputs.shading_normal)
        } else {
            (-geometric_normal, -inputs.shading_normal)
        };
        let continues = ray.depth < context.options.max_depth;
        SurfaceVertex {
            site,
            lobes: bsdf.flags(),
            bsdf,
            front,
            ng,
            ns,
            wo: -ray.direction,
            continues,
            rough_continues: continues && ray.diffuse_depth < tracer.diffuse_bounces,
        }
    }
}

/// Next-event estimation at a surface vertex: one light sampled, its shadow ray queued.
fn sample_direct_light(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    vertex: &SurfaceVertex,
    u: &VertexSamples,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    let transmits = vertex.bsdf.transmits_with_density();
    let spawn = &vertex.site.spawn;
    let point = ShadingPoint {
        position: spawn.position,
        origin: spawn.offset_origin(vertex.ng),
        origin_through: if transmits {
            spawn.offset_origin(-vertex.ng)
        } else {
            Vec3::ZERO
        },
        sigma: ray.sigma,
        sigma_through: medium_beyond(context, vertex.site.material, vertex.front),
        wo: vertex.wo,
        scatterer: Scatterer::Surface {
            ng: vertex.ng,
            ns: vertex.ns,
            bsdf: &vertex.bsdf,
            transmits,
        },
        throughput: ray.throughput,
        slot: ray.slot,
        // No BSDF ray competes when none continues along a non-delta lobe.
        last: !vertex.rough_continues,
    };
    sample_light(
        tracer,
        context,
        &point,
        u.light,
        u.light_point,
        waves,
        worker,
    );
}

/// The BSDF-sampled ray the path continues along from a surface vertex, queued for the next
/// wave, unless the sample, the depth, the diffuse-bounce limit or Russian roulette ends the
/// path here.
fn continue_by_bsdf(
    context: &RenderContext,
    ray: &PathRay,
    vertex: &SurfaceVertex,
    u: &VertexSamples,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    // At the last bounce light sampling alone covers the non-delta lobes; a delta lobe
    // (mirror, smooth glass) still sends its ray, which only collects the emission or
    // environment it reaches: a path of `max_depth + 2` segments counts whichever kind of
    // lobe its last vertex has, as in pbrt-v4 and Mitsuba 3.
    if !vertex.continues && !vertex.lobes.is_specular() {
        return;
    }
    let Some(sample) = vertex.bsdf.sample(vertex.wo, u.lobe, u.direction) else {
        return;
    };
    let delta = sample.is_specular();
    if !delta && !vertex.rough_continues {
        return;
    }
    let wi = sample.wi;
    let crosses = wi.dot(vertex.ng) < 0.0;
    // A lobe sampled about a tilted shading normal (normal map, smooth vertex normals) can
    // reflect below the geometric surface. Only a boundary that transmits with a density
    // sends light through; for any other such sample the light would leak through an
    // opaque surface, so the path ends (as light sampling, which `admits` only the
    // viewer's side, already treats that direction).
    if crosses && !delta && !vertex.bsdf.transmits_with_density() {
        return;
    }
    let bsdf = &vertex.bsdf;
    let spread = FootprintSpread {
        site: vertex.site,
        sample: &sample,
        crosses,
        value: || bsdf.eval(vertex.wo, wi),
        boundary_eta: || bsdf.dielectric.split(ray.direction).boundary.eta,
    };
    let side = (vertex.ng, vertex.front);
    queue_continuation(context, ray, spread, side, u.roulette, waves, worker);
}

/// Queue the ray a path continues along `spread.sample` from a surface vertex whose
/// geometric normal on the viewer's side is `ng` (`front`: the ray arrived on the front
/// side), unless Russian roulette (`u_roulette`) or a degenerate throughput ends it.
pub(super) fn queue_continuation(
    context: &RenderContext,
    ray: &PathRay,
    spread: FootprintSpread<impl FnOnce() -> Vec3, impl FnOnce() -> f32>,
    (ng, front): (Vec3, bool),
    u_roulette: f32,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    let (site, sample, crosses) = (spread.site, *spread.sample, spread.crosses);
    let delta = sample.is_specular();
    let throughput = ray.throughput * sample.weight;
    let (footprint, approximate_footprint) = spread_footprint(context, ray, spread, worker);
    let sigma = if crosses {
        medium_beyond(context, site.material, front)
    } else {
        ray.sigma
    };
    let depth = ray.depth + 1;
    let Some(throughput) = continuing_throughput(throughput, depth, u_roulette, worker) else {
        return;
    };
    let kind = if crosses {
        RayKind::Refraction
    } else {
        RayKind::Reflection
    };
    worker.counters.count_rays(kind, 1);
    worker.counters.path_bounces += 1;
    waves.buffers.rays.next.push(PathRay {
        origin: site.spawn.offset_origin(if crosses { -ng } else { ng }),
        direction: sample.wi,
        start: 0.0,
        throughput,
        footprint,
        approximate_footprint,
        slot: ray.slot,
        depth,
        diffuse_depth: ray.diffuse_depth + u32::from(!delta),
        bsdf_pdf: (!delta).then_some(sample.pdf),
        from: site.position,
        kind,
        sigma,
        first_sample: ray.first_sample,
        sampler: ray.sampler,
    });
}

/// What the footprint of a continuing ray is spread by: the vertex's site, the BSDF's
/// sample, whether it leaves below the geometric surface, and what the BSDF answers when
/// asked (only when needed): its value towards the sample, and the relative index of its
/// smooth boundary.
pub(super) struct FootprintSpread<'a, V, E> {
    pub(super) site: &'a SurfaceSite<'a>,
    pub(super) sample: &'a BsdfSample,
    pub(super) crosses: bool,
    pub(super) value: V,
    pub(super) boundary_eta: E,
}

/// The footprint of the ray continuing along `spread.sample`, and whether it is to be
/// replaced by the camera's at the next hit: mirror and refraction as in Whitted, a cone
/// widened by the BSDF spread heuristic (`crate::footprint::bsdf_spread_angle`) for a rough
/// bounce. After a delta bounce the footprint was rebuilt at this hit and carries on.
pub(super) fn spread_footprint(
    context: &RenderContext,
    ray: &PathRay,
    spread: FootprintSpread<impl FnOnce() -> Vec3, impl FnOnce() -> f32>,
    worker: &mut WorkerState,
) -> (Footprint, bool) {
    if !context.effects.footprints {
        return (ray.footprint, false);
    }
    worker.counters.footprint_updates += 1;
    let sample = spread.sample;
    let wi = sample.wi;
    if !sample.is_specular() {
        let f = (spread.value)();
        return (ray.footprint.scatter(bsdf_spread_angle(luminance(f))), true);
    }
    let surface = &*spread.site.record(context, ray.direction);
    if !spread.crosses {
        return (ray.footprint.reflect(ray.direction, surface, wi), false);
    }
    // A delta reflection that leaves below the geometric surface bends the footprint as the
    // boundary's refraction would.
    let eta = if sample.is_transmission() {
        sample.eta
    } else {
        (spread.boundary_eta)()
    };
    (
        ray.footprint.refract(ray.direction, surface, eta, wi),
        false,
    )
}

/// The absorption coefficient of the medium on the far side of a surface of `material`
/// seen from its front (`front`) or back: crossing the surface enters the material's medium
/// from the front, and leaves it for the outside (no medium) from the back.
#[inline]
pub(super) fn medium_beyond(context: &RenderContext, material: u32, front: bool) -> Vec3 {
    if front {
        context.materials.sigma[material as usize]
    } else {
        Vec3::ZERO
    }
}

/// The throughput a path continues with after its `depth`-th bounce, or `None` when it
/// ends there: after [`ROULETTE_AFTER`] bounces, Russian roulette ends it with probability
/// `max(ROULETTE_MIN_END, 1 - max(throughput))` (`u_roulette` decides) when the throughput
/// has fallen below 1 and divides the survivors' by the survival probability; a zero, NaN
/// or infinite throughput ends it too (infinities counted as non-finite samples).
pub(super) fn continuing_throughput(
    mut throughput: Vec3,
    depth: u32,
    u_roulette: f32,
    worker: &mut WorkerState,
) -> Option<Vec3> {
    if depth > ROULETTE_AFTER {
        let largest = throughput.max_element();
        if largest < 1.0 {
            let end = (1.0 - largest).max(ROULETTE_MIN_END);
            if u_roulette < end {
                worker.counters.roulette_terminations += 1;
                return None;
            }
            throughput /= 1.0 - end;
        }
    }
    let largest = throughput.max_element();
    if largest.is_nan() || largest <= 0.0 {
        return None;
    }
    if !throughput.is_finite() {
        worker.counters.nonfinite_samples += 1;
        return None;
    }
    Some(throughput)
}

/// The weight of light found by a ray (emission it hits, the environment it escapes to)
/// from a light that light sampling chooses with probability `pmf` and then samples the
/// ray's direction with density `light_pdf()`.
#[inline]
fn found_light_weight(
    tracer: &PathTracer,
    ray: &PathRay,
    pmf: f32,
    light_pdf: impl FnOnce() -> f32,
) -> f32 {
    let Some(bsdf_pdf) = ray.bsdf_pdf else {
        // The camera or a delta bounce: light sampling cannot find this light.
        return 1.0;
    };
    if pmf <= 0.0 {
        return 1.0;
    }
    match tracer.strategy {
        LightStrategy::BsdfSampling => 1.0,
        LightStrategy::LightSampling => 0.0,
        LightStrategy::MultipleImportance => power_heuristic(bsdf_pdf, pmf * light_pdf()),
    }
}

/// The emission a BSDF-sampled `ray` finds on the area light `light` where it hits it
/// (`hit`), with its weight against light sampling; `None` when it emits nothing towards
/// the ray.
fn found_area_light(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    hit: &LightHit,
    light: LightRef,
    worker: &mut WorkerState,
) -> Option<(Vec3, f32)> {
    let lights = &context.lights;
    let emission = lights.le(light, hit, &mut ContextEmission { context, worker });
    if emission == Vec3::ZERO {
        // Behind a one-sided light (or on a black texel): nothing to add.
        return None;
    }
    let weight = found_light_weight(tracer, ray, lights.pmf(light), || {
        lights.pdf_li(light, ray.from, hit)
    });
    Some((emission, weight))
}

/// Whether the BSDF has a non-delta part that light sampling can reach from `wo`: its
/// density is positive for some direction above the surface (the normal is one).
#[inline(always)]
pub(super) fn bsdf_has_smooth_part(bsdf: &impl Bsdf, wo: Vec3, ns: Vec3) -> bool {
    bsdf.pdf(wo, ns) > 0.0 || bsdf.eval(wo, ns).max_element() > 0.0
}

/// The surface AOVs of the first camera sample's hit when fog in front of it scattered the
/// path first: the pixel's depth, normal, texture coordinates and albedo describe the surface
/// behind the fog, as Whitted's do, not a miss. Nothing is computed when the render keeps no
/// surface AOVs.
fn record_hidden_surface_aovs(
    context: &RenderContext,
    ray: &PathRay,
    hit: &TraceHit,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if image.depth.is_empty() && image.albedo.is_empty() {
        return;
    }
    let surface =
        context
            .surfaces
            .surface_hit(ray.origin, ray.direction, hit, SurfaceDetail::Texturing);
    write_geometry_aovs(context, image, ray.slot, ray.direction, &surface);
    if image.albedo.is_empty() {
        return;
    }
    // Sampling the collision moved only the sampler on: the footprint is the camera's.
    let mut footprint = ray.footprint;
    if context.effects.footprints {
        footprint.transfer(ray.direction, &surface);
    }
    let lookup = LookupRay {
        direction: ray.direction,
        footprint: &footprint,
        slot: ray.slot,
        first_sample: true,
    };
    let material = &context.scene.materials[surface.material as usize];
    let inputs = texturing::surface_inputs(context, lookup, material, &surface, image, worker);
    write_material_aovs(image, ray.slot, &inputs);
}
