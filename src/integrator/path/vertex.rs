//! One vertex of a path: what a ray finds where it ends (a surface or the environment), the
//! light it adds there (emission, weighted against light sampling; light sampling itself),
//! and the ray the BSDF continues the path with, or why the path ends.

use glam::Vec3;

use super::medium;
use super::mis::power_heuristic;
use super::next_event::{sample_light, ContextEmission, Scatterer, ShadingPoint};
use super::{add_radiance, LightStrategy, PathRay, PathTracer, PathWaves};
use crate::film::TileImage;
use crate::footprint::{bsdf_spread_angle, Footprint, LodStrategy, RayDifferential};
use crate::hit::SurfaceHit;
use crate::integrator::texturing::{self, environment_lookup, LookupRay};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::{GeometryRef, SurfaceDetail};
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::shading::surface_inputs::SurfaceInputs;
use crate::shading::{self, area_lights::luminance, Bsdf, LightHit, LightRef, MaterialBsdf};

/// Bounces after which Russian roulette may end a path.
const ROULETTE_AFTER: u32 = 3;
/// Smallest probability with which roulette ends a path it applies to.
const ROULETTE_MIN_END: f32 = 0.05;

/// Shade where `ray` ends: the environment for a miss, else the hit surface.
pub(super) fn shade(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &mut PathRay,
    hit: &TraceHit,
    image: &mut TileImage,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    let lights = &context.lights;
    // Fog between the ray's origin and what it meets: a sampled collision makes this a
    // medium vertex instead (`medium`); a ray that passes keeps its throughput.
    if context.effects.fog {
        let t_end = if hit.is_hit() { hit.t } else { f32::INFINITY };
        let camera_footprint = ray.footprint;
        if let Some(collision) = medium::sample_collision(context, ray, t_end, worker) {
            if ray.depth > context.options.max_depth {
                // A ray past the last bounce only looks for emission, which the fog
                // stops here (collisions are sampled by the transmittance).
                return;
            }
            if ray.kind == RayKind::Camera && ray.first_sample && hit.is_hit() {
                record_hidden_surface_aovs(context, ray, camera_footprint, hit, image, worker);
            }
            medium::scatter(tracer, context, *ray, collision, waves, worker);
            return;
        }
    }
    if !hit.is_hit() {
        // A ray that sees the environment whole (from the camera or a delta lobe) reads it
        // through its footprint. One a non-delta lobe sampled finds the environment as a
        // light, weighted against light sampling, and reads what light sampling reads: the
        // map's nearest level-0 texel. A filtered lookup there would count a sharp sun's
        // blurred glow under both strategies, and shift it to coarse texel centres.
        let environment = LightRef::Environment;
        let escape = LightHit::escaping(ray.direction);
        let radiance = if ray.bsdf_pdf.is_some() {
            lights.le(
                environment,
                &escape,
                &mut ContextEmission { context, worker },
            )
        } else {
            environment_lookup(context, ray.direction, &ray.footprint, worker)
        };
        let weight = found_light_weight(tracer, ray, lights.pmf(environment), || {
            lights.pdf_li(environment, ray.from, &escape)
        });
        add_radiance(image, ray.slot, ray.throughput * radiance * weight);
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
    // Beer's law over the distance travelled inside the medium (seed 004).
    if context.effects.absorption && ray.sigma != Vec3::ZERO {
        ray.throughput *= shading::transmittance(ray.sigma, surface.t);
        worker.counters.absorption_evaluations += 1;
    }
    if context.effects.footprints {
        worker.counters.footprint_updates += 1;
        if ray.approximate_footprint && ray.footprint.strategy() == LodStrategy::Differential {
            let spp = context.options.spp;
            let (dpdx, dpdy) =
                context
                    .camera
                    .approximate_dp_dxy(surface.position, surface.geometric_normal, spp);
            ray.footprint = Footprint::Differential(RayDifferential::parallel(dpdx, dpdy));
        } else {
            ray.footprint.transfer(ray.direction, &surface);
        }
    }
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

    // Emission, from the front side unless the material is two-sided
    // (`shading::area_lights`).
    if shading::material_features::emits(material) {
        let light = match context.surfaces.geometries[hit.geometry as usize] {
            GeometryRef::Mesh(mesh) => lights.area.mesh_light(mesh, hit.primitive),
            GeometryRef::Spheres => lights.area.sphere_light(hit.primitive as usize),
            GeometryRef::Patches | GeometryRef::HeightPatches => None,
        };
        let found = match light {
            // A BSDF-sampled ray reads the light's emission as light sampling does, so both
            // strategies estimate the same radiance.
            Some(index) if ray.bsdf_pdf.is_some() => found_area_light(
                tracer,
                context,
                ray,
                &surface,
                LightRef::Area(index),
                worker,
            ),
            // Seen by the camera or through a delta lobe: taken whole, filtered by the
            // ray's footprint. Emitters that are not lights are found by BSDF rays alone.
            _ => shading::area_lights::emits_towards(material, &surface, ray.direction)
                .then_some((inputs.emission, 1.0)),
        };
        if let Some((emission, weight)) = found {
            add_radiance(image, ray.slot, ray.throughput * emission * weight);
        }
    }
    if ray.depth > context.options.max_depth {
        // Past the last bounce a delta lobe's ray only collects emission (below).
        return;
    }

    // The same seven dimensions at every vertex, whichever are used.
    let u_light = ray.sampler.next_1d();
    let u_light_point = ray.sampler.next_2d();
    let u_lobe = ray.sampler.next_1d();
    let u_direction = ray.sampler.next_2d();
    let u_roulette = ray.sampler.next_1d();

    let bsdf = MaterialBsdf::from_surface_inputs(
        material,
        &inputs,
        ray.direction,
        surface.geometric_normal,
        context.effects.fresnel.then_some(context.options.fresnel),
    );
    let front = surface.is_front_face(ray.direction);
    let (ng, ns) = if front {
        (surface.geometric_normal, inputs.shading_normal)
    } else {
        (-surface.geometric_normal, -inputs.shading_normal)
    };
    let wo = -ray.direction;
    let spawn = surface.spawn_point();
    let continues = ray.depth < context.options.max_depth;

    let lobes = bsdf.flags();
    if lobes.has_density() && bsdf_has_smooth_part(&bsdf, wo, ns) {
        let transmits = bsdf.transmits_with_density();
        let point = ShadingPoint {
            position: spawn.position,
            origin: spawn.offset_origin(ng),
            origin_through: if transmits {
                spawn.offset_origin(-ng)
            } else {
                Vec3::ZERO
            },
            sigma: ray.sigma,
            sigma_through: medium_beyond(context, &surface, front),
            wo,
            scatterer: Scatterer::Surface {
                ng,
                ns,
                bsdf: &bsdf,
                transmits,
            },
            throughput: ray.throughput,
            slot: ray.slot,
            // No BSDF ray competes when none continues along a non-delta lobe.
            last: !continues || ray.diffuse_depth >= tracer.diffuse_bounces,
        };
        sample_light(
            tracer,
            context,
            &point,
            u_light,
            u_light_point,
            waves,
            worker,
        );
    }

    // At the last bounce light sampling alone covers the non-delta lobes; a delta lobe
    // (mirror, smooth glass) still sends its ray, which only collects the emission or
    // environment it reaches: a path of `max_depth + 2` segments counts whichever kind of
    // lobe its last vertex has, as in pbrt-v4 and Mitsuba 3.
    if !continues && !lobes.is_specular() {
        return;
    }
    let Some(sample) = bsdf.sample(wo, u_lobe, u_direction) else {
        return;
    };
    let delta = sample.is_specular();
    if !delta && (!continues || ray.diffuse_depth >= tracer.diffuse_bounces) {
        return;
    }
    let wi = sample.wi;
    let crosses = wi.dot(ng) < 0.0;
    // A lobe sampled about a tilted shading normal (normal map, smooth vertex normals) can
    // reflect below the geometric surface. Only a boundary that transmits with a density
    // sends light through; for any other such sample the light would leak through an
    // opaque surface, so the path ends (as light sampling, which `admits` only the
    // viewer's side, already treats that direction).
    if crosses && !delta && !bsdf.transmits_with_density() {
        return;
    }
    let throughput = ray.throughput * sample.weight;
    // Footprint of the continuing ray: mirror and refraction as in Whitted, a widened cone
    // for a rough bounce (seed 000, "BSDF scattering").
    let mut approximate_footprint = false;
    let footprint = if !context.effects.footprints {
        ray.footprint
    } else if delta && !crosses {
        worker.counters.footprint_updates += 1;
        ray.footprint.reflect(ray.direction, &surface, wi)
    } else if delta {
        worker.counters.footprint_updates += 1;
        // A delta reflection that leaves below the geometric surface bends the footprint as
        // the boundary's refraction would.
        let eta = if sample.is_transmission() {
            sample.eta
        } else {
            bsdf.dielectric.split(ray.direction).boundary.eta
        };
        ray.footprint.refract(ray.direction, &surface, eta, wi)
    } else {
        worker.counters.footprint_updates += 1;
        approximate_footprint = true;
        let f = bsdf.eval(wo, wi);
        ray.footprint.scatter(bsdf_spread_angle(luminance(f)))
    };
    let sigma = if crosses {
        medium_beyond(context, &surface, front)
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
    waves.rays.next.push(PathRay {
        origin: spawn.offset_origin(if crosses { -ng } else { ng }),
        direction: wi,
        start: 0.0,
        throughput,
        footprint,
        // After a delta bounce the footprint was rebuilt at this hit and carried on.
        approximate_footprint,
        slot: ray.slot,
        depth,
        diffuse_depth: ray.diffuse_depth + u32::from(!delta),
        bsdf_pdf: (!delta).then_some(sample.pdf),
        from: surface.position,
        kind,
        sigma,
        first_sample: ray.first_sample,
        sampler: ray.sampler,
    });
}

/// The absorption coefficient of the medium on the far side of `surface` seen from its
/// front (`front`) or back: crossing the surface enters the material's medium from the
/// front, and leaves it for the outside (no medium) from the back.
#[inline]
fn medium_beyond(context: &RenderContext, surface: &SurfaceHit, front: bool) -> Vec3 {
    if front {
        context.materials.sigma[surface.material as usize]
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

/// The emission a BSDF-sampled `ray` finds on the area light `light` at `surface`, with its
/// weight against light sampling; `None` when it emits nothing towards the ray.
fn found_area_light(
    tracer: &PathTracer,
    context: &RenderContext,
    ray: &PathRay,
    surface: &SurfaceHit,
    light: LightRef,
    worker: &mut WorkerState,
) -> Option<(Vec3, f32)> {
    let lights = &context.lights;
    let hit = LightHit {
        direction: ray.direction,
        point: surface.position,
        normal: surface.geometric_normal,
        st: surface.st,
    };
    let emission = lights.le(light, &hit, &mut ContextEmission { context, worker });
    if emission == Vec3::ZERO {
        // Behind a one-sided light (or on a black texel): nothing to add.
        return None;
    }
    let weight = found_light_weight(tracer, ray, lights.pmf(light), || {
        lights.pdf_li(light, ray.from, &hit)
    });
    Some((emission, weight))
}

/// Whether the BSDF has a non-delta part that light sampling can reach from `wo`: its
/// density is positive for some direction above the surface (the normal is one).
#[inline]
fn bsdf_has_smooth_part(bsdf: &MaterialBsdf, wo: Vec3, ns: Vec3) -> bool {
    bsdf.pdf(wo, ns) > 0.0 || bsdf.eval(wo, ns).max_element() > 0.0
}

/// The depth, shading normal and texture coordinates of the first camera sample's hit, if
/// the render keeps surface AOVs.
fn write_geometry_aovs(
    context: &RenderContext,
    image: &mut TileImage,
    pixel: u32,
    direction: Vec3,
    surface: &SurfaceHit,
) {
    if image.depth.is_empty() {
        return;
    }
    let pixel = pixel as usize;
    image.depth[pixel] = surface.t * direction.dot(context.camera_forward);
    image.normal[pixel] = surface.shading_normal.to_array();
    image.uv[pixel] = surface.st.to_array();
}

/// The albedo and the (normal-mapped) shading normal of the first camera sample's hit, if
/// the render keeps them.
fn write_material_aovs(image: &mut TileImage, pixel: u32, inputs: &SurfaceInputs) {
    if image.albedo.is_empty() {
        return;
    }
    let pixel = pixel as usize;
    image.albedo[pixel] = inputs.albedo.to_array();
    if !image.normal.is_empty() {
        image.normal[pixel] = inputs.shading_normal.to_array();
    }
}

/// The surface AOVs of the first camera sample's hit when fog in front of it scattered the
/// path first: the pixel's depth, normal, texture coordinates and albedo describe the surface
/// behind the fog, as Whitted's do, not a miss. Nothing is computed when the render keeps no
/// surface AOVs.
fn record_hidden_surface_aovs(
    context: &RenderContext,
    ray: &PathRay,
    camera_footprint: Footprint,
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
    let mut footprint = camera_footprint;
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
