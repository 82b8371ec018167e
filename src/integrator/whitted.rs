//! Whitted ray tracing (seed 001's recursion, seed 004's Fresnel and Beer's law), traced in
//! waves.
//!
//! Instead of recursing ray by ray, a tile is rendered breadth first: the camera rays of
//! each 4x4 pixel block form one 16-wide packet; every hit is shaded, its shadow rays are
//! batched and traced as one occlusion stream, and the reflection and refraction rays it
//! spawns form the next wave, traced as an incoherent ray stream. A ray carries its
//! throughput (the product of the coefficients on its way from the camera), so the sum over
//! all waves equals the
//! recursive formulation `local + k_r * trace(reflected) + k_t * trace(refracted)`.
//!
//! Recursion stops at the maximum depth or when a ray's throughput falls below the
//! threshold (seed 001's termination rules).
//!
//! Every ray that leaves a surface (shadow rays, reflections, refractions, and shadow rays
//! continuing past a transmissive occluder) starts from the hit's spawn point: the point
//! recomputed from the surface, moved along the geometric normal just past the bound on its
//! rounding error (`shading::ray_offset`), so no ray meets the surface it leaves, whatever
//! the scene's scale or the camera's distance. The geometric normal is also the one rule for
//! which side of a dielectric a ray is on (`shading::DielectricBoundary`).

use glam::{Vec2, Vec3};

use crate::film::sample_sum;
use crate::footprint::Footprint;
use crate::hit::SurfaceHit;
use crate::integrator::{block_order, Integrator, TileImage, TileRect};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::{binding_query, environment_radiance, SurfaceDetail};
use crate::render::sampling;
use crate::render::stats::RayKind;
use crate::render::tracer::{TraceHit, TraceRay};
use crate::scene::Material;
use crate::shading::{self, DielectricBoundary, SpawnPoint};

/// Shadow rays stop passing through transmissive occluders below this strength (seed 001).
const SHADOW_CUTOFF: f32 = 0.002;
/// At most this many transmissive occluders are crossed by one shadow ray.
const MAX_SHADOW_CROSSINGS: u32 = 16;

/// The Whitted integrator.
#[derive(Clone, Copy, Debug, Default)]
pub struct Whitted;

/// A ray in flight, with what it carries from the camera.
#[derive(Clone, Copy, Debug)]
struct PathRay {
    origin: Vec3,
    direction: Vec3,
    /// Where tracing starts along the ray: just before the scene's bounds for camera rays
    /// from far away (`shading::entry_distance`), 0 for rays leaving a surface.
    start: f32,
    throughput: Vec3,
    footprint: Footprint,
    /// Index of the pixel inside the tile.
    pixel: u32,
    depth: u32,
    kind: RayKind,
    /// Absorption coefficient of the medium the ray travels in (zero outside media).
    sigma: Vec3,
    /// Whether this ray belongs to the pixel's first sample (which writes the AOVs).
    first_sample: bool,
}

/// A shadow ray and the radiance it delivers if unoccluded.
#[derive(Clone, Copy, Debug)]
struct ShadowRay {
    origin: Vec3,
    direction: Vec3,
    /// Where the ray stops (`shading::shadow_ray_end`).
    tfar: f32,
    /// The point light's position (`None` for directional lights): continuations past
    /// transmissive occluders measure their far end from it.
    light: Option<Vec3>,
    contribution: Vec3,
    pixel: u32,
}

/// Reused buffers of one tile's waves.
#[derive(Default)]
struct Waves {
    current: Vec<PathRay>,
    next: Vec<PathRay>,
    trace_rays: Vec<TraceRay>,
    trace_hits: Vec<TraceHit>,
    shadows: Vec<ShadowRay>,
    shadow_rays: Vec<TraceRay>,
    shadow_blocked: Vec<bool>,
    /// Walks of shadow rays through transmissive occluders.
    walk: ShadowWalk,
}

/// Reused state of shadow rays walking through transmissive occluders.
#[derive(Default)]
struct ShadowWalk {
    strength: Vec<Vec3>,
    active: Vec<usize>,
    still_active: Vec<usize>,
    entered_at: Vec<f32>,
    travelled: Vec<f32>,
    batch: Vec<TraceRay>,
}

