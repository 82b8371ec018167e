//! Spawn points: where reflected, refracted and shadow rays start, so that they do not hit
//! the surface they leave, at any scene scale and any camera distance.
//!
//! Seed 001 ("Sec. rays can and will intersect with originating surface point (self
//! intersection) ... Offset the origin"): a hit point computed in floating point lies a few
//! rounding errors off the true surface, on either side. A fixed epsilon is wrong at some
//! scale, and an offset in ULPs of the point's own coordinates is wrong too when the point
//! was computed as `origin + t * direction`: that point inherits rounding errors of the ray's
//! origin and length, so a camera 1e4 units away puts its hits on a unit sphere some 1e-3
//! off the surface, far more than any ULP of the sphere's coordinates.
//!
//! So a hit point is recomputed from the surface itself and carries a bound on its own
//! rounding error ([`SpawnPoint`]), and a new ray starts just outside that bound, in the
//! spirit of pbrt-v4 (Pharr, Jakob, Humphreys, *Physically Based Rendering*, 4th ed.,
//! sec. 6.8, "Managing Rounding Error") and Wächter and Binder (*Ray Tracing Gems*, ch. 6):
//!
//! - on a triangle, `P = b0 p0 + b1 p1 + b2 p2` from Embree's barycentrics, evaluated in f64
//!   and rounded once to f32, whose error per coordinate is at most `gamma(1) * sum |b_i p_i|`
//!   ([`SpawnPoint::on_triangle`]);
//! - on a sphere, the point projected onto the sphere, `c + r (P - c) / |P - c|`, with error
//!   at most `gamma(7) * (|c| + |P - c|)` per coordinate ([`SpawnPoint::on_sphere`]);
//!
//! where `gamma(n) = n u / (1 - n u)` bounds `n` successive roundings with unit roundoff
//! `u = 2^-24` (Higham, *Accuracy and Stability of Numerical Algorithms*, sec. 3.1). Neither
//! bound depends on the ray that found the point.
//!
//! [`SpawnPoint::offset_origin`] then moves the point along the geometric normal by the
//! extent of the error box in that direction (`|n| . error`), and finally one float further
//! in every coordinate, rounding away from the surface, so that the addition's own rounding
//! cannot pull the origin back. The intersector evaluates the triangle's plane or the
//! sphere's quadratic with rounding of its own, which the bounds above do not model;
//! [`INTERSECTOR_SLACK`] widens them for it. `tests/spawn_points.rs` traces rays leaving
//! triangles and spheres through Embree (sizes 1e-4 to 1e6, up to 1e6 from the origin,
//! grazing to normal): none meets its surface. Without the slack, none does with only a
//! quarter of the `gamma(7)` bound either, while with no offset beyond one float 48 of
//! 17,904 triangle rays and 205 of 13,951 sphere rays do.
//!
//! Two more places where rounding grows with distance are handled here: a shadow ray towards
//! a point light stops short of it by a margin measured from the ray's own origin and the
//! light's coordinates ([`shadow_ray_end`]), and a camera ray from far away starts tracing
//! where it enters the scene's bounds ([`entry_distance`]), because the intersector's
//! rounding grows with the distance from the ray's origin to the vertices.
//!
//! What this module must not do: know about Embree, rays in flight or materials. Callers
//! pick the side a ray leaves from (the geometric normal, flipped towards the incident side
//! for reflections and shadow rays, away from it for refractions).

use glam::{DVec3, Vec3};

/// Unit roundoff of f32 (round to nearest): half the distance from 1 to the next float.
pub const UNIT_ROUNDOFF: f32 = f32::EPSILON * 0.5;

/// `gamma(n) = n u / (1 - n u)`: a bound on the relative error of `n` successive f32
/// roundings (Higham, sec. 3.1; pbrt-v4, sec. 6.8.1).
#[inline]
pub const fn gamma(n: u32) -> f32 {
    let nu = n as f32 * UNIT_ROUNDOFF;
    nu / (1.0 - nu)
}

