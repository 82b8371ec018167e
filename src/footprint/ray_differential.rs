//! Ray differentials: derivatives of a ray's position and direction with respect to the
//! image-plane coordinates x and y (Igehy, seed 002).
//!
//! A differential is four vectors, dP/dx, dP/dy, dD/dx, dD/dy, carried with the ray and
//! updated by differentiating each operation applied to it: camera generation (eq. 8),
//! transfer to a hit (eqs. 10-12), reflection (eqs. 13-15) and refraction (eqs. 16-19).
//! Derivatives are per pixel, so at a hit dP/dx and dP/dy span the pixel's footprint
//! (a parallelogram, seed 002 eq. 25) and give texture derivatives directly.
//!
//! Transfer uses the geometric normal (where the neighbouring ray meets the surface);
//! reflection and refraction use the shading normal and its derivative (seed 002, 3.3).

use glam::Vec3;

use super::gradients::{surface_gradients, TextureGradients};
use super::normal_derivatives::shading_normal_derivative;
use super::robust::{away_from_zero, finite, finite3, unit_direction, unit_normal, MIN_COSINE};
use crate::hit::SurfaceHit;

/// Derivatives of a ray (position P, unit direction D) with respect to pixel x and y.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayDifferential {
    /// dP/dx: how the ray's position moves per pixel in x.
    pub dpdx: Vec3,
    /// dP/dy: how the ray's position moves per pixel in y.
    pub dpdy: Vec3,
    /// dD/dx: how the ray's unit direction turns per pixel in x.
    pub dddx: Vec3,
    /// dD/dy: how the ray's unit direction turns per pixel in y.
    pub dddy: Vec3,
}

/// Derivative of `normalize(d)` when `d` changes by `dd` (seed 002, eq. 8):
/// ((d.d) dd - (d.dd) d) / (d.d)^(3/2).
#[inline]
pub fn normalized_derivative(d: Vec3, dd: Vec3) -> Vec3 {
    let dot = d.length_squared();
    if !(dot.is_finite() && dot > 1.0e-30) {
        return Vec3::ZERO;
    }
    finite3((dd * dot - d * d.dot(dd)) / (dot * dot.sqrt()))
}

/// The refracted unit direction of seed 002, eqs. 16-17 (`None` under total internal
/// reflection); `n` may face either side.
#[inline]
fn refraction_direction(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let eta = if eta.is_finite() && eta > 0.0 {
        eta
    } else {
        1.0
    };
    let n = if d.dot(n) > 0.0 { -n } else { n };
    let dn = d.dot(n);
    let radicand = 1.0 - eta * eta * (1.0 - dn * dn);
    (radicand >= 0.0).then(|| eta * d - (eta * dn + radicand.sqrt()) * n)
}

impl RayDifferential {
    /// A differential with all four vectors made finite.
    #[inline]
    pub fn new(dpdx: Vec3, dpdy: Vec3, dddx: Vec3, dddy: Vec3) -> RayDifferential {
        RayDifferential {
            dpdx: finite3(dpdx),
            dpdy: finite3(dpdy),
            dddx: finite3(dddx),
            dddy: finite3(dddy),
        }
    }

    /// Rays from a fixed point through `d(x, y)` (unnormalised), where `d` moves by
    /// `dd_dx` and `dd_dy` per pixel (seed 002, eq. 8: dP = 0, dD = derivative of d/|d|).
    /// A pinhole camera has d = View + x Right + y Up; a thin lens with a fixed lens sample
    /// has d = (point on the focal plane) - (lens point), which moves the same way.
    #[inline]
    pub fn from_point(d: Vec3, dd_dx: Vec3, dd_dy: Vec3) -> RayDifferential {
        RayDifferential::new(
            Vec3::ZERO,
            Vec3::ZERO,
            normalized_derivative(d, dd_dx),
            normalized_derivative(d, dd_dy),
        )
    }

