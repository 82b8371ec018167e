//! Shading a hit: what the camera hit writes to the AOVs, absorption on the way in, the
//! material's inputs (albedo, emission, normal-mapped normal) under the ray's footprint,
//! emission and ambient light, and which
//! secondary rays the material spawns (direct light in `lights`, mirror and dielectric rays
//! in `spawn` and `dielectric`).

use glam::Vec3;

use super::dielectric::scatter_dielectric;
use super::lights::queue_shadow_rays;
use super::spawn::{HitSurface, Spawner};
use super::{add_radiance, PathRay, Waves};
use crate::film::TileImage;
use crate::hit::SurfaceHit;
use crate::integrator::texturing::{self, LookupRay};
use crate::integrator::wave_integrator::{write_geometry_aovs, write_material_aovs};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::SurfaceDetail;
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::scene::Material;
use crate::shading::surface_inputs::SurfaceInputs;
use crate::shading::{self, MaterialBsdf, OpaqueLobe, SpawnPoint};

/// A hit's opaque lobe, as the light beyond the punctual lights' shadow rays sees it.
pub(crate) struct IndirectQuery<'a> {
    /// The hit, and its spawn point when the shading already computed it (see
    /// [`IndirectQuery::position`]).
    pub(crate) surface: &'a SurfaceHit,
    pub(crate) spawn: Option<SpawnPoint>,
    /// Unit geometric normal on the incident side.
    pub(crate) geometric_normal: Vec3,
    /// Unit direction towards the viewer (`-ray.direction`).
    pub(crate) outgoing: Vec3,
    /// The opaque lobe (its shading normal faces the viewer).
    pub(crate) bsdf: &'a OpaqueLobe,
    /// The material's (textured) albedo at the hit.
    pub(crate) albedo: Vec3,
    /// The lobe's weight in the material.
    pub(crate) weight: f32,
}

impl IndirectQuery<'_> {
    /// Where light is gathered from: the hit's spawn point, computed here only when the
    /// shading did not need it (only an indirect light that asks pays for it).
    pub(crate) fn position(&self) -> Vec3 {
        self.spawn
            .unwrap_or_else(|| self.surface.spawn_point())
            .position
    }
}

/// Light reaching a hit's opaque lobe from everything but the punctual lights (whose shadow
/// rays Whitted traces): the radiance it adds towards the viewer.
pub(crate) trait IndirectLight: Sync {
    fn opaque_indirect(
        &self,
        context: &RenderContext,
        query: &IndirectQuery,
        worker: &mut WorkerState,
    ) -> Vec3;

    /// Whether this is [`AmbientEnvironment`], which depends on the lobe's weight and albedo
    /// alone, so shading waves add it over lane arrays without a hit record.
    fn is_ambient_environment(&self) -> bool {
        false
    }
}

/// Whitted's indirect light: the environment's mean radiance on the diffuse albedo, a
/// constant ambient term.
pub(crate) struct AmbientEnvironment;

impl IndirectLight for AmbientEnvironment {
    fn opaque_indirect(
        &self,
        context: &RenderContext,
        query: &IndirectQuery,
        _worker: &mut WorkerState,
    ) -> Vec3 {
        AmbientEnvironment::radiance(context, query.weight, query.albedo)
    }

    fn is_ambient_environment(&self) -> bool {
        true
    }
}

impl AmbientEnvironment {
    /// The ambient light an opaque lobe of weight `weight` and albedo `albedo` reflects.
    #[inline]
    pub(crate) fn radiance(context: &RenderContext, weight: f32, albedo: Vec3) -> Vec3 {
        if context.effects.environment {
            weight * albedo * context.lights.environment.mean_radiance
        } else {
            Vec3::ZERO
        }
    }
}

/// Texture coordinates are needed for textured materials and for the camera hit's AOVs.
#[inline]
pub(super) fn surface_detail(
    context: &RenderContext,
    ray: &PathRay,
    hit: &TraceHit,
) -> SurfaceDetail {
    let camera_first = ray.kind == RayKind::Camera && ray.first_sample;
    texturing::surface_detail(context, camera_first, hit)
}

