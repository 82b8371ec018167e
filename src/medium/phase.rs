//! The Henyey–Greenstein phase function: how a fog particle redirects the light it scatters,
//! for the path tracer's medium vertices.
//!
//! Henyey & Greenstein ("Diffuse radiation in the galaxy", ApJ 93, 1941) give the density
//! of the scattering angle `theta` between the direction light travelled in and the
//! direction it leaves in, with one parameter, the mean cosine `g` in (-1, 1):
//!
//! `p(cos theta) = (1 - g^2) / (4 pi (1 + g^2 - 2 g cos theta)^(3/2))`
//!
//! per steradian. `g > 0` scatters forward (mist, haze), `g < 0` backward, `g = 0` is
//! isotropic, `1 / (4 pi)`. The function is normalised over the sphere, so it is its own
//! sampling density: sampling it exactly gives the weight `p / pdf = 1` and a scattered
//! path's throughput changes only by the albedo (docs/fog.md).
//!
//! Sampling inverts the cumulative distribution of `cos theta` in closed form (pbrt-v4,
//! section 11.3.1, derives the same inverse):
//!
//! `cos theta = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g u))^2) / (2 g)`
//!
//! which maps `u = 0` to `cos theta = -1` and `u = 1` to `+1`; near `g = 0` the form
//! divides two vanishing quantities, so `|g| < 1e-3` samples the sphere uniformly instead
//! (the density differs from isotropic by at most `3|g| = 0.3 %` there, and `eval`/`pdf`
//! use that same isotropic density, so sample and pdf stay consistent).
//!
//! Directions: `travel` is the direction the light was going when it reached the particle
//! (the ray's direction), `wi` the direction it leaves in; `cos theta = travel . wi`.

use glam::{Vec2, Vec3};

use crate::shading::bsdf::orthonormal_basis;

/// Below this `|g|` the phase function is taken as isotropic (see the module doc).
const ISOTROPIC_BELOW: f32 = 1e-3;

const INV_FOUR_PI: f32 = 1.0 / (4.0 * std::f32::consts::PI);

/// A Henyey–Greenstein phase function with mean cosine `g`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    pub g: f32,
}

/// A direction drawn from the phase function, with its density per steradian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseSample {
    pub wi: Vec3,
    pub pdf: f32,
}

impl HenyeyGreenstein {
    /// The phase function of `g`, clamped into (-0.999, 0.999) so the density stays finite.
    pub fn new(g: f32) -> HenyeyGreenstein {
        let g = if g.is_nan() {
            0.0
        } else {
            g.clamp(-0.999, 0.999)
        };
        HenyeyGreenstein { g }
    }

    #[inline]
    fn isotropic(&self) -> bool {
        self.g.abs() < ISOTROPIC_BELOW
    }

    /// The density of scattering by the angle whose cosine is `cos_theta`, per steradian.
    #[inline]
    pub fn eval_cos(&self, cos_theta: f32) -> f32 {
        if self.isotropic() {
            return INV_FOUR_PI;
        }
        let g = self.g;
        let denominator = 1.0 + g * g - 2.0 * g * cos_theta.clamp(-1.0, 1.0);
        INV_FOUR_PI * (1.0 - g * g) / (denominator * denominator.sqrt())
    }

    /// The phase function's value for light travelling along `travel` leaving along `wi`
    /// (both unit vectors).
    #[inline]
    pub fn eval(&self, travel: Vec3, wi: Vec3) -> f32 {
        self.eval_cos(travel.dot(wi))
    }

    /// The density [`Self::sample`] draws `wi` with: the phase function itself.
    #[inline]
    pub fn pdf(&self, travel: Vec3, wi: Vec3) -> f32 {
        self.eval(travel, wi)
    }

