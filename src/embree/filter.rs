//! Alpha cut-outs: Rust closures run by Embree as per-geometry intersection and occlusion
//! filter functions.
//!
//! Embree 3 ignores filters set on the intersect context for `rtcIntersect4/8/16` (embree
//! issue #321), so the closure is installed per geometry, where Embree calls it for single
//! rays, packets and streams alike. For every valid lane of a candidate hit the closure gets
//! a [`FilterCandidate`]; returning `false` rejects the hit and traversal continues behind it.
//!
//! A panic inside the closure never unwinds into Embree: it is caught, the candidate is
//! rejected (deterministically: a failing alpha test cuts the surface out) and the tracing
//! call returns [`EmbreeError::FilterPanicked`](super::EmbreeError::FilterPanicked).

use std::any::Any;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use glam::Vec3;

use super::context::{RayPayload, TraceContext};
use super::error::EmbreeError;
use super::ffi;
use super::geometry::GeometryRecord;
use super::packet::{DIR_X, DIR_Y, DIR_Z, ID, NG_X, ORG_X, ORG_Y, ORG_Z, PRIM_ID, TFAR, U, V};

/// An alpha test: `true` keeps the candidate hit, `false` lets the ray pass through.
pub type AlphaFilter = Arc<dyn Fn(&FilterCandidate) -> bool + Send + Sync>;

/// One candidate hit, as a filter callback sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterCandidate {
    /// Ray origin (world space).
    pub origin: Vec3,
    /// Ray direction as traced (not necessarily unit length).
    pub direction: Vec3,
    /// Distance of the candidate hit along `direction`.
    pub t: f32,
    /// Barycentric u of the candidate (triangles).
    pub u: f32,
    /// Barycentric v of the candidate (triangles).
    pub v: f32,
    /// Primitive (triangle or sphere index) within the geometry.
    pub prim_id: u32,
    /// Geometry id (our geometry index, read from the geometry's user data).
    pub geom_id: u32,
    /// Lane within the packet (0 for single rays, the index for streams).
    pub lane: u32,
    /// The payload the tracing call supplied for this ray (default if none).
    pub payload: RayPayload,
    /// True for occlusion (shadow) queries, false for closest-hit queries.
    pub occlusion: bool,
}

/// Embree's intersection filter for geometries with an alpha filter.
pub(crate) unsafe extern "C" fn intersect_filter(args: *const ffi::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes valid filter arguments for the duration of the call.
    unsafe { run_filter(args, false) }
}

/// Embree's occlusion filter for geometries with an alpha filter.
pub(crate) unsafe extern "C" fn occluded_filter(args: *const ffi::RTCFilterFunctionNArguments) {
    // SAFETY: as for `intersect_filter`.
    unsafe { run_filter(args, true) }
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        String::from("(non-string panic payload)")
    }
}

/// Runs the geometry's closure on every valid lane and clears `valid[i]` for rejected hits.
///
/// # Safety
/// `args` must be the arguments Embree passes to a filter function of a geometry whose user
/// pointer is a live `GeometryRecord`, traced with a context created by `TraceContext::new`.
unsafe fn run_filter(args: *const ffi::RTCFilterFunctionNArguments, occlusion: bool) {
    // SAFETY (whole function): Embree guarantees `args` and its pointers are valid during
    // the call: `valid` has N ints; `ray`/`hit` point to SoA RTCRayN/RTCHitN blocks of N
    // lanes (field k of lane i at element k*N + i, per rtcore_ray.h's RTCRayN_* accessors);
    // `geometryUserPtr` is the `GeometryRecord` the scene owns (it outlives the scene's
    // traversal); `context` is the pointer our trace call passed, a `TraceContext` that lives
    // on the caller's stack for the whole call and is only used through shared references.
    let args = unsafe { &*args };
    let n = args.N as usize;
    if args.geometryUserPtr.is_null() || args.context.is_null() || n == 0 {
        return;
    }
    let record = unsafe { &*(args.geometryUserPtr as *const GeometryRecord) };
    let context = unsafe { &*(args.context as *const TraceContext) };
    let Some(filter) = record.filter.as_ref() else {
        return;
    };
    let valid = unsafe { std::slice::from_raw_parts_mut(args.valid, n) };
    let ray = args.ray as *const f32;
    let hit = args.hit as *const f32;
    // Rows are those of `RayPacket`'s layout; hit rows count from the start of RTCHitN.
    let ray_f = |row: usize, lane: usize| unsafe { *ray.add(row * n + lane) };
    let ray_u = |row: usize, lane: usize| unsafe { *(ray as *const u32).add(row * n + lane) };
    let hit_f = |row: usize, lane: usize| unsafe { *hit.add((row - NG_X) * n + lane) };
    let hit_u =
        |row: usize, lane: usize| unsafe { *(hit as *const u32).add((row - NG_X) * n + lane) };

    for (lane, valid_lane) in valid.iter_mut().enumerate() {
        if *valid_lane == 0 {
            continue;
        }
        let id = ray_u(ID, lane);
        let candidate = FilterCandidate {
            origin: Vec3::new(ray_f(ORG_X, lane), ray_f(ORG_Y, lane), ray_f(ORG_Z, lane)),
            direction: Vec3::new(ray_f(DIR_X, lane), ray_f(DIR_Y, lane), ray_f(DIR_Z, lane)),
            t: ray_f(TFAR, lane),
            u: hit_f(U, lane),
            v: hit_f(V, lane),
            prim_id: hit_u(PRIM_ID, lane),
            geom_id: record.index,
            lane: id,
            payload: context.payload(id),
            occlusion,
        };
        let accepted = match catch_unwind(AssertUnwindSafe(|| filter(&candidate))) {
            Ok(accepted) => accepted,
            Err(payload) => {
                context.record_panic(candidate.geom_id, panic_message(payload.as_ref()));
                false
            }
        };
        if !accepted {
            *valid_lane = 0;
        }
    }
}

impl super::scene::SceneBuilder {
    /// Installs `filter` as geometry `geom_id`'s intersection and occlusion filter
    /// (replacing any earlier one).
    pub fn set_alpha_filter(
        &mut self,
        geom_id: u32,
        filter: AlphaFilter,
    ) -> Result<(), EmbreeError> {
        let (raw, record) = self.geometry_mut(geom_id)?;
        record.filter = Some(filter);
        // SAFETY: `raw` is a live geometry of this builder; the functions are valid for the
        // program's lifetime and read the record through the user pointer set at attach.
        unsafe {
            ffi::rtcSetGeometryIntersectFilterFunction(raw, Some(intersect_filter));
            ffi::rtcSetGeometryOccludedFilterFunction(raw, Some(occluded_filter));
        }
        self.device.check("rtcSetGeometryIntersectFilterFunction")
    }
}
