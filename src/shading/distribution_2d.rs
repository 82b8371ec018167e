//! Piecewise-constant distributions over [0, 1) and [0, 1)^2, sampled by inverting their
//! cumulative distribution (pbrt-v4, sections A.4.1 and A.5.2): the environment light draws
//! directions in proportion to its texels' brightness with them.
//!
//! A 1D distribution of `n` non-negative values `f_i` has density
//! `p(x) = f_i / I` on `[i/n, (i+1)/n)`, with `I = (1/n) sum f_i`. The 2D one over an
//! `nu x nv` grid is a marginal distribution over rows (each row's integral) and one
//! conditional distribution per row, so `p(u, v) = p(v) p(u | v) = f(u, v) / I`.
//! Sums are accumulated in f64: a sun ten thousand times brighter than the sky over a
//! million texels keeps its share exact.

use glam::Vec2;

/// A piecewise-constant density over [0, 1).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    /// The values (negative and non-finite ones count as 0).
    func: Vec<f32>,
    /// `cdf[i]` = probability of `[0, i/n)`; `n + 1` entries, the last 1.
    cdf: Vec<f32>,
    /// `(1/n) sum func`: the integral of the piecewise-constant function.
    integral: f64,
}

impl Distribution1D {
    /// The distribution proportional to `values` (at least one value). All-zero values give
    /// the uniform distribution, so sampling still returns points (of density 1).
    pub fn new(values: &[f32]) -> Distribution1D {
        let n = values.len().max(1);
        let func: Vec<f32> = (0..n)
            .map(|i| match values.get(i) {
                Some(&v) if v.is_finite() && v > 0.0 => v,
                _ => 0.0,
            })
            .collect();
        let mut running = vec![0.0f64; n + 1];
        for i in 0..n {
            running[i + 1] = running[i] + f64::from(func[i]) / n as f64;
        }
        let integral = running[n];
        let cdf = if integral > 0.0 {
            running.iter().map(|&c| (c / integral) as f32).collect()
        } else {
            (0..=n).map(|i| i as f32 / n as f32).collect()
        };
        let mut cdf: Vec<f32> = cdf;
        cdf[n] = 1.0;
        Distribution1D {
            func,
            cdf,
            integral,
        }
    }

    /// Number of pieces.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Always false: a distribution has at least one piece.
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// `(1/n) sum f_i`.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// Density of the piece `index`.
    #[inline]
    fn piece_pdf(&self, index: usize) -> f32 {
        if self.integral > 0.0 {
            (f64::from(self.func[index]) / self.integral) as f32
        } else {
            1.0
        }
    }

    /// Density at `x` in [0, 1).
    #[inline]
    pub fn pdf(&self, x: f32) -> f32 {
        let n = self.func.len();
        let index = ((x * n as f32) as usize).min(n - 1);
        self.piece_pdf(index)
    }

    /// The point `x` in [0, 1) the uniform number `u` maps to by inverting the cumulative
    /// distribution, with its density and its piece.
    #[inline]
    pub fn sample(&self, u: f32) -> (f32, f32, usize) {
        let n = self.func.len();
        // The last piece whose cdf lies at or below u; pieces of probability zero have
        // cdf[i] == cdf[i + 1] and are skipped by taking the last such i.
        let index = (self.cdf.partition_point(|&c| c <= u).max(1) - 1).min(n - 1);
        let (lo, hi) = (self.cdf[index], self.cdf[index + 1]);
        let offset = if hi > lo {
            ((u - lo) / (hi - lo)).clamp(0.0, 1.0)
        } else {
            0.5
        };
        // Keep x below 1 (u just under 1 may round up).
        let x = ((index as f32 + offset) / n as f32).min(1.0 - f32::EPSILON / 2.0);
        (x, self.piece_pdf(index), index)
    }
}