    /// A direction distributed as the phase function around `travel` (unit), from two
    /// uniform numbers: `u.x` picks `cos theta` by the inverse above, `u.y` the azimuth.
    pub fn sample(&self, travel: Vec3, u: Vec2) -> PhaseSample {
        let cos_theta = if self.isotropic() {
            1.0 - 2.0 * u.x
        } else {
            let g = self.g;
            let ratio = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
            (1.0 + g * g - ratio * ratio) / (2.0 * g)
        }
        .clamp(-1.0, 1.0);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = 2.0 * std::f32::consts::PI * u.y;
        let (tangent, bitangent) = orthonormal_basis(travel);
        let wi = (tangent * (sin_theta * phi.cos())
            + bitangent * (sin_theta * phi.sin())
            + travel * cos_theta)
            .normalize();
        PhaseSample {
            wi,
            pdf: self.eval_cos(cos_theta),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Integral of the density over the sphere, by the midpoint rule in `cos theta` (the
    /// density depends on nothing else; the azimuth contributes 2 pi).
    fn integral_over_sphere(phase: HenyeyGreenstein) -> f64 {
        let n = 200_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let mu = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
            sum += f64::from(phase.eval_cos(mu as f32));
        }
        sum * 2.0 / n as f64 * 2.0 * PI
    }

    #[test]
    fn integrates_to_one_for_every_g() {
        for g in [-0.9, -0.5, -0.1, 0.0, 0.0005, 0.1, 0.5, 0.8, 0.9] {
            let total = integral_over_sphere(HenyeyGreenstein::new(g));
            assert!((total - 1.0).abs() < 2e-3, "g = {g}: {total}");
        }
    }

    #[test]
    fn zero_g_is_isotropic_and_g_is_the_mean_cosine() {
        let iso = HenyeyGreenstein::new(0.0);
        for mu in [-1.0, -0.3, 0.0, 0.7, 1.0] {
            assert_eq!(iso.eval_cos(mu), INV_FOUR_PI);
        }
        // The mean cosine of HG is g (its defining property).
        for g in [-0.6f32, 0.3, 0.85] {
            let phase = HenyeyGreenstein::new(g);
            let n = 200_000;
            let mut mean = 0.0f64;
            for i in 0..n {
                let mu = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                mean += mu * f64::from(phase.eval_cos(mu as f32));
            }
            mean *= 2.0 / n as f64 * 2.0 * PI;
            assert!(
                (mean - f64::from(g)).abs() < 2e-3,
                "g = {g}: mean cosine {mean}"
            );
        }
    }

    #[test]
    fn the_sample_density_is_pdf_and_eval() {
        let travel = Vec3::new(0.3, -0.5, 0.8).normalize();
        for g in [-0.7, 0.0, 0.4, 0.95] {
            let phase = HenyeyGreenstein::new(g);
            for u in [
                Vec2::new(0.1, 0.2),
                Vec2::new(0.5, 0.9),
                Vec2::new(0.97, 0.4),
            ] {
                let s = phase.sample(travel, u);
                assert!((s.wi.length() - 1.0).abs() < 1e-5);
                let pdf = phase.pdf(travel, s.wi);
                assert!(
                    (s.pdf - pdf).abs() <= 1e-3 * pdf,
                    "g = {g}: {} vs {pdf}",
                    s.pdf
                );
                assert_eq!(phase.eval(travel, s.wi), pdf);
            }
        }
    }

    /// Chi-square test of the sampled `cos theta` against the density's integral over bins
    /// (the azimuth is uniform by construction and checked apart): 40 bins of equal
    /// expected count from the closed-form CDF, 200 000 samples of a stratified-free
    /// deterministic generator.
    #[test]
    fn sampled_cosines_follow_the_density_chi_square() {
        let travel = Vec3::new(0.0, 0.6, -0.8);
        let (tangent, _) = orthonormal_basis(travel);
        for g in [-0.8f32, 0.0, 0.3, 0.9] {
            let phase = HenyeyGreenstein::new(g);
            let bins = 40usize;
            let n = 200_000usize;
            // Bin edges in cos theta with equal probability: the CDF's inverse at k / bins
            // is what `sample` computes for u.x = k / bins, so the edges are taken from a
            // numerical CDF instead (midpoint rule), independent of the sampling code.
            let grid = 400_000;
            let mut cdf = Vec::with_capacity(grid + 1);
            cdf.push(0.0f64);
            for i in 0..grid {
                let mu = -1.0 + (i as f64 + 0.5) * 2.0 / grid as f64;
                let last = *cdf.last().unwrap();
                cdf.push(
                    last + f64::from(phase.eval_cos(mu as f32)) * 2.0 * PI * 2.0 / grid as f64,
                );
            }
            let bin_of = |mu: f32| -> usize {
                let x = (((f64::from(mu) + 1.0) / 2.0) * grid as f64).clamp(0.0, grid as f64);
                let i = (x as usize).min(grid - 1);
                let within = cdf[i] + (x - i as f64) * (cdf[i + 1] - cdf[i]);
                let c = within / cdf[grid];
                ((c * bins as f64) as usize).min(bins - 1)
            };
            let mut counts = vec![0usize; bins];
            let mut azimuth_positive = 0usize;
            let mut state = 0x9e37_79b9_7f4a_7c15u64 ^ (g.to_bits() as u64);
            let mut uniform = move || {
                state ^= state >> 12;
                state ^= state << 25;
                state ^= state >> 27;
                (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u32 << 24) as f32
            };
            for _ in 0..n {
                let s = phase.sample(travel, Vec2::new(uniform(), uniform()));
                counts[bin_of(s.wi.dot(travel))] += 1;
                azimuth_positive += usize::from(s.wi.dot(tangent) > 0.0);
            }
            let expected = n as f64 / bins as f64;
            let chi2: f64 = counts
                .iter()
                .map(|&c| (c as f64 - expected).powi(2) / expected)
                .sum();
            // 39 degrees of freedom: the 99.9 % quantile is 72.1.
            assert!(
                chi2 < 72.1,
                "g = {g}: chi-square {chi2} over {bins} bins: {counts:?}"
            );
            let share = azimuth_positive as f64 / n as f64;
            assert!((share - 0.5).abs() < 0.01, "g = {g}: azimuth share {share}");
        }
    }

    #[test]
    fn forward_scattering_concentrates_around_the_travel_direction() {
        let phase = HenyeyGreenstein::new(0.8);
        assert!(phase.eval_cos(1.0) > 100.0 * phase.eval_cos(-1.0));
        // Exact values: p(1) = (1 - g^2) / (4 pi (1 - g)^3).
        let expected = (1.0 - 0.64) / (4.0 * std::f32::consts::PI * 0.2f32.powi(3));
        assert!((phase.eval_cos(1.0) - expected).abs() < 1e-4 * expected);
        // g outside (-1, 1) or NaN is clamped, never an infinite density.
        assert!(HenyeyGreenstein::new(1.0).eval_cos(1.0).is_finite());
        assert_eq!(HenyeyGreenstein::new(f32::NAN).g, 0.0);
    }
}
