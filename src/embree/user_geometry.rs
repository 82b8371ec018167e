//! User geometry (`RTC_GEOMETRY_TYPE_USER`): primitives whose bounds and ray intersections
//! are computed by Rust code, such as exactly traced curved patches.
//!
//! The caller implements [`UserGeometry`] (bounds of primitive `i`, the hit of one ray with
//! primitive `i`); [`SceneBuilder::add_user_geometry`] installs Embree callbacks that call it.
//! Embree calls the intersect and occluded callbacks with N-wide packets (N = 1 for single
//! rays and streams, 4, 8 or 16 for packets) and a valid mask; each valid lane is handed to
//! [`UserGeometry::intersect`] as one [`UserRay`]. A closest hit is written only when it is
//! nearer than the lane's current `tfar`; an occlusion hit sets `tfar` to `-inf`, as
//! Embree's own primitives do.
//!
//! A panic inside the trait's methods never unwinds into Embree: it is caught, the lane
//! counts as missed, and the tracing call returns
//! [`EmbreeError::FilterPanicked`](super::EmbreeError::FilterPanicked) (the same error as a
//! panicking alpha filter). A panic in the bounds callback, which runs during commit, gives
//! the primitive empty bounds, so it is never hit.
//!
//! Alpha cut-outs: Embree runs no filter functions for user geometries, so a user geometry
//! given an alpha test ([`SceneBuilder::set_user_alpha_filter`]) runs it itself on each
//! candidate hit ([`UserGeometry::intersect_accepting`]); a panic in the test is caught
//! like one in the intersection.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Arc;

use glam::Vec3;

use super::context::TraceContext;
use super::error::EmbreeError;
use super::ffi;
use super::filter::{AlphaFilter, FilterCandidate};
use super::geometry::GeometryRecord;
use super::packet::{
    DIR_X, DIR_Y, DIR_Z, GEOM_ID, ID, INST_ID, NG_X, NG_Y, NG_Z, ORG_X, ORG_Y, ORG_Z, PRIM_ID,
    TFAR, TNEAR, U, V,
};
use super::scene::{Bounds, SceneBuilder};

/// One ray as a user geometry sees it: `origin + t direction` for `t` in `(tnear, tfar)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UserRay {
    pub origin: Vec3,
    /// As traced (not necessarily unit length).
    pub direction: Vec3,
    pub tnear: f32,
    pub tfar: f32,
}

/// A user primitive's hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UserHit {
    /// Distance along the ray's direction, in `(tnear, tfar)`.
    pub t: f32,
    /// The primitive's own surface parameters, reported as the hit's u and v.
    pub u: f32,
    pub v: f32,
    /// Geometric normal (any length, not zero), reported as the hit's `Ng`.
    pub normal: Vec3,
}

/// Primitives traced by Rust code.
pub trait UserGeometry: Send + Sync {
    /// Number of primitives (at least 1).
    fn primitive_count(&self) -> u32;
    /// World-space bounds of primitive `primitive`; every hit must lie inside.
    fn bounds(&self, primitive: u32) -> Bounds;
    /// The hit of `ray` with primitive `primitive`: the closest, or with `any_hit` (shadow
    /// rays) any hit in `(tnear, tfar)`.
    fn intersect(&self, primitive: u32, ray: &UserRay, any_hit: bool) -> Option<UserHit>;

    /// As [`UserGeometry::intersect`], reporting only a hit that `accept` (the geometry's
    /// alpha test, see [`SceneBuilder::set_user_alpha_filter`]) keeps: a rejected hit lets
    /// the ray through to whatever the primitive holds behind it. The default tests the
    /// closest hit only, which is right for primitives a ray meets at most once; others
    /// (curved patches) search on behind a rejected hit.
    fn intersect_accepting(
        &self,
        primitive: u32,
        ray: &UserRay,
        any_hit: bool,
        accept: &mut dyn FnMut(&UserHit) -> bool,
    ) -> Option<UserHit> {
        self.intersect(primitive, ray, any_hit)
            .filter(|hit| accept(hit))
    }
}

