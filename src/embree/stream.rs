//! Single rays (`rtcIntersect1`/`rtcOccluded1`) and ray streams (`rtcIntersect1M`/
//! `rtcOccluded1M`) over slices of [`RayHit`].
//!
//! Streams with `Coherence::Incoherent` are the recommended path for secondary rays (bounce
//! and shadow rays); 16-wide packets stay the path for camera tiles. Measured with
//! `cargo run --release --example secondary_rays` (1 thread, 100k random triangles + 1k
//! spheres, 2^20 bounce rays from random surface points in random directions, every method
//! on the same blocks of rays in one run, the machine shared with other builds):
//!
//! | 1 thread, Mrays/s        | single | 8-wide | 16-wide | stream (incoherent) | stream (coherent flag) |
//! |--------------------------|--------|--------|---------|---------------------|------------------------|
//! | closest hit, run A       | 1.44   | 1.54   | 1.57    | 1.58                | 0.37                   |
//! | closest hit, run B       | 1.11   | 1.16   | 1.20    | 1.20                | 0.30                   |
//! | occlusion, run A         | 2.47   | 2.36   | 2.57    | 2.67                | 0.72                   |
//! | occlusion, run B         | 1.33   | 1.30   | 1.38    | 1.45                | 0.45                   |
//!
//! Streams tie with 16-wide packets on closest hits and lead by 4-5% on shadow rays (within
//! the machine's run-to-run noise, but in the same direction in both runs; earlier, noisier
//! runs ranged from packets +9% to streams +4%). Never pass `Coherence::Coherent` for
//! incoherent streams: Embree then sorts them into packets, 3-4x slower.
//!
//! On a device without stream support ([`CommittedScene::stream_supported`] false), streams
//! are traced ray by ray with `rtcIntersect1` / `rtcOccluded1`, same ids and payloads.
//!
//! Stream rays get their index in the slice as ray id, so filter callbacks see it as
//! `FilterCandidate::lane` and look up the stream's payload with it.

use super::context::{TraceContext, TraceOptions};
use super::error::EmbreeError;
use super::ffi;
use super::ray::{Hit, Ray, RayHit};
use super::scene::CommittedScene;

impl CommittedScene {
    /// The closest hit along `ray`, `None` for a miss. Payload index 0 belongs to this ray.
    pub fn intersect1(&self, ray: &Ray, options: TraceOptions) -> Result<Option<Hit>, EmbreeError> {
        let mut ray_hit = RayHit::new(ray);
        let mut context = TraceContext::new(&options);
        self.trace_one(&mut ray_hit, &mut context, false);
        self.finish_trace(context, "rtcIntersect1")?;
        Ok(ray_hit.hit())
    }

    /// Whether anything blocks `ray` between `tnear` and `tfar`.
    pub fn occluded1(&self, ray: &Ray, options: TraceOptions) -> Result<bool, EmbreeError> {
        let mut ray_hit = RayHit::new(ray);
        let mut context = TraceContext::new(&options);
        self.trace_one(&mut ray_hit, &mut context, true);
        self.finish_trace(context, "rtcOccluded1")?;
        Ok(ray_hit.is_occluded())
    }

    /// One `rtcIntersect1` / `rtcOccluded1` call; the caller reads the device's error state
    /// and the filters' panics afterwards ([`CommittedScene::finish_trace`]).
    pub(super) fn trace_one(
        &self,
        ray_hit: &mut RayHit,
        context: &mut TraceContext,
        occlusion: bool,
    ) {
        let ctx = context.as_raw();
        // SAFETY: the scene is committed; `ray_hit` is a properly aligned RTCRayHit (RTCRay
        // is its first member, for rtcOccluded1) and the context is live for the call.
        unsafe {
            if occlusion {
                ffi::rtcOccluded1(self.raw(), ctx, &mut ray_hit.0.ray);
            } else {
                ffi::rtcIntersect1(self.raw(), ctx, &mut ray_hit.0);
            }
        }
    }

    /// Closest hits for a stream of rays (`rtcIntersect1M`, or one `rtcIntersect1` per ray on
    /// a device without stream support); results are in each `RayHit`.
    pub fn intersect_stream(
        &self,
        rays: &mut [RayHit],
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.trace_stream(rays, options, false)
    }

    /// Occlusion for a stream of rays (`rtcOccluded1M`, or one `rtcOccluded1` per ray on a
    /// device without stream support); see [`RayHit::is_occluded`].
    pub fn occluded_stream(
        &self,
        rays: &mut [RayHit],
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.trace_stream(rays, options, true)
    }

    fn trace_stream(
        &self,
        rays: &mut [RayHit],
        options: TraceOptions,
        occlusion: bool,
    ) -> Result<(), EmbreeError> {
        // Ray ids are u32, so (absurdly) long streams are traced in chunks, each with the
        // matching part of the payload.
        const CHUNK: usize = u32::MAX as usize;
        let streams = self.stream_supported();
        let mut first_error = Ok(());
        for (chunk_index, chunk) in rays.chunks_mut(CHUNK).enumerate() {
            let payload = options
                .payload
                .map(|p| p.get(chunk_index * CHUNK..).unwrap_or(&[]));
            let mut context = TraceContext::new(&TraceOptions { payload, ..options });
            for (i, r) in chunk.iter_mut().enumerate() {
                r.0.ray.id = i as u32;
            }
            let operation = if streams {
                let ctx = context.as_raw();
                // SAFETY: `RayHit` is repr(transparent) over RTCRayHit, so `chunk` is `len`
                // consecutive, 16-byte aligned RTCRayHits with stride
                // size_of::<RTCRayHit>(); RTCRay is their first member (for
                // rtcOccluded1M). The scene is committed and the context outlives the call;
                // Embree writes only within the slice.
                unsafe {
                    let first = chunk.as_mut_ptr() as *mut ffi::RTCRayHit;
                    let stride = std::mem::size_of::<ffi::RTCRayHit>();
                    if occlusion {
                        ffi::rtcOccluded1M(
                            self.raw(),
                            ctx,
                            first as *mut ffi::RTCRay,
                            chunk.len() as u32,
                            stride,
                        );
                    } else {
                        ffi::rtcIntersect1M(self.raw(), ctx, first, chunk.len() as u32, stride);
                    }
                }
                if occlusion {
                    "rtcOccluded1M"
                } else {
                    "rtcIntersect1M"
                }
            } else {
                for ray_hit in chunk.iter_mut() {
                    self.trace_one(ray_hit, &mut context, occlusion);
                }
                if occlusion {
                    "rtcOccluded1"
                } else {
                    "rtcIntersect1"
                }
            };
            let result = self.finish_trace(context, operation);
            if first_error.is_ok() {
                first_error = result;
            }
        }
        first_error
    }
}