/// Roundings added to a point's error bound for the intersector's own evaluation of the
/// surface. Embree's triangle test measures the plane through a vertex with a normal rounded
/// from the edges, and its sphere test solves the quadratic relative to the centre: a few
/// roundings of the coordinates involved. A margin, not a proof: the `gamma(7)` bounds alone
/// pass `tests/spawn_points.rs` four times over.
pub const INTERSECTOR_SLACK: u32 = 4;

/// The error bound of a point computed with `roundings` roundings from values of
/// `magnitude` (per coordinate), widened for the intersector.
///
/// The intersector's own arithmetic is not per coordinate: a triangle test works with
/// `vertex - origin` and cross products that mix the coordinates, so its rounding scales with
/// the largest magnitude involved in every direction. A point on the plane `y = 0` has an
/// exact y (error 0), yet a ray leaving it one float above (a denormal, which Embree's
/// flush-to-zero mode reads as 0) still meets the plane. So the slack is isotropic:
/// `gamma(INTERSECTOR_SLACK)` of the largest magnitude, added to every coordinate.
#[inline]
fn with_intersector_slack(magnitude: Vec3, roundings: u32) -> Vec3 {
    magnitude * gamma(roundings + INTERSECTOR_SLACK)
        + Vec3::splat(magnitude.max_element() * gamma(INTERSECTOR_SLACK))
}

/// A point on a surface with a bound on the rounding error of each of its coordinates: the
/// exact surface point it stands for lies within `position +- error` (componentwise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpawnPoint {
    pub position: Vec3,
    /// Absolute error bound per coordinate (non-negative).
    pub error: Vec3,
}

impl SpawnPoint {
    /// The point of triangle `p` at Embree's barycentrics `(u, v)`:
    /// `P = (1 - u - v) p0 + u p1 + v p2`, evaluated in f64.
    ///
    /// Error: in f64 the weights sum to 1 exactly (`u` and `v` are f32), each product of an
    /// f32 coordinate and an f32-sized weight is exact, and the two sums round at 2^-53, so
    /// the f64 point lies on the triangle's plane far below one f32 rounding; rounding it to
    /// f32 is the error, `gamma(1) * sum |b_i p_i|` per coordinate, plus the intersector's
    /// slack on the same magnitude. Evaluated in f32 (five roundings, two more in
    /// `1 - u - v`) the bound was `gamma(7)`, and the offset origins built on it stood about
    /// 40 % further from the surface: 0.13 units at 131072 instead of 0.09.
    #[inline]
    pub fn on_triangle(p: [Vec3; 3], u: f32, v: f32) -> SpawnPoint {
        let (u, v) = (f64::from(u), f64::from(v));
        let w = 1.0 - u - v;
        let position = p[0].as_dvec3() * w + p[1].as_dvec3() * u + p[2].as_dvec3() * v;
        let magnitude = p[0].as_dvec3().abs() * w.abs()
            + p[1].as_dvec3().abs() * u.abs()
            + p[2].as_dvec3().abs() * v.abs();
        SpawnPoint {
            position: position.as_vec3(),
            error: with_intersector_slack(magnitude.as_vec3(), 1),
        }
    }

    /// The point of the sphere (`center`, `radius`) in the direction of `near` (any point
    /// close to the surface, e.g. `origin + t * direction` of the ray that hit it), with
    /// its unit outward normal. A `near` at the centre gives the sphere's top.
    ///
    /// Error: normalising rounds about five times, scaling by the radius once and adding
    /// the centre once more; each coordinate is off by at most
    /// `gamma(7) * (|c_i| + r |n_i|)`, plus the intersector's slack on the same magnitude.
    #[inline]
    pub fn on_sphere(center: Vec3, radius: f32, near: Vec3) -> (SpawnPoint, Vec3) {
        let normal = (near - center).normalize_or(Vec3::Y);
        let from_center = normal * radius;
        let position = center + from_center;
        let magnitude = center.abs() + from_center.abs();
        (
            SpawnPoint {
                position,
                error: with_intersector_slack(magnitude, 7),
            },
            normal,
        )
    }

