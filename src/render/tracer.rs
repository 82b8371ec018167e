//! Ray batches through Embree: the render stage's only door into `crate::embree`.
//!
//! The integrator works on slices of rays (a 4x4 tile of camera rays, a wave of secondary
//! rays, a batch of shadow rays); this file cuts them into packets of the device's native
//! width and copies hits back. Camera rays of a 4x4 pixel block sit in consecutive slots,
//! so a 16-wide packet is exactly one block.

use glam::Vec3;

/// A ray to trace: unit direction, `t` in (0, tfar].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRay {
    pub origin: Vec3,
    pub direction: Vec3,
    pub tfar: f32,
    /// Cone width at the origin and spread angle, for alpha-cutout callbacks.
    pub cone_width: f32,
    pub cone_spread: f32,
}

/// The closest hit of a [`TraceRay`], or a miss (`geometry == u32::MAX`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceHit {
    pub t: f32,
    pub geometry: u32,
    pub primitive: u32,
    pub u: f32,
    pub v: f32,
}

impl TraceHit {
    pub const MISS: TraceHit = TraceHit {
        t: f32::INFINITY,
        geometry: u32::MAX,
        primitive: u32::MAX,
        u: 0.0,
        v: 0.0,
    };

    #[inline]
    pub fn is_hit(&self) -> bool {
        self.geometry != u32::MAX
    }
}
