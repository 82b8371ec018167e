//! SoA ray packets of 4, 8 or 16 lanes traced with `rtcIntersect4/8/16` and
//! `rtcOccluded4/8/16`.
//!
//! [`RayPacket<N>`] stores the rays and hits exactly as Embree's `RTCRayHitN` (rows of N
//! 4-byte values: origin, tnear, direction, time, tfar, mask, id, flags, then Ng, u, v,
//! primID, geomID, instID) followed by the validity mask, so it is passed to Embree without
//! copying. Camera tiles are 4x4 = 16 lanes. Every packet trace honours the device's packet
//! width ([`CommittedScene::packet_width`]): a packet wider than it is split into 8- or
//! 4-wide packets, and on a device without packet support (width 1) each lane is traced as a
//! single ray. After every Embree call the device's error state is read, so an error Embree
//! reports during traversal is returned, never left as misses. A lane's ray id is its lane index, which filter callbacks use to
//! find the lane's [`RayPayload`](super::RayPayload).
//!
//! Packets are the path for camera rays (coherent 4x4 tiles, `Coherence::Coherent`). For
//! incoherent secondary rays, ray streams are recommended instead: in
//! `examples/secondary_rays.rs` (release, 1 thread, 100k random triangles + 1k spheres,
//! 2^20 bounce rays in random directions, methods interleaved in one run) 16-wide packets and
//! streams tied on closest hits (1.57 vs 1.58 Mrays/s; 1.20 vs 1.20 in a second run) and
//! streams were ahead on shadow rays (2.67 vs 2.57; 1.45 vs 1.38 Mrays/s). See `stream.rs`.

use glam::Vec3;

use super::context::TraceContext;
use super::context::TraceOptions;
use super::error::EmbreeError;
use super::ffi;
use super::ray::{Hit, Ray, RayHit, INVALID_GEOMETRY_ID};
use super::scene::CommittedScene;

// Row indices of Embree's RTCRayHitN layout (rtcore_ray.h, RTCRayN_* / RTCHitN_* accessors).
pub(super) const ORG_X: usize = 0;
pub(super) const ORG_Y: usize = 1;
pub(super) const ORG_Z: usize = 2;
pub(super) const TNEAR: usize = 3;
pub(super) const DIR_X: usize = 4;
pub(super) const DIR_Y: usize = 5;
pub(super) const DIR_Z: usize = 6;
pub(super) const TIME: usize = 7;
pub(super) const TFAR: usize = 8;
pub(super) const MASK: usize = 9;
pub(super) const ID: usize = 10;
pub(super) const FLAGS: usize = 11;
pub(super) const NG_X: usize = 12;
pub(super) const NG_Y: usize = 13;
pub(super) const NG_Z: usize = 14;
pub(super) const U: usize = 15;
pub(super) const V: usize = 16;
pub(super) const PRIM_ID: usize = 17;
pub(super) const GEOM_ID: usize = 18;
pub(super) const INST_ID: usize = 19;
const ROWS: usize = INST_ID + ffi::RTC_MAX_INSTANCE_LEVEL_COUNT as usize;

// The row layout must be Embree's, for every width we pass to Embree.
const _: () = {
    use std::mem::{offset_of, size_of};
    assert!(size_of::<[[u32; 16]; ROWS]>() == size_of::<ffi::RTCRayHit16>());
    assert!(size_of::<[[u32; 8]; ROWS]>() == size_of::<ffi::RTCRayHit8>());
    assert!(size_of::<[[u32; 4]; ROWS]>() == size_of::<ffi::RTCRayHit4>());
    assert!(offset_of!(ffi::RTCRayHit16, hit) == NG_X * 16 * 4);
    assert!(offset_of!(ffi::RTCRayHit8, hit) == NG_X * 8 * 4);
    assert!(offset_of!(ffi::RTCRayHit4, hit) == NG_X * 4 * 4);
    assert!(offset_of!(ffi::RTCRay16, tfar) == TFAR * 16 * 4);
    assert!(offset_of!(ffi::RTCRay16, id) == ID * 16 * 4);
    assert!(offset_of!(ffi::RTCHit16, u) == (U - NG_X) * 16 * 4);
    assert!(offset_of!(ffi::RTCHit16, primID) == (PRIM_ID - NG_X) * 16 * 4);
    assert!(offset_of!(ffi::RTCHit16, geomID) == (GEOM_ID - NG_X) * 16 * 4);
    assert!(offset_of!(ffi::RTCHit16, instID) == (INST_ID - NG_X) * 16 * 4);
    assert!(std::mem::align_of::<RayPacket<16>>() >= std::mem::align_of::<ffi::RTCRayHit16>());
};