impl Integrator for Whitted {
    fn render_tile(
        &self,
        context: &RenderContext,
        tile: TileRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
    ) {
        let options = &context.options;
        let spp = options.spp.max(1);
        let mut waves = Waves::default();
        let image_width = options.width;
        let samples = image.samples.clone().unwrap_or(0..spp);
        let sample_count = samples.len() as u32;
        for sample in samples {
            generate_camera_rays(context, tile, sample, image_width, &mut waves.current);
            worker
                .counters
                .count_rays(RayKind::Camera, waves.current.len() as u64);
            while !waves.current.is_empty() {
                trace_wave(context, &mut waves, worker);
                shade_wave(context, &mut waves, image, worker);
                trace_shadows(context, &mut waves, image, worker);
                std::mem::swap(&mut waves.current, &mut waves.next);
                waves.next.clear();
            }
            // This sample's radiance joins the exact sums (`film::sample_sum`): any split of
            // the samples into ranges then adds up to the same bits.
            for (sum, color) in image.color_sum.iter_mut().zip(image.color.iter_mut()) {
                sample_sum::add_sample(sum, *color);
                *color = [0.0; 3];
            }
        }
        for (color, sum) in image.color.iter_mut().zip(&image.color_sum) {
            *color = sum.map(|s| sample_sum::mean_of_sum(s, sample_count));
        }
        // The background is rendered too: a finished pixel is opaque. (Alpha 0 marks pixels
        // an interrupted render did not reach.)
        image.alpha.fill(1.0);
    }
}

/// Camera rays of one sample for a tile, ordered so that each run of 16 is a 4x4 block.
fn generate_camera_rays(
    context: &RenderContext,
    tile: TileRect,
    sample: u32,
    image_width: u32,
    out: &mut Vec<PathRay>,
) {
    out.clear();
    let camera = &context.camera;
    let lod = context.options.lod;
    let spp = context.options.spp.max(1);
    let dof = context.effects.depth_of_field;
    for (x, y) in block_order(tile) {
        let (px, py) = (tile.x0 + x, tile.y0 + y);
        let pixel_id = py * image_width + px;
        let offset = sampling::pixel_offset(pixel_id, sample, spp);
        let lens = if dof {
            sampling::lens_sample(pixel_id, sample)
        } else {
            Vec2::splat(0.5)
        };
        let (fx, fy) = (px as f32 + offset.x, py as f32 + offset.y);
        let (origin, direction) = camera.generate_ray(fx, fy, lens);
        let start = context.surfaces.bounds.map_or(0.0, |bounds| {
            shading::entry_distance(origin, direction, bounds)
        });
        let footprint = if context.effects.footprints {
            camera.initial_footprint(lod, fx, fy, origin, direction)
        } else {
            Footprint::none()
        };
        out.push(PathRay {
            origin,
            direction,
            start,
            throughput: Vec3::ONE,
            footprint,
            pixel: y * tile.width + x,
            depth: 0,
            kind: RayKind::Camera,
            sigma: Vec3::ZERO,
            first_sample: sample == 0,
        });
    }
}

/// Trace the current wave: camera waves as coherent 4x4 packets, later waves as incoherent
/// ray streams (see `render::tracer`).
fn trace_wave(context: &RenderContext, waves: &mut Waves, worker: &mut WorkerState) {
    waves.trace_rays.clear();
    waves.trace_rays.extend(waves.current.iter().map(|ray| {
        let (cone_width, cone_spread) = ray.footprint.cone_at_origin();
        // Traced from `start`: the cone is as wide there as it has grown by then.
        TraceRay {
            origin: ray.origin + ray.direction * ray.start,
            direction: ray.direction,
            tfar: f32::INFINITY,
            cone_width: cone_width + cone_spread * ray.start,
            cone_spread,
        }
    }));
    let coherent = waves
        .current
        .first()
        .is_some_and(|r| r.kind == RayKind::Camera);
    context.tracer.intersect(
        &waves.trace_rays,
        &mut waves.trace_hits,
        coherent,
        &mut worker.counters,
    );
    // Distances count from the ray's origin again.
    for (hit, ray) in waves.trace_hits.iter_mut().zip(&waves.current) {
        if ray.start > 0.0 && hit.is_hit() {
            hit.t += ray.start;
        }
    }
}