/// A piecewise-constant density over [0, 1)^2 on an `nu x nv` grid (`u` across, `v` down).
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    /// One distribution over u per row v.
    conditional: Vec<Distribution1D>,
    /// The distribution over rows, by each row's integral.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The distribution proportional to `values`, `nu` values per row, `nv` rows.
    pub fn new(values: &[f32], nu: usize, nv: usize) -> Distribution2D {
        let (nu, nv) = (nu.max(1), nv.max(1));
        let conditional: Vec<Distribution1D> = (0..nv)
            .map(|v| {
                let start = (v * nu).min(values.len());
                let end = (start + nu).min(values.len());
                Distribution1D::new(&values[start..end])
            })
            .collect();
        let row_integrals: Vec<f32> = conditional.iter().map(|c| c.integral() as f32).collect();
        Distribution2D {
            marginal: Distribution1D::new(&row_integrals),
            conditional,
        }
    }

    /// Grid size `(nu, nv)`.
    pub fn size(&self) -> (usize, usize) {
        (self.conditional[0].len(), self.conditional.len())
    }

    /// The point the uniform numbers `u` map to, with its density over [0, 1)^2.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample(u.y);
        let (x, pdf_u, _) = self.conditional[row].sample(u.x);
        (Vec2::new(x, v), pdf_v * pdf_u)
    }

    /// Density at `p` in [0, 1)^2.
    #[inline]
    pub fn pdf(&self, p: Vec2) -> f32 {
        let nv = self.conditional.len();
        let row = ((p.y * nv as f32) as usize).min(nv - 1);
        self.marginal.pdf(p.y) * self.conditional[row].pdf(p.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    #[test]
    fn one_dimension_samples_follow_the_values() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 4.0]);
        assert_eq!(d.integral(), 2.0);
        assert_eq!(d.pdf(0.3), 0.0);
        assert_eq!(d.pdf(0.9), 2.0);
        let mut u = Uniforms(5);
        let mut counts = [0usize; 4];
        let count = 80_000;
        for _ in 0..count {
            let (x, pdf, index) = d.sample(u.next());
            assert!((0.0..1.0).contains(&x));
            assert_eq!(index, (x * 4.0) as usize);
            assert_eq!(pdf, d.pdf(x));
            counts[index] += 1;
        }
        assert_eq!(counts[1], 0, "a piece of value 0 was sampled");
        for (i, expected) in [(0, 0.125), (2, 0.375), (3, 0.5)] {
            let share = counts[i] as f32 / count as f32;
            assert!((share - expected).abs() < 0.01, "{i}: {share}");
        }
        // Inversion is monotonic and exact at the piece boundaries.
        assert_eq!(d.sample(0.125).2, 2);
        assert!(d.sample(1.0).0 < 1.0);
    }

    #[test]
    fn all_zero_values_are_uniform() {
        let d = Distribution1D::new(&[0.0, 0.0]);
        assert_eq!(d.pdf(0.7), 1.0);
        assert_eq!(d.sample(0.75).0, 0.75);
    }

    #[test]
    fn two_dimensions_pdf_matches_the_normalised_values() {
        let values = [1.0, 2.0, 0.0, 5.0, 0.0, 0.0, 3.0, 1.0, 4.0];
        let d = Distribution2D::new(&values, 3, 3);
        let total: f32 = values.iter().sum::<f32>() / 9.0;
        for v in 0..3 {
            for u in 0..3 {
                let p = Vec2::new((u as f32 + 0.5) / 3.0, (v as f32 + 0.5) / 3.0);
                let expected = values[v * 3 + u] / total;
                assert!(
                    (d.pdf(p) - expected).abs() < 1e-5,
                    "({u}, {v}): {}",
                    d.pdf(p)
                );
            }
        }
        let mut rng = Uniforms(9);
        for _ in 0..10_000 {
            let (p, pdf) = d.sample(rng.vec2());
            assert!(pdf > 0.0);
            assert!(
                (pdf - d.pdf(p)).abs() < 1e-5 * pdf,
                "{p} {pdf} {}",
                d.pdf(p)
            );
        }
    }
}
