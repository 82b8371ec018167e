//! The lat-long environment parameterisation and its footprint gradients.
//!
//! Lat-long convention (used everywhere in conetrace, including the sphere's st):
//! with polar angle theta measured from +Y and azimuth phi measured from +X towards +Z,
//! a unit direction is `(sin(theta) cos(phi), cos(theta), sin(theta) sin(phi))` and
//! `s = phi / 2pi` in [0, 1), `t = theta / pi` in [0, 1] (t = 0 at +Y, growing downwards as
//! OpenImageIO's t does).
//!
//! An environment map is infinitely far away, so only a footprint's angular spread matters
//! (seed 000, "Texture Derivatives on an Environment Map"); ray differentials use the exact
//! derivative of the mapping along dD/dx, dD/dy instead.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use super::gradients::TextureGradients;
use super::robust::{finite, unit_or};

/// Lat-long st of a direction (need not be unit; zero/NaN maps to the +Y pole).
#[inline]
pub fn direction_to_lat_long(dir: Vec3) -> Vec2 {
    let d = unit_or(dir, Vec3::Y);
    let mut phi = d.z.atan2(d.x);
    if phi < 0.0 {
        phi += TAU;
    }
    let s = (phi / TAU).min(1.0);
    let t = d.y.clamp(-1.0, 1.0).acos() / PI;
    // s may round up to exactly 1.0 for tiny negative angles; keep it in [0, 1).
    Vec2::new(if s >= 1.0 { 0.0 } else { s }, t)
}

/// Unit direction of lat-long coordinates `st` (inverse of [`direction_to_lat_long`]).
#[inline]
pub fn lat_long_to_direction(st: Vec2) -> Vec3 {
    let (sin_phi, cos_phi) = (st.x * TAU).sin_cos();
    let (sin_theta, cos_theta) = (st.y * PI).sin_cos();
    Vec3::new(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi)
}

/// The lat-long parameterisation of a sphere of `radius` at unit outward normal `n`:
/// `(st, dP/ds, dP/dt)`. dP/ds vanishes at the poles.
#[inline]
pub fn lat_long_frame(n: Vec3, radius: f32) -> (Vec2, Vec3, Vec3) {
    let st = direction_to_lat_long(n);
    let (sin_phi, cos_phi) = (st.x * TAU).sin_cos();
    let (sin_theta, cos_theta) = (st.y * PI).sin_cos();
    let dpdphi = Vec3::new(-sin_theta * sin_phi, 0.0, sin_theta * cos_phi);
    let dpdtheta = Vec3::new(cos_theta * cos_phi, -sin_theta, cos_theta * sin_phi);
    (st, dpdphi * (TAU * radius), dpdtheta * (PI * radius))
}

/// Lat-long gradients of a cone with spread angle `angle` around direction `dir`:
/// ddx = (alpha / (2pi sin theta), 0), ddy = (0, alpha / pi).
///
/// Seed 000 gives (alpha / 2pi, 0), (0, alpha / pi), which holds at the equator only: a
/// circle of latitude at polar angle theta has radius sin theta, so alpha radians across it
/// are alpha / sin theta radians of azimuth and ds = dphi / 2pi widens by 1 / sin theta
/// towards the poles (the derivative [`lat_long_offset`] takes for differentials). Right at
/// the poles, where that would exceed the whole circle of latitude, ds is capped at 1.
#[inline]
pub fn lat_long_cone_gradients(angle: f32, dir: Vec3) -> TextureGradients {
    let a = finite(angle).abs();
    let d = unit_or(dir, Vec3::Y);
    let sin_theta = (d.x * d.x + d.z * d.z).sqrt();
    let ds = if a == 0.0 {
        0.0
    } else if a >= TAU * sin_theta {
        1.0
    } else {
        a / (TAU * sin_theta)
    };
    TextureGradients::from_axes(Vec2::new(ds, 0.0), Vec2::new(0.0, a / PI))
}

