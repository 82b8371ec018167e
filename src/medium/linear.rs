//! Linear-density fog bounded by a plane: zero on the plane and on its far side, growing
//! linearly with the distance from the plane on the fog side.
//!
//! Seed 004, "Linear Density Fog": the density at a point is the point's signed distance
//! to the fog plane times a growth factor, `FogDensity = (A x + B y + C z + D) * growth`.
//! Here the plane `[A, B, C, D]` is normalised when the scene is loaded (so `sigma` is the
//! growth per unit of distance whatever the length of `(A, B, C)`), the fog lies on the side
//! the normal points away from, and negative densities are clamped to zero:
//! `density(p) = sigma * max(0, -(n . p + d))`.
//!
//! Along a line `p(t) = o + t w` the unclamped height is affine, `h(t) = a + b t` with
//! `a = -(n . o + d)` and `b = -(n . w)`, so over the part of `[t0, t1]` where `h > 0` the
//! integral is the seed's trapezoid, width times the mean of the two end densities
//! ("the trapezoid area formula", seed 004 "Analytic Fog Density - Integrals"). The clamp is
//! honoured by cutting the interval at the zero crossing `t = -a / b` first, where the
//! density is set to exactly zero rather than evaluated (which would leave a rounding
//! residue). A line parallel to the plane (`b = 0`) never crosses: constant height `a`.

use glam::DVec3;

use super::segment::Line;

/// `sigma * max(0, -(normal . p + offset))` with `normal` of unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearDensity {
    pub sigma: f64,
    pub normal: DVec3,
    pub offset: f64,
}

impl LinearDensity {
    /// From the scene's plane `[A, B, C, D]`, normalised by `|(A, B, C)|`; `None` for a zero
    /// or non-finite normal.
    pub fn from_plane(sigma: f64, plane: [f64; 4]) -> Option<LinearDensity> {
        let n = DVec3::new(plane[0], plane[1], plane[2]);
        let length = n.length();
        if !(length > 0.0 && length.is_finite() && plane[3].is_finite()) {
            return None;
        }
        Some(LinearDensity {
            sigma,
            normal: n / length,
            offset: plane[3] / length,
        })
    }

    pub fn density_at(&self, p: DVec3) -> f64 {
        self.sigma * (-(self.normal.dot(p) + self.offset)).max(0.0)
    }

    /// `h(t) = a + b t`, the unclamped distance into the fog along `line`.
    #[inline]
    fn height_line(&self, line: &Line) -> (f64, f64) {
        (
            -(self.normal.dot(line.origin) + self.offset),
            -self.normal.dot(line.direction),
        )
    }

    /// The part `[u0, u1]` of `[t0, t1]` where the fog is present (`h > 0`), with the
    /// heights at its ends (exactly 0 at a zero crossing), or `None` where it is absent.
    fn fogged_part(&self, line: &Line, t0: f64, t1: f64) -> Option<FoggedPart> {
        let (a, b) = self.height_line(line);
        let height = |t: f64| (a + b * t).max(0.0);
        if b == 0.0 {
            return (a > 0.0 && t1 > t0).then_some(FoggedPart {
                u0: t0,
                u1: t1,
                h0: a,
                h1: a,
                slope: 0.0,
            });
        }
        let crossing = -a / b;
        let (u0, h0, u1, h1) = if b > 0.0 {
            // Rising into the fog: it starts at the crossing.
            if crossing >= t0 {
                (crossing, 0.0, t1, height(t1))
            } else {
                (t0, height(t0), t1, height(t1))
            }
        } else if crossing <= t1 {
            // Leaving the fog at the crossing.
            (t0, height(t0), crossing, 0.0)
        } else {
            (t0, height(t0), t1, height(t1))
        };
        (u1 > u0).then_some(FoggedPart {
            u0,
            u1,
            h0,
            h1,
            slope: b,
        })
    }

    /// The integral of the density over `[t0, t1]` (`t1` may be infinite: then the depth is
    /// infinite if the line stays in or heads into the fog, finite if it leaves it).
    pub fn optical_depth(&self, line: &Line, t0: f64, t1: f64) -> f64 {
        if self.sigma == 0.0 {
            return 0.0;
        }
        let Some(part) = self.fogged_part(line, t0, t1) else {
            return 0.0;
        };
        if part.u1.is_infinite() {
            return f64::INFINITY;
        }
        // The trapezoid: width times mean height.
        self.sigma * (part.u1 - part.u0) * (0.5 * (part.h0 + part.h1))
    }

