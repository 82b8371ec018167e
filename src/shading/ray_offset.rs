//! Self-intersection avoidance for secondary rays, independent of the scene's scale.
//!
//! Seed 001 ("Sec. rays can and will intersect with originating surface point (self
//! intersection) ... Offset the origin"): a hit point computed in floating point lies a few
//! rounding errors off the true surface, on either side, so a reflected, refracted or shadow
//! ray started exactly there may hit its own surface again. A fixed epsilon such as 0.01 is
//! too large for millimetre-sized scenes and too small far from the origin.
//!
//! Instead, in the spirit of Wächter and Binder ("A Fast and Robust Method for Avoiding
//! Self-Intersection", Ray Tracing Gems, ch. 6), the offset is a fixed number of ULPs of the
//! point's own coordinates: rounding errors of a computed position scale with the magnitude
//! of its coordinates, so an offset measured in ULPs is right at every scale. Here the ULP is
//! that of the *largest* coordinate, so a coordinate that happens to be near zero (a point on
//! the plane `y = 0`, say) still moves by an amount matching the point's real rounding error.
//! Near the origin, where all coordinates are tiny, a tiny absolute floor keeps the offset
//! from vanishing.
//!
//! The offset must exceed the rounding error of `p`, which scales with the magnitude of the
//! numbers `p` was computed from. [`offset_ray_origin`] assumes that is `p`'s own magnitude
//! (true for a point interpolated on a triangle whose vertices are not much larger than the
//! point, or on a sphere); [`offset_ray_origin_with_scale`] takes the magnitude explicitly,
//! e.g. the largest absolute vertex coordinate of the hit triangle, for points near the origin
//! on large triangles. A point computed as `origin + t * direction` from a far-away ray
//! origin carries errors of the origin's magnitude and needs that as its scale.

use glam::Vec3;

/// How many ULPs of the largest coordinate the origin is moved along the normal.
pub const OFFSET_ULPS: f32 = 64.0;

/// The smallest ULP used: `2^-60`, the ULP of coordinates around `1e-11`. Points with all
/// coordinates below that share one absolute offset of `OFFSET_ULPS * 2^-60`.
pub const MIN_ULP: f32 = 8.673_617e-19;

/// Moves the hit point `p` off its surface to the side of `geometric_normal`, by
/// [`OFFSET_ULPS`] units in the last place of `p`'s largest coordinate.
///
/// `geometric_normal` is the unit geometric normal flipped by the caller to the side the
/// new ray leaves from (the incident side for reflections and shadow rays towards lights in
/// front, the far side for refractions). Non-finite points are returned unchanged.
#[inline]
pub fn offset_ray_origin(p: Vec3, geometric_normal: Vec3) -> Vec3 {
    offset_ray_origin_with_scale(p, geometric_normal, 0.0)
}

