//! Stage 6 of the path tracer's lanes: the BSDF of every lane, one loop per material's
//! range of lanes (the lanes are ordered by material), so that each loop runs one lobe's
//! code. A material without mirror or transmission runs its opaque lobe alone
//! (`shading::OpaqueOnly`: Lambert, Lambert plus Blinn-Phong, or glTF metallic-roughness);
//! any other runs the whole mixture (`shading::MaterialBsdf`), built per lane from the
//! lanes' inputs as `vertex::SurfaceVertex` builds it.
//!
//! Two passes: before the lights ([`test_smooth_parts`]), whether light sampling runs at
//! each lane; after them ([`scatter`]), what the light sample delivers through the BSDF,
//! weighted against BSDF sampling by the power heuristic (`next_event::sample_light`), and
//! the BSDF-sampled direction the path continues along (`vertex::continue_by_bsdf`), each
//! from the lane's own uniform numbers and with the scalar path's operations.

use std::ops::Range;

use glam::Vec3;

use super::lane_scatter::{LaneContinuation, ScatterLanes};
use super::lane_waves::PathLanes;
use super::next_event::{delta_contribution, weighted_contribution};
use super::vertex::{bsdf_has_smooth_part, medium_beyond, VertexSamples};
use super::{LightStrategy, PathTracer};
use crate::integrator::lanes::textures::lane_inputs;
use crate::integrator::lanes::WaveLanes;
use crate::integrator::trace_wave::ShadowRay;
use crate::render::context::{RenderContext, WorkerState};
use crate::scene::MaterialModel;
use crate::shading::{
    self, Bsdf, BsdfSample, LobeFlags, MaterialBsdf, MetallicRoughnessBsdf, OpaqueBsdf, OpaqueOnly,
    SpawnPoint,
};

/// A loop over one material's lanes, given the material and the lobe its lanes share.
trait MaterialLoop {
    fn run<B: Bsdf>(&mut self, material: u32, lanes: Range<usize>, lobe: impl Fn(usize) -> B);

    /// [`MaterialLoop::run`] for the classic opaque lobe, which draws its directions by the
    /// cosine about its normal alone, whatever the lanes' inputs: a loop may draw them for
    /// the whole range first.
    #[inline(always)]
    fn run_classic(
        &mut self,
        material: u32,
        lanes: Range<usize>,
        lobe: impl Fn(usize) -> OpaqueOnly<OpaqueBsdf>,
    ) {
        self.run(material, lanes, lobe)
    }

    /// [`MaterialLoop::run`] for a mixture whose every lobe with a weight is a delta lobe
    /// (a classic material with no opaque weight: mirror and smooth boundary alone), which
    /// gives every lane the same flags, with no density.
    #[inline(always)]
    fn run_delta_only<B: Bsdf>(
        &mut self,
        material: u32,
        lanes: Range<usize>,
        lobe: impl Fn(usize) -> B,
    ) {
        self.run(material, lanes, lobe)
    }
}