    /// The distance `t` in `[t0, t1]` where the depth from `t0` reaches `tau`, or `None`
    /// when the interval holds less.
    ///
    /// Inside the fogged part the depth is the quadratic `sigma (h0 s + b s^2 / 2)` of
    /// `s = t - u0`; its root is taken in the form `s = 2 T / (h0 + sqrt(h0^2 + 2 b T))`
    /// (`T = tau / sigma`), which subtracts nothing and so stays exact for `b -> 0` (the
    /// line parallel to the plane, `s = T / h0`) and for `h0 = 0` (entering at the plane).
    pub fn distance_at_optical_depth(
        &self,
        line: &Line,
        t0: f64,
        t1: f64,
        tau: f64,
    ) -> Option<f64> {
        if tau <= 0.0 {
            return Some(t0);
        }
        if self.sigma <= 0.0 {
            return None;
        }
        let part = self.fogged_part(line, t0, t1)?;
        let target = tau / self.sigma;
        let discriminant = part.h0 * part.h0 + 2.0 * part.slope * target;
        if discriminant < 0.0 {
            // The density falls to zero before the depth is reached.
            return None;
        }
        let denominator = part.h0 + discriminant.sqrt();
        if denominator <= 0.0 {
            return None;
        }
        let t = part.u0 + 2.0 * target / denominator;
        (t <= part.u1).then_some(t)
    }
}

struct FoggedPart {
    u0: f64,
    u1: f64,
    h0: f64,
    h1: f64,
    slope: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fog below y = 2 (the scene format's example plane `[0, 1, 0, -2]`).
    fn below_two(sigma: f64) -> LinearDensity {
        LinearDensity::from_plane(sigma, [0.0, 1.0, 0.0, -2.0]).unwrap()
    }

    #[test]
    fn the_plane_is_normalised_and_the_fog_is_behind_it() {
        let fog = LinearDensity::from_plane(0.5, [0.0, 4.0, 0.0, -8.0]).unwrap();
        assert_eq!(fog, below_two(0.5));
        assert_eq!(fog.density_at(DVec3::new(0.0, 0.0, 0.0)), 1.0);
        assert_eq!(fog.density_at(DVec3::new(0.0, 3.0, 0.0)), 0.0);
        assert!(LinearDensity::from_plane(1.0, [0.0, 0.0, 0.0, 1.0]).is_none());
    }

    #[test]
    fn a_vertical_segment_through_the_plane_is_a_triangle() {
        let fog = below_two(0.5);
        // From y = 0 (height 2) up to y = 4: the fog ends at y = 2; area 0.5 * 2 * 2 / 2.
        let up = Line {
            origin: DVec3::ZERO,
            direction: DVec3::Y,
        };
        assert_eq!(fog.optical_depth(&up, 0.0, 4.0), 1.0);
        // Rising out of the fog: finite depth to infinity.
        assert_eq!(fog.optical_depth(&up, 0.0, f64::INFINITY), 1.0);
        // Going down: unbounded.
        let down = Line {
            origin: DVec3::ZERO,
            direction: DVec3::NEG_Y,
        };
        assert_eq!(fog.optical_depth(&down, 0.0, f64::INFINITY), f64::INFINITY);
        assert_eq!(fog.optical_depth(&down, 0.0, 1.0), 0.5 * (2.0 + 3.0) / 2.0);
    }

    #[test]
    fn parallel_segments_have_constant_density() {
        let fog = below_two(0.25);
        let inside = Line {
            origin: DVec3::new(0.0, 1.0, 0.0),
            direction: DVec3::X,
        };
        assert_eq!(fog.optical_depth(&inside, 0.0, 8.0), 0.25 * 1.0 * 8.0);
        assert_eq!(
            fog.optical_depth(&inside, 0.0, f64::INFINITY),
            f64::INFINITY
        );
        let above = Line {
            origin: DVec3::new(0.0, 3.0, 0.0),
            direction: DVec3::X,
        };
        assert_eq!(fog.optical_depth(&above, 0.0, f64::INFINITY), 0.0);
    }

    #[test]
    fn inversion_entering_at_the_plane_and_leaving_it() {
        let fog = below_two(0.5);
        let down = Line {
            origin: DVec3::new(0.0, 4.0, 0.0),
            direction: DVec3::NEG_Y,
        };
        // Enters at t = 2; depth 0.5 * s^2 / 2 = 1 at s = 2.
        let t = fog
            .distance_at_optical_depth(&down, 0.0, 10.0, 1.0)
            .unwrap();
        assert!((t - 4.0).abs() < 1e-12, "{t}");
        let up = Line {
            origin: DVec3::ZERO,
            direction: DVec3::Y,
        };
        // Total depth to infinity is 1: more is never reached.
        assert_eq!(
            fog.distance_at_optical_depth(&up, 0.0, f64::INFINITY, 1.5),
            None
        );
        let t = fog
            .distance_at_optical_depth(&up, 0.0, f64::INFINITY, 0.75)
            .unwrap();
        assert!((fog.optical_depth(&up, 0.0, t) - 0.75).abs() < 1e-12);
    }
}