    /// Parallel rays whose origins move by `dp_dx`, `dp_dy` per pixel (orthographic
    /// camera: the counterpart of eq. 8 with a constant direction).
    #[inline]
    pub fn parallel(dp_dx: Vec3, dp_dy: Vec3) -> RayDifferential {
        RayDifferential::new(dp_dx, dp_dy, Vec3::ZERO, Vec3::ZERO)
    }

    /// The differential transferred along unit `dir` by `t` onto a surface with geometric
    /// normal `normal` (seed 002, eqs. 10 and 12):
    /// dP' = (dP + t dD) + dt D, dt = -((dP + t dD).N) / (D.N), dD' = dD.
    /// |D.N| is floored at 1e-7 so grazing hits stay finite.
    #[inline]
    pub fn transfer_to(self, dir: Vec3, t: f32, normal: Vec3) -> RayDifferential {
        let d = unit_direction(dir);
        let n = unit_normal(normal, d);
        let t = if t.is_nan() { 0.0 } else { t.max(0.0) };
        let dn = away_from_zero(d.dot(n), MIN_COSINE);
        let moved_x = self.dpdx + self.dddx * t;
        let moved_y = self.dpdy + self.dddy * t;
        let dtdx = -moved_x.dot(n) / dn;
        let dtdy = -moved_y.dot(n) / dn;
        RayDifferential::new(moved_x + d * dtdx, moved_y + d * dtdy, self.dddx, self.dddy)
    }

    /// [`Self::transfer_to`] onto `hit` (distance `hit.t`, its geometric normal).
    #[inline]
    pub fn transfer(self, dir: Vec3, hit: &SurfaceHit) -> RayDifferential {
        self.transfer_to(dir, hit.t, hit.geometric_normal)
    }

    /// Mirror reflection about a unit normal `n` whose derivatives are `dndx`, `dndy`
    /// (seed 002, eqs. 14-15): dP' = dP, dD' = dD - 2 [(D.N) dN + d(D.N) N],
    /// d(D.N) = dD.N + D.dN. Either orientation of `n` works (with matching derivatives).
    #[inline]
    pub fn reflect_about(self, dir: Vec3, n: Vec3, dndx: Vec3, dndy: Vec3) -> RayDifferential {
        let d = unit_direction(dir);
        let n = unit_normal(n, d);
        let dn = d.dot(n);
        let reflect = |ddir: Vec3, dnorm: Vec3| {
            let d_dn = ddir.dot(n) + d.dot(dnorm);
            ddir - 2.0 * (dnorm * dn + n * d_dn)
        };
        RayDifferential::new(
            self.dpdx,
            self.dpdy,
            reflect(self.dddx, dndx),
            reflect(self.dddy, dndy),
        )
    }

    /// Reflection at `hit` producing the caller's `reflected` direction. The shading normal
    /// and its derivative are used when they produce `reflected`; otherwise the renderer
    /// fell back to the geometric normal (a shading normal that would reflect below the
    /// surface), and so does the differential, with a constant normal.
    #[inline]
    pub fn reflect(self, dir: Vec3, hit: &SurfaceHit, reflected: Vec3) -> RayDifferential {
        let d = unit_direction(dir);
        let ns = unit_normal(hit.shading_normal, d);
        let expected = d - 2.0 * d.dot(ns) * ns;
        let r = unit_direction(reflected);
        if (expected - r).length_squared() < 1.0e-6 || !reflected.is_finite() {
            let dndx = shading_normal_derivative(hit, self.dpdx);
            let dndy = shading_normal_derivative(hit, self.dpdy);
            self.reflect_about(d, ns, dndx, dndy)
        } else {
            self.reflect_about(d, hit.geometric_normal, Vec3::ZERO, Vec3::ZERO)
        }
    }