impl SceneBuilder {
    /// Adds a user geometry whose `primitive_count()` primitives are bounded and intersected
    /// by `geometry`; returns its geometry id. A hit's `prim_id` is the primitive index.
    pub fn add_user_geometry(
        &mut self,
        geometry: Arc<dyn UserGeometry>,
    ) -> Result<u32, EmbreeError> {
        let count = geometry.primitive_count() as usize;
        if count == 0 || count >= u32::MAX as usize {
            return Err(EmbreeError::BadPrimitiveCount {
                kind: "user geometry",
                count,
            });
        }
        let raw = self.new_geometry(ffi::RTC_GEOMETRY_TYPE_USER)?;
        // SAFETY: `raw` is a live geometry of this builder.
        unsafe { ffi::rtcSetGeometryUserPrimitiveCount(raw, count as u32) };
        if let Err(error) = self.device.check("rtcSetGeometryUserPrimitiveCount") {
            self.discard_last_geometry();
            return Err(error);
        }
        let id = self.attach(raw)?;
        let (raw, record) = self.geometry_mut(id)?;
        record.user = Some(geometry);
        let user = record as *mut GeometryRecord as *mut std::ffi::c_void;
        // SAFETY: `raw` is live and attached; `user` is the boxed record that `attach` made
        // the geometry's user data, which lives until the scene is released; the callbacks
        // are valid for the program's lifetime.
        unsafe {
            ffi::rtcSetGeometryBoundsFunction(raw, Some(bounds_callback), user);
            ffi::rtcSetGeometryIntersectFunction(raw, Some(intersect_callback));
            ffi::rtcSetGeometryOccludedFunction(raw, Some(occluded_callback));
        }
        self.device.check("rtcSetGeometryIntersectFunction")?;
        Ok(id)
    }

    /// Gives user geometry `geom_id` an alpha test: its intersect and occluded callbacks
    /// hand every candidate hit to `filter` (as a [`FilterCandidate`] with the hit's t, u,
    /// v and the ray's payload, as Embree's filter functions do for triangles) and report
    /// only the hits it keeps. Embree runs no filter functions of its own for user
    /// geometries, so none is installed. `geom_id` must be a user geometry
    /// ([`EmbreeError::UnknownGeometry`] otherwise).
    pub fn set_user_alpha_filter(
        &mut self,
        geom_id: u32,
        filter: AlphaFilter,
    ) -> Result<(), EmbreeError> {
        let (_, record) = self.geometry_mut(geom_id)?;
        if record.user.is_none() {
            // Not a user geometry: its callbacks would never run the test.
            return Err(EmbreeError::UnknownGeometry { geom_id });
        }
        record.filter = Some(filter);
        Ok(())
    }
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        String::from("(non-string panic payload)")
    }
}

unsafe extern "C" fn bounds_callback(args: *const ffi::RTCBoundsFunctionArguments) {
    // SAFETY: Embree passes valid arguments for the call; `geometryUserPtr` is the record
    // given to rtcSetGeometryBoundsFunction, alive while the scene exists; `bounds_o` points
    // to one writable RTCBounds.
    let args = unsafe { &*args };
    if args.geometryUserPtr.is_null() || args.bounds_o.is_null() {
        return;
    }
    let record = unsafe { &*(args.geometryUserPtr as *const GeometryRecord) };
    let empty = Bounds {
        lower: Vec3::splat(f32::INFINITY),
        upper: Vec3::splat(f32::NEG_INFINITY),
    };
    let b = match &record.user {
        Some(user) => match catch_unwind(AssertUnwindSafe(|| user.bounds(args.primID))) {
            Ok(b) if b.lower.is_finite() && b.upper.is_finite() => b,
            _ => empty,
        },
        None => empty,
    };
    let out = unsafe { &mut *args.bounds_o };
    out.lower_x = b.lower.x;
    out.lower_y = b.lower.y;
    out.lower_z = b.lower.z;
    out.upper_x = b.upper.x;
    out.upper_y = b.upper.y;
    out.upper_z = b.upper.z;
}

unsafe extern "C" fn intersect_callback(args: *const ffi::RTCIntersectFunctionNArguments) {
    // SAFETY: Embree passes valid arguments for the duration of the call.
    let args = unsafe { &*args };
    // SAFETY: as documented on `run_lanes`; `rayhit` is an RTCRayHitN of N lanes.
    unsafe {
        run_lanes(
            args.valid,
            args.geometryUserPtr,
            args.context,
            args.rayhit as *mut u32,
            args.N as usize,
            args.primID,
            args.geomID,
            false,
        )
    }
}

