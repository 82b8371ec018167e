//! Analytic spheres as an Embree user geometry with our own ray/sphere test, the
//! alternative to Embree's point geometry (`RTC_GEOMETRY_TYPE_SPHERE_POINT`) that
//! [`crate::render::tracer::SphereTraversal`] chooses between.
//!
//! The test is the numerically careful quadratic of Haines, Günther and Akenine-Möller 2019,
//! "Precision Improvements for Ray/Sphere Intersection" (Ray Tracing Gems, chapter 7):
//! - the discriminant is `r^2 - |f - (f.d / d.d) d|^2` (their equation 7.10), the squared
//!   distance of the centre from the ray's line subtracted from `r^2`, which loses nothing
//!   to cancellation when a small sphere is far away (the classic `b^2 - 4ac` subtracts two
//!   huge, nearly equal numbers there);
//! - the two roots are `c / q` and `q / a` with `q = b' + sign(b') sqrt(discriminant)`
//!   (their equation 7.15, after Press et al.), so the root near the origin is not the
//!   difference of two nearly equal numbers when a large sphere is close by.
//!
//! Evaluated in double precision, which costs a scalar test nothing and leaves the f32
//! inputs as the only rounding.
//!
//! A hit reports `u = v = 0`, as Embree's point geometry does: the surface lookup
//! (`render::prepared`) rebuilds the point, normal and lat-long coordinates of a sphere hit
//! from its `t` and primitive id alone.

use glam::Vec3;

use crate::embree::{Bounds, UserGeometry, UserHit, UserRay};

/// The scene's spheres `(centre, radius)` as Embree user primitives.
pub struct SphereGeometry {
    spheres: Vec<(Vec3, f32)>,
}

impl SphereGeometry {
    pub fn new(spheres: &[(Vec3, f32)]) -> SphereGeometry {
        SphereGeometry {
            spheres: spheres.to_vec(),
        }
    }
}

/// The distances along `direction` at which the ray from `origin` meets the sphere, nearer
/// first, or `None` when its line misses the sphere (Haines et al. 2019, equations 7.10 and
/// 7.15; see the module doc). `direction` need not be unit length.
pub fn ray_sphere_roots(
    origin: Vec3,
    direction: Vec3,
    center: Vec3,
    radius: f32,
) -> Option<(f64, f64)> {
    let d = direction.as_dvec3();
    let f = origin.as_dvec3() - center.as_dvec3();
    let r = f64::from(radius);
    let a = d.length_squared();
    // A sphere of radius 0 is a point, which no ray of a render should land on.
    if !(a > 0.0 && r > 0.0) {
        return None;
    }
    let b_half = -f.dot(d);
    let closest = f + (b_half / a) * d;
    let discriminant = a * (r * r - closest.length_squared());
    // Negative: the line passes the sphere; NaN: an infinite or NaN input.
    if discriminant.is_nan() || discriminant < 0.0 {
        return None;
    }
    let c = f.length_squared() - r * r;
    let q = b_half + discriminant.sqrt().copysign(b_half);
    if q == 0.0 {
        // The origin is on the sphere and the ray is tangent to it: one root, at 0.
        return Some((0.0, 0.0));
    }
    let (t0, t1) = (c / q, q / a);
    Some(if t0 <= t1 { (t0, t1) } else { (t1, t0) })
}

/// The nearest root of [`ray_sphere_roots`] in `(tnear, tfar)`, as f32: the nearer root,
/// else (the origin inside the sphere, or the nearer root cut off by `tnear`) the farther.
fn nearest_root(ray: &UserRay, center: Vec3, radius: f32) -> Option<f32> {
    let (t0, t1) = ray_sphere_roots(ray.origin, ray.direction, center, radius)?;
    [t0, t1]
        .into_iter()
        .map(|t| t as f32)
        .find(|&t| t > ray.tnear && t < ray.tfar)
}

impl UserGeometry for SphereGeometry {
    fn primitive_count(&self) -> u32 {
        self.spheres.len() as u32
    }

