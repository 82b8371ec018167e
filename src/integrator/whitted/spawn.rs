//! Secondary rays leaving a hit: queued for the next wave with the parent's throughput
//! times their weight, from the hit's spawn point, unless too weak to matter (seed 001).
//! Their footprints read the hit record ([`HitSurface`]), which the shading lanes make only
//! when a footprint needs it.

use std::cell::OnceCell;

use glam::Vec3;

use super::{PathRay, Waves};
use crate::footprint::{curvature_at, Footprint};
use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::render::tracer::TraceHit;
use crate::shading::SpawnPoint;

/// What a secondary ray's footprint reads of its hit (a cone's curvature, a differential's
/// normal and its derivatives): the scalar path's hit record, or, for a hit shaded in lanes
/// (`lane_waves`), the curvature the lanes know, and a record made from the trace hit the
/// first time a footprint asks, as the scalar path makes it.
pub(super) enum HitSurface<'a> {
    Made(&'a SurfaceHit),
    Deferred {
        /// The hit of `ray`, the wave's ray as traced.
        hit: &'a TraceHit,
        ray: &'a PathRay,
        /// The surface's curvature as `footprint::curvature_at` computes it before signing
        /// it for the arriving side (`None`: from the record), and the unit geometric
        /// normal, facing outward, that signs it.
        curvature: Option<f32>,
        geometric_normal: Vec3,
        /// The record once made (held by the caller, so the enum stays small).
        record: &'a OnceCell<SurfaceHit>,
    },
}

impl HitSurface<'_> {
    /// The hit record, made as `whitted::shade_hits` makes it for the scalar path.
    pub(super) fn record(&self, context: &RenderContext) -> &SurfaceHit {
        match self {
            HitSurface::Made(surface) => surface,
            HitSurface::Deferred {
                hit, ray, record, ..
            } => record.get_or_init(|| {
                let detail = super::surface::surface_detail(context, ray, hit);
                context
                    .surfaces
                    .surface_hit(ray.origin, ray.direction, hit, detail)
            }),
        }
    }

    /// The curvature seen by a ray along `direction` (`footprint::curvature_at`).
    pub(super) fn curvature(&self, context: &RenderContext, direction: Vec3) -> f32 {
        match self {
            HitSurface::Deferred {
                curvature: Some(k),
                geometric_normal,
                ..
            } => {
                // `SurfaceHit::is_front_face`.
                if direction.dot(*geometric_normal) < 0.0 {
                    *k
                } else {
                    -*k
                }
            }
            _ => curvature_at(self.record(context), direction),
        }
    }
}

/// Spawns the secondary rays of one hit.
pub(super) struct Spawner<'a> {
    pub(super) parent: &'a PathRay,
    /// The hit's position with its error bound: rays start just past it.
    pub(super) spawn: SpawnPoint,
    pub(super) min_throughput: f32,
}

impl Spawner<'_> {
    /// Queue a ray leaving the surface on the side of `leave_normal`, unless its throughput
    /// has fallen below the threshold (seed 001's "contribution too small" rule).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn spawn(
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
        waves.buffers.rays.next.push(PathRay {
            origin: self.spawn.offset_origin(leave_normal),
            direction,
            start: 0.0,
            throughput,
            footprint,
            slot: self.parent.slot,
            depth: self.parent.depth + 1,
            kind,
            sigma,
            first_sample: self.parent.first_sample,
        });
    }

    /// Queue the mirror reflection `reflected` of the parent ray (leaving on the side of the
    /// geometric normal `ng`, which faces the incident ray) with weight `weight`, its
    /// footprint reflected too.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn spawn_reflection(
        &self,
        context: &RenderContext,
        surface: &HitSurface,
        reflected: Vec3,
        ng: Vec3,
        weight: f32,
        waves: &mut Waves,
        worker: &mut WorkerState,
    ) {
        let ray = self.parent;
        let footprint = footprint_reflect(context, ray, surface, reflected, worker);
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

/// The footprint of `ray` (moved to its hit) mirrored into `reflected`.
#[inline]
fn footprint_reflect(
    context: &RenderContext,
    ray: &PathRay,
    surface: &HitSurface,
    reflected: Vec3,
    worker: &mut WorkerState,
) -> Footprint {
    if !context.effects.footprints {
        return ray.footprint;
    }
    worker.counters.footprint_updates += 1;
    ray.footprint.reflect_with(
        ray.direction,
        reflected,
        || surface.curvature(context, ray.direction),
        || surface.record(context),
    )
}