    /// The point of a curved patch evaluated in f64 (`crate::render::patch_geometry`), whose
    /// control points have coordinates of at most `magnitude`. The f64 evaluation's own error
    /// (a few dozen roundings of 2^-53 on sums of Bernstein-weighted control points, whose
    /// weights sum to 1) is far below one f32 rounding, so the bound is the rounding to f32
    /// (`gamma(1)`) plus the intersector's slack, on the control points' magnitude. The
    /// patch intersector solves in f64 to 1e-9 of the patch's size, also far below it.
    #[inline]
    pub fn on_curved_patch(position: glam::DVec3, magnitude: Vec3) -> SpawnPoint {
        SpawnPoint {
            position: position.as_vec3(),
            error: with_intersector_slack(magnitude, 1),
        }
    }

    /// The point `origin + t * direction` of a ray, when the surface is not at hand. Its
    /// error bound covers the rounding of the expression and a relative error of a few
    /// roundings in `t` (`gamma(INTERSECTOR_SLACK)`), but an intersector's `t` can be off
    /// by more at grazing angles: prefer [`SpawnPoint::on_triangle`] and
    /// [`SpawnPoint::on_sphere`], which do not depend on the ray.
    #[inline]
    pub fn along_ray(origin: Vec3, direction: Vec3, t: f32) -> SpawnPoint {
        let travelled = direction * t;
        SpawnPoint {
            position: origin + travelled,
            error: origin.abs() * gamma(1) + travelled.abs() * gamma(2 + INTERSECTOR_SLACK),
        }
    }

    /// The origin of a ray leaving the surface on the side of `leave_normal` (a unit
    /// geometric normal, flipped by the caller to the side the ray goes to): the point
    /// moved along `leave_normal` past its error box, then each coordinate rounded one float
    /// further away from the surface. Non-finite points are returned unchanged.
    // Always inlined, as lane loops (`integrator::lanes::lights`) vectorise only what is
    // inlined into them.
    #[inline(always)]
    pub fn offset_origin(&self, leave_normal: Vec3) -> Vec3 {
        let p = self.position;
        if !p.is_finite() || !leave_normal.is_finite() {
            return p;
        }
        // The extent of the error box along the normal: the support function of the box.
        let distance = leave_normal.abs().dot(self.error);
        let moved = p + leave_normal * distance;
        Vec3::new(
            away(moved.x, leave_normal.x),
            away(moved.y, leave_normal.y),
            away(moved.z, leave_normal.z),
        )
    }
}

/// Shadow rays towards a point stop this fraction of the distance short of it: far more
/// than the rounding of the distance (`gamma(3)`) or of the intersector's `t` (a few
/// roundings), so a surface the light sits on (a lamp on a wall) does not occlude it.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// The far end (`tfar`) of a shadow ray towards a point light, or a point sampled on an
/// area light, at `light`, `distance` away from the ray's origin (measured from that origin,
/// so it carries only the relative rounding of `|light - origin|`). The ray stops
/// [`SHADOW_EPSILON`] of the distance short of the light and, in addition, by the rounding
/// of the coordinates the light is placed with: the larger of the light point's own and
/// `surface_scale`, the magnitude of the coordinates of the surface it lies on
/// ([`crate::shading::AreaLight::coordinate_scale`]; 0 for a point light). The intersector
/// finds that surface a few such roundings from where the point was computed, wherever on
/// it the point is: a point on a unit sphere light 1e-4 from the shading point, sampled and
/// found 1e-7 apart, would otherwise have the light block its own shadow ray. At `|light| =
/// 1e4` the margin is about 5e-3, more than `SHADOW_EPSILON` of a distance under 50. An
/// infinite distance (directional lights) stays infinite.
#[inline]
pub fn shadow_ray_end(distance: f32, light: Vec3, surface_scale: f32) -> f32 {
    if !distance.is_finite() {
        return f32::INFINITY;
    }
    let scale = light.abs().max_element().max(surface_scale);
    let placement = scale * gamma(7 + INTERSECTOR_SLACK);
    (distance * (1.0 - SHADOW_EPSILON) - placement).max(0.0)
}