/// Run `each` over every material's range of lanes with its lobe.
#[inline(always)]
fn for_each_material(context: &RenderContext, lanes: &WaveLanes, each: &mut impl MaterialLoop) {
    let fresnel = context.effects.fresnel.then_some(context.options.fresnel);
    let (ns, albedo) = (&lanes.incident_shading, &lanes.albedo);
    let (roughness, metallic) = (&lanes.roughness, &lanes.metallic);
    for run in 0..lanes.material_runs.len() {
        let (index, range) = lanes.material_run(run);
        let material = &context.scene.materials[index as usize];
        // The mixture's weights are then (1, 0, 0) exactly.
        let opaque_only = material.mirror == 0.0 && material.transmission == 0.0;
        match &material.model {
            MaterialModel::Classic(classic) if opaque_only && classic.specular > 0.0 => each
                .run_classic(index, range, |lane| {
                    OpaqueOnly::classic(OpaqueBsdf {
                        n: ns.get(lane),
                        albedo: albedo.get(lane),
                        specular: classic.specular,
                        shininess: classic.shininess,
                    })
                }),
            // `OpaqueBsdf` reads `specular` only to test it for a positive value: the same
            // lobe with a constant 0 compiles to Lambert alone.
            MaterialModel::Classic(classic) if opaque_only => {
                each.run_classic(index, range, |lane| {
                    OpaqueOnly::classic(OpaqueBsdf {
                        n: ns.get(lane),
                        albedo: albedo.get(lane),
                        specular: 0.0,
                        shininess: classic.shininess,
                    })
                })
            }
            MaterialModel::MetallicRoughness(_) if opaque_only => each.run(index, range, |lane| {
                let lobe = MetallicRoughnessBsdf::new(
                    ns.get(lane),
                    albedo.get(lane),
                    roughness[lane],
                    metallic[lane],
                );
                OpaqueOnly::metallic_roughness(lobe)
            }),
            model => {
                let mixture = |lane| {
                    MaterialBsdf::from_surface_inputs(
                        material,
                        &lane_inputs(material, lanes, lane),
                        lanes.direction.get(lane),
                        lanes.geometric_normal.get(lane),
                        fresnel,
                    )
                };
                // The classic model has no rough boundary; with no opaque weight its
                // mixture keeps only the mirror and the smooth boundary.
                let opaque_weight = (1.0 - material.mirror) * (1.0 - material.transmission);
                if matches!(model, MaterialModel::Classic(_)) && opaque_weight <= 0.0 {
                    each.run_delta_only(index, range, mixture)
                } else {
                    each.run(index, range, mixture)
                }
            }
        }
    }
}

/// Which lanes sample a light (`ScatterLanes::samples_light`): those whose path scatters
/// here and whose BSDF has a part with a density that light from above the shading normal
/// reaches; and whether each BSDF transmits with a density.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(super) fn test_smooth_parts(
    context: &RenderContext,
    lanes: &WaveLanes,
    scatter: &mut ScatterLanes,
) {
    struct SmoothParts<'a> {
        lanes: &'a WaveLanes,
        scatter: &'a mut ScatterLanes,
    }
    impl MaterialLoop for SmoothParts<'_> {
        #[inline(always)]
        fn run<B: Bsdf>(&mut self, _: u32, range: Range<usize>, lobe: impl Fn(usize) -> B) {
            let scatter = &mut *self.scatter;
            for lane in range {
                if !scatter.active[lane] {
                    continue;
                }
                let bsdf = lobe(lane);
                let flags = bsdf.flags();
                scatter.transmits[lane] = flags.contains(LobeFlags::GLOSSY_TRANSMISSION);
                let wo = -self.lanes.direction.get(lane);
                let ns = self.lanes.incident_shading.get(lane);
                scatter.samples_light[lane] =
                    flags.has_density() && bsdf_has_smooth_part(&bsdf, wo, ns);
            }
        }

        /// Delta lobes alone: no lane transmits with a density or samples a light, as
        /// `ScatterLanes::reset` left them, so no lane's mixture is built here.
        #[inline(always)]
        fn run_delta_only<B: Bsdf>(&mut self, _: u32, _: Range<usize>, _: impl Fn(usize) -> B) {}
    }
    for_each_material(context, lanes, &mut SmoothParts { lanes, scatter });
}

/// What each lane's light sample delivers through its BSDF if unoccluded, and whether its
/// shadow ray is queued; and the BSDF sample its path continues along, if it continues.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(super) fn scatter(
    tracer: &PathTracer,
    context: &RenderContext,
    path: &mut PathLanes,
    worker: &mut WorkerState,
) {
    let PathLanes {
        lanes,
        scatter,
        vertex_samples,
        ..
    } = path;
    let mut scattering = Scattering {
        context,
        light_alone: tracer.strategy == LightStrategy::LightSampling,
        lanes,
        samples: vertex_samples,
        scatter,
        worker,
    };
    for_each_material(context, lanes, &mut scattering);
}