fn shade_wave(
    context: &RenderContext,
    waves: &mut Waves,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    waves.shadows.clear();
    for index in 0..waves.current.len() {
        let ray = waves.current[index];
        let hit = waves.trace_hits[index];
        if !hit.is_hit() {
            shade_miss(context, &ray, image, worker);
            continue;
        }
        let detail = surface_detail(context, &ray, &hit);
        let surface = context
            .surfaces
            .surface_hit(ray.origin, ray.direction, &hit, detail);
        shade_hit(context, ray, &surface, image, waves, worker);
    }
}

/// Texture coordinates are needed for textured materials and for the camera hit's AOVs.
#[inline]
fn surface_detail(context: &RenderContext, ray: &PathRay, hit: &TraceHit) -> SurfaceDetail {
    let aov = ray.kind == RayKind::Camera && ray.first_sample && context.options.aovs.surface;
    if aov || context.surfaces.is_textured(hit) {
        SurfaceDetail::Texturing
    } else {
        SurfaceDetail::Geometry
    }
}

fn shade_miss(
    context: &RenderContext,
    ray: &PathRay,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    let effects = &context.effects;
    let gradients = if effects.footprints {
        let g = ray.footprint.environment_gradients(ray.direction);
        [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
    } else {
        [0.0; 4]
    };
    if matches!(
        context.scene.environment,
        crate::scene::Environment::LatLong { .. }
    ) {
        worker.counters.texture_lookups += 1;
    }
    let radiance = environment_radiance(
        &context.scene.environment,
        &context.textures,
        ray.direction,
        gradients,
        &context.texture_filters,
        context.external_textures.as_deref(),
    );
    add_radiance(image, ray.pixel, ray.throughput * radiance);
}

#[inline]
fn add_radiance(image: &mut TileImage, pixel: u32, radiance: Vec3) {
    let c = &mut image.color[pixel as usize];
    c[0] += radiance.x;
    c[1] += radiance.y;
    c[2] += radiance.z;
}

fn shade_hit(
    context: &RenderContext,
    mut ray: PathRay,
    surface: &SurfaceHit,
    image: &mut TileImage,
    waves: &mut Waves,
    worker: &mut WorkerState,
) {
    let effects = &context.effects;
    let options = &context.options;
    let material: &Material = &context.scene.materials[surface.material as usize];
    let pixel = ray.pixel as usize;

    if ray.kind == RayKind::Camera {
        if ray.first_sample && !image.depth.is_empty() {
            image.depth[pixel] = surface.t * ray.direction.dot(context.camera_forward);
            image.normal[pixel] = surface.shading_normal.to_array();
            image.uv[pixel] = surface.st.to_array();
        }
    }

    // Beer's law over the distance travelled inside the medium (seed 004).
    if effects.absorption && ray.sigma != Vec3::ZERO {
        ray.throughput *= shading::transmittance(ray.sigma, surface.t);
        worker.counters.absorption_evaluations += 1;
    }
    if effects.footprints {
        ray.footprint.transfer(ray.direction, surface);
        worker.counters.footprint_updates += 1;
    }

    let albedo = surface_albedo(context, &ray, material, surface, image, worker);
    if ray.kind == RayKind::Camera && ray.first_sample && !image.albedo.is_empty() {
        image.albedo[pixel] = albedo.to_array();
    }

    let front = ray.direction.dot(surface.geometric_normal) < 0.0;
    let (ng, ns) = if front {
        (surface.geometric_normal, surface.shading_normal)
    } else {
        (-surface.geometric_normal, -surface.shading_normal)
    };
    let mut radiance = material.emission;
    let spawn = surface.spawn_point();

    // Local illumination of the opaque part: direct light with shadow rays, plus ambient
    // environment light.
    let opaque = (1.0 - material.mirror) * (1.0 - material.transmission);
    if opaque > 0.0 {
        let wo = -ray.direction;
        if effects.shadows {
            let origin = spawn.offset_origin(ng);
            for light in &context.scene.lights {
                // Direction and distance from the shadow ray's own origin, so its far end
                // is measured from where it starts.
                let sample = shading::light_sample(light, origin);
                let wi = sample.direction_to_light;
                if wi.dot(ng) <= 0.0 || wi.dot(ns) <= 0.0 {
                    continue;
                }
                let f = shading::eval_surface(
                    albedo,
                    material.specular,
                    material.shininess,
                    ns,
                    wo,
                    wi,
                );
                let contribution = ray.throughput * opaque * f * sample.radiance_scale;
                if contribution.max_element() <= 0.0 {
                    continue;
                }
                let light_position = shading::light_position(light);
                waves.shadows.push(ShadowRay {
                    origin,
                    direction: wi,
                    tfar: shadow_tfar(sample.distance, light_position),
                    light: light_position,
                    contribution,
                    pixel: ray.pixel,
                });
            }
        }
        if effects.environment {
            radiance += opaque * albedo * context.environment_mean;
        }
    }
    add_radiance(image, ray.pixel, ray.throughput * radiance);

    let can_spawn = ray.depth < options.max_depth;
    if !can_spawn {
        return;
    }
    let spawner = Spawner {
        parent: &ray,
        spawn,
        min_throughput: options.min_throughput,
    };
    if effects.mirror_reflection && material.mirror > 0.0 {
        spawner.spawn_reflection(context, surface, ns, ng, material.mirror, waves, worker);
    }

    if effects.refraction && material.transmission > 0.0 {
        // Which side the ray comes from, eta = n_incident / n_transmitted (outside = 1): the
        // geometric normal decides, as it decides `front` and the medium below.
        let boundary = DielectricBoundary::with_shading_normal(
            ray.direction,
            surface.geometric_normal,
            surface.shading_normal,
            material.ior,
        );
        let refracted = shading::refract(ray.direction, boundary.normal, boundary.eta)
            .filter(|d| d.dot(ng) < 0.0);
        // Total internal reflection (or a refracted ray that would stay on the incident side)
        // reflects everything; otherwise the Fresnel share (seed 004), which is zero for
        // index-matched media (the `fresnel` effect is off when every medium has ior 1).
        let reflectance = if refracted.is_none() {
            1.0
        } else if effects.fresnel {
            shading::fresnel(options.fresnel, boundary.cos_i, boundary.eta)
        } else {
            0.0
        };
        if let Some(refracted) = refracted {
            let footprint = if effects.footprints {
                worker.counters.footprint_updates += 1;
                ray.footprint
                    .refract(ray.direction, surface, boundary.eta, refracted)
            } else {
                ray.footprint
            };
            // Entering the material: its medium; leaving: back outside.
            let sigma = if front {
                context.materials.sigma[surface.material as usize]
            } else {
                Vec3::ZERO
            };
            spawner.spawn(
                waves,
                worker,
                refracted,
                -ng,
                Vec3::splat(material.transmission * (1.0 - reflectance)),
                RayKind::Refraction,
                footprint,
                sigma,
            );
        }
        if reflectance > 0.0 {
            let weight = material.transmission * reflectance;
            spawner.spawn_reflection(context, surface, ns, ng, weight, waves, worker);
        }
    }
}

/// Spawns the secondary rays of one hit.
struct Spawner<'a> {
    parent: &'a PathRay,
    /// The hit's position with its error bound: rays start just past it.
    spawn: SpawnPoint,
    min_throughput: f32,
}