/// A packet of `N` rays (N = 4, 8 or 16) in Embree's SoA layout, with a validity mask.
/// Invalid lanes are never read or written by traces.
#[derive(Clone)]
#[repr(C, align(64))]
pub struct RayPacket<const N: usize> {
    rows: [[u32; N]; ROWS],
    /// Embree's mask: -1 traces the lane, 0 skips it. Aligned to N * 4 bytes because the
    /// rows before it span a multiple of N * 4 bytes and the struct is 64-byte aligned.
    valid: [i32; N],
}

impl<const N: usize> Default for RayPacket<N> {
    fn default() -> Self {
        RayPacket::new()
    }
}

impl<const N: usize> RayPacket<N> {
    const SUPPORTED_WIDTH: () = assert!(N == 4 || N == 8 || N == 16, "packets are 4, 8 or 16 wide");

    /// A packet with every lane invalid.
    #[inline]
    pub fn new() -> RayPacket<N> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SUPPORTED_WIDTH;
        let mut rows = [[0u32; N]; ROWS];
        rows[GEOM_ID] = [INVALID_GEOMETRY_ID; N];
        RayPacket {
            rows,
            valid: [0; N],
        }
    }

    /// Number of lanes.
    pub const LANES: usize = N;

    #[inline]
    fn f(&self, row: usize, lane: usize) -> f32 {
        f32::from_bits(self.rows[row][lane])
    }

    #[inline]
    fn set_f(&mut self, row: usize, lane: usize, value: f32) {
        self.rows[row][lane] = value.to_bits();
    }

    /// Puts `ray` in `lane`, marks the lane valid and clears its hit.
    #[inline]
    pub fn set_ray(&mut self, lane: usize, ray: &Ray) {
        self.put_ray(lane, ray);
        self.set_f(TIME, lane, 0.0);
        self.rows[MASK][lane] = u32::MAX;
        self.rows[ID][lane] = lane as u32;
        self.rows[FLAGS][lane] = 0;
        self.rows[GEOM_ID][lane] = INVALID_GEOMETRY_ID;
        self.rows[PRIM_ID][lane] = INVALID_GEOMETRY_ID;
        for level in 0..ffi::RTC_MAX_INSTANCE_LEVEL_COUNT as usize {
            self.rows[INST_ID + level][lane] = INVALID_GEOMETRY_ID;
        }
    }

    /// Every lane invalid, with the rows that every ray sets alike (time, mask, id, flags
    /// and the cleared hit) written whole: then [`RayPacket::put_ray`] writes only a ray's
    /// own values, and the packet is the one [`RayPacket::set_ray`] would make.
    #[inline]
    pub fn reset_lanes(&mut self) {
        self.rows[TIME] = [0; N];
        self.rows[MASK] = [u32::MAX; N];
        self.rows[ID] = std::array::from_fn(|lane| lane as u32);
        self.rows[FLAGS] = [0; N];
        for row in [GEOM_ID, PRIM_ID] {
            self.rows[row] = [INVALID_GEOMETRY_ID; N];
        }
        for level in 0..ffi::RTC_MAX_INSTANCE_LEVEL_COUNT as usize {
            self.rows[INST_ID + level] = [INVALID_GEOMETRY_ID; N];
        }
        self.valid = [0; N];
    }

    /// Puts `ray` in `lane` of a packet made ready by [`RayPacket::reset_lanes`] and marks
    /// the lane valid.
    #[inline]
    pub fn put_ray(&mut self, lane: usize, ray: &Ray) {
        self.set_f(ORG_X, lane, ray.origin.x);
        self.set_f(ORG_Y, lane, ray.origin.y);
        self.set_f(ORG_Z, lane, ray.origin.z);
        self.set_f(TNEAR, lane, ray.tnear);
        self.set_f(DIR_X, lane, ray.direction.x);
        self.set_f(DIR_Y, lane, ray.direction.y);
        self.set_f(DIR_Z, lane, ray.direction.z);
        self.set_f(TFAR, lane, ray.tfar);
        self.valid[lane] = -1;
    }

    /// Marks `lane` valid (traced) or invalid (left untouched by traces).
    #[inline]
    pub fn set_valid(&mut self, lane: usize, valid: bool) {
        self.valid[lane] = if valid { -1 } else { 0 };
    }

    /// Whether `lane` will be traced.
    #[inline]
    pub fn is_valid(&self, lane: usize) -> bool {
        self.valid[lane] != 0
    }

    /// Number of valid lanes.
    #[inline]
    pub fn valid_count(&self) -> usize {
        self.valid.iter().filter(|&&v| v != 0).count()
    }

    /// The ray in `lane` (`tfar` is the hit distance after an intersect trace).
    #[inline]
    pub fn ray(&self, lane: usize) -> Ray {
        Ray {
            origin: Vec3::new(
                self.f(ORG_X, lane),
                self.f(ORG_Y, lane),
                self.f(ORG_Z, lane),
            ),
            direction: Vec3::new(
                self.f(DIR_X, lane),
                self.f(DIR_Y, lane),
                self.f(DIR_Z, lane),
            ),
            tnear: self.f(TNEAR, lane),
            tfar: self.f(TFAR, lane),
        }
    }

    /// `tfar` of `lane`: the hit distance after an intersect, `-inf` when occluded.
    #[inline]
    pub fn tfar(&self, lane: usize) -> f32 {
        self.f(TFAR, lane)
    }

    /// Geometry id of `lane`'s hit, [`INVALID_GEOMETRY_ID`] for a miss.
    #[inline]
    pub fn geom_id(&self, lane: usize) -> u32 {
        self.rows[GEOM_ID][lane]
    }

    /// `lane`'s hit after an intersect trace, `None` for a miss.
    #[inline]
    pub fn hit(&self, lane: usize) -> Option<Hit> {
        let geom_id = self.rows[GEOM_ID][lane];
        if geom_id == INVALID_GEOMETRY_ID {
            return None;
        }
        Some(Hit {
            t: self.f(TFAR, lane),
            geom_id,
            prim_id: self.rows[PRIM_ID][lane],
            u: self.f(U, lane),
            v: self.f(V, lane),
            ng: Vec3::new(self.f(NG_X, lane), self.f(NG_Y, lane), self.f(NG_Z, lane)),
        })
    }

    /// After an occluded trace: whether `lane`'s segment is blocked.
    #[inline]
    pub fn is_occluded(&self, lane: usize) -> bool {
        self.f(TFAR, lane) == f32::NEG_INFINITY
    }

    /// Copies `count` lanes (rays, hits, validity) from `src` starting at `from` into this
    /// packet starting at `to`.
    #[inline]
    fn copy_lanes<const M: usize>(
        &mut self,
        to: usize,
        src: &RayPacket<M>,
        from: usize,
        count: usize,
    ) {
        for (dst_row, src_row) in self.rows.iter_mut().zip(src.rows.iter()) {
            dst_row[to..to + count].copy_from_slice(&src_row[from..from + count]);
        }
        self.valid[to..to + count].copy_from_slice(&src.valid[from..from + count]);
    }
}