    fn bounds(&self, primitive: u32) -> Bounds {
        let (center, radius) = self.spheres[primitive as usize];
        // Rounded outwards: `center +- radius` in f32 may fall a rounding step inside the
        // sphere's true box, and a box that cuts off a hit loses it.
        let pad = Vec3::splat(radius) + (center.abs() + radius) * (2.0 * f32::EPSILON);
        Bounds {
            lower: center - pad,
            upper: center + pad,
        }
    }

    fn intersect(&self, primitive: u32, ray: &UserRay, _any_hit: bool) -> Option<UserHit> {
        let (center, radius) = self.spheres[primitive as usize];
        let t = nearest_root(ray, center, radius)?;
        let point = ray.origin.as_dvec3() + f64::from(t) * ray.direction.as_dvec3();
        let normal = (point - center.as_dvec3()).as_vec3();
        Some(UserHit {
            t,
            u: 0.0,
            v: 0.0,
            normal: if normal == Vec3::ZERO {
                Vec3::Z
            } else {
                normal
            },
        })
    }
}

/// Distance from `point` to the sphere's surface, in units of the sphere's radius.
#[cfg(test)]
fn relative_surface_error(point: glam::DVec3, center: Vec3, radius: f32) -> f64 {
    ((point - center.as_dvec3()).length() - f64::from(radius)).abs() / f64::from(radius)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(origin: Vec3, direction: Vec3) -> UserRay {
        UserRay {
            origin,
            direction,
            tnear: 0.0,
            tfar: f32::INFINITY,
        }
    }

    fn hit_t(origin: Vec3, direction: Vec3, center: Vec3, radius: f32) -> Option<f32> {
        SphereGeometry::new(&[(center, radius)])
            .intersect(0, &ray(origin, direction), false)
            .map(|h| h.t)
    }

    #[test]
    fn head_on_hit_is_the_near_side() {
        let t = hit_t(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z, Vec3::ZERO, 1.0);
        assert_eq!(t, Some(4.0));
    }

    #[test]
    fn non_unit_direction_scales_t() {
        let t = hit_t(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z * 2.0, Vec3::ZERO, 1.0);
        assert_eq!(t, Some(2.0));
    }

    #[test]
    fn ray_from_inside_hits_the_far_side() {
        let t = hit_t(Vec3::new(0.0, 0.5, 0.0), Vec3::Y, Vec3::ZERO, 2.0);
        assert_eq!(t, Some(1.5));
    }

    #[test]
    fn ray_pointing_away_misses() {
        assert_eq!(
            hit_t(Vec3::new(0.0, 0.0, 5.0), Vec3::Z, Vec3::ZERO, 1.0),
            None
        );
    }

    #[test]
    fn tfar_before_the_sphere_misses_and_tnear_past_the_front_gives_the_back() {
        let sphere = SphereGeometry::new(&[(Vec3::ZERO, 1.0)]);
        let mut r = ray(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z);
        r.tfar = 3.9;
        assert_eq!(sphere.intersect(0, &r, false), None);
        r.tfar = f32::INFINITY;
        r.tnear = 4.5;
        assert_eq!(sphere.intersect(0, &r, false).map(|h| h.t), Some(6.0));
    }

    #[test]
    fn grazing_rays_hit_inside_the_radius_and_miss_outside() {
        let origin = Vec3::new(-10.0, 0.0, 0.0);
        let inside = hit_t(origin + Vec3::Y * 0.999_99, Vec3::X, Vec3::ZERO, 1.0)
            .expect("a ray 1e-5 inside the silhouette hits");
        // The chord's midpoint is at x = 0: t near 10 (half-chord sqrt(2e-5)).
        assert!((inside - 10.0).abs() < 0.0046, "t = {inside}");
        assert_eq!(
            hit_t(origin + Vec3::Y * 1.000_01, Vec3::X, Vec3::ZERO, 1.0),
            None
        );
    }

    #[test]
    fn tiny_sphere_far_away_is_hit_on_its_surface() {
        // A 1 mm sphere 10 km away: b^2 - 4ac in f32 cancels to noise here.
        let center = Vec3::new(0.0, 0.0, -1.0e4);
        let radius = 1.0e-3;
        let origin = Vec3::ZERO;
        for offset in [0.0, 0.5e-3, 0.9e-3] {
            let target = center + Vec3::new(offset, 0.0, 0.0);
            let direction = (target - origin).normalize();
            let t = hit_t(origin, direction, center, radius).expect("hit");
            let point = origin.as_dvec3() + f64::from(t) * direction.as_dvec3();
            // t is rounded to f32 (1e4 has an ulp of 1e-3): the point is within an ulp of t.
            let error = (point - center.as_dvec3()).length() - f64::from(radius);
            assert!(error.abs() < 1.0e-3, "offset {offset}: error {error}");
            let (t0, _) = ray_sphere_roots(origin, direction, center, radius).unwrap();
            let exact_point = origin.as_dvec3() + t0 * direction.as_dvec3();
            assert!(
                relative_surface_error(exact_point, center, radius) < 1.0e-6,
                "offset {offset}"
            );
        }
    }

    #[test]
    fn huge_sphere_close_by_gives_the_small_root_to_full_precision() {
        // A 1 km sphere 1 cm below the origin: in (-b - sqrt(b^2 - 4ac)) / 2a the near root
        // is the difference of two numbers near 2000, and f32 keeps only its first digits.
        let radius = 1.0e3_f32;
        let center = Vec3::new(0.0, -1000.01, 0.0);
        let gap = -f64::from(center.y) - f64::from(radius);
        let t = hit_t(Vec3::ZERO, Vec3::NEG_Y, center, radius).expect("hit");
        assert!(
            (f64::from(t) - gap).abs() < 1.0e-6 * gap,
            "t = {t}, gap {gap}"
        );
        let (t0, t1) = ray_sphere_roots(Vec3::ZERO, Vec3::NEG_Y, center, radius).unwrap();
        assert!((t0 - gap).abs() < 1.0e-12, "t0 = {t0}");
        assert!((t1 - (gap + 2.0e3)).abs() < 1.0e-9, "t1 = {t1}");
    }

    #[test]
    fn oblique_hits_lie_on_the_surface() {
        let center = Vec3::new(1.0, 2.0, -3.0);
        let radius = 0.75;
        let origin = Vec3::new(-4.0, 5.0, 6.0);
        for i in 0..64 {
            let angle = i as f32 * 0.1;
            let target = center + Vec3::new(angle.cos(), angle.sin(), 0.3) * radius * 0.8;
            let direction = (target - origin).normalize();
            let t = hit_t(origin, direction, center, radius).expect("hit");
            let point = origin.as_dvec3() + f64::from(t) * direction.as_dvec3();
            assert!(
                relative_surface_error(point, center, radius) < 1.0e-5,
                "ray {i}"
            );
            assert!(
                point.distance(origin.as_dvec3()) < target.as_dvec3().distance(origin.as_dvec3())
            );
        }
    }

    #[test]
    fn zero_radius_sphere_is_never_hit_and_normal_points_out() {
        assert_eq!(hit_t(Vec3::Z, Vec3::NEG_Z, Vec3::ZERO, 0.0), None);
        let hit = SphereGeometry::new(&[(Vec3::ZERO, 2.0)])
            .intersect(0, &ray(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z), false)
            .unwrap();
        assert!(hit.normal.normalize().abs_diff_eq(Vec3::Z, 1e-6));
    }

    #[test]
    fn bounds_contain_the_sphere() {
        let center = Vec3::new(1.0e4, -3.0, 0.1);
        let radius = 0.3;
        let b = SphereGeometry::new(&[(center, radius)]).bounds(0);
        assert!(b.lower.x <= center.x - radius && b.upper.x >= center.x + radius);
        assert!(b.lower.y <= center.y - radius && b.upper.y >= center.y + radius);
        assert!(b.lower.z <= center.z - radius && b.upper.z >= center.z + radius);
    }
}