/// The lanes of one material in [`scatter`].
struct Scattering<'a> {
    context: &'a RenderContext,
    /// Light sampling stands alone (`LightStrategy::LightSampling`): never weighted.
    light_alone: bool,
    lanes: &'a WaveLanes,
    samples: &'a [VertexSamples],
    scatter: &'a mut ScatterLanes,
    worker: &'a mut WorkerState,
}

impl MaterialLoop for Scattering<'_> {
    #[inline(always)]
    fn run<B: Bsdf>(&mut self, material: u32, range: Range<usize>, lobe: impl Fn(usize) -> B) {
        self.each_lane(material, range, lobe, |bsdf, wo, u, _| {
            bsdf.sample(wo, u.lobe, u.direction)
        });
    }

    /// The cosine's directions drawn for the whole range in three short loops (the disk's
    /// polar coordinates, their cosines and sines, the lift onto the hemisphere), whose
    /// lanes the processor overlaps and the compiler vectorises, then each lane as
    /// [`MaterialLoop::run`] takes it, with its drawn direction.
    #[inline(always)]
    fn run_classic(
        &mut self,
        material: u32,
        range: Range<usize>,
        lobe: impl Fn(usize) -> OpaqueOnly<OpaqueBsdf>,
    ) {
        self.draw_cosine_directions(range.clone());
        self.each_lane(material, range, lobe, |bsdf, wo, _, wi| {
            bsdf.sample_along(wo, wi)
        });
    }
}