impl CommittedScene {
    /// Closest hits for the valid lanes of an N-wide packet: one `rtcIntersect4/8/16` call
    /// when N is within the device's packet width ([`CommittedScene::packet_width`]), else
    /// split into packets of that width, or traced lane by lane with `rtcIntersect1` on a
    /// device without packet support. Lane ids stay the packet's lane indices either way, so
    /// payload lookup in filters is unchanged.
    pub fn intersect_packet<const N: usize>(
        &self,
        packet: &mut RayPacket<N>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.trace_packet(packet, options, false)
    }

    /// Occlusion for the valid lanes of an N-wide packet (`rtcOccluded4/8/16`, split or
    /// single rays as for [`CommittedScene::intersect_packet`]); blocked lanes get
    /// `tfar = -inf` (see [`RayPacket::is_occluded`]).
    pub fn occluded_packet<const N: usize>(
        &self,
        packet: &mut RayPacket<N>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.trace_packet(packet, options, true)
    }

    /// `rtcIntersect16` on a 16-lane packet.
    #[inline]
    pub fn intersect16(
        &self,
        packet: &mut RayPacket<16>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.intersect_packet(packet, options)
    }

    /// `rtcOccluded16` on a 16-lane packet.
    #[inline]
    pub fn occluded16(
        &self,
        packet: &mut RayPacket<16>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.occluded_packet(packet, options)
    }

    /// `rtcIntersect8` on an 8-lane packet.
    #[inline]
    pub fn intersect8(
        &self,
        packet: &mut RayPacket<8>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.intersect_packet(packet, options)
    }