/// Derivative of the lat-long st of unit direction `d` along the direction change `dd`.
#[inline]
pub fn lat_long_offset(d: Vec3, dd: Vec3) -> Vec2 {
    // s = atan2(z, x) / 2pi  =>  ds = (x dz - z dx) / (2pi (x^2 + z^2));
    // t = acos(y) / pi       =>  dt = -dy / (pi sqrt(1 - y^2)) = -dy / (pi sqrt(x^2 + z^2)).
    let rho2 = (d.x * d.x + d.z * d.z).max(1.0e-12);
    let ds = (d.x * dd.z - d.z * dd.x) / (TAU * rho2);
    let dt = -dd.y / (PI * rho2.sqrt());
    Vec2::new(finite(ds), finite(dt))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lat_long_round_trips_and_matches_the_convention() {
        assert!((direction_to_lat_long(Vec3::Y) - Vec2::new(0.0, 0.0)).length() < 1e-6);
        assert!((direction_to_lat_long(Vec3::X) - Vec2::new(0.0, 0.5)).length() < 1e-6);
        assert!((direction_to_lat_long(Vec3::Z) - Vec2::new(0.25, 0.5)).length() < 1e-6);
        assert!((direction_to_lat_long(Vec3::NEG_X) - Vec2::new(0.5, 0.5)).length() < 1e-6);
        for &(s, t) in &[(0.1f32, 0.2f32), (0.6, 0.7), (0.9, 0.45)] {
            let d = lat_long_to_direction(Vec2::new(s, t));
            assert!((d.length() - 1.0).abs() < 1e-5);
            let back = direction_to_lat_long(d);
            assert!((back - Vec2::new(s, t)).length() < 1e-5, "{back:?}");
        }
        let st = direction_to_lat_long(Vec3::splat(f32::NAN));
        assert!(st.is_finite());
    }

    #[test]
    fn lat_long_frame_matches_finite_differences() {
        let st = Vec2::new(0.3, 0.35);
        let n = lat_long_to_direction(st);
        let (_, dpds, dpdt) = lat_long_frame(n, 2.0);
        let h = 1e-3;
        let fd_s = (lat_long_to_direction(st + Vec2::new(h, 0.0))
            - lat_long_to_direction(st - Vec2::new(h, 0.0)))
            * (2.0 / (2.0 * h));
        let fd_t = (lat_long_to_direction(st + Vec2::new(0.0, h))
            - lat_long_to_direction(st - Vec2::new(0.0, h)))
            * (2.0 / (2.0 * h));
        assert!((dpds - fd_s).length() < 1e-2 * dpds.length());
        assert!((dpdt - fd_t).length() < 1e-2 * dpdt.length());
    }

    #[test]
    fn lat_long_offset_matches_finite_differences() {
        let d = Vec3::new(0.3, 0.4, -0.5).normalize();
        let dd = Vec3::new(0.01, -0.02, 0.005);
        let dd = dd - d * d.dot(dd);
        let h = 1e-2;
        let fd =
            (direction_to_lat_long(d + dd * h) - direction_to_lat_long(d - dd * h)) / (2.0 * h);
        let an = lat_long_offset(d, dd);
        assert!((an - fd).length() < 2e-2 * an.length(), "{an:?} {fd:?}");
    }

    #[test]
    fn cone_gradients_follow_seed_000_at_the_equator_and_widen_towards_the_poles() {
        let g = lat_long_cone_gradients(-0.02, Vec3::X);
        assert!((g.dsdx - 0.02 / TAU).abs() < 1e-9 && (g.dtdy - 0.02 / PI).abs() < 1e-9);
        assert_eq!((g.dtdx, g.dsdy), (0.0, 0.0));
        for theta in [0.1f32, 0.7, 2.9] {
            let d = lat_long_to_direction(Vec2::new(0.3, theta / PI));
            let g = lat_long_cone_gradients(0.02, d);
            let expected = 0.02 / (TAU * theta.sin());
            assert!(
                (g.dsdx - expected).abs() < 1e-4 * expected,
                "{theta}: {g:?}"
            );
            assert!((g.dtdy - 0.02 / PI).abs() < 1e-9);
        }
        // At the poles (and for degenerate directions) the whole row, never infinity.
        for d in [Vec3::Y, Vec3::NEG_Y, Vec3::ZERO, Vec3::splat(f32::NAN)] {
            let g = lat_long_cone_gradients(0.02, d);
            assert!(g.is_finite() && g.dsdx == 1.0, "{d}: {g:?}");
        }
        assert_eq!(
            lat_long_cone_gradients(0.0, Vec3::Y),
            TextureGradients::ZERO
        );
    }
}