impl Spawner<'_> {
    /// Queue a ray leaving the surface on the side of `leave_normal`, unless its throughput
    /// has fallen below the threshold (seed 001's "contribution too small" rule).
    #[allow(clippy::too_many_arguments)]
    fn spawn(
        &self,
        waves: &mut Waves,
        worker: &mut WorkerState,
        direction: Vec3,
        leave_normal: Vec3,
        weight: Vec3,
        kind: RayKind,
        footprint: Footprint,
        sigma: Vec3,
    ) {
        let throughput = self.parent.throughput * weight;
        if throughput.max_element() < self.min_throughput {
            return;
        }
        worker.counters.count_rays(kind, 1);
        waves.next.push(PathRay {
            origin: self.spawn.offset_origin(leave_normal),
            direction,
            start: 0.0,
            throughput,
            footprint,
            pixel: self.parent.pixel,
            depth: self.parent.depth + 1,
            kind,
            sigma,
            first_sample: self.parent.first_sample,
        });
    }

    /// Queue the mirror reflection of the parent ray (about the shading normal `ns`, kept
    /// above the geometric normal `ng`, both on the incident side) with weight `weight`, its
    /// footprint reflected too.
    #[allow(clippy::too_many_arguments)]
    fn spawn_reflection(
        &self,
        context: &RenderContext,
        surface: &SurfaceHit,
        ns: Vec3,
        ng: Vec3,
        weight: f32,
        waves: &mut Waves,
        worker: &mut WorkerState,
    ) {
        let ray = self.parent;
        let reflected = reflect_above(ray.direction, ns, ng);
        let footprint =
            footprint_reflect(context.effects.footprints, ray, surface, reflected, worker);
        self.spawn(
            waves,
            worker,
            reflected,
            ng,
            Vec3::splat(weight),
            RayKind::Reflection,
            footprint,
            ray.sigma,
        );
    }
}

