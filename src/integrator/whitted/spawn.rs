//! Secondary rays leaving a hit: queued for the next wave with the parent's throughput
//! times their weight, from the hit's spawn point, unless too weak to matter (seed 001).

use glam::Vec3;

use super::{PathRay, Waves};
use crate::footprint::Footprint;
use crate::hit::SurfaceHit;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::stats::RayKind;
use crate::shading::{self, SpawnPoint};

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
    pub(super) fn spawn_reflection(
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
pub(super) fn reflect_above(direction: Vec3, ns: Vec3, ng: Vec3) -> Vec3 {
    let r = shading::reflect(direction, ns);
    if r.dot(ng) > 0.0 {
        r
    } else {
        shading::reflect(direction, ng)
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
