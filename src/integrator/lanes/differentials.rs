//! Stage 3 for ray differentials: each lane's differential moved to its hit, from the
//! lane arrays alone (no `SurfaceHit`), as `footprint::Footprint::transfer` and the path
//! tracer's replacement by the camera's footprint move it.
//!
//! A differential's transfer reads the hit's distance and geometric normal (Igehy 1999,
//! eqs. 10-12): the lanes hold both once stage 2 has run, so the transfer runs here, after
//! `interpolate` and before the texture gradients (`footprints::texture_gradients`), which
//! then project the differential's dP/dx, dP/dy onto st as they project a cone's ellipse.

use glam::Vec3;

use super::{LaneArray, WaveLanes};
use crate::camera::Camera;
use crate::footprint::RayDifferential;

/// How a lane's ray differential reaches its hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum LaneDifferential {
    /// The ray's differential, transferred along it onto the hit's tangent plane
    /// (`RayDifferential::transfer`).
    Carried(RayDifferential),
    /// Replaced at the hit by the camera's footprint there (`Camera::approximate_dp_dxy`):
    /// the path tracer's differentials after a non-delta bounce.
    FromCamera,
}

/// Every lane's differential at its hit into `lanes.differential_at_hit` (zero for lanes
/// without one): `RayDifferential::transfer` onto the lane's distance and geometric normal,
/// or the camera's parallel differential at the lane's point for the path tracer's
/// approximated ones (with `spp` the render's samples per pixel, as the scalar path
/// passes it).
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn differentials_at_hits(lanes: &mut WaveLanes, camera: &Camera, spp: u32) {
    let len = lanes.len();
    lanes.differential_at_hit.clear();
    if lanes.differential.is_empty() {
        return;
    }
    lanes
        .differential_at_hit
        .resize_lanes(len, RayDifferential::default());
    for lane in 0..len {
        let Some(differential) = lanes.differential[lane] else {
            continue;
        };
        let normal = lanes.geometric_normal.get(lane);
        lanes.differential_at_hit[lane] = match differential {
            LaneDifferential::Carried(d) => {
                d.transfer_to(lanes.direction.get(lane), lanes.t[lane], normal)
            }
            LaneDifferential::FromCamera => {
                let point = lanes.surface_point(lane);
                let (dpdx, dpdy) = camera.approximate_dp_dxy(point, normal, spp);
                RayDifferential::parallel(dpdx, dpdy)
            }
        };
    }
}

/// The world-space footprint axes of lane `lane`'s differential at its hit (Igehy 1999,
/// section 4: dP/dx and dP/dy span the pixel's footprint on the surface).
#[inline(always)]
pub(crate) fn differential_axes(at_hit: &[RayDifferential], lane: usize) -> (Vec3, Vec3) {
    let d = &at_hit[lane];
    (d.dpdx, d.dpdy)
}