    /// `rtcOccluded8` on an 8-lane packet.
    #[inline]
    pub fn occluded8(
        &self,
        packet: &mut RayPacket<8>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.occluded_packet(packet, options)
    }

    /// `rtcIntersect4` on a 4-lane packet.
    #[inline]
    pub fn intersect4(
        &self,
        packet: &mut RayPacket<4>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.intersect_packet(packet, options)
    }

    /// `rtcOccluded4` on a 4-lane packet.
    #[inline]
    pub fn occluded4(
        &self,
        packet: &mut RayPacket<4>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.occluded_packet(packet, options)
    }

    /// Closest hits for a 16-lane tile (4x4 pixels) with the device's packet width: one
    /// 16-wide call, or two 8-wide, or four 4-wide, or 16 single rays.
    pub fn intersect_tile(
        &self,
        packet: &mut RayPacket<16>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.intersect_packet(packet, options)
    }

    /// Occlusion for a 16-lane tile with the device's packet width.
    pub fn occluded_tile(
        &self,
        packet: &mut RayPacket<16>,
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.occluded_packet(packet, options)
    }

    /// Dispatches an N-wide trace on the device's packet width.
    fn trace_packet<const N: usize>(
        &self,
        packet: &mut RayPacket<N>,
        options: TraceOptions,
        occlusion: bool,
    ) -> Result<(), EmbreeError> {
        #[allow(clippy::let_unit_value)]
        let () = RayPacket::<N>::SUPPORTED_WIDTH;
        let width = self.packet_width();
        if N <= width {
            self.trace_native(packet, options, occlusion)
        } else if width >= 8 {
            self.trace_split::<N, 8>(packet, options, occlusion)
        } else if width >= 4 {
            self.trace_split::<N, 4>(packet, options, occlusion)
        } else {
            self.trace_lanes_one_by_one(packet, options, occlusion)
        }
    }

    /// One `rtcIntersectN` / `rtcOccludedN` call, then the device's error state and the
    /// filters' panics.
    fn trace_native<const N: usize>(
        &self,
        packet: &mut RayPacket<N>,
        options: TraceOptions,
        occlusion: bool,
    ) -> Result<(), EmbreeError> {
        let mut context = TraceContext::new(&options);
        let ctx = context.as_raw();
        let valid = packet.valid.as_ptr();
        let rays = packet.rows.as_mut_ptr() as *mut std::ffi::c_void;
        // SAFETY: `RayPacket<N>` has Embree's RTCRayHitN layout for N = 4, 8, 16 (checked
        // by the const assertions above; other N do not compile), it is 64-byte aligned and
        // `valid` is aligned to N * 4 bytes as Embree requires. The ray rows are Embree's
        // RTCRayN, the first member of RTCRayHitN (for the occluded calls, which write only
        // `tfar` of valid lanes). The scene is committed; the context outlives the call;
        // Embree writes only valid lanes of `packet`, which we borrow mutably for the call.
        unsafe {
            match (N, occlusion) {
                (16, false) => {
                    ffi::rtcIntersect16(valid, self.raw(), ctx, rays as *mut ffi::RTCRayHit16)
                }
                (8, false) => {
                    ffi::rtcIntersect8(valid, self.raw(), ctx, rays as *mut ffi::RTCRayHit8)
                }
                (_, false) => {
                    ffi::rtcIntersect4(valid, self.raw(), ctx, rays as *mut ffi::RTCRayHit4)
                }
                (16, true) => {
                    ffi::rtcOccluded16(valid, self.raw(), ctx, rays as *mut ffi::RTCRay16)
                }
                (8, true) => ffi::rtcOccluded8(valid, self.raw(), ctx, rays as *mut ffi::RTCRay8),
                (_, true) => ffi::rtcOccluded4(valid, self.raw(), ctx, rays as *mut ffi::RTCRay4),
            }
        }
        let operation = match (N, occlusion) {
            (16, false) => "rtcIntersect16",
            (8, false) => "rtcIntersect8",
            (_, false) => "rtcIntersect4",
            (16, true) => "rtcOccluded16",
            (8, true) => "rtcOccluded8",
            (_, true) => "rtcOccluded4",
        };
        self.finish_trace(context, operation)
    }

