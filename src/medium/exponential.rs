//! Exponential height fog: `density(p) = sigma * exp(-falloff * (p.y - height))`, dense
//! below `height` and thinning above it (for a positive falloff).
//!
//! Seed 004's method ("Analytic Fog Density - Integrals"): the fog amount between two
//! points is the definite integral of the density, `G(B) - G(A)` with `G` the indefinite
//! integral, stretched over the segment's length. Along `p(t) = o + t w` the density is
//! `rho(t) = rho(t_r) * exp(c (t - t_r))` with `c = -falloff * w.y`, so
//!
//! `tau = rho(t_r) * integral_0^L exp(+-|c| s) ds`.
//!
//! Written naively, `(G(B) - G(A)) / (B.y - A.y)` divides a vanishing difference by a
//! vanishing difference when the segment is nearly horizontal (`c L -> 0`), and overflows
//! on steep, long segments. Here the integral is always taken from the denser end, as
//! `rho_max * L * phi(-|c| L)` with `phi(x) = expm1(x) / x` (`phi(0) = 1`): `expm1` keeps
//! full precision for small `|c L|`, and `phi` of a non-positive argument lies in (0, 1],
//! so the product cannot overflow beyond the density itself.

use super::segment::Line;

/// `sigma * exp(-falloff * (y - height))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExponentialDensity {
    pub sigma: f64,
    pub height: f64,
    pub falloff: f64,
}

/// `expm1(x) / x`, 1 at 0: the mean of `exp` over `[0, x]`.
#[inline]
pub(crate) fn expm1_over_x(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        x.exp_m1() / x
    }
}

/// `log1p(x) / x`, 1 at 0.
#[inline]
fn log1p_over_x(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        x.ln_1p() / x
    }
}

impl ExponentialDensity {
    pub fn density_at(&self, y: f64) -> f64 {
        self.sigma * (-self.falloff * (y - self.height)).exp()
    }

    /// `ln(density)` at distance `t` along `line`: no underflow far above the fog.
    #[inline]
    fn log_density(&self, line: &Line, t: f64) -> f64 {
        let above = (line.origin.y - self.height) + line.direction.y * t;
        self.sigma.ln() - self.falloff * above
    }

    /// The integral of the density over `[t0, t1]`; `t1` may be infinite (finite depth when
    /// the density decreases along the line: `rho(t0) / |c|`).
    pub fn optical_depth(&self, line: &Line, t0: f64, t1: f64) -> f64 {
        if self.sigma == 0.0 || t1 <= t0 {
            return 0.0;
        }
        let rate = -self.falloff * line.direction.y;
        if t1.is_infinite() {
            if rate >= 0.0 {
                return f64::INFINITY;
            }
            return self.log_density(line, t0).exp() / -rate;
        }
        let length = t1 - t0;
        // Integrate from the denser end towards the thinner one.
        let denser_end = if rate > 0.0 { t1 } else { t0 };
        let rho_max = self.log_density(line, denser_end).exp();
        if rho_max == 0.0 {
            return 0.0;
        }
        rho_max * length * expm1_over_x(-rate.abs() * length)
    }

    /// The distance `t` in `[t0, t1]` where the depth from `t0` reaches `tau`, or `None`
    /// when the interval holds less.
    ///
    /// `rho0 (exp(c s) - 1) / c = tau` gives `s = ln(1 + c tau / rho0) / c`, written as
    /// `(tau / rho0) * log1p(x) / x` with `x = c tau / rho0` so it stays exact as `c -> 0`;
    /// when `x` is huge (deep below a thin start), as `(ln(c tau) - ln rho0) / c` from the
    /// log-density, which neither overflows nor underflows. `x <= -1` means the depth left
    /// to infinity is less than `tau`.
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
        let rate = -self.falloff * line.direction.y;
        let log_rho0 = self.log_density(line, t0);
        let scaled = tau * (-log_rho0).exp(); // tau / rho0
        let x = rate * scaled;
        let s = if x <= -1.0 {
            return None;
        } else if x.is_finite() && x < 1e15 {
            scaled * log1p_over_x(x)
        } else {
            ((rate * tau).ln() - log_rho0) / rate
        };
        let t = t0 + s;
        (t.is_finite() && t <= t1).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn height_fog() -> ExponentialDensity {
        ExponentialDensity {
            sigma: 0.3,
            height: 1.0,
            falloff: 0.5,
        }
    }

    #[test]
    fn horizontal_segments_have_constant_density() {
        let fog = height_fog();
        let line = Line {
            origin: DVec3::new(0.0, 3.0, 0.0),
            direction: DVec3::X,
        };
        let expected = 0.3 * (-1.0f64).exp() * 10.0;
        assert!((fog.optical_depth(&line, 0.0, 10.0) - expected).abs() <= 1e-15 * expected);
        assert_eq!(fog.optical_depth(&line, 0.0, f64::INFINITY), f64::INFINITY);
    }

    #[test]
    fn vertical_segments_match_the_indefinite_integral() {
        let fog = height_fog();
        let up = Line {
            origin: DVec3::new(0.0, 1.0, 0.0),
            direction: DVec3::Y,
        };
        // G(y) = -sigma/falloff exp(-falloff (y - height)); G(5) - G(1).
        let expected = 0.3 / 0.5 * (1.0 - (-2.0f64).exp());
        let tau = fog.optical_depth(&up, 0.0, 4.0);
        assert!(
            (tau - expected).abs() <= 1e-15 * expected,
            "{tau} {expected}"
        );
        // Upwards to infinity: sigma / falloff.
        let to_infinity = fog.optical_depth(&up, 0.0, f64::INFINITY);
        assert!((to_infinity - 0.6).abs() < 1e-15);
        // Downwards the same stretch has the same depth.
        let down = Line {
            origin: DVec3::new(0.0, 5.0, 0.0),
            direction: DVec3::NEG_Y,
        };
        assert!((fog.optical_depth(&down, 0.0, 4.0) - expected).abs() <= 1e-15 * expected);
    }

    #[test]
    fn far_above_the_fog_nothing_overflows_or_becomes_nan() {
        let fog = height_fog();
        let down = Line {
            origin: DVec3::new(0.0, 3000.0, 0.0),
            direction: DVec3::NEG_Y,
        };
        let tau = fog.optical_depth(&down, 0.0, 3000.0);
        let expected = 0.3 / 0.5 * (1.0 - (-1500.0f64).exp()) * 0.5f64.exp();
        assert!(
            (tau - expected).abs() <= 1e-13 * expected,
            "{tau} {expected}"
        );
        // The inverse from a start where the density underflows to zero.
        let t = fog
            .distance_at_optical_depth(&down, 0.0, 3000.0, 0.5)
            .unwrap();
        let back = fog.optical_depth(&down, 0.0, t);
        assert!((back - 0.5).abs() < 1e-9, "{t} {back}");
    }

    #[test]
    fn inversion_round_trips_and_knows_the_finite_total() {
        let fog = height_fog();
        let up = Line {
            origin: DVec3::new(0.0, 1.0, 0.0),
            direction: DVec3::new(0.6, 0.8, 0.0),
        };
        assert_eq!(
            fog.distance_at_optical_depth(&up, 0.0, f64::INFINITY, 0.8),
            None
        );
        let t = fog
            .distance_at_optical_depth(&up, 0.0, f64::INFINITY, 0.5)
            .unwrap();
        assert!((fog.optical_depth(&up, 0.0, t) - 0.5).abs() < 1e-14);
    }
}
