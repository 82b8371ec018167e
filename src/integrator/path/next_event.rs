//! Next-event estimation: at a hit, one light chosen by power, one point (or direction) on
//! it, and the shadow ray that delivers its light if nothing blocks it, weighted against
//! BSDF sampling by the power heuristic when the light has an area (or is the environment).
//! A scattering point inside fog does the same with its phase function in place of the
//! BSDF, and every shadow ray that reaches its light passes the exact transmittance
//! `exp(-tau)` of the fog on its segment (`crate::medium::segment_fog`).

use glam::{Vec2, Vec3};

use super::mis::power_heuristic;
use super::{add_radiance, LightStrategy, PathTracer, PathWaves};
use crate::film::TileImage;
use crate::integrator::texturing::environment_light_lookup;
use crate::integrator::trace_wave::{shadow_ray, shadow_trace_rays};
use crate::medium::{segment_fog, FogModel, HenyeyGreenstein};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::render::surface_textures::area_light_radiance;
use crate::shading::{self, Bsdf, LightRef, MaterialBsdf};

/// A shadow ray and the radiance it delivers to its pixel if unoccluded.
#[derive(Clone, Copy, Debug)]
pub(super) struct ShadowRay {
    pub(super) origin: Vec3,
    pub(super) direction: Vec3,
    /// Where the ray stops short of the light (`shading::shadow_ray_end`), or infinity.
    pub(super) tfar: f32,
    pub(super) contribution: Vec3,
    /// The colour-buffer slot the contribution goes to.
    pub(super) slot: u32,
}

/// What scatters light at a shading point: a surface's BSDF or a fog volume's phase
/// function.
pub(super) enum Scatterer<'a> {
    Surface {
        /// Geometric normal on the viewer's side.
        ng: Vec3,
        /// Shading normal on the viewer's side.
        ns: Vec3,
        bsdf: &'a MaterialBsdf,
        /// Whether the BSDF transmits with a density (a rough boundary), so that light
        /// from the far side reaches the viewer too.
        transmits: bool,
    },
    Medium(HenyeyGreenstein),
}

impl Scatterer<'_> {
    /// Whether light can arrive from `wi` at all: a surface takes it from its viewer's side,
    /// and from the far side when it transmits with a density.
    #[inline]
    fn admits(&self, wi: Vec3) -> bool {
        match self {
            Scatterer::Surface { ng, transmits, .. } => {
                let cos = wi.dot(*ng);
                cos > 0.0 || (*transmits && cos < 0.0)
            }
            Scatterer::Medium(_) => true,
        }
    }

    /// Whether `wi` leaves a surface on its far side.
    #[inline]
    fn crosses(&self, wi: Vec3) -> bool {
        match self {
            Scatterer::Surface { ng, .. } => wi.dot(*ng) < 0.0,
            Scatterer::Medium(_) => false,
        }
    }

    /// The factor light from `wi` is scattered towards `wo` by: `f |cos|` for a surface,
    /// the phase function's value for fog (light travels along `-wi` before scattering).
    #[inline]
    fn value(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            Scatterer::Surface { ns, bsdf, .. } => bsdf.eval(wo, wi) * ns.dot(wi).abs(),
            Scatterer::Medium(phase) => Vec3::splat(phase.eval(-wi, wo)),
        }
    }

    /// The density with which the path would have sampled `wi` itself.
    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Scatterer::Surface { bsdf, .. } => bsdf.pdf(wo, wi),
            Scatterer::Medium(phase) => phase.pdf(-wo, wi),
        }
    }
}

/// The shading point light sampling starts from.
pub(super) struct ShadingPoint<'a> {
    /// The point lights are seen from: the surface point itself (its spawn point's
    /// position) or the scattering point inside fog.
    pub(super) position: Vec3,
    /// Where shadow rays start: the hit's spawn point moved off the surface on the side of
    /// `ng`, or the scattering point inside fog.
    pub(super) origin: Vec3,
    /// Where shadow rays through a transmitting surface start: the spawn point moved off on
    /// the far side (unused otherwise).
    pub(super) origin_through: Vec3,
    /// Absorption coefficients of the media on the viewer's side and on the far side, for
    /// Beer's law along shadow rays (zero outside media).
    pub(super) sigma: Vec3,
    pub(super) sigma_through: Vec3,
    pub(super) wo: Vec3,
    pub(super) scatterer: Scatterer<'a>,
    pub(super) throughput: Vec3,
    /// The colour-buffer slot of the path.
    pub(super) slot: u32,
    /// True when no BSDF ray continues from this hit (the last bounce): light sampling then
    /// stands alone and is not weighted.
    pub(super) last: bool,
}

