//! How a segment's optical depth is integrated: in closed form (the default, seed 004's
//! `G(B) - G(A)`), or by ray marching with a fixed number of steps per segment, kept to
//! measure what the closed form saves (`conetrace accuracy --mode fog`).
//!
//! Seed 004 ("Analytic Fog Density - Integrals") names marching as the alternative to the
//! definite integral: "take multiple samples along the line segment ... and either calculate
//! the fog amount in each section, or maybe average the densities". Marching here is the
//! composite midpoint rule on the density: the clipped segment `[t0, t1]` is cut into `N`
//! equal steps of length `h = (t1 - t0) / N` and `tau ~ h * sum_i rho(t0 + (i + 1/2) h)`.
//! Its error is `-(t1 - t0) h^2 rho''(xi) / 24` for some `xi` in the segment (the midpoint
//! rule's error term), so it falls by 16 from `N` to `4 N` wherever the density is smooth,
//! and is exact for a density that is constant or affine along the segment (constant fog,
//! and linear fog away from its zero plane, as the seed's own trapezoid shows). Exponential
//! height fog is the case it approximates.
//!
//! An interval that reaches infinity (an escaping ray in unbounded fog) has no finite steps;
//! there marching falls back to the closed form, so only finite segments differ between the
//! two choices.

use super::segment::Line;
use super::Density;

/// The choice of `[render] fog_march_steps` / `--fog-march-steps`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FogIntegration {
    /// The closed-form definite integral of each density (exact to rounding).
    #[default]
    Exact,
    /// The midpoint rule with this many density samples per clipped segment (at least 1).
    March { steps_per_segment: u32 },
}

impl FogIntegration {
    /// Marching with `steps` per segment; `None` for zero steps.
    pub fn march(steps: u32) -> Option<FogIntegration> {
        (steps > 0).then_some(FogIntegration::March {
            steps_per_segment: steps,
        })
    }

    /// The optical depth of `density` along `line` over the clipped interval `[t0, t1]`,
    /// and how many density samples it took (0 for the closed form).
    pub fn optical_depth(&self, density: &Density, line: &Line, t0: f64, t1: f64) -> (f64, u64) {
        match *self {
            FogIntegration::March { steps_per_segment } if t1.is_finite() && t1 > t0 => (
                marched_optical_depth(density, line, t0, t1, steps_per_segment),
                u64::from(steps_per_segment.max(1)),
            ),
            _ => (density.optical_depth(line, t0, t1), 0),
        }
    }

    /// `exact` or `march N`, as reports print it.
    pub fn label(&self) -> String {
        match self {
            FogIntegration::Exact => "exact".to_string(),
            FogIntegration::March { steps_per_segment } => format!("march {steps_per_segment}"),
        }
    }
}

/// The composite midpoint rule on `density` over the finite `[t0, t1]` with `steps` equal
/// steps (at least one): `h * sum rho(t0 + (i + 1/2) h)`.
// `!(t1 > t0)` also returns for a NaN end, which `t1 <= t0` would let through.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn marched_optical_depth(density: &Density, line: &Line, t0: f64, t1: f64, steps: u32) -> f64 {
    if !(t1 > t0) {
        return 0.0;
    }
    let steps = steps.max(1);
    let step = (t1 - t0) / f64::from(steps);
    let sum: f64 = (0..steps)
        .map(|i| density.density_at(line.at(t0 + (f64::from(i) + 0.5) * step)))
        .sum();
    sum * step
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::{ConstantDensity, ExponentialDensity, LinearDensity};
    use glam::DVec3;

    fn height_fog() -> Density {
        Density::Exponential(ExponentialDensity {
            sigma: 0.05,
            height: 0.5,
            falloff: 0.5,
        })
    }

    fn slanted_line() -> Line {
        Line {
            origin: DVec3::new(0.0, 6.0, 7.0),
            direction: DVec3::new(0.2, -0.5, -1.0).normalize(),
        }
    }

    /// The midpoint rule's error is O(h^2): from N to 4 N steps it falls by 16 (within a few
    /// per cent, the next term being O(h^4)), and at 256 steps it is below 1e-5 relative.
    #[test]
    fn marching_converges_to_the_closed_form_at_second_order() {
        let fog = height_fog();
        let line = slanted_line();
        let (t0, t1) = (0.0, 12.0);
        let exact = fog.optical_depth(&line, t0, t1);
        let mut previous_error = f64::INFINITY;
        for steps in [4u32, 16, 64, 256] {
            let marched = marched_optical_depth(&fog, &line, t0, t1, steps);
            let error = (marched - exact).abs();
            println!("{steps:>4} steps: tau {marched:.12} vs {exact:.12}, error {error:.3e}");
            if previous_error.is_finite() {
                let ratio = previous_error / error;
                assert!(
                    (15.0..17.0).contains(&ratio),
                    "{steps} steps: ratio {ratio}"
                );
            }
            previous_error = error;
        }
        assert!(previous_error < 1e-5 * exact, "{previous_error} vs {exact}");
        // The midpoint rule underestimates a convex density.
        assert!(marched_optical_depth(&fog, &line, t0, t1, 4) < exact);
    }

    #[test]
    fn constant_and_affine_densities_are_marched_exactly() {
        let line = slanted_line();
        let constant = Density::Constant(ConstantDensity { sigma: 0.3 });
        let exact = constant.optical_depth(&line, 1.0, 9.0);
        assert!((marched_optical_depth(&constant, &line, 1.0, 9.0, 4) - exact).abs() < 1e-14);
        // Linear fog below the plane y = 10: affine along the whole segment (no clamp).
        let linear =
            Density::Linear(LinearDensity::from_plane(0.1, [0.0, 1.0, 0.0, -10.0]).unwrap());
        let exact = linear.optical_depth(&line, 0.0, 8.0);
        let marched = marched_optical_depth(&linear, &line, 0.0, 8.0, 4);
        assert!((marched - exact).abs() < 1e-13 * exact, "{marched} {exact}");
    }

    #[test]
    fn infinite_intervals_and_the_exact_choice_use_the_closed_form() {
        let fog = height_fog();
        let up = Line {
            origin: DVec3::ZERO,
            direction: DVec3::Y,
        };
        let closed = fog.optical_depth(&up, 0.0, f64::INFINITY);
        let march = FogIntegration::march(16).unwrap();
        assert_eq!(
            march.optical_depth(&fog, &up, 0.0, f64::INFINITY),
            (closed, 0)
        );
        let finite = march.optical_depth(&fog, &up, 0.0, 3.0);
        assert_eq!(finite.1, 16);
        assert_eq!(finite.0, marched_optical_depth(&fog, &up, 0.0, 3.0, 16));
        assert_eq!(
            FogIntegration::Exact.optical_depth(&fog, &up, 0.0, 3.0),
            (fog.optical_depth(&up, 0.0, 3.0), 0)
        );
        assert_eq!(FogIntegration::march(0), None);
        assert_eq!(march.label(), "march 16");
    }
}
