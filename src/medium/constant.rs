//! Constant-density fog: the same extinction everywhere inside the volume.
//!
//! Seed 004, "Constant Density Fog": the fog amount is the density times the distance spent
//! in the fog, `tau = sigma * (t1 - t0)` (the rectangle under a flat density graph).

/// Extinction `sigma` per unit length everywhere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstantDensity {
    pub sigma: f64,
}

impl ConstantDensity {
    #[inline]
    pub fn density_at(&self) -> f64 {
        self.sigma
    }

    /// `sigma * (t1 - t0)`; an infinite interval has infinite depth unless `sigma` is 0.
    pub fn optical_depth(&self, t0: f64, t1: f64) -> f64 {
        if self.sigma == 0.0 || t1 <= t0 {
            return 0.0;
        }
        self.sigma * (t1 - t0)
    }

    /// The distance `t` in `[t0, t1]` where the depth from `t0` reaches `tau`:
    /// `t0 + tau / sigma`, or `None` when the interval holds less than `tau`.
    pub fn distance_at_optical_depth(&self, t0: f64, t1: f64, tau: f64) -> Option<f64> {
        if tau <= 0.0 {
            return Some(t0);
        }
        if self.sigma <= 0.0 {
            return None;
        }
        let t = t0 + tau / self.sigma;
        (t <= t1).then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_is_sigma_times_length_and_inverts() {
        let fog = ConstantDensity { sigma: 0.04 };
        assert_eq!(fog.optical_depth(2.0, 12.0), 0.04 * 10.0);
        assert_eq!(fog.optical_depth(0.0, f64::INFINITY), f64::INFINITY);
        assert_eq!(
            ConstantDensity { sigma: 0.0 }.optical_depth(0.0, f64::INFINITY),
            0.0
        );
        let t = fog.distance_at_optical_depth(2.0, 100.0, 0.4).unwrap();
        assert!((t - 12.0).abs() < 1e-12);
        assert_eq!(fog.distance_at_optical_depth(2.0, 5.0, 0.4), None);
    }
}