/// Choose a light with `u_light`, sample it with `u_point` and queue the shadow ray.
pub(super) fn sample_light(
    tracer: &PathTracer,
    context: &RenderContext,
    point: &ShadingPoint,
    u_light: f32,
    u_point: Vec2,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    let lights = &context.lights;
    let Some((light, pmf)) = lights.choose(u_light) else {
        return;
    };
    let strategy = tracer.strategy;
    // Delta lights always; lights with an area only when light sampling takes part.
    let (wi, distance, light_point, radiance, pdf) = match light {
        LightRef::Punctual(index) => {
            let light = &context.scene.lights[index];
            let sample = shading::sample_li(light, point.position);
            (
                sample.direction_to_light,
                sample.distance,
                shading::light_position(light).map(|position| (position.as_dvec3(), 0.0)),
                sample.radiance_scale,
                f32::INFINITY,
            )
        }
        _ if strategy == LightStrategy::BsdfSampling => return,
        LightRef::Environment => {
            let sample = lights.environment.sample_li(u_point);
            if !point.scatterer.admits(sample.wi) {
                return;
            }
            // The environment as a light: what a BSDF ray that finds it reads too
            // (`vertex::shade`), so that both strategies estimate one function.
            let radiance = environment_light_lookup(context, sample.wi, worker);
            (sample.wi, f32::INFINITY, None, radiance, sample.pdf)
        }
        LightRef::Area(index) => {
            let light = &lights.area.lights[index];
            let Some(sample) = light.sample(point.position, u_point) else {
                return;
            };
            // Emission textures are read at the sampled point, as for a ray that hits it.
            let radiance = area_light_radiance(context, light, sample.st, worker);
            (
                sample.direction_to_light,
                sample.distance,
                Some((sample.point, light.coordinate_scale())),
                radiance,
                sample.pdf,
            )
        }
    };
    if !point.scatterer.admits(wi) || radiance.max_element() <= 0.0 || pdf.is_nan() || pdf <= 0.0 {
        return;
    }
    let f = point.scatterer.value(point.wo, wi);
    if f.max_element() <= 0.0 {
        return;
    }
    // Delta lights carry irradiance (no density); lights with an area radiance over a
    // solid-angle density, weighted against the BSDF's density of the same direction.
    let contribution = if pdf.is_infinite() {
        point.throughput * f * radiance / pmf
    } else {
        let light_pdf = pmf * pdf;
        let weight = if point.last || strategy == LightStrategy::LightSampling {
            1.0
        } else {
            power_heuristic(light_pdf, point.scatterer.pdf(point.wo, wi))
        };
        point.throughput * f * radiance * (weight / light_pdf)
    };
    // Beer's law along the shadow ray inside an absorbing medium on its side.
    let crosses = point.scatterer.crosses(wi);
    let sigma = if crosses {
        point.sigma_through
    } else {
        point.sigma
    };
    let contribution = if context.effects.absorption && sigma != Vec3::ZERO {
        worker.counters.absorption_evaluations += 1;
        contribution * shading::transmittance(sigma, distance)
    } else {
        contribution
    };
    let largest = contribution.max_element();
    if largest.is_nan() || largest <= 0.0 {
        return;
    }
    // The light was seen from the surface point; the shadow ray asks only whether the
    // segment from the offset origin to the light's point is clear.
    let origin = if crosses {
        point.origin_through
    } else {
        point.origin
    };
    let Some((direction, tfar)) = shading::shadow_ray_towards(origin, light_point, wi) else {
        return;
    };
    // A sphere lamp hides nothing of itself from the surface point, but the offset origin
    // sits closer to it and sees less of it: the segment stops where it enters the lamp.
    let tfar = match light {
        LightRef::Area(index) => lights.area.lights[index].clip_shadow_ray(origin, direction, tfar),
        _ => tfar,
    };
    waves.shadows.push(ShadowRay {
        origin,
        direction,
        tfar,
        contribution,
        slot: point.slot,
    });
}

/// Trace the wave's shadow rays as one occlusion stream and add what reaches the lights.
/// Any surface blocks a shadow ray (light through glass arrives by BSDF-sampled paths).
/// With fog, what reaches a light is attenuated by the exact transmittance of the fog on
/// the shadow segment, evaluated only for the rays that are not blocked.
pub(super) fn trace_shadow_rays(
    context: &RenderContext,
    waves: &mut PathWaves,
    camera_wave: bool,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if waves.shadows.is_empty() {
        return;
    }
    let segments = waves
        .shadows
        .iter()
        .map(|s| (s.origin, s.direction, s.tfar));
    if camera_wave {
        // The camera wave's shadow rays are coherent: packets.
        shadow_trace_rays(segments, &mut waves.shadow_rays, &mut worker.counters);
        context.tracer.occluded_wave(
            &waves.shadow_rays,
            &mut waves.shadow_blocked,
            true,
            &mut worker.counters,
        );
    } else {
        // A later wave's shadow rays fill Embree's stream straight from the segments.
        worker
            .counters
            .count_rays(RayKind::Shadow, waves.shadows.len() as u64);
        context.tracer.occluded_stream(
            segments.map(|(origin, direction, tfar)| shadow_ray(origin, direction, tfar)),
            &mut waves.shadow_blocked,
            &mut worker.counters,
        );
    }
    for (shadow, blocked) in waves.shadows.iter().zip(&waves.shadow_blocked) {
        if *blocked {
            continue;
        }
        let mut contribution = shadow.contribution;
        if context.effects.fog {
            let fog = segment_fog(
                &context.scene.fog,
                shadow.origin,
                shadow.direction,
                shadow.tfar,
            );
            worker.counters.fog_segments += 1;
            worker.counters.fog_volume_crossings += u64::from(fog.crossed);
            // The path tracer's medium is Beer-Lambert's whatever `fog_model` says (the
            // clamped blend is Whitted's model of seed 004, not a transmittance).
            contribution *= fog.transmittance(FogModel::Exact);
        }
        add_radiance(image, shadow.slot, contribution);
    }
}
