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
        // SAFETY: the scene is committed; `ray_hit` is a properly aligned RTCRayHit and the
        // context is live for the call.
        unsafe { ffi::rtcIntersect1(self.raw(), context.as_raw(), &mut ray_hit.0) };
        context.finish()?;
        Ok(ray_hit.hit())
    }

    /// Whether anything blocks `ray` between `tnear` and `tfar`.
    pub fn occluded1(&self, ray: &Ray, options: TraceOptions) -> Result<bool, EmbreeError> {
        let mut ray_hit = RayHit::new(ray);
        let mut context = TraceContext::new(&options);
        // SAFETY: as in `intersect1`; RTCRay is the first member of RTCRayHit.
        unsafe { ffi::rtcOccluded1(self.raw(), context.as_raw(), &mut ray_hit.0.ray) };
        context.finish()?;
        Ok(ray_hit.is_occluded())
    }

    /// Closest hits for a stream of rays (`rtcIntersect1M`); results are in each `RayHit`.
    pub fn intersect_stream(
        &self,
        rays: &mut [RayHit],
        options: TraceOptions,
    ) -> Result<(), EmbreeError> {
        self.trace_stream(rays, options, false)
    }

    /// Occlusion for a stream of rays (`rtcOccluded1M`); see [`RayHit::is_occluded`].
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
        let mut first_error = Ok(());
        for (chunk_index, chunk) in rays.chunks_mut(CHUNK).enumerate() {
            let payload = options
                .payload
                .map(|p| p.get(chunk_index * CHUNK..).unwrap_or(&[]));
            let mut context = TraceContext::new(&TraceOptions { payload, ..options });
            for (i, r) in chunk.iter_mut().enumerate() {
                r.0.ray.id = i as u32;
            }
            let ctx = context.as_raw();
            // SAFETY: `RayHit` is repr(transparent) over RTCRayHit, so `chunk` is `len`
            // consecutive, 16-byte aligned RTCRayHits with stride size_of::<RTCRayHit>();
            // RTCRay is their first member (for rtcOccluded1M). The scene is committed and the
            // context outlives the call; Embree writes only within the slice.
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
            let result = context.finish();
            if first_error.is_ok() {
                first_error = result;
            }
        }
        first_error
    }
}