unsafe extern "C" fn occluded_callback(args: *const ffi::RTCOccludedFunctionNArguments) {
    // SAFETY: Embree passes valid arguments for the duration of the call.
    let args = unsafe { &*args };
    // SAFETY: as documented on `run_lanes`; `ray` is an RTCRayN of N lanes.
    unsafe {
        run_lanes(
            args.valid,
            args.geometryUserPtr,
            args.context,
            args.ray as *mut u32,
            args.N as usize,
            args.primID,
            args.geomID,
            true,
        )
    }
}

/// Intersects every valid lane of an N-wide ray block with primitive `prim_id`.
///
/// # Safety
/// `valid` holds `n` ints; `rows` is Embree's SoA block of `n` lanes (rows of `n` 4-byte
/// values in `RayPacket`'s row order: a full RTCRayHitN for intersection, the RTCRayN part
/// only for occlusion); `user` is a live `GeometryRecord`; `context` is the `TraceContext`
/// of the trace call (every trace in this module creates one).
#[allow(clippy::too_many_arguments)]
unsafe fn run_lanes(
    valid: *const i32,
    user: *mut std::ffi::c_void,
    context: *mut ffi::RTCIntersectContext,
    rows: *mut u32,
    n: usize,
    prim_id: u32,
    geom_id: u32,
    occlusion: bool,
) {
    if user.is_null() || context.is_null() || valid.is_null() || rows.is_null() || n == 0 {
        return;
    }
    // SAFETY (whole function): see the function's contract; row k of lane i is element
    // k * n + i, and for occlusion only rows up to FLAGS exist, which is all we touch then.
    let record = unsafe { &*(user as *const GeometryRecord) };
    let trace = unsafe { &*(context as *const TraceContext) };
    let Some(geometry) = record.user.as_ref() else {
        return;
    };
    let valid = unsafe { std::slice::from_raw_parts(valid, n) };
    let get = |row: usize, lane: usize| f32::from_bits(unsafe { *rows.add(row * n + lane) });
    let set = |row: usize, lane: usize, value: u32| unsafe { *rows.add(row * n + lane) = value };
    let inst_id = unsafe { (*context).instID[0] };
    let ray_id = |lane: usize| unsafe { *rows.add(ID * n + lane) };
    for (lane, &mask) in valid.iter().enumerate() {
        if mask == 0 {
            continue;
        }
        let ray = UserRay {
            origin: Vec3::new(get(ORG_X, lane), get(ORG_Y, lane), get(ORG_Z, lane)),
            direction: Vec3::new(get(DIR_X, lane), get(DIR_Y, lane), get(DIR_Z, lane)),
            tnear: get(TNEAR, lane),
            tfar: get(TFAR, lane),
        };
        if ray.tnear.is_nan() || ray.tfar.is_nan() || ray.tnear > ray.tfar {
            continue; // an occluded lane (tfar = -inf) or an empty interval
        }
        let hit = match catch_unwind(AssertUnwindSafe(|| match record.filter.as_ref() {
            None => geometry.intersect(prim_id, &ray, occlusion),
            Some(filter) => {
                let id = ray_id(lane);
                let mut accept = |hit: &UserHit| {
                    filter(&FilterCandidate {
                        origin: ray.origin,
                        direction: ray.direction,
                        t: hit.t,
                        u: hit.u,
                        v: hit.v,
                        prim_id,
                        geom_id: record.index,
                        lane: id,
                        payload: trace.payload(id),
                        occlusion,
                    })
                };
                geometry.intersect_accepting(prim_id, &ray, occlusion, &mut accept)
            }
        })) {
            Ok(hit) => hit,
            Err(payload) => {
                trace.record_panic(record.index, panic_message(payload.as_ref()));
                None
            }
        };
        let Some(hit) = hit else { continue };
        if !(hit.t > ray.tnear && hit.t < ray.tfar) {
            continue;
        }
        if occlusion {
            set(TFAR, lane, f32::NEG_INFINITY.to_bits());
            continue;
        }
        set(TFAR, lane, hit.t.to_bits());
        set(NG_X, lane, hit.normal.x.to_bits());
        set(NG_Y, lane, hit.normal.y.to_bits());
        set(NG_Z, lane, hit.normal.z.to_bits());
        set(U, lane, hit.u.to_bits());
        set(V, lane, hit.v.to_bits());
        set(PRIM_ID, lane, prim_id);
        set(GEOM_ID, lane, geom_id);
        set(INST_ID, lane, inst_id);
    }
}