impl Scattering<'_> {
    /// Each active lane of `range`: the light its sample delivers, then its continuation,
    /// drawn by `draw` from the BSDF, the outgoing direction, the lane's vertex numbers and
    /// its drawn cosine direction (read only by the classic lobe's runs).
    #[inline(always)]
    fn each_lane<B: Bsdf>(
        &mut self,
        material: u32,
        range: Range<usize>,
        lobe: impl Fn(usize) -> B,
        draw: impl Fn(&B, Vec3, &VertexSamples, Vec3) -> Option<BsdfSample>,
    ) {
        for lane in range {
            if !self.scatter.active[lane] {
                continue;
            }
            let bsdf = lobe(lane);
            if self.scatter.lit[lane] {
                self.deliver_light(material, lane, &bsdf);
            }
            let wi = self.scatter.cosine_wi.get(lane);
            self.sample_continuation(lane, &bsdf, |wo, u| draw(&bsdf, wo, u, wi));
        }
    }

    /// `next_event::sample_light` after the light's sample, and `queue_shadow_ray` up to
    /// the queue: the BSDF's value and, for a light with an area, the power heuristic
    /// against BSDF sampling; Beer's law inside the medium the shadow ray crosses.
    #[inline(always)]
    fn deliver_light(&mut self, material: u32, lane: usize, bsdf: &impl Bsdf) {
        let (lanes, scatter) = (self.lanes, &mut *self.scatter);
        let wo = -lanes.direction.get(lane);
        let ns = lanes.incident_shading.get(lane);
        let wi = scatter.light_wi.get(lane);
        let f = bsdf.eval(wo, wi) * ns.dot(wi).abs();
        if f.max_element() <= 0.0 {
            return;
        }
        let unweighted = lanes.throughput.get(lane) * f * scatter.radiance.get(lane);
        let pmf = scatter.pmf[lane];
        let contribution = if scatter.delta[lane] {
            delta_contribution(unweighted, pmf)
        } else {
            // No BSDF ray competes when none continues along a non-delta lobe.
            let alone = !scatter.rough_continues[lane] || self.light_alone;
            let light_pdf = pmf * scatter.light_pdf[lane];
            weighted_contribution(unweighted, light_pdf, alone, || bsdf.pdf(wo, wi))
        };
        let ng = lanes.incident_geometric.get(lane);
        let sigma = if wi.dot(ng) < 0.0 {
            medium_beyond(self.context, material, arrives_on_front(lanes, lane))
        } else {
            scatter.sigma.get(lane)
        };
        let contribution = if self.context.effects.absorption && sigma != Vec3::ZERO {
            self.worker.counters.absorption_evaluations += 1;
            contribution * shading::transmittance(sigma, scatter.light_distance[lane])
        } else {
            contribution
        };
        let largest = contribution.max_element();
        if largest.is_nan() || largest <= 0.0 || !scatter.segment[lane] {
            return;
        }
        scatter.shadow[lane] = Some(ShadowRay {
            origin: scatter.shadow_origin.get(lane),
            direction: scatter.shadow_direction.get(lane),
            tfar: scatter.shadow_tfar[lane],
            light: None,
            contribution,
            slot: 0,
        });
    }

    /// The cosine-distributed direction about each lane's shading normal
    /// (`bsdf::sample_cosine_hemisphere`) from its vertex numbers, for the lanes of `range`
    /// whose paths may continue along a rough lobe, into `ScatterLanes::cosine_wi`.
    #[inline(always)]
    fn draw_cosine_directions(&mut self, range: Range<usize>) {
        let (lanes, scatter) = (self.lanes, &mut *self.scatter);
        for lane in range.clone() {
            (scatter.disk_radius[lane], scatter.disk_angle[lane]) =
                shading::concentric_polar(self.samples[lane].direction);
        }
        for lane in range.clone() {
            if scatter.active[lane] && scatter.rough_continues[lane] {
                let angle = scatter.disk_angle[lane];
                (scatter.disk_cos[lane], scatter.disk_sin[lane]) = (angle.cos(), angle.sin());
            }
        }
        for lane in range {
            let (r, cos, sin) = (
                scatter.disk_radius[lane],
                scatter.disk_cos[lane],
                scatter.disk_sin[lane],
            );
            let n = lanes.incident_shading.get(lane);
            let wi = shading::lift_to_hemisphere(n, shading::disk_point(r, cos, sin));
            scatter.cosine_wi.set(lane, wi);
        }
    }

    /// `vertex::continue_by_bsdf` up to the queue: the BSDF's sample (`draw`, given the
    /// outgoing direction and the lane's vertex numbers), unless the depth, the
    /// diffuse-bounce limit or a rough lobe's leak below the surface ends the path.
    #[inline(always)]
    fn sample_continuation(
        &mut self,
        lane: usize,
        bsdf: &impl Bsdf,
        draw: impl FnOnce(Vec3, &VertexSamples) -> Option<BsdfSample>,
    ) {
        let (lanes, scatter) = (self.lanes, &mut *self.scatter);
        if !scatter.continues[lane] && !bsdf.flags().is_specular() {
            return;
        }
        let wo = -lanes.direction.get(lane);
        let Some(sample) = draw(wo, &self.samples[lane]) else {
            return;
        };
        let delta = sample.is_specular();
        if !delta && !scatter.rough_continues[lane] {
            return;
        }
        let wi = sample.wi;
        let ng = lanes.incident_geometric.get(lane);
        let crosses = wi.dot(ng) < 0.0;
        if crosses && !delta && !scatter.transmits[lane] {
            return;
        }
        let value = if self.context.effects.footprints && !delta {
            bsdf.eval(wo, wi)
        } else {
            Vec3::ZERO
        };
        let front = arrives_on_front(lanes, lane);
        scatter.next[lane] = Some(LaneContinuation {
            sample,
            crosses,
            value,
            spawn: SpawnPoint {
                position: lanes.position.get(lane),
                error: lanes.error.get(lane),
            },
            ng,
            front,
        });
    }
}

/// Whether the lane's ray arrived on the front of its surface (against the geometric
/// normal), as `vertex::SurfaceVertex::front` says for one ray.
#[inline(always)]
fn arrives_on_front(lanes: &WaveLanes, lane: usize) -> bool {
    lanes
        .direction
        .get(lane)
        .dot(lanes.geometric_normal.get(lane))
        < 0.0
}