/// Mirror direction about the shading normal, kept above the geometric surface.
#[inline]
fn reflect_above(direction: Vec3, ns: Vec3, ng: Vec3) -> Vec3 {
    let r = shading::reflect(direction, ns);
    if r.dot(ng) > 0.0 {
        r
    } else {
        shading::reflect(direction, ng)
    }
}

#[inline]
fn footprint_reflect(
    enabled: bool,
    ray: &PathRay,
    surface: &SurfaceHit,
    reflected: Vec3,
    worker: &mut WorkerState,
) -> Footprint {
    if enabled {
        worker.counters.footprint_updates += 1;
        ray.footprint.reflect(ray.direction, surface, reflected)
    } else {
        ray.footprint
    }
}

/// The material's albedo at the hit: base colour times its texture, filtered by the ray's
/// footprint. Fills the first-lookup AOVs of the pixel.
fn surface_albedo(
    context: &RenderContext,
    ray: &PathRay,
    material: &Material,
    surface: &SurfaceHit,
    image: &mut TileImage,
    worker: &mut WorkerState,
) -> Vec3 {
    let Some(binding) = &material.base_color_texture else {
        return material.base_color;
    };
    let options = &context.options;
    let filter = &context.texture_filters[binding.texture];
    let gradients = if context.effects.footprints {
        let g = ray
            .footprint
            .texture_gradients(ray.direction, surface, options.filter.max_aniso);
        [g.dsdx, g.dtdx, g.dsdy, g.dtdy]
    } else {
        [0.0; 4]
    };
    let query = binding_query(&binding.transform, surface.st, gradients);
    let texture = &context.textures[binding.texture];
    worker.counters.texture_lookups += 1;
    let texel = match (
        &context.external_textures,
        worker.tiles.get_mut(binding.texture),
    ) {
        (Some(external), _) => crate::render::external_textures::sample_external(
            external.as_ref(),
            binding.texture,
            &query,
            filter,
        ),
        (None, Some(tiles)) => texture.sample_recording(&query, filter, tiles),
        (None, None) => texture.sample(&query, filter),
    };
    let pixel = ray.pixel as usize;
    if ray.first_sample && !image.lookup_done.is_empty() && !image.lookup_done[pixel] {
        image.lookup_done[pixel] = true;
        if !image.tex.is_empty() {
            image.tex[pixel] = [
                query.s, query.t, query.dsdx, query.dtdx, query.dsdy, query.dtdy,
            ];
            image.texcolor[pixel] = [texel.x, texel.y, texel.z, 1.0];
        }
        if !image.lod.is_empty() {
            image.lod[pixel] = texture.lod(&query, filter);
            image.footprint[pixel] = ray.footprint.width();
        }
    }
    material.base_color * texel.truncate()
}

