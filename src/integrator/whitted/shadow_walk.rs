//! The shadow walk: shadow rays traced as occlusion queries, or, when some surfaces
//! transmit, walked through each transmissive occluder they meet, attenuated by its
//! transmission and by Beer's law inside its medium (seed 001, "Shadow Rays"; seed 004).

use glam::Vec3;

use super::lights::{shadow_tfar, ShadowRay};
use super::{add_radiance, Waves};
use crate::film::TileImage;
use crate::integrator::camera_sample::slot_place;
use crate::integrator::trace_wave::shadow_trace_rays;
use crate::integrator::wave_order::group_by_place;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::SurfaceDetail;
use crate::render::stats::RayKind;
use crate::render::tracer::TraceRay;
use crate::shading;

/// Shadow rays stop passing through transmissive occluders below this strength (seed 001).
pub(super) const SHADOW_CUTOFF: f32 = 0.002;
/// At most this many transmissive occluders are crossed by one shadow ray.
pub(super) const MAX_SHADOW_CROSSINGS: u32 = 16;

/// Reused state of shadow rays walking through transmissive occluders.
#[derive(Default)]
pub(super) struct ShadowWalk {
    pub(super) strength: Vec<Vec3>,
    pub(super) active: Vec<usize>,
    pub(super) still_active: Vec<usize>,
    pub(super) entered_at: Vec<f32>,
    pub(super) travelled: Vec<f32>,
    pub(super) batch: Vec<TraceRay>,
}

/// Trace the wave's shadow rays as occlusion packets and add what reaches the lights.
/// With transmissive occluders, a shadow ray is attenuated by each one it crosses (seed 001).
pub(super) fn trace_shadows(
    context: &RenderContext,
    waves: &mut Waves,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if waves.shadows.is_empty() {
        return;
    }
    // A camera wave's shadow rays belong to all samples in flight, a later wave's to one.
    let camera_wave = waves.camera_wave;
    let places = if camera_wave { waves.in_flight } else { 1 };
    let tile_pixels = waves.tile_pixels;
    let place = |shadow: &ShadowRay| {
        if places > 1 {
            slot_place(shadow.slot, tile_pixels) as usize
        } else {
            0
        }
    };
    if context.effects.transmissive_shadows && places > 1 {
        // The walk finds closest hits: each sample's shadow rays are traced as their own
        // stream (`Tracer::intersect_grouped`), as a render of that sample alone traces them.
        group_by_place(
            &mut waves.shadows,
            &mut waves.shadow_scratch,
            &mut waves.shadow_order,
            place,
            places,
            &mut waves.group_ends,
        );
    }
    shadow_trace_rays(
        waves
            .shadows
            .iter()
            .map(|s| (s.origin, s.direction, s.tfar)),
        &mut waves.shadow_rays,
        &mut worker.counters,
    );
    if !context.effects.transmissive_shadows {
        // A camera wave's shadow rays are coherent: a packet holds one pixel's samples.
        context.tracer.occluded_wave(
            &waves.shadow_rays,
            &mut waves.shadow_blocked,
            camera_wave,
            &mut worker.counters,
        );
        for (shadow, blocked) in waves.shadows.iter().zip(&waves.shadow_blocked) {
            if !blocked {
                add_radiance(image, shadow.slot, delivered(context, shadow, worker));
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
        // The batch keeps the shadows' order, grouped by sample: where each group ends.
        waves.group_ends.clear();
        for (index, &i) in walk.active.iter().enumerate() {
            let p = place(&waves.shadows[i]);
            while waves.group_ends.len() < p {
                waves.group_ends.push(index);
            }
        }
        waves.group_ends.resize(places, walk.batch.len());
        context.tracer.intersect_grouped(
            &walk.batch,
            &waves.group_ends,
            &mut waves.trace_hits,
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
            add_radiance(image, shadow.slot, delivered(context, shadow, worker) * *s);
        }
    }
}

/// What an unblocked shadow ray delivers: its contribution, times the fog's transmittance
/// along the whole shadow segment when the scene has fog (evaluated only for rays that
/// reach their light, and once for a walk through transmissive occluders, whose pieces lie
/// on one line).
#[inline]
fn delivered(context: &RenderContext, shadow: &ShadowRay, worker: &mut WorkerState) -> Vec3 {
    if context.effects.fog {
        let t = super::fog::shadow_transmittance(
            context,
            shadow.origin,
            shadow.direction,
            shadow.tfar,
            worker,
        );
        shadow.contribution * t
    } else {
        shadow.contribution
    }
}
