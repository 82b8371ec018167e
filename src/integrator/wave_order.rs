//! The order a run of samples is traced in, shared by the wave integrators.
//!
//! A run ([`crate::integrator::camera_sample::SampleRun`]) holds up to 16 samples of every
//! pixel of a tile (Whitted and voxel cone tracing take 16, the path tracer one). Its
//! camera rays are traced first, in waves of [`CAMERA_WAVE_RAYS`] rays cut from the packet
//! order (a pixel's samples together), so that each packet is one pixel's samples and a
//! wave's rays, hits and shadow rays stay in the core's caches. The
//! rays those waves spawn are then grouped by sample, and each sample continues on its own,
//! wave after wave, over the whole tile: exactly the waves, in the same order, that a render
//! of that sample alone traces. Embree packs an incoherent stream into packets of its own
//! choosing, and which of two triangles hit at the same distance it reports can depend on
//! the packet; grouped this way, no stream depends on which other samples are in flight,
//! and a render split by sample range adds up to the whole render bit for bit.

use crate::integrator::trace_wave::{trace_wave, WaveRay};
use crate::render::stats::WorkCounters;
use crate::render::tracer::{TraceHit, TraceRay};
use crate::render::RenderContext;

/// Camera rays per camera wave: 16 packets.
pub(crate) const CAMERA_WAVE_RAYS: usize = 256;

/// The queues of rays a wave integrator keeps for a tile, reused from tile to tile.
pub(crate) struct WaveQueues<R> {
    /// The wave being traced and the rays it spawns; for a camera wave, whether the render
    /// keeps each of its rays.
    pub current: Vec<R>,
    pub kept: Vec<bool>,
    pub next: Vec<R>,
    /// What the camera waves spawned, the order that groups it by sample, and where each
    /// group ends in that order.
    pending: Vec<R>,
    order: Vec<u32>,
    pending_ends: Vec<usize>,
}

impl<R> Default for WaveQueues<R> {
    fn default() -> Self {
        WaveQueues {
            current: Vec::new(),
            kept: Vec::new(),
            next: Vec::new(),
            pending: Vec::new(),
            order: Vec::new(),
            pending_ends: Vec::new(),
        }
    }
}

/// Which wave [`run_waves`] asks for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Wave {
    /// Camera rays, made into `current` with `kept`: trace them as packets, drop the rays
    /// the render does not keep and their hits ([`drop_unkept`]), shade.
    Camera,
    /// Rays of one sample leaving surfaces: trace them as one incoherent stream, shade.
    Scattered,
}

/// Traces the wave in `queues.current`, each ray seen through `wave_ray`, its hits into
/// `hits`: a camera wave as packets, then without the rays the render does not keep (and
/// their hits); a later wave as one incoherent stream (`trace_wave`).
pub(crate) fn trace_current<R>(
    context: &RenderContext,
    queues: &mut WaveQueues<R>,
    wave: &Wave,
    wave_ray: for<'r> fn(&'r R) -> WaveRay<'r>,
    trace_rays: &mut Vec<TraceRay>,
    hits: &mut Vec<TraceHit>,
    counters: &mut WorkCounters,
) {
    let camera = *wave == Wave::Camera;
    let rays = queues.current.iter().map(wave_ray);
    trace_wave(context, rays, camera, trace_rays, hits, counters);
    if camera {
        drop_unkept(&mut queues.current, hits, &queues.kept);
    }
}

/// Runs the waves of one sample run. `queues(state)` gives the state's queues;
/// `camera_wave(state)` makes the run's next [`CAMERA_WAVE_RAYS`] camera rays (fewer at the
/// end) into `current` and `kept`, and says whether it made any; `place` tells which of the
/// `places` samples in flight a ray belongs to; `wave(state, kind)` traces and shades
/// `current`, pushing the rays that continue onto `next`.
pub(crate) fn run_waves<S, R: Copy>(
    state: &mut S,
    queues: impl Fn(&mut S) -> &mut WaveQueues<R>,
    places: usize,
    place: impl Fn(&R) -> usize,
    mut camera_wave: impl FnMut(&mut S) -> bool,
    mut wave: impl FnMut(&mut S, Wave),
) {
    // The camera waves' continuing rays pile up in `next`.
    queues(state).next.clear();
    while camera_wave(state) {
        wave(state, Wave::Camera);
    }
    let q = queues(state);
    if places == 1 {
        // One sample in flight: its rays continue as they are.
        std::mem::swap(&mut q.current, &mut q.next);
        q.next.clear();
        continue_waves(state, &queues, &mut wave);
        return;
    }
    std::mem::swap(&mut q.pending, &mut q.next);
    q.next.clear();
    sort_by_place(
        &q.pending,
        &place,
        places,
        &mut q.order,
        &mut q.pending_ends,
    );
    let mut start = 0;
    for group in 0..places {
        let q = queues(state);
        let end = q.pending_ends[group];
        q.current.clear();
        let pending = &q.pending;
        q.current
            .extend(q.order[start..end].iter().map(|&i| pending[i as usize]));
        start = end;
        continue_waves(state, &queues, &mut wave);
    }
}