/// Trace the wave's shadow rays as occlusion packets and add what reaches the lights.
/// With transmissive occluders, a shadow ray is attenuated by each one it crosses (seed 001).
fn trace_shadows(
    context: &RenderContext,
    waves: &mut Waves,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if waves.shadows.is_empty() {
        return;
    }
    worker
        .counters
        .count_rays(RayKind::Shadow, waves.shadows.len() as u64);
    waves.shadow_rays.clear();
    waves
        .shadow_rays
        .extend(waves.shadows.iter().map(|s| TraceRay {
            origin: s.origin,
            direction: s.direction,
            tfar: s.tfar,
            cone_width: 0.0,
            cone_spread: 0.0,
        }));
    if !context.effects.transmissive_shadows {
        context.tracer.occluded(
            &waves.shadow_rays,
            &mut waves.shadow_blocked,
            &mut worker.counters,
        );
        for (shadow, blocked) in waves.shadows.iter().zip(&waves.shadow_blocked) {
            if !blocked {
                add_radiance(image, shadow.pixel, shadow.contribution);
            }
        }
        return;
    }
    // Transmissive occluders: walk each shadow ray through the surfaces it meets.
    let n = waves.shadows.len();
    let walk = &mut waves.walk;
    walk.strength.clear();
    walk.strength.resize(n, Vec3::ONE);
    walk.entered_at.clear();
    walk.entered_at.resize(n, 0.0);
    walk.travelled.clear();
    walk.travelled.resize(n, 0.0);
    walk.active.clear();
    walk.active.extend(0..n);
    for _ in 0..MAX_SHADOW_CROSSINGS {
        if walk.active.is_empty() {
            break;
        }
        walk.batch.clear();
        walk.batch
            .extend(walk.active.iter().map(|&i| waves.shadow_rays[i]));
        worker.counters.shadow_walk_queries += walk.batch.len() as u64;
        context.tracer.intersect(
            &walk.batch,
            &mut waves.trace_hits,
            false,
            &mut worker.counters,
        );
        walk.still_active.clear();
        for (slot, &i) in walk.active.iter().enumerate() {
            let hit = waves.trace_hits[slot];
            if !hit.is_hit() {
                continue;
            }
            let ray = walk.batch[slot];
            let surface = context.surfaces.surface_hit(
                ray.origin,
                ray.direction,
                &hit,
                SurfaceDetail::Geometry,
            );
            let material = &context.scene.materials[surface.material as usize];
            if material.transmission <= 0.0 {
                walk.strength[i] = Vec3::ZERO;
                continue;
            }
            let front = ray.direction.dot(surface.geometric_normal) < 0.0;
            let mut s = walk.strength[i] * material.transmission;
            if front {
                walk.entered_at[i] = walk.travelled[i] + hit.t;
            } else if context.effects.absorption {
                // Leaving the medium: absorb over the distance travelled inside (clear media,
                // sigma = 0, absorb nothing and are skipped).
                let sigma = context.materials.sigma[surface.material as usize];
                if sigma != Vec3::ZERO {
                    let inside = (walk.travelled[i] + hit.t - walk.entered_at[i]).max(0.0);
                    s *= shading::transmittance(sigma, inside);
                    worker.counters.absorption_evaluations += 1;
                }
            }
            walk.strength[i] = s;
            if s.max_element() < SHADOW_CUTOFF {
                walk.strength[i] = Vec3::ZERO;
                continue;
            }
            let leave = if front {
                -surface.geometric_normal
            } else {
                surface.geometric_normal
            };
            let origin = surface.spawn_point().offset_origin(leave);
            let moved = (origin - ray.origin).dot(ray.direction);
            walk.travelled[i] += moved;
            // The far end is measured again from the new origin, not carried over, so its
            // margin does not depend on how far the walk has come.
            let light = waves.shadows[i].light;
            let remaining = match light {
                Some(position) => shadow_tfar((position - origin).length(), light),
                None => ray.tfar - moved,
            };
            if remaining <= 0.0 {
                continue;
            }
            waves.shadow_rays[i] = TraceRay {
                origin,
                tfar: remaining,
                ..ray
            };
            worker.counters.count_rays(RayKind::Shadow, 1);
            walk.still_active.push(i);
        }
        std::mem::swap(&mut walk.active, &mut walk.still_active);
    }
    for &i in &walk.active {
        // Ran out of crossings: treat as blocked.
        walk.strength[i] = Vec3::ZERO;
    }
    for (shadow, s) in waves.shadows.iter().zip(&walk.strength) {
        if s.max_element() > 0.0 {
            add_radiance(image, shadow.pixel, shadow.contribution * *s);
        }
    }
}

/// Shadow rays stop short of a point light robustly (`shading::shadow_ray_end`); towards a
/// directional light (no position) they are unbounded.
#[inline]
fn shadow_tfar(distance: f32, light: Option<Vec3>) -> f32 {
    match light {
        Some(position) => shading::shadow_ray_end(distance, position),
        None => f32::INFINITY,
    }
}
