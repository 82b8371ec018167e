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
use crate::integrator::trace_wave::ShadowRay;
use crate::medium::{segment_fog, FogModel, HenyeyGreenstein};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::surface_textures::area_light_radiance;
use crate::shading::{
    self, AreaLight, Bsdf, EmissionLookup, EnvironmentLight, LiSample, LightRef, MaterialBsdf,
};

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
            Scatterer::Surface { ng, transmits, .. } => surface_admits(*ng, *transmits, wi),
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

/// Whether a surface whose geometric normal on the viewer's side is `ng` receives light
/// from `wi`: from the viewer's side, and from the far side when it `transmits` with a
/// density.
#[inline(always)]
pub(super) fn surface_admits(ng: Vec3, transmits: bool, wi: Vec3) -> bool {
    let cos = wi.dot(ng);
    cos > 0.0 || (transmits && cos < 0.0)
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
    let delta = lights.is_delta(light);
    // Delta lights always; lights with an area only when light sampling takes part.
    if !delta && strategy == LightStrategy::BsdfSampling {
        return;
    }
    let mut emission = AdmittedEmission {
        admits: |wi| point.scatterer.admits(wi),
        lookup: ContextEmission { context, worker },
    };
    let Some(sample) = lights.sample_li(light, point.position, u_point, &mut emission) else {
        return;
    };
    let (wi, pdf) = (sample.wi, sample.pdf);
    if !point.scatterer.admits(wi)
        || sample.radiance.max_element() <= 0.0
        || pdf.is_nan()
        || pdf <= 0.0
    {
        return;
    }
    let f = point.scatterer.value(point.wo, wi);
    if f.max_element() <= 0.0 {
        return;
    }
    let unweighted = point.throughput * f * sample.radiance;
    let contribution = if delta {
        delta_contribution(unweighted, pmf)
    } else {
        let alone = point.last || strategy == LightStrategy::LightSampling;
        weighted_contribution(unweighted, pmf * pdf, alone, || {
            point.scatterer.pdf(point.wo, wi)
        })
    };
    queue_shadow_ray(context, point, light, &sample, contribution, waves, worker);
}