/// Shade the hit of `ray` at `surface`: its AOVs, emission and ambient light, the shadow
/// rays of its direct light, and the secondary rays of the next wave.
pub(super) fn shade_hit(
    context: &RenderContext,
    mut ray: PathRay,
    surface: &SurfaceHit,
    image: &mut TileImage,
    waves: &mut Waves,
    worker: &mut WorkerState,
    indirect: &dyn IndirectLight,
) {
    let effects = &context.effects;
    let options = &context.options;
    let material: &Material = &context.scene.materials[surface.material as usize];
    let inputs = arrive_at_hit(context, &mut ray, material, surface, image, worker);
    let albedo = inputs.albedo;

    // Emission leaves the front side, or both sides of a two-sided material, as the path
    // tracer's area lights do (`shading::area_lights`).
    let mut radiance =
        if shading::area_lights::emits_towards(material, surface.geometric_normal, ray.direction) {
            inputs.emission
        } else {
            Vec3::ZERO
        };
    // The index-matched case (the `fresnel` effect is off when every medium has ior 1)
    // reflects nothing but total internal reflection.
    let bsdf = MaterialBsdf::from_surface_inputs(
        material,
        &inputs,
        ray.direction,
        surface.geometric_normal,
        effects.fresnel.then_some(options.fresnel),
    );

    // Local illumination of the opaque lobe: direct light with shadow rays, plus indirect
    // light (Whitted: the ambient environment term); the delta lobes' rays below.
    let lobes = bsdf.whitted_lobes();
    // The geometric normal on the incident side: rays leaving on that side start above it.
    let ng = bsdf.mirror.ng;
    let shadows = effects.shadows && lobes.opaque.is_some();
    let mirror = lobes.mirror.filter(|_| effects.mirror_reflection);
    let boundary = lobes.boundary.filter(|_| effects.refraction);
    let spawns = ray.depth < options.max_depth && (mirror.is_some() || boundary.is_some());
    // The spawn point (with its error bounds) only when a ray leaves the hit.
    let spawn = (shadows || spawns).then(|| surface.spawn_point());
    if let Some(opaque) = lobes.opaque {
        if let (true, Some(spawn)) = (shadows, spawn) {
            queue_shadow_rays(context, &ray, opaque.lobe, opaque.weight, spawn, ng, waves);
        }
        let query = IndirectQuery {
            surface,
            spawn,
            geometric_normal: ng,
            outgoing: -ray.direction,
            bsdf: opaque.lobe,
            albedo,
            weight: opaque.weight,
        };
        radiance += indirect.opaque_indirect(context, &query, worker);
    }
    add_radiance(image, ray.slot, ray.throughput * radiance);

    let (true, Some(spawn)) = (spawns, spawn) else {
        return;
    };
    let spawner = Spawner {
        parent: &ray,
        spawn,
        min_throughput: options.min_throughput,
    };
    let surface = (&HitSurface::Made(surface), surface.material);
    if let Some(mirror) = mirror {
        let reflected = mirror.lobe.direction(-ray.direction);
        let weight = mirror.weight;
        spawner.spawn_reflection(context, surface.0, reflected, ng, weight, waves, worker);
    }
    if let Some(boundary) = boundary {
        scatter_dielectric(context, &ray, surface, boundary, &spawner, waves, worker);
    }
}

/// What `ray` brings to its hit before the hit's own light (the fog on the way is the
/// wave's, `fog::fog_wave_segments`): the camera hit's AOVs, absorption on the way, the
/// footprint carried there, and the material's inputs under that
/// footprint (also the camera hit's albedo AOV).
fn arrive_at_hit(
    context: &RenderContext,
    ray: &mut PathRay,
    material: &Material,
    surface: &SurfaceHit,
    image: &mut TileImage,
    worker: &mut WorkerState,
) -> SurfaceInputs {
    let effects = &context.effects;
    // The AOVs are written by first samples only, whose slot is their pixel.
    let camera_first = ray.kind == RayKind::Camera && ray.first_sample;
    if camera_first {
        write_geometry_aovs(context, image, ray.slot, ray.direction, surface);
    }
    // Beer's law over the distance travelled inside the medium.
    if effects.absorption && ray.sigma != Vec3::ZERO {
        ray.throughput *= shading::transmittance(ray.sigma, surface.t);
        worker.counters.absorption_evaluations += 1;
    }
    if effects.footprints {
        ray.footprint.transfer(ray.direction, surface);
        worker.counters.footprint_updates += 1;
    }
    let inputs = surface_inputs(context, ray, material, surface, image, worker);
    if camera_first {
        write_material_aovs(image, ray.slot, &inputs);
    }
    inputs
}

/// The material's shading inputs at the hit (`crate::shading::surface_inputs`): albedo,
/// emission and the normal-mapped shading normal, every texture filtered by the ray's
/// footprint. The base-colour lookup fills the first-lookup AOVs of the pixel.
pub(super) fn surface_inputs(
    context: &RenderContext,
    ray: &PathRay,
    material: &Material,
    surface: &SurfaceHit,
    image: &mut TileImage,
    worker: &mut WorkerState,
) -> SurfaceInputs {
    let lookup = LookupRay {
        direction: ray.direction,
        footprint: &ray.footprint,
        slot: ray.slot,
        first_sample: ray.first_sample,
    };
    texturing::surface_inputs(context, lookup, material, surface, image, worker)
}