/// Like [`offset_ray_origin`], but measures the ULP at `max(|p|_max, coordinate_scale)`:
/// pass the largest absolute coordinate of the values `p` was computed from (for a triangle
/// hit, of its three vertices) when that can exceed `p`'s own coordinates.
#[inline]
pub fn offset_ray_origin_with_scale(
    p: Vec3,
    geometric_normal: Vec3,
    coordinate_scale: f32,
) -> Vec3 {
    let largest = p.abs().max_element().max(coordinate_scale.abs());
    if !largest.is_finite() {
        return p;
    }
    // ULP of `largest`: its power-of-two exponent times 2^-23.
    let power_of_two = f32::from_bits(largest.to_bits() & 0x7f80_0000);
    let ulp = (power_of_two * f32::EPSILON).max(MIN_ULP);
    p + geometric_normal * (OFFSET_ULPS * ulp)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use proptest::prelude::*;

    fn ulp_of(x: f32) -> f64 {
        let x = x.abs();
        (f32::from_bits(x.to_bits() + 1) - x) as f64
    }

    /// Checks that `offset` is strictly on the `n` side of the plane through `p` with normal
    /// `n` (in f64) and moved by at most a few ULPs relative to `p`'s magnitude.
    fn check(p: Vec3, n: Vec3) {
        let moved = offset_ray_origin(p, n);
        let delta = moved.as_dvec3() - p.as_dvec3();
        let signed = delta.dot(n.as_dvec3());
        assert!(
            signed > 0.0,
            "p {p} n {n}: offset point on the wrong side ({signed})"
        );
        let ulp = ulp_of(p.abs().max_element()).max(MIN_ULP as f64);
        let ulps_moved = delta.length() / ulp;
        assert!(
            ulps_moved <= 2.0 * OFFSET_ULPS as f64,
            "moved {ulps_moved} ULPs"
        );
        assert!(
            ulps_moved >= 0.5 * OFFSET_ULPS as f64,
            "moved only {ulps_moved} ULPs"
        );
    }

    #[test]
    fn offset_is_relative_at_every_scale() {
        let normals = [
            Vec3::Y,
            -Vec3::Y,
            Vec3::new(1.0, 1.0, 1.0).normalize(),
            Vec3::new(-0.2, 0.05, 0.97).normalize(),
        ];
        for &scale in &[1e-4f32, 1.0, 1e5] {
            for &n in &normals {
                check(Vec3::new(0.3, -0.7, 0.9) * scale, n);
                // A coordinate near zero (point on the y = 0 plane, with rounding noise).
                check(Vec3::new(0.8 * scale, 1e-12, -0.4 * scale), n);
                let moved = offset_ray_origin(Vec3::splat(scale), n);
                let relative = (moved - Vec3::splat(scale)).length() / scale;
                assert!(relative < 2e-5, "scale {scale}: relative move {relative}");
            }
        }
    }

    #[test]
    fn explicit_scale_enlarges_the_offset_for_points_near_the_origin() {
        let p = Vec3::new(1e-3, 0.0, 2e-3);
        let small = offset_ray_origin(p, Vec3::Y).y;
        let large = offset_ray_origin_with_scale(p, Vec3::Y, 100.0).y;
        assert!(large > 1e4 * small);
        assert!(large >= OFFSET_ULPS * 64.0 * f32::EPSILON);
        // A scale below p's own magnitude changes nothing.
        assert_eq!(
            offset_ray_origin_with_scale(p, Vec3::Y, 1e-9),
            offset_ray_origin(p, Vec3::Y)
        );
    }

    #[test]
    fn points_at_the_origin_still_move() {
        let moved = offset_ray_origin(Vec3::ZERO, Vec3::Z);
        assert!(moved.z > 0.0 && moved.z < 1e-15);
        assert_eq!(moved.x, 0.0);
    }

    #[test]
    fn non_finite_points_are_left_alone() {
        let p = Vec3::new(f32::INFINITY, 0.0, 1.0);
        assert_eq!(offset_ray_origin(p, Vec3::Y), p);
    }

    proptest! {
        /// A point interpolated in f32 on a random triangle at a random scale, offset along
        /// the f32 geometric normal, lies strictly in front of the exact (f64) triangle plane.
        #[test]
        fn interpolated_hit_points_leave_their_triangle_plane(
            exponent in -4i32..=5,
            coords in proptest::array::uniform9(-1.0f32..1.0),
            shift in proptest::array::uniform3(-4.0f32..4.0),
            u in 0.0f32..1.0, v in 0.0f32..1.0,
            flip in proptest::bool::ANY,
        ) {
            let scale = 10f32.powi(exponent);
            let offset = Vec3::from_array(shift) * scale;
            let v0 = Vec3::new(coords[0], coords[1], coords[2]) * scale + offset;
            let v1 = Vec3::new(coords[3], coords[4], coords[5]) * scale + offset;
            let v2 = Vec3::new(coords[6], coords[7], coords[8]) * scale + offset;
            let n_exact: DVec3 = (v1.as_dvec3() - v0.as_dvec3()).cross(v2.as_dvec3() - v0.as_dvec3());
            // Skip slivers: their normals are ill-conditioned in any precision.
            let edge = (v1 - v0).length().max((v2 - v0).length()).max((v2 - v1).length()) as f64;
            prop_assume!(n_exact.length() > 0.05 * edge * edge);
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let p = (1.0 - u - v) * v0 + u * v1 + v * v2;
            let n = (v1 - v0).cross(v2 - v0).normalize();
            let n = if flip { -n } else { n };
            let n_exact = if flip { -n_exact } else { n_exact }.normalize();
            let vertex_scale = v0.abs().max(v1.abs()).max(v2.abs()).max_element();
            let moved = offset_ray_origin_with_scale(p, n, vertex_scale);
            prop_assert!((moved - p).length() <= 2.0 * OFFSET_ULPS * vertex_scale * f32::EPSILON);
            let signed = (moved.as_dvec3() - v0.as_dvec3()).dot(n_exact);
            prop_assert!(signed > 0.0, "signed distance {}", signed);
        }
    }
}