    /// Refraction with `eta` = n_incident / n_transmitted about unit normal `n` facing the
    /// incident side (D.N < 0; flipped here, with its derivatives, if not) (seed 002,
    /// eqs. 16-19): dD' = eta dD - (mu dN + dmu N), mu = eta (D.N) - D'.N,
    /// D'.N = -sqrt(1 - eta^2 (1 - (D.N)^2)), dmu = [eta - eta^2 (D.N) / (D'.N)] d(D.N).
    /// `None` under total internal reflection.
    #[inline]
    pub fn refract_about(
        self,
        dir: Vec3,
        n: Vec3,
        dndx: Vec3,
        dndy: Vec3,
        eta: f32,
    ) -> Option<RayDifferential> {
        let eta = if eta.is_finite() && eta > 0.0 {
            eta
        } else {
            1.0
        };
        let d = unit_direction(dir);
        let mut n = unit_normal(n, d);
        let (mut dndx, mut dndy) = (dndx, dndy);
        if d.dot(n) > 0.0 {
            n = -n;
            dndx = -dndx;
            dndy = -dndy;
        }
        let dn = d.dot(n);
        let radicand = 1.0 - eta * eta * (1.0 - dn * dn);
        if radicand.is_nan() || radicand < 0.0 {
            return None;
        }
        let dtn = -radicand.sqrt();
        let mu = eta * dn - dtn;
        // At the critical angle D'.N -> 0 and dmu diverges: keep it finite.
        let dmu_factor = eta - eta * eta * dn / away_from_zero(dtn, MIN_COSINE);
        let refract = |ddir: Vec3, dnorm: Vec3| {
            let d_dn = ddir.dot(n) + d.dot(dnorm);
            eta * ddir - (dnorm * mu + n * (dmu_factor * d_dn))
        };
        Some(RayDifferential::new(
            self.dpdx,
            self.dpdy,
            refract(self.dddx, dndx),
            refract(self.dddy, dndy),
        ))
    }

    /// Refraction at `hit` producing the caller's `refracted` direction, with the shading
    /// normal and its derivative. If the shading normal does not produce `refracted` (the
    /// renderer refracted about the geometric normal), the geometric normal is used with a
    /// constant normal. Under total internal reflection (no refracted ray exists) the
    /// reflected differential is returned.
    #[inline]
    pub fn refract(
        self,
        dir: Vec3,
        hit: &SurfaceHit,
        eta: f32,
        refracted: Vec3,
    ) -> RayDifferential {
        let d = unit_direction(dir);
        let ns = unit_normal(hit.shading_normal, d);
        let use_shading = match refraction_direction(d, ns, eta) {
            Some(expected) => {
                !refracted.is_finite()
                    || (expected - unit_direction(refracted)).length_squared() < 1.0e-6
            }
            None => true,
        };
        let (n, dndx, dndy) = if use_shading {
            (
                ns,
                shading_normal_derivative(hit, self.dpdx),
                shading_normal_derivative(hit, self.dpdy),
            )
        } else {
            (hit.geometric_normal, Vec3::ZERO, Vec3::ZERO)
        };
        match self.refract_about(d, n, dndx, dndy, eta) {
            Some(r) => r,
            None => self.reflect_about(d, n, dndx, dndy),
        }
    }

    /// World-space footprint width: the square root of the area of the parallelogram
    /// spanned by dP/dx and dP/dy.
    #[inline]
    pub fn width(&self) -> f32 {
        finite(self.dpdx.cross(self.dpdy).length().sqrt())
    }

    /// An isotropic cone equivalent to the differential: (sqrt |dPdx x dPdy|,
    /// sqrt |dDdx x dDdy|).
    #[inline]
    pub fn equivalent_cone(&self) -> (f32, f32) {
        (
            self.width(),
            finite(self.dddx.cross(self.dddy).length().sqrt()),
        )
    }