    /// Traces an N-lane packet as N / M packets of M lanes. Lane ids stay the N-lane
    /// indices, so payload lookup in filters is unchanged.
    fn trace_split<const N: usize, const M: usize>(
        &self,
        packet: &mut RayPacket<N>,
        options: TraceOptions,
        occlusion: bool,
    ) -> Result<(), EmbreeError> {
        let mut first_error = Ok(());
        let mut part = RayPacket::<M>::new();
        for start in (0..N).step_by(M) {
            if packet.valid[start..start + M].iter().all(|&v| v == 0) {
                continue;
            }
            part.copy_lanes(0, packet, start, M);
            let result = self.trace_native(&mut part, options, occlusion);
            packet.copy_lanes(start, &part, 0, M);
            first_error = merge_part_errors(first_error, result);
        }
        first_error
    }

    /// Traces every valid lane as a single ray (`rtcIntersect1` / `rtcOccluded1`) for
    /// devices without packet support, with the lane index as ray id.
    fn trace_lanes_one_by_one<const N: usize>(
        &self,
        packet: &mut RayPacket<N>,
        options: TraceOptions,
        occlusion: bool,
    ) -> Result<(), EmbreeError> {
        let mut context = TraceContext::new(&options);
        for lane in 0..N {
            if packet.valid[lane] == 0 {
                continue;
            }
            let mut ray_hit = packet.lane_ray_hit(lane);
            self.trace_one(&mut ray_hit, &mut context, occlusion);
            packet.store_lane(lane, &ray_hit, occlusion);
        }
        self.finish_trace(
            context,
            if occlusion {
                "rtcOccluded1"
            } else {
                "rtcIntersect1"
            },
        )
    }
}

impl<const N: usize> RayPacket<N> {
    /// `lane` as a single ray in Embree's `RTCRayHit` layout, keeping its id and mask.
    fn lane_ray_hit(&self, lane: usize) -> RayHit {
        let mut ray_hit = RayHit::new(&self.ray(lane));
        ray_hit.0.ray.time = self.f(TIME, lane);
        ray_hit.0.ray.mask = self.rows[MASK][lane];
        ray_hit.0.ray.id = self.rows[ID][lane];
        ray_hit.0.ray.flags = self.rows[FLAGS][lane];
        ray_hit
    }

    /// Writes a single-ray result back into `lane`: `tfar` only after an occlusion trace (as
    /// packet traces do), `tfar` and the hit after an intersect trace that hit something.
    fn store_lane(&mut self, lane: usize, ray_hit: &RayHit, occlusion: bool) {
        self.set_f(TFAR, lane, ray_hit.0.ray.tfar);
        let hit = &ray_hit.0.hit;
        if occlusion || hit.geomID == INVALID_GEOMETRY_ID {
            return;
        }
        self.set_f(NG_X, lane, hit.Ng_x);
        self.set_f(NG_Y, lane, hit.Ng_y);
        self.set_f(NG_Z, lane, hit.Ng_z);
        self.set_f(U, lane, hit.u);
        self.set_f(V, lane, hit.v);
        self.rows[PRIM_ID][lane] = hit.primID;
        self.rows[GEOM_ID][lane] = hit.geomID;
        for (level, &id) in hit.instID.iter().enumerate() {
            self.rows[INST_ID + level][lane] = id;
        }
    }
}

