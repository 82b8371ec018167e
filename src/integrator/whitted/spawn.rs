//! Secondary rays leaving a hit: queued for the next wave with the parent's throughput
//! times their weight, from the hit's spawn point, unless too weak to matter (seed 001).

use glam::Vec3;

use super::{PathRay, Waves};
use crate::footprint::Footprint;
use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::shading::SpawnPoint;

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
        surface: &SurfaceHit,
        reflected: Vec3,
        ng: Vec3,
        weight: f32,
        waves: &mut Waves,
        worker: &mut WorkerState,
    ) {
        let ray = self.parent;
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

#[inline]
pub(super) fn footprint_reflect(
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