    /// Texture derivatives at `hit` (seed 002, eqs. 24-25 and the triangle box).
    #[inline]
    pub fn texture_gradients(&self, hit: &SurfaceHit) -> TextureGradients {
        surface_gradients(hit, self.dpdx, self.dpdy)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hit::Patch;
    use glam::Vec2;

    // --- Analytic scene for finite-difference checks -------------------------------------

    /// A ray-sphere intersection (nearest positive root, or the far one from inside).
    fn hit_sphere(o: Vec3, d: Vec3, c: Vec3, r: f32) -> Option<f32> {
        let oc = o - c;
        let b = oc.dot(d);
        let disc = b * b - (oc.length_squared() - r * r);
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        [-b - s, -b + s].into_iter().find(|&t| t > 1e-4)
    }

    fn hit_plane(o: Vec3, d: Vec3, point: Vec3, n: Vec3) -> Option<f32> {
        let t = (point - o).dot(n) / d.dot(n);
        (t > 1e-4).then_some(t)
    }

    fn reflect(d: Vec3, n: Vec3) -> Vec3 {
        d - 2.0 * d.dot(n) * n
    }

    fn refract(d: Vec3, n: Vec3, eta: f32) -> Vec3 {
        let n = if d.dot(n) > 0.0 { -n } else { n };
        let c = d.dot(n);
        let k = 1.0 - eta * eta * (1.0 - c * c);
        eta * d - (eta * c + k.sqrt()) * n
    }

    fn sphere_hit(o: Vec3, d: Vec3, t: f32, c: Vec3, r: f32) -> SurfaceHit {
        let p = o + d * t;
        let n = (p - c).normalize();
        SurfaceHit {
            t,
            position: p,
            geometric_normal: n,
            shading_normal: n,
            barycentric: Vec2::ZERO,
            st: Vec2::ZERO,
            dpds: Vec3::ZERO,
            dpdt: Vec3::ZERO,
            material: 0,
            patch: Patch::Sphere {
                center: c,
                radius: r,
            },
        }
    }

    fn plane_hit(o: Vec3, d: Vec3, t: f32, n: Vec3) -> SurfaceHit {
        let p = o + d * t;
        let (a, b) = n.any_orthonormal_pair();
        SurfaceHit {
            t,
            position: p,
            geometric_normal: n,
            shading_normal: n,
            barycentric: Vec2::ZERO,
            st: Vec2::ZERO,
            dpds: Vec3::ZERO,
            dpdt: Vec3::ZERO,
            material: 0,
            patch: Patch::Triangle {
                p: [p - a * 100.0, p + a * 100.0 - b * 50.0, p + b * 100.0],
                n: None,
                st: None,
            },
        }
    }

    /// Pinhole ray through image coordinates (x, y): d = View + x Right + y Up (eq. 4).
    const VIEW: Vec3 = Vec3::new(0.0, 0.0, -1.0);
    const RIGHT: Vec3 = Vec3::new(0.002, 0.0, 0.0);
    const UP: Vec3 = Vec3::new(0.0, -0.002, 0.0);

    fn camera_dir(x: f32, y: f32) -> Vec3 {
        (VIEW + RIGHT * x + UP * y).normalize()
    }

    fn assert_close(analytic: Vec3, fd: Vec3, tol: f32, what: &str) {
        let err = (analytic - fd).length() / fd.length().max(1e-12);
        assert!(
            err <= tol,
            "{what}: analytic {analytic:?} vs finite differences {fd:?} (rel {err})"
        );
    }

    /// Sphere mirror, then a plane: where each ray lands on the plane.
    fn trace_reflection(x: f32, y: f32) -> (Vec3, Vec3, SurfaceHit, SurfaceHit) {
        let (c, r) = (Vec3::new(0.0, 0.0, -5.0), 1.5);
        let d = camera_dir(x, y);
        let t = hit_sphere(Vec3::ZERO, d, c, r).expect("camera ray misses the sphere");
        let s = sphere_hit(Vec3::ZERO, d, t, c, r);
        let rd = reflect(d, s.shading_normal);
        let pn = Vec3::new(-1.0, 0.0, 0.0);
        let t2 = hit_plane(s.position, rd, Vec3::new(4.0, 0.0, 0.0), pn)
            .expect("reflected ray misses the plane");
        let q = plane_hit(s.position, rd, t2, pn);
        (q.position, rd, s, q)
    }

    #[test]
    fn reflection_off_a_sphere_matches_neighbouring_rays() {
        let (x, y) = (100.0, -30.0);
        let (_, rd, s, q) = trace_reflection(x, y);
        let d = camera_dir(x, y);
        let rdiff = RayDifferential::from_point(VIEW + RIGHT * x + UP * y, RIGHT, UP)
            .transfer(d, &s)
            .reflect(d, &s, rd)
            .transfer(rd, &q);
        let h = 0.5;
        let fd_x = (trace_reflection(x + h, y).0 - trace_reflection(x - h, y).0) / (2.0 * h);
        let fd_y = (trace_reflection(x, y + h).0 - trace_reflection(x, y - h).0) / (2.0 * h);
        assert_close(rdiff.dpdx, fd_x, 1e-2, "dP/dx after sphere reflection");
        assert_close(rdiff.dpdy, fd_y, 1e-2, "dP/dy after sphere reflection");
        let fd_dx = (trace_reflection(x + h, y).1 - trace_reflection(x - h, y).1) / (2.0 * h);
        assert_close(rdiff.dddx, fd_dx, 1e-2, "dD/dx after sphere reflection");
        // The curved mirror spreads the beam far more than the camera does.
        assert!(rdiff.dddx.length() > 5.0 * normalized_derivative(VIEW, RIGHT).length());
    }

    /// Through a glass slab between z = -3 and z = -4 (tilted entry face), then onto z = -10.
    fn trace_slab(x: f32, y: f32) -> (Vec3, [SurfaceHit; 3], [Vec3; 3]) {
        let eta = 1.0 / 1.5;
        let entry_n = Vec3::new(0.3, 0.1, 1.0).normalize();
        let d0 = camera_dir(x, y);
        let t0 = hit_plane(Vec3::ZERO, d0, Vec3::new(0.0, 0.0, -3.0), entry_n).unwrap();
        let a = plane_hit(Vec3::ZERO, d0, t0, entry_n);
        let d1 = refract(d0, entry_n, eta);
        // The exit face's outward normal is -Z; the ray meets it from inside.
        let exit_n = Vec3::NEG_Z;
        let t1 = hit_plane(a.position, d1, Vec3::new(0.0, 0.0, -4.0), exit_n).unwrap();
        let b = plane_hit(a.position, d1, t1, exit_n);
        let d2 = refract(d1, exit_n, 1.0 / eta);
        let screen_n = Vec3::Z;
        let t2 = hit_plane(b.position, d2, Vec3::new(0.0, 0.0, -10.0), screen_n).unwrap();
        let c = plane_hit(b.position, d2, t2, screen_n);
        (c.position, [a, b, c], [d0, d1, d2])
    }

    #[test]
    fn refraction_through_a_slab_matches_neighbouring_rays() {
        let (x, y) = (120.0, 80.0);
        let (_, [a, b, c], [d0, d1, d2]) = trace_slab(x, y);
        let eta = 1.0 / 1.5;
        let rdiff = RayDifferential::from_point(VIEW + RIGHT * x + UP * y, RIGHT, UP)
            .transfer(d0, &a)
            .refract(d0, &a, eta, d1)
            .transfer(d1, &b)
            .refract(d1, &b, 1.0 / eta, d2)
            .transfer(d2, &c);
        let h = 0.5;
        let fd_x = (trace_slab(x + h, y).0 - trace_slab(x - h, y).0) / (2.0 * h);
        let fd_y = (trace_slab(x, y + h).0 - trace_slab(x, y - h).0) / (2.0 * h);
        assert_close(rdiff.dpdx, fd_x, 1e-2, "dP/dx through the slab");
        assert_close(rdiff.dpdy, fd_y, 1e-2, "dP/dy through the slab");
    }

    /// Refraction into and out of a glass ball (curved, so dN matters), onto z = -20.
    fn trace_ball(x: f32, y: f32) -> (Vec3, [SurfaceHit; 3], [Vec3; 3]) {
        let (center, r) = (Vec3::new(0.0, 0.0, -6.0), 2.0);
        let d0 = camera_dir(x, y);
        let t0 = hit_sphere(Vec3::ZERO, d0, center, r).unwrap();
        let a = sphere_hit(Vec3::ZERO, d0, t0, center, r);
        let d1 = refract(d0, a.shading_normal, 1.0 / 1.5);
        let t1 = hit_sphere(a.position, d1, center, r).unwrap();
        let b = sphere_hit(a.position, d1, t1, center, r);
        let d2 = refract(d1, b.shading_normal, 1.5);
        let t2 = hit_plane(b.position, d2, Vec3::new(0.0, 0.0, -20.0), Vec3::Z).unwrap();
        let c = plane_hit(b.position, d2, t2, Vec3::Z);
        (c.position, [a, b, c], [d0, d1, d2])
    }

    #[test]
    fn refraction_through_a_ball_matches_neighbouring_rays() {
        let (x, y) = (150.0, 90.0);
        let (_, [a, b, c], [d0, d1, d2]) = trace_ball(x, y);
        let rdiff = RayDifferential::from_point(VIEW + RIGHT * x + UP * y, RIGHT, UP)
            .transfer(d0, &a)
            .refract(d0, &a, 1.0 / 1.5, d1)
            .transfer(d1, &b)
            .refract(d1, &b, 1.5, d2)
            .transfer(d2, &c);
        let h = 0.25;
        let fd_x = (trace_ball(x + h, y).0 - trace_ball(x - h, y).0) / (2.0 * h);
        let fd_y = (trace_ball(x, y + h).0 - trace_ball(x, y - h).0) / (2.0 * h);
        assert_close(rdiff.dpdx, fd_x, 1e-2, "dP/dx through the ball");
        assert_close(rdiff.dpdy, fd_y, 1e-2, "dP/dy through the ball");
    }

    #[test]
    fn camera_derivative_matches_finite_differences() {
        let d = VIEW + RIGHT * 300.0 + UP * 100.0;
        let an = normalized_derivative(d, RIGHT);
        let fd = ((d + RIGHT * 0.5).normalize() - (d - RIGHT * 0.5).normalize()) / 1.0;
        assert_close(an, fd, 1e-3, "eq. 8");
    }

    #[test]
    fn total_internal_reflection_and_grazing_hits_stay_finite() {
        let diff = RayDifferential::from_point(VIEW, RIGHT, UP);
        let d = Vec3::new(0.9, 0.0, -(1.0f32 - 0.81).sqrt());
        assert!(diff
            .refract_about(d, Vec3::Z, Vec3::ZERO, Vec3::ZERO, 1.5)
            .is_none());
        let grazing = Vec3::new(1.0, 0.0, -1e-7).normalize();
        let moved = diff.transfer_to(grazing, 10.0, Vec3::Z);
        assert!(moved.dpdx.is_finite() && moved.dpdy.is_finite());
        let hit = plane_hit(Vec3::ZERO, d, 1.0, Vec3::Z);
        let r = diff.refract(d, &hit, 1.5, Vec3::ZERO);
        assert!(r.dddx.is_finite() && r.dddy.is_finite());
        // eta exactly 1 leaves the direction derivatives unchanged on a flat surface.
        let same = diff.refract(Vec3::NEG_Z, &hit, 1.0, Vec3::NEG_Z);
        // The largest differentials allowed still have a finite area.
        let huge = RayDifferential::new(
            Vec3::splat(1e30),
            Vec3::new(-1e30, 1e30, 0.0),
            Vec3::ZERO,
            Vec3::ZERO,
        );
        assert!(huge.width().is_finite() && huge.equivalent_cone().1.is_finite());
        assert!((same.dddx - diff.dddx).length() < 1e-7);
    }
}
