//! The shadow walk: shadow rays traced as occlusion queries, or, when some surfaces
//! transmit, walked through each transmissive occluder they meet, attenuated by its
//! transmission and by Beer's law inside its medium (seed 001, "Shadow Rays"; seed 004).

use glam::Vec3;

use super::lights::shadow_tfar;
use super::{add_radiance, Waves};
use crate::film::TileImage;
use crate::integrator::camera_sample::slot_place;
use crate::integrator::trace_wave::shadow_trace_rays;
use crate::integrator::trace_wave::ShadowRay;
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

/// Trace the wave's shadow rays and add what reaches the lights: as occlusion queries
/// (`WaveBuffers::trace_shadow_segments`), or, with transmissive occluders, walked through
/// each one they cross and attenuated by it (`walk_shadows`).
pub(super) fn trace_shadows(
    context: &RenderContext,
    waves: &mut Waves,
    image: &mut TileImage,
    worker: &mut WorkerState,
) {
    if waves.shadows.is_empty() {
        return;
    }
    if !context.effects.transmissive_shadows {
        // A camera wave's shadow rays are coherent: a packet holds one pixel's samples.
        waves
            .buffers
            .trace_shadow_segments(context, &waves.shadows, &mut worker.counters);
        for (shadow, blocked) in waves.shadows.iter().zip(&waves.buffers.shadow_blocked) {
            if !blocked {
                add_radiance(image, shadow.slot, delivered(context, shadow, worker));
            }
        }
        return;
    }
    walk_shadows(context, waves, worker);
    for (shadow, s) in waves.shadows.iter().zip(&waves.walk.strength) {
        if s.max_element() > 0.0 {
            add_radiance(image, shadow.slot, delivered(context, shadow, worker) * *s);
        }
    }
}

/// Walk each of the wave's shadow rays through the surfaces it meets, up to
/// [`MAX_SHADOW_CROSSINGS`] of them, leaving in `waves.walk.strength` what of its light
/// reaches the shading point (zero when an opaque surface blocks it).
fn walk_shadows(context: &RenderContext, waves: &mut Waves, worker: &mut WorkerState) {
    // A camera wave's shadow rays belong to all samples in flight, a later wave's to one.
    let places = if waves.buffers.camera_wave {
        waves.buffers.in_flight
    } else {
        1
    };
    let tile_pixels = waves.buffers.tile_pixels;
    let place = |shadow: &ShadowRay| {
        if places > 1 {
            slot_place(shadow.slot, tile_pixels) as usize
        } else {
            0
        }
    };
    if places > 1 {
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
        &waves.shadows,
        &mut waves.buffers.shadow_rays,
        &mut worker.counters,
    );
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
        if waves.walk.active.is_empty() {
            break;
        }
        trace_walk_batch(context, waves, places, &place, worker);
        waves.walk.still_active.clear();
        for slot in 0..waves.walk.active.len() {
            let i = waves.walk.active[slot];
            if cross_occluder(context, waves, slot, i, worker) {
                waves.walk.still_active.push(i);
            }
        }
        let walk = &mut waves.walk;
        std::mem::swap(&mut walk.active, &mut walk.still_active);
    }
    for &i in &waves.walk.active {
        // Ran out of crossings: treat as blocked.
        waves.walk.strength[i] = Vec3::ZERO;
    }
}

/// The closest hits of the walk's active shadow rays, into `waves.buffers.trace_hits` in
/// the order of `waves.walk.active`, each sample's rays traced as their own group.
fn trace_walk_batch(
    context: &RenderContext,
    waves: &mut Waves,
    places: usize,
    place: &impl Fn(&ShadowRay) -> usize,
    worker: &mut WorkerState,
) {
    let walk = &mut waves.walk;
    walk.batch.clear();
    walk.batch
        .extend(walk.active.iter().map(|&i| waves.buffers.shadow_rays[i]));
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
        &mut waves.buffers.trace_hits,
        &mut worker.counters,
    );
}

/// The walk's shadow ray `i`, the batch's ray `slot`, at what it hit: a miss reaches the
/// light; an opaque surface blocks it; a transmissive one attenuates it by its transmission
/// and, leaving its medium, by Beer's law over the distance inside, and the ray
/// continues past it towards the light. Returns whether it continues.
fn cross_occluder(
    context: &RenderContext,
    waves: &mut Waves,
    slot: usize,
    i: usize,
    worker: &mut WorkerState,
) -> bool {
    let hit = waves.buffers.trace_hits[slot];
    if !hit.is_hit() {
        return false;
    }
    let walk = &mut waves.walk;
    let ray = walk.batch[slot];
    let surface =
        context
            .surfaces
            .surface_hit(ray.origin, ray.direction, &hit, SurfaceDetail::Geometry);
    let material = &context.scene.materials[surface.material as usize];
    if material.transmission <= 0.0 {
        walk.strength[i] = Vec3::ZERO;
        return false;
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
        return false;
    }
    let leave = if front {
        -surface.geometric_normal
    } else {
        surface.geometric_normal
    };
    let origin = surface.spawn_point().offset_origin(leave);
    let moved = (origin - ray.origin).dot(ray.direction);
    walk.travelled[i] += moved;
    // The far end is measured again from the new origin, not carried over, so its margin
    // does not depend on how far the walk has come.
    let light = waves.shadows[i].light;
    let remaining = match light {
        Some(position) => shadow_tfar((position - origin).length(), light),
        None => ray.tfar - moved,
    };
    if remaining <= 0.0 {
        return false;
    }
    waves.buffers.shadow_rays[i] = TraceRay {
        origin,
        tfar: remaining,
        ..ray
    };
    worker.counters.count_rays(RayKind::Shadow, 1);
    true
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