/// Queue the shadow ray towards `sample` of `light`, carrying `contribution` (attenuated by
/// Beer's law inside an absorbing medium on its side) if nothing blocks it.
fn queue_shadow_ray(
    context: &RenderContext,
    point: &ShadingPoint,
    light: LightRef,
    sample: &LiSample,
    contribution: Vec3,
    waves: &mut PathWaves,
    worker: &mut WorkerState,
) {
    let wi = sample.wi;
    let crosses = point.scatterer.crosses(wi);
    let sigma = if crosses {
        point.sigma_through
    } else {
        point.sigma
    };
    let contribution = if context.effects.absorption && sigma != Vec3::ZERO {
        worker.counters.absorption_evaluations += 1;
        contribution * shading::transmittance(sigma, sample.distance)
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
    let Some((direction, tfar)) = shadow_segment(context, light, origin, sample) else {
        return;
    };
    waves.shadows.push(ShadowRay {
        origin,
        direction,
        tfar,
        light: None,
        contribution,
        slot: point.slot,
    });
}

/// The shadow ray from `origin` towards `sample` of `light`: its unit direction and far
/// end, `None` when the sampled point coincides with the origin.
#[inline(always)]
pub(super) fn shadow_segment(
    context: &RenderContext,
    light: LightRef,
    origin: Vec3,
    sample: &LiSample,
) -> Option<(Vec3, f32)> {
    let (direction, tfar) = shading::shadow_ray_towards(origin, sample.light_point, sample.wi)?;
    // A sphere lamp hides nothing of itself from the surface point, but the offset origin
    // sits closer to it and sees less of it: the segment stops where it enters the lamp.
    let tfar = match light {
        LightRef::Area(index) => {
            context.lights.area.lights[index].clip_shadow_ray(origin, direction, tfar)
        }
        _ => tfar,
    };
    Some((direction, tfar))
}

/// What a delta light's sample adds: it arrives from one direction with probability 1, so
/// no BSDF-sampled ray finds it and only the choice of the light (`pmf`) divides it.
#[inline]
pub(super) fn delta_contribution(unweighted: Vec3, pmf: f32) -> Vec3 {
    unweighted / pmf
}

/// What a sample of a light with an area (or the environment) adds, drawn with density
/// `light_pdf` (choice times direction): weighted by the power heuristic against the density
/// `bsdf_pdf()` with which BSDF sampling draws the same direction, unless it stands
/// `alone`. A density that overflowed to infinity leaves nothing.
#[inline]
pub(super) fn weighted_contribution(
    unweighted: Vec3,
    light_pdf: f32,
    alone: bool,
    bsdf_pdf: impl FnOnce() -> f32,
) -> Vec3 {
    let weight = if alone {
        1.0
    } else {
        power_heuristic(light_pdf, bsdf_pdf())
    };
    unweighted * (weight / light_pdf)
}

/// Emission read by the render stage's texture lookups: the environment as a BSDF-sampled
/// ray that escapes reads it, and area lights' emission textures at the sampled point.
pub(super) struct ContextEmission<'a, 'w> {
    pub(super) context: &'a RenderContext,
    pub(super) worker: &'w mut WorkerState,
}

impl EmissionLookup for ContextEmission<'_, '_> {
    #[inline]
    fn environment(&mut self, _environment: &EnvironmentLight, wi: Vec3) -> Vec3 {
        environment_light_lookup(self.context, wi, self.worker)
    }

    #[inline]
    fn area(&mut self, light: &AreaLight, st: Vec2) -> Vec3 {
        area_light_radiance(self.context, light, st, self.worker)
    }
}

/// [`ContextEmission`] for a shading point: a direction it cannot receive light from
/// (`admits` false) reads nothing (black), as its sample is dropped anyway.
pub(super) struct AdmittedEmission<'a, 'w, A> {
    pub(super) admits: A,
    pub(super) lookup: ContextEmission<'a, 'w>,
}

impl<A: Fn(Vec3) -> bool> EmissionLookup for AdmittedEmission<'_, '_, A> {
    #[inline]
    fn environment(&mut self, environment: &EnvironmentLight, wi: Vec3) -> Vec3 {
        if (self.admits)(wi) {
            self.lookup.environment(environment, wi)
        } else {
            Vec3::ZERO
        }
    }

    #[inline]
    fn area(&mut self, light: &AreaLight, st: Vec2) -> Vec3 {
        self.lookup.area(light, st)
    }
}

/// Trace the wave's shadow rays (`WaveBuffers::trace_shadow_segments`) and add what reaches
/// the lights.
/// Any surface blocks a shadow ray (light through glass arrives by BSDF-sampled paths).
/// With fog, what reaches a light is attenuated by the exact transmittance of the fog on
/// the shadow segment, evaluated only for the rays that are not blocked.
pub(super) fn trace_shadow_rays(
    context: &RenderContext,
    waves: &mut PathWaves,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if waves.shadows.is_empty() {
        return;
    }
    waves
        .buffers
        .trace_shadow_segments(context, &waves.shadows, &mut worker.counters);
    for (shadow, blocked) in waves.shadows.iter().zip(&waves.buffers.shadow_blocked) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_delta_light_is_divided_by_its_choice_alone() {
        let unweighted = Vec3::new(0.5, 1.0, 2.0);
        assert_eq!(delta_contribution(unweighted, 0.25), unweighted * 4.0);
    }

    #[test]
    fn a_light_sample_with_an_overflowed_density_adds_nothing() {
        // A density that overflowed: the sample is worth nothing, however the weight comes
        // out (no density stands for a delta light).
        let unweighted = Vec3::splat(3.0);
        for alone in [false, true] {
            let contribution = weighted_contribution(unweighted, f32::INFINITY, alone, || 0.7);
            assert_eq!(contribution, Vec3::ZERO, "alone: {alone}");
        }
        // A finite density: p_l^2 / (p_l^2 + p_b^2) / p_l, with p_l = 2 and p_b = 1.
        let weighted = weighted_contribution(unweighted, 2.0, false, || 1.0);
        assert!(
            (weighted - unweighted * 0.4).abs().max_element() < 1e-6,
            "{weighted}"
        );
        assert_eq!(
            weighted_contribution(unweighted, 2.0, true, || 1.0),
            unweighted * 0.5
        );
    }
}