/// The shadow ray from `origin` (a spawn point's offset origin) to `target` (a point light,
/// or a sampled point on an area light with the coordinate scale of the light's surface,
/// 0 for a point light): its unit direction and its far end ([`shadow_ray_end`] of the
/// distance from `origin`); `None` when they coincide. A light without a position (`target`
/// `None`: directional, environment) is reached along `direction_to_light`, unbounded.
///
/// The light itself is seen from the surface point, not from `origin`: the offset grows
/// with the coordinates (about 0.1 units at 131072), and a light measured from there came
/// that much closer (`tests/far_from_origin.rs`). Only visibility is asked from `origin`.
///
/// `target` is in f64 and the direction is taken from the exact difference: a sampled
/// point rounded to f32 lies up to half a unit in the last place off the light's surface
/// (5e-4 at 1e4), and a shadow ray that grazes a sphere light on its way to such a point
/// enters the sphere that much divided by the grazing cosine before it, further than
/// [`shadow_ray_end`] stops short.
#[inline]
pub fn shadow_ray_towards(
    origin: Vec3,
    target: Option<(DVec3, f32)>,
    direction_to_light: Vec3,
) -> Option<(Vec3, f32)> {
    let Some((target, surface_scale)) = target else {
        return Some((direction_to_light, f32::INFINITY));
    };
    let to_target = target - origin.as_dvec3();
    let distance = to_target.length();
    if !(distance > 0.0 && distance.is_finite()) {
        return None;
    }
    let direction = (to_target / distance).as_vec3();
    Some((
        direction.normalize(),
        shadow_ray_end(distance as f32, target.as_vec3(), surface_scale),
    ))
}

/// How far along the ray (`origin`, unit `direction`) tracing may start without skipping
/// anything inside the box `bounds` (the scene's bounds): just before the ray enters the
/// box, or 0 when the origin is inside it, the ray misses it, or a value is not finite.
///
/// A camera far from the scene makes the intersector's rounding grow with the origin's
/// distance: Embree's triangle test works with `vertex - origin`, so edges shared by two
/// triangles open cracks of about `u |vertex - origin|`, and a camera ray 1e4 units away
/// slips through a closed mesh now and then and hits its far side. Starting the ray near the
/// box keeps those differences at the scene's size. The start stops short of the entry by a
/// thousandth of the box's diagonal plus the rounding of `origin + start * direction`.
#[inline]
pub fn entry_distance(origin: Vec3, direction: Vec3, bounds: (Vec3, Vec3)) -> f32 {
    let [start] = entry_distances(
        origin,
        &[[direction.x], [direction.y], [direction.z]],
        bounds,
    );
    start
}

/// [`entry_distance`] of the rays from one `origin` along each of `directions` (unit
/// vectors as structure-of-arrays: x, y and z of every lane), each lane on its own, the
/// lanes' divisions running as vector instructions. Always inlined, so that a
/// `simd::dispatch` kernel compiles it for its level.
#[inline(always)]
pub fn entry_distances<const N: usize>(
    origin: Vec3,
    directions: &[[f32; N]; 3],
    bounds: (Vec3, Vec3),
) -> [f32; N] {
    let (lo, hi) = bounds;
    let mut out = [0.0f32; N];
    // An origin inside the bounds enters at 0 whatever the direction: on every axis one of
    // the two slab distances below is <= 0, so `enter` stays 0. Said without dividing.
    let inside = origin.cmpge(lo).all() && origin.cmple(hi).all();
    if !(origin.is_finite() && lo.is_finite() && hi.is_finite()) || inside {
        return out;
    }
    let diagonal_margin = 1e-3 * (hi - lo).length();
    let origin_size = origin.abs().max_element();
    for (lane, start) in out.iter_mut().enumerate() {
        let mut finite = true;
        let mut parallel_outside = false;
        let mut enter = 0.0f32;
        let mut exit = f32::INFINITY;
        for axis in 0..3 {
            let (o, d) = (origin[axis], directions[axis][lane]);
            finite &= d.is_finite();
            // Computed for every lane, used where `d` is not zero (as `entry_distance` does).
            let (a, b) = ((lo[axis] - o) / d, (hi[axis] - o) / d);
            if d == 0.0 {
                parallel_outside |= o < lo[axis] || o > hi[axis];
            } else {
                enter = enter.max(a.min(b));
                exit = exit.min(a.max(b));
            }
        }
        let entered =
            finite && !parallel_outside && enter > 0.0 && enter <= exit && enter.is_finite();
        let margin = diagonal_margin + gamma(8) * (origin_size + enter);
        *start = if entered {
            (enter - margin).max(0.0)
        } else {
            0.0
        };
    }
    out
}