/// Traces and shades `current` and the waves that follow it until no ray continues.
fn continue_waves<S, R>(
    state: &mut S,
    queues: &impl Fn(&mut S) -> &mut WaveQueues<R>,
    wave: &mut impl FnMut(&mut S, Wave),
) {
    while !queues(state).current.is_empty() {
        wave(state, Wave::Scattered);
        let q = queues(state);
        std::mem::swap(&mut q.current, &mut q.next);
        q.next.clear();
    }
}

/// The indices of `rays` ordered by place (`place(ray)`, below `places`), places in
/// increasing order and each place's rays in their order in `rays` (a stable counting
/// sort), into `order`; where each place's indices end, into `group_ends`.
fn sort_by_place<R>(
    rays: &[R],
    place: impl Fn(&R) -> usize,
    places: usize,
    order: &mut Vec<u32>,
    group_ends: &mut Vec<usize>,
) {
    group_ends.clear();
    group_ends.resize(places, 0);
    for ray in rays {
        group_ends[place(ray)] += 1;
    }
    let mut end = 0;
    for count in group_ends.iter_mut() {
        end += *count;
        *count = end;
    }
    order.clear();
    order.resize(rays.len(), 0);
    // Back to front, each index into the last free place of its group: the ends become the
    // groups' starts, and each group keeps its rays' order.
    for (index, ray) in rays.iter().enumerate().rev() {
        let p = place(ray);
        group_ends[p] -= 1;
        order[group_ends[p]] = index as u32;
    }
    if places > 0 {
        group_ends.rotate_left(1);
        group_ends[places - 1] = rays.len();
    }
}

/// Reorders `rays` so that the rays of each place (`place(ray)`, below `places`) follow one
/// another, places in increasing order and each place's rays in their order before (a
/// stable counting sort), and writes where each place's group ends into `group_ends`.
///
/// A camera wave's shadow rays belong to several samples of each pixel; grouped by sample
/// this way, each sample's can be traced as a stream of their own, as a render of that sample
/// alone traces them.
pub(crate) fn group_by_place<T: Copy>(
    rays: &mut [T],
    scratch: &mut Vec<T>,
    order: &mut Vec<u32>,
    place: impl Fn(&T) -> usize,
    places: usize,
    group_ends: &mut Vec<usize>,
) {
    sort_by_place(rays, place, places, order, group_ends);
    scratch.clear();
    scratch.extend(order.iter().map(|&i| rays[i as usize]));
    rays.copy_from_slice(scratch);
}

/// Drops the camera rays the render does not keep (`CameraRay::kept`), with their hits,
/// after the wave was traced.
pub(crate) fn drop_unkept<T>(rays: &mut Vec<T>, hits: &mut Vec<TraceHit>, kept: &[bool]) {
    if kept.iter().all(|&k| k) {
        return;
    }
    let mut keep = kept.iter();
    rays.retain(|_| *keep.next().unwrap_or(&true));
    let mut keep = kept.iter();
    hits.retain(|_| *keep.next().unwrap_or(&true));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grouping_by_place_is_a_stable_sort_with_group_ends() {
        // (place, original index)
        let mut rays: Vec<(usize, usize)> = [2, 0, 1, 2, 0, 2, 1, 0]
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, i))
            .collect();
        let mut scratch = Vec::new();
        let mut order = Vec::new();
        let mut ends = Vec::new();
        group_by_place(&mut rays, &mut scratch, &mut order, |r| r.0, 4, &mut ends);
        assert_eq!(
            rays,
            vec![
                (0, 1),
                (0, 4),
                (0, 7),
                (1, 2),
                (1, 6),
                (2, 0),
                (2, 3),
                (2, 5)
            ]
        );
        assert_eq!(ends, vec![3, 5, 8, 8]);
        // One place: nothing moves.
        let mut one = vec![(0usize, 5usize), (0, 3)];
        group_by_place(&mut one, &mut scratch, &mut order, |r| r.0, 1, &mut ends);
        assert_eq!((one, ends), (vec![(0, 5), (0, 3)], vec![2]));
    }

    #[test]
    fn sorting_by_place_orders_indices_stably_with_group_ends() {
        let places = [2usize, 0, 1, 2, 0, 2, 1, 0];
        let (mut order, mut ends) = (Vec::new(), Vec::new());
        sort_by_place(&places, |&p| p, 4, &mut order, &mut ends);
        assert_eq!(order, vec![1, 4, 7, 2, 6, 0, 3, 5]);
        assert_eq!(ends, vec![3, 5, 8, 8]);
        sort_by_place(&places[..0], |&p| p, 2, &mut order, &mut ends);
        assert_eq!((order.len(), ends), (0, vec![0, 0]));
    }

    #[test]
    fn unkept_rays_and_their_hits_are_dropped_together() {
        let mut rays = vec![10, 11, 12, 13];
        let mut hits: Vec<TraceHit> = (0..4)
            .map(|i| TraceHit {
                t: i as f32,
                ..TraceHit::MISS
            })
            .collect();
        drop_unkept(&mut rays, &mut hits, &[true, false, false, true]);
        assert_eq!(rays, vec![10, 13]);
        assert_eq!(hits.iter().map(|h| h.t).collect::<Vec<_>>(), vec![0.0, 3.0]);
    }
}