/// The error of a packet traced in parts from the error so far and the next part's: the
/// first error, except that panics of filters add up, so the count is the whole packet's
/// as an unsplit trace reports it.
fn merge_part_errors(
    so_far: Result<(), EmbreeError>,
    next: Result<(), EmbreeError>,
) -> Result<(), EmbreeError> {
    match (so_far, next) {
        (Ok(()), next) => next,
        (
            Err(EmbreeError::FilterPanicked {
                geom_id,
                count,
                message,
            }),
            Err(EmbreeError::FilterPanicked { count: more, .. }),
        ) => Err(EmbreeError::FilterPanicked {
            geom_id,
            count: count.saturating_add(more),
            message,
        }),
        (so_far, _) => so_far,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_packet_is_all_invalid_and_set_ray_round_trips() {
        let mut p = RayPacket::<8>::new();
        assert_eq!(p.valid_count(), 0);
        let ray = Ray::segment(
            Vec3::new(1.0, -2.0, 3.5),
            Vec3::new(0.0, 0.6, 0.8),
            0.25,
            9.0,
        );
        p.set_ray(5, &ray);
        assert!(p.is_valid(5));
        assert_eq!(p.valid_count(), 1);
        assert_eq!(p.ray(5), ray);
        assert_eq!(p.geom_id(5), INVALID_GEOMETRY_ID);
        assert!(p.hit(5).is_none());
        p.set_valid(5, false);
        assert!(!p.is_valid(5));
    }

    /// A packet reset and filled ray by ray holds, in every lane it fills, what `set_ray`
    /// writes, its other lanes invalid, whatever the packet held before.
    #[test]
    fn reset_and_put_rays_match_set_ray() {
        let ray = |lane: usize| {
            let x = lane as f32;
            Ray::segment(
                Vec3::new(x, -2.0, 3.5),
                Vec3::new(0.0, 0.6, 0.8),
                0.25 * x,
                9.0 + x,
            )
        };
        let mut expected = RayPacket::<16>::new();
        (0..11).for_each(|lane| expected.set_ray(lane, &ray(lane)));
        let mut packet = RayPacket::<16>::new();
        // Leftovers of a fuller packet, hit and all.
        (0..16).for_each(|lane| packet.set_ray(lane, &ray(lane + 20)));
        packet.rows[GEOM_ID] = [3; 16];
        packet.rows[TIME] = [7; 16];
        packet.reset_lanes();
        (0..11).for_each(|lane| packet.put_ray(lane, &ray(lane)));
        assert_eq!(packet.valid, expected.valid);
        for (row, (got, want)) in packet.rows.iter().zip(&expected.rows).enumerate() {
            assert_eq!(got[..11], want[..11], "row {row}");
        }
    }

    /// An error Embree reports while a trace runs (here provoked from inside a filter
    /// callback, on the tracing thread) is returned by the trace call, on every path.
    #[test]
    fn an_embree_error_during_a_trace_is_returned() {
        use crate::embree::{Device, FilterCandidate, RayHit, SceneBuilder};
        use std::sync::Arc;
        let device = Device::new().expect("device");
        let mut builder = SceneBuilder::new(&device).expect("builder");
        let quad = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let id = builder
            .add_triangle_mesh(&quad, &[[0, 1, 2], [0, 2, 3]])
            .expect("mesh");
        let inside = device.clone();
        builder
            .set_alpha_filter(
                id,
                Arc::new(move |_: &FilterCandidate| {
                    // An unknown property id: Embree records RTC_ERROR_INVALID_ARGUMENT.
                    inside.raw_property(9999);
                    true
                }),
            )
            .expect("filter");
        let scene = builder.commit().expect("commit");
        let ray = |lane: usize| {
            let x = -0.9 + 0.1 * lane as f32;
            Ray::new(Vec3::new(x, 0.3, 1.0), -Vec3::Z)
        };
        let is_invalid_argument = |result: Result<(), EmbreeError>, path: &str| match result {
            Err(EmbreeError::Embree { code, message, .. }) => {
                assert_eq!(code, "RTC_ERROR_INVALID_ARGUMENT", "{path}");
                assert!(message.contains("property"), "{path}: {message}");
            }
            other => panic!("{path}: {other:?}"),
        };
        let mut packet = RayPacket::<16>::new();
        (0..16).for_each(|lane| packet.set_ray(lane, &ray(lane)));
        is_invalid_argument(
            scene.intersect_tile(&mut packet, TraceOptions::coherent()),
            "tile",
        );
        // The rays were traced all the same.
        assert!((0..16).all(|lane| packet.hit(lane).is_some()));
        is_invalid_argument(
            scene.occluded_tile(&mut packet, TraceOptions::coherent()),
            "occluded tile",
        );
        is_invalid_argument(
            scene
                .intersect1(&ray(0), TraceOptions::incoherent())
                .map(|_| ()),
            "single",
        );
        let mut stream: Vec<RayHit> = (0..16).map(|lane| RayHit::new(&ray(lane))).collect();
        is_invalid_argument(
            scene.intersect_stream(&mut stream, TraceOptions::incoherent()),
            "stream",
        );
        is_invalid_argument(
            scene.occluded_stream(&mut stream, TraceOptions::incoherent()),
            "occluded stream",
        );
        // Nothing is left behind for the next call.
        assert!(device.check("after").is_ok());
    }

    #[test]
    fn valid_mask_is_aligned_as_embree_requires() {
        let p16 = RayPacket::<16>::new();
        let p8 = RayPacket::<8>::new();
        let p4 = RayPacket::<4>::new();
        assert_eq!(p16.valid.as_ptr() as usize % 64, 0);
        assert_eq!(p8.valid.as_ptr() as usize % 32, 0);
        assert_eq!(p4.valid.as_ptr() as usize % 16, 0);
        assert_eq!(&p16 as *const _ as usize % 64, 0);
    }
}