/// `x` moved to the next float in the direction of `sign` (unchanged when `sign` is zero).
#[inline(always)]
fn away(x: f32, sign: f32) -> f32 {
    if sign > 0.0 {
        x.next_up()
    } else if sign < 0.0 {
        x.next_down()
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::{unit_f32, xorshift32};

    #[test]
    fn entry_distances_are_entry_distance_bit_for_bit() {
        // Origins outside, inside and on the box, near and far; directions of every kind,
        // axis-parallel and non-finite ones included.
        let bounds = (Vec3::new(-2.0, 0.0, -3.0), Vec3::new(4.0, 1.5, 1.0));
        let origins = [
            Vec3::new(0.0, 1.6, 3.0),
            Vec3::new(1.0, 0.5, 0.0),
            Vec3::new(4.0, 0.5, 0.0),
            Vec3::new(-2.0, 7.0, 1.0),
            Vec3::new(3.0e4, -2.0e4, 1.0e5),
            Vec3::new(f32::NAN, 0.0, 0.0),
        ];
        let mut state = 0x2545_f491u32;
        let mut next = move || unit_f32(xorshift32(&mut state)) * 2.0 - 1.0;
        for origin in origins {
            for round in 0..200 {
                let mut directions = [[0.0f32; 16]; 3];
                for lane in 0..16 {
                    let mut d = Vec3::new(next(), next(), next());
                    match (round % 4, lane % 8) {
                        (0, 0) => d.x = 0.0,
                        (0, 1) => d = Vec3::new(0.0, 0.0, -1.0),
                        (0, 2) => d.y = f32::NAN,
                        (0, 3) => d.z = f32::INFINITY,
                        (0, 4) => d = Vec3::ZERO,
                        _ => {}
                    }
                    let d = d.normalize_or(d);
                    for (axis, column) in directions.iter_mut().enumerate() {
                        column[lane] = d[axis];
                    }
                }
                let starts = entry_distances(origin, &directions, bounds);
                for (lane, start) in starts.iter().enumerate() {
                    let d = Vec3::new(
                        directions[0][lane],
                        directions[1][lane],
                        directions[2][lane],
                    );
                    let one = entry_distance(origin, d, bounds);
                    assert_eq!(
                        start.to_bits(),
                        one.to_bits(),
                        "origin {origin}, direction {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_point_on_an_axis_plane_leaves_by_a_normal_float() {
        // Every vertex has y = 0 exactly, so the interpolated y is exact; the intersector's
        // rounding is not, and scales with the other coordinates.
        let p = [
            Vec3::new(-5.0, 0.0, -5.0),
            Vec3::new(5.0, 0.0, 5.0),
            Vec3::new(5.0, 0.0, -5.0),
        ];
        let spawn = SpawnPoint::on_triangle(p, 0.3, 0.2);
        let origin = spawn.offset_origin(Vec3::Y);
        assert!(
            origin.y >= 5.0 * gamma(INTERSECTOR_SLACK),
            "origin {origin}: a denormal offset is flushed to zero by the intersector"
        );
        let (sphere, normal) = SpawnPoint::on_sphere(Vec3::ZERO, 1.0, Vec3::new(0.0, 2.0, 0.0));
        assert!(sphere.offset_origin(normal).y > 1.0 + 0.5 * gamma(INTERSECTOR_SLACK));
    }
    use glam::DVec3;
    use proptest::prelude::*;

    #[test]
    fn gamma_matches_its_definition() {
        let u = 2f64.powi(-24);
        for n in [1u32, 3, 7, 11] {
            let expected = n as f64 * u / (1.0 - n as f64 * u);
            assert!(((gamma(n) as f64) - expected).abs() <= 1e-6 * expected);
        }
    }

    #[test]
    fn a_point_with_no_error_still_leaves_its_plane() {
        let p = SpawnPoint {
            position: Vec3::new(3.0, 0.0, -2.0),
            error: Vec3::ZERO,
        };
        let up = p.offset_origin(Vec3::Y);
        assert!(up.y > 0.0 && up.y < 1e-37, "{up}");
        assert_eq!((up.x, up.z), (3.0, -2.0));
        let down = p.offset_origin(-Vec3::Y);
        assert!(down.y < 0.0);
    }

    #[test]
    fn points_on_an_axis_aligned_plane_keep_that_coordinate_exact() {
        // A ground plane y = 0 far from the origin: the interpolated y is exactly zero, but
        // the intersector's rounding scales with x and z, so the bound does too, in y as well.
        let tri = [
            Vec3::new(1e4, 0.0, 1e4),
            Vec3::new(1e4 + 50.0, 0.0, 1e4),
            Vec3::new(1e4, 0.0, 1e4 + 50.0),
        ];
        let s = SpawnPoint::on_triangle(tri, 0.3, 0.2);
        assert_eq!(s.position.y, 0.0);
        assert!(s.error.y >= 1e4 * gamma(INTERSECTOR_SLACK), "{}", s.error);
        assert!(s.error.x > s.error.y);
    }

    #[test]
    fn sphere_points_lie_on_the_sphere_within_their_bound() {
        let center = Vec3::new(1e3, -2e3, 5e2);
        let radius = 0.75;
        for &near in &[
            center + Vec3::new(0.75, 0.001, 0.0),
            center + Vec3::new(-0.3, 0.6, 0.5) * 1.01,
            center + Vec3::new(0.0, 0.0, -0.7),
        ] {
            let (s, n) = SpawnPoint::on_sphere(center, radius, near);
            let from_center = s.position.as_dvec3() - center.as_dvec3();
            let off_surface = (from_center.length() - radius as f64).abs();
            assert!(off_surface <= s.error.as_dvec3().length(), "{off_surface}");
            assert!((n.length() - 1.0).abs() < 1e-6);
            let outside = s.offset_origin(n).as_dvec3() - center.as_dvec3();
            let inside = s.offset_origin(-n).as_dvec3() - center.as_dvec3();
            assert!(outside.length() > radius as f64);
            assert!(inside.length() < radius as f64);
        }
    }

    #[test]
    fn non_finite_points_are_left_alone() {
        let s = SpawnPoint {
            position: Vec3::new(f32::INFINITY, 0.0, 1.0),
            error: Vec3::ZERO,
        };
        assert_eq!(s.offset_origin(Vec3::Y), s.position);
    }

    #[test]
    fn along_ray_bounds_grow_with_the_ray_not_the_surface() {
        let near = SpawnPoint::along_ray(Vec3::new(0.0, 0.0, 2.0), -Vec3::Z, 1.0);
        let far = SpawnPoint::along_ray(Vec3::new(0.0, 0.0, 1e4 + 1.0), -Vec3::Z, 1e4);
        assert_eq!(near.position, far.position);
        assert!(far.error.z > 1e3 * near.error.z);
    }

    #[test]
    fn shadow_rays_stop_short_of_lights_at_every_distance() {
        let near_origin = shadow_ray_end(2.0, Vec3::new(0.0, 2.0, 0.0), 0.0);
        assert!(near_origin < 2.0 && near_origin > 2.0 * (1.0 - 2.0 * SHADOW_EPSILON));
        // A light 1e4 from the origin, 1 unit from the point: the rounding of its
        // coordinates (ULP 1e-3) dominates the relative shortfall.
        let far = Vec3::new(1e4, 1.0, 0.0);
        let end = shadow_ray_end(1.0, far, 0.0);
        assert!(end < 1.0 - 1e-3 && end > 0.99, "{end}");
        assert_eq!(
            shadow_ray_end(f32::INFINITY, Vec3::ZERO, 0.0),
            f32::INFINITY
        );
        assert_eq!(shadow_ray_end(1e-9, far, 0.0), 0.0);
        // A point sampled on a light whose surface is computed from coordinates of 1e4
        // stops as short as a light at 1e4, wherever the point itself is.
        let on_big_light = shadow_ray_end(1.0, Vec3::new(0.0, 1.0, 0.0), 1e4);
        assert!(on_big_light < 1.0 - 1e-3, "{on_big_light}");
    }

    #[test]
    fn far_rays_start_just_before_the_scene() {
        let bounds = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
        let origin = Vec3::new(0.0, 1.0, 1e4);
        let start = entry_distance(origin, -Vec3::Z, bounds);
        assert!(start < 1e4 - 1.0 && start > 1e4 - 1.05, "{start}");
        // Inside the box, beside it, pointing away: start at the origin.
        assert_eq!(
            entry_distance(Vec3::new(0.0, 1.0, 0.0), Vec3::X, bounds),
            0.0
        );
        assert_eq!(
            entry_distance(Vec3::new(5.0, 1.0, 1e4), -Vec3::Z, bounds),
            0.0
        );
        assert_eq!(entry_distance(origin, Vec3::Z, bounds), 0.0);
        let nan = (Vec3::splat(f32::NAN), Vec3::ONE);
        assert_eq!(entry_distance(origin, -Vec3::Z, nan), 0.0);
    }

    /// Exact (f64) signed distance of `q` from the plane of `tri`, positive on the side of
    /// `(p1 - p0) x (p2 - p0)`, divided by nothing: only its sign is used.
    fn plane_side(tri: [Vec3; 3], q: Vec3) -> f64 {
        let [a, b, c] = tri.map(|v| v.as_dvec3());
        let n: DVec3 = (b - a).cross(c - a);
        // f64 holds the products of f32 differences exactly enough for the sign: every
        // difference of two f32 is exact in f64 and the cross and dot products of such
        // values carry relative errors of 1e-16, far below the offsets tested.
        (q.as_dvec3() - a).dot(n)
    }

    proptest! {
        /// A point recomputed from barycentrics on a random triangle far from the origin,
        /// at scales 1e-4 to 1e6, offset along the (f32, unit) geometric normal, lies
        /// strictly on that side of the exact triangle plane; and on the other side when
        /// offset the other way.
        #[test]
        fn triangle_spawn_points_leave_the_exact_plane(
            exponent in -4i32..=6,
            coords in proptest::array::uniform9(-1.0f32..1.0),
            shift in proptest::array::uniform3(-1.0f32..1.0),
            distance_exponent in 0i32..=4,
            u in 0.0f32..1.0, v in 0.0f32..1.0,
            flip in proptest::bool::ANY,
        ) {
            let scale = 10f32.powi(exponent);
            // The triangle sits up to 1e4 triangle sizes away from the origin.
            let offset = Vec3::from_array(shift) * scale * 10f32.powi(distance_exponent);
            let tri = [
                Vec3::new(coords[0], coords[1], coords[2]) * scale + offset,
                Vec3::new(coords[3], coords[4], coords[5]) * scale + offset,
                Vec3::new(coords[6], coords[7], coords[8]) * scale + offset,
            ];
            let n_exact = (tri[1].as_dvec3() - tri[0].as_dvec3())
                .cross(tri[2].as_dvec3() - tri[0].as_dvec3());
            let edge = (tri[1] - tri[0]).length().max((tri[2] - tri[0]).length()) as f64;
            // Slivers have ill-conditioned normals in any precision.
            prop_assume!(n_exact.length() > 0.05 * edge * edge);
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let s = SpawnPoint::on_triangle(tri, u, v);
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize();
            let n = if flip { -n } else { n };
            let sign = if flip { -1.0 } else { 1.0 };
            let front = s.offset_origin(n);
            let back = s.offset_origin(-n);
            prop_assert!(sign * plane_side(tri, front) > 0.0, "front {front} of {tri:?}");
            prop_assert!(sign * plane_side(tri, back) < 0.0, "back {back} of {tri:?}");
            // The move is a few ULPs of the triangle's coordinates, not more.
            let largest = tri.iter().map(|p| p.abs().max_element()).fold(0.0, f32::max);
            prop_assert!((front - s.position).length() <= 64.0 * f32::EPSILON * largest);
        }
    }
}
