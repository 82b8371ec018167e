//! Energy compensation for the GGX metals: the light a single-scattering microfacet lobe
//! loses between microfacets, given back as a second, diffuse-like lobe (Kulla and Conty
//! 2017, "Revisiting Physically Based Shading at Imageworks", section "Multiple
//! scattering").
//!
//! With `E(mu)` the directional albedo of the white (`F = 1`) single-scattering lobe seen
//! from `mu = cos(theta_o)` and `E_avg = 2 integral_0^1 E(mu) mu dmu` its cosine-weighted
//! mean, the compensation lobe is
//!
//! `f_ms(wo, wi) = (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg))`,
//!
//! symmetric in its two directions, and its albedo from `wo` is `1 - E(mu_o)` exactly: a
//! white metal of any roughness then reflects everything it receives. A coloured metal
//! scales it by `F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg))`, the sum over every
//! number of extra bounces of the energy that the mean Fresnel reflectance `F_avg`
//! (`2 integral F(mu) mu dmu`; for Schlick's `F0 + (1 - F0)(1 - mu)^5` it is
//! `F0 + (1 - F0) / 21`) keeps, so multiple scattering saturates the colour as it does on
//! real rough metals.
//!
//! `E` comes from a table over the perceptual roughness `r = sqrt(alpha)` and the cosine
//! of the view in the stretched configuration where the distribution has `alpha = 1`,
//! `z = mu / sqrt(mu^2 + alpha^2 (1 - mu^2))` (Heitz 2018's stretch). Smith's masking
//! depends on the view only through `alpha tan(theta)`, which `z` follows: a nearly
//! smooth metal loses energy only within a fraction of a degree of grazing, a band that a
//! grid uniform in `mu` would straddle with one or two nodes and interpolate badly (too
//! much or too little compensation there), while in `z` it spans the whole table. The
//! nodes sit at `z = t^2` for `t` uniform in [0, 1], denser towards grazing. The table
//! holds `1 - E` (what the lobe loses, exact in `f64` however small), is filled once, on
//! first use, by integrating the lobe's own visible-normal weight `G2 / G1` over a fixed
//! grid of sample positions, and is interpolated bilinearly between nodes.
//! `1 - E_avg` is the `mu`-weighted integral of that interpolated loss by a fine midpoint
//! sum, so the lobe's albedo balance holds for the table as used.
//!
//! Sampling follows `f_ms cos(theta_i)`, that is `(1 - E(mu_i)) mu_i`: for a nearly smooth
//! metal that product lives only at grazing `wi`, where a cosine-weighted sampler would
//! almost never go and would then weigh a sample by thousands. Each roughness row keeps a
//! density over `t` that follows it at 257 points, linear between them (continuous, so
//! a direction's density does not jump with its last bit), so `f_ms cos / pdf` stays
//! within about ten times `1 - E(mu_o)` (test
//! `sampling_follows_the_lobe_and_its_density_integrates_to_one`).

use std::f32::consts::{FRAC_PI_2, PI};
use std::sync::OnceLock;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::microfacet::{Ggx, MIN_ALPHA};

/// Table nodes along the view parameter `t` ([`view_parameter`]), uniform in [0, 1].
const VIEW_NODES: usize = 64;
/// Table nodes along the GGX width, uniform in `ln(alpha)` from [`MIN_ALPHA`] to 1:
/// neighbouring rows differ by 15 % in `alpha` at every roughness.
const ROUGHNESS_NODES: usize = 48;
/// Sample positions per side of the grid each table entry integrates over.
const GRID: usize = 48;
/// Bins along `t` of the sampling density, uniform in [0, 1].
const SAMPLING_BINS: usize = 256;
/// Midpoints per sampling bin in the sums for the bin's weight and for `1 - E_avg`.
const POINTS_PER_BIN: usize = 8;
/// The smallest `mu` the table integrates at: at exactly zero the view is tangent and
/// Smith's masking is singular.
const MIN_MU: f32 = 1e-6;
/// Below this `1 - E_avg` the lobe loses nothing worth giving back (a mirror-like metal).
const NEGLIGIBLE_LOSS: f64 = 1e-9;

/// `1 - E(t, r)` on its nodes, `1 - E_avg(r)` and the sampling distribution per roughness
/// node.
struct LossTable {
    lost: [[f32; VIEW_NODES]; ROUGHNESS_NODES],
    lost_average: [f32; ROUGHNESS_NODES],
    /// Per row, the sampling density over `t` at the bins' edges (linear between them).
    density: [[f32; SAMPLING_BINS + 1]; ROUGHNESS_NODES],
    /// Per row, the cumulative distribution at the bins' edges (0 first, 1 last).
    cdf: [[f32; SAMPLING_BINS + 1]; ROUGHNESS_NODES],
}

static TABLE: OnceLock<Box<LossTable>> = OnceLock::new();

fn table() -> &'static LossTable {
    TABLE.get_or_init(LossTable::integrate)
}

/// The table's view parameter `t` of `mu` for width `alpha`: the stretched angle
/// `theta' = atan(alpha tan(theta))` mapped by `theta' = (pi / 2)(1 - (1 - t)^2)`, so that
/// nodes crowd towards grazing.
#[inline]
fn view_parameter(mu: f32, alpha: f32) -> f32 {
    1.0 - view_parameter_complement(mu, alpha)
}

/// `1 - t` of [`view_parameter`], computed directly (exact near grazing, where `t` is near
/// 1).
#[inline]
fn view_parameter_complement(mu: f32, alpha: f32) -> f32 {
    let mu = mu.clamp(0.0, 1.0);
    let sin = (1.0 - mu * mu).max(0.0).sqrt();
    let stretched = (alpha * sin).atan2(mu);
    (1.0 - stretched / FRAC_PI_2).max(0.0).sqrt()
}

/// `mu` of the view parameter `t` (the inverse of [`view_parameter`]):
/// `mu = alpha cos(theta') / sqrt(alpha^2 cos^2(theta') + sin^2(theta'))`.
#[inline]
fn view_cosine(t: f32, alpha: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    let stretched = FRAC_PI_2 * (1.0 - (1.0 - t) * (1.0 - t));
    let (sin, cos) = stretched.sin_cos();
    let cos = cos.max(0.0);
    let denominator = (alpha * alpha * cos * cos + sin * sin).sqrt();
    if denominator > 0.0 {
        (alpha * cos / denominator).min(1.0)
    } else {
        1.0
    }
}

/// `|dt / dmu|` at `mu`: `dtheta'/dmu = alpha / (sin(theta) D)` with
/// `D = mu^2 + alpha^2 (1 - mu^2)`, and `dt/dtheta' = 1 / (pi (1 - t))`; infinite at
/// normal incidence and at grazing, where `t` moves faster than `mu`.
#[inline]
fn t_per_mu(mu: f32, alpha: f32) -> f32 {
    let sin = (1.0 - mu * mu).max(0.0).sqrt();
    let d = mu * mu + alpha * alpha * (1.0 - mu * mu);
    let denominator = sin * d * PI * view_parameter_complement(mu, alpha);
    if denominator > 0.0 {
        alpha / denominator
    } else {
        f32::INFINITY
    }
}

/// The directional albedo of the white single-scattering lobe of `ggx` seen from
/// `mu`, by midpoint quadrature over a `grid x grid` grid of the visible-normal sampler's
/// inputs: each position gives the sample weight `G2(wo, wi) / G1(wo)` of
/// `crate::shading::conductor` with `F = 1`, or 0 when the reflection leaves below the
/// surface.
pub(crate) fn single_scattering_albedo(ggx: Ggx, mu: f32, grid: usize) -> f64 {
    let mu = mu.clamp(MIN_MU, 1.0);
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let g1 = ggx.g1(wo);
    let mut sum = 0.0f64;
    for u in midpoint_grid(grid) {
        if let Some((wi, _)) = ggx.sample_reflection(wo, u) {
            if wi.z > 0.0 {
                sum += (ggx.g2(wo, wi) / g1) as f64;
            }
        }
    }
    sum / (grid * grid) as f64
}

/// The midpoints of a `side x side` grid over the unit square.
pub(crate) fn midpoint_grid(side: usize) -> impl Iterator<Item = Vec2> {
    (0..side * side).map(move |k| {
        Vec2::new(
            ((k / side) as f32 + 0.5) / side as f32,
            ((k % side) as f32 + 0.5) / side as f32,
        )
    })
}

/// The GGX width of roughness row `j`: `MIN_ALPHA^(1 - j / (ROUGHNESS_NODES - 1))`.
fn row_alpha(j: usize) -> f32 {
    MIN_ALPHA.powf(1.0 - j as f32 / (ROUGHNESS_NODES - 1) as f32)
}

/// Where `alpha` falls between the roughness rows: `1 - ln(alpha) / ln(MIN_ALPHA)`.
fn row_position(alpha: f32) -> (usize, f32) {
    let s = 1.0 - alpha.clamp(MIN_ALPHA, 1.0).ln() / MIN_ALPHA.ln();
    node_position(s, ROUGHNESS_NODES)
}

impl LossTable {
    fn integrate() -> Box<LossTable> {
        let rows: Vec<[f32; VIEW_NODES]> = (0..ROUGHNESS_NODES)
            .into_par_iter()
            .map(|j| {
                let alpha = row_alpha(j);
                let ggx = Ggx::from_alpha(alpha);
                std::array::from_fn(|i| {
                    let mu = view_cosine(i as f32 / (VIEW_NODES - 1) as f32, alpha);
                    (1.0 - single_scattering_albedo(ggx, mu, GRID)).max(0.0) as f32
                })
            })
            .collect();
        let mut table = Box::new(LossTable {
            lost: [[0.0; VIEW_NODES]; ROUGHNESS_NODES],
            lost_average: [0.0; ROUGHNESS_NODES],
            density: [[0.0; SAMPLING_BINS + 1]; ROUGHNESS_NODES],
            cdf: [[0.0; SAMPLING_BINS + 1]; ROUGHNESS_NODES],
        });
        table.lost.copy_from_slice(&rows);
        for j in 0..ROUGHNESS_NODES {
            let alpha = row_alpha(j);
            let lost = table.lost[j];
            // (1 - E) mu dmu/dt at t: the integrand over t of the lobe's cosine-weighted
            // albedo (zero at both ends, where dmu/dt or mu vanish).
            let integrand = |t: f32| -> f64 {
                let mu = view_cosine(t, alpha);
                let jacobian = t_per_mu(mu, alpha);
                if jacobian > 0.0 && jacobian.is_finite() {
                    interpolate(&lost, t) as f64 * mu as f64 / jacobian as f64
                } else {
                    0.0
                }
            };
            // 1 - E_avg = 2 integral (1 - E) mu dmu, by a fine midpoint sum over t.
            let points = SAMPLING_BINS * POINTS_PER_BIN;
            let sub: Vec<f64> = (0..points)
                .map(|k| integrand((k as f32 + 0.5) / points as f32))
                .collect();
            let half_loss = sub.iter().sum::<f64>() / points as f64;
            table.lost_average[j] = (2.0 * half_loss).clamp(0.0, 1.0) as f32;
            // The sampling density: at each bin edge, the largest integrand over the two
            // bins beside it (so the linear density between edges stays near or above the
            // integrand, and sample weights near or below the lobe's albedo), never zero
            // inside (a floor of 1e-4 of its mean), normalised over t.
            // The end edges keep the integrand's own zeros: a density that vanishes there
            // as t and 1 - t do keeps the solid-angle density finite at normal incidence
            // and at grazing (dt/dmu is infinite at both).
            let mut knots: [f64; SAMPLING_BINS + 1] = std::array::from_fn(|k| {
                if k == 0 || k == SAMPLING_BINS {
                    return 0.0;
                }
                let first = (k - 1) * POINTS_PER_BIN;
                let last = (k * POINTS_PER_BIN + POINTS_PER_BIN).min(points);
                sub[first..last]
                    .iter()
                    .fold(integrand(k as f32 / SAMPLING_BINS as f32), |m, &v| m.max(v))
            });
            let mean = knots.iter().sum::<f64>() / (SAMPLING_BINS + 1) as f64;
            let floor = if mean > 0.0 { 1e-4 * mean } else { 1.0 };
            for knot in &mut knots[1..SAMPLING_BINS] {
                *knot = knot.max(floor);
            }
            let width = 1.0 / SAMPLING_BINS as f64;
            let mut cumulative = [0.0f64; SAMPLING_BINS + 1];
            for b in 0..SAMPLING_BINS {
                cumulative[b + 1] = cumulative[b] + 0.5 * (knots[b] + knots[b + 1]) * width;
            }
            let total = cumulative[SAMPLING_BINS];
            for k in 0..=SAMPLING_BINS {
                table.density[j][k] = (knots[k] / total) as f32;
                table.cdf[j][k] = (cumulative[k] / total) as f32;
            }
            table.cdf[j][SAMPLING_BINS] = 1.0;
        }
        table
    }

    /// `1 - E` on roughness row `j` at `t`, interpolated linearly.
    #[inline]
    fn row_lost(&self, j: usize, t: f32) -> f32 {
        interpolate(&self.lost[j], t)
    }
}

/// A row of table values at `t`, interpolated linearly between its uniform nodes.
#[inline]
fn interpolate(row: &[f32; VIEW_NODES], t: f32) -> f32 {
    let (i, w) = node_position(t, VIEW_NODES);
    row[i] * (1.0 - w) + row[i + 1] * w
}

/// Where a value falls between two nodes of `count` uniform nodes over [0, 1].
#[inline]
fn node_position(x: f32, count: usize) -> (usize, f32) {
    let s = x.clamp(0.0, 1.0) * (count - 1) as f32;
    let i = (s as usize).min(count - 2);
    (i, s - i as f32)
}

/// The compensation lobe of one GGX width, ready to evaluate and sample (see the module
/// doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MultipleScattering {
    /// The GGX width.
    alpha: f32,
    /// The lower roughness row of the table and the weight of the upper one.
    row: usize,
    row_weight: f32,
    /// `1 / (pi (1 - E_avg))`, or 0 when the lobe loses nothing worth compensating.
    normalisation: f32,
    /// `1 - E_avg`.
    lost_average: f32,
}

impl MultipleScattering {
    /// No compensation: a lobe that adds nothing (for lobes with no metal in them).
    pub const NONE: MultipleScattering = MultipleScattering {
        alpha: 1.0,
        row: 0,
        row_weight: 0.0,
        normalisation: 0.0,
        lost_average: 0.0,
    };

    /// The compensation for `ggx`.
    pub fn new(ggx: Ggx) -> MultipleScattering {
        let table = table();
        let (row, row_weight) = row_position(ggx.alpha);
        // 1 - E_avg falls as a power of alpha for smooth lobes (as alpha^2: mu dmu at a
        // fixed view parameter scales so), so it is interpolated in log-log.
        let log_lost = |j: usize| table.lost_average[j].max(f32::MIN_POSITIVE).ln();
        let lost_average = (log_lost(row) * (1.0 - row_weight) + log_lost(row + 1) * row_weight)
            .exp()
            .min(1.0);
        MultipleScattering {
            alpha: ggx.alpha,
            row,
            row_weight,
            normalisation: if lost_average as f64 > NEGLIGIBLE_LOSS {
                1.0 / (PI * lost_average)
            } else {
                0.0
            },
            lost_average,
        }
    }

    /// True when the lobe adds something.
    #[inline]
    pub fn is_on(&self) -> bool {
        self.normalisation > 0.0
    }

    /// `1 - E(mu)`, what the white single-scattering lobe loses seen from `mu`.
    #[inline]
    fn table_lost(&self, mu: f32) -> f32 {
        let table = table();
        let t = view_parameter(mu, self.alpha);
        table.row_lost(self.row, t) * (1.0 - self.row_weight)
            + table.row_lost(self.row + 1, t) * self.row_weight
    }

    /// `E(mu)`, the white single-scattering lobe's directional albedo, interpolated.
    #[inline]
    pub fn albedo(&self, mu: f32) -> f32 {
        1.0 - self.table_lost(mu)
    }

    /// `E_avg`.
    #[inline]
    pub fn average_albedo(&self) -> f32 {
        1.0 - self.lost_average
    }

    /// The white lobe `f_ms(wo, wi)` for `mu_o`, `mu_i` (both positive; zero otherwise).
    #[inline]
    pub fn eval(&self, mu_o: f32, mu_i: f32) -> f32 {
        if !self.is_on() || mu_o <= 0.0 || mu_i <= 0.0 {
            return 0.0;
        }
        self.table_lost(mu_o) * self.table_lost(mu_i) * self.normalisation
    }

    /// The white lobe's albedo seen from `mu_o`: `1 - E(mu_o)`, or 0 where it is off.
    #[inline]
    pub fn lost(&self, mu_o: f32) -> f32 {
        if !self.is_on() || mu_o <= 0.0 {
            0.0
        } else {
            self.table_lost(mu_o)
        }
    }

    /// The roughness row whose sampling distribution this lobe uses (the nearer one).
    #[inline]
    fn sampling_row(&self) -> usize {
        self.row + usize::from(self.row_weight >= 0.5)
    }

    /// A local direction (about `+z`) drawn from the lobe's sampling density.
    pub fn sample(&self, u: Vec2) -> Vec3 {
        let table = table();
        let row = self.sampling_row();
        let (cdf, density) = (&table.cdf[row], &table.density[row]);
        // The bin whose cumulative range holds u.x, then the point in it where the linear
        // density's integral reaches the rest: d0 x w + (d1 - d0) x^2 w / 2 = rest,
        // solved in the form that stays exact when d1 = d0.
        let b = cdf.partition_point(|&c| c <= u.x).clamp(1, SAMPLING_BINS) - 1;
        let width = 1.0 / SAMPLING_BINS as f32;
        let rest = (u.x - cdf[b]).max(0.0);
        let (d0, d1) = (density[b], density[b + 1]);
        let linear = d0 * width;
        let quadratic = 0.5 * (d1 - d0) * width;
        let discriminant = (linear * linear + 4.0 * quadratic * rest).max(0.0);
        let denominator = linear + discriminant.sqrt();
        let x = if denominator > 0.0 {
            (2.0 * rest / denominator).clamp(0.0, 1.0)
        } else {
            0.5
        };
        let t = (b as f32 + x) * width;
        let mu = view_cosine(t, self.alpha).max(MIN_MU);
        let sin = (1.0 - mu * mu).max(0.0).sqrt();
        let phi = 2.0 * PI * u.y;
        Vec3::new(sin * phi.cos(), sin * phi.sin(), mu)
    }

    /// The solid-angle density of [`MultipleScattering::sample`] at the local `mu_i`:
    /// the density over `t`, times `dt/dmu`, over `2 pi` of azimuth.
    pub fn pdf(&self, mu_i: f32) -> f32 {
        if mu_i <= 0.0 {
            return 0.0;
        }
        let density = &table().density[self.sampling_row()];
        let (b, x) = node_position(view_parameter(mu_i, self.alpha), SAMPLING_BINS + 1);
        let density_t = density[b] * (1.0 - x) + density[b + 1] * x;
        let pdf = density_t * t_per_mu(mu_i, self.alpha) / (2.0 * PI);
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// The colour `F_ms` of the compensation for a Schlick metal of normal reflectance
    /// `f0`: `F_avg^2 E_avg / (1 - F_avg (1 - E_avg))` with `F_avg = F0 + (1 - F0) / 21`.
    #[inline]
    pub fn schlick_colour(&self, f0: Vec3) -> Vec3 {
        let f_avg = (f0 + (Vec3::ONE - f0) / 21.0).clamp(Vec3::ZERO, Vec3::ONE);
        let e = 1.0 - self.lost_average;
        f_avg * f_avg * e / (Vec3::ONE - f_avg * self.lost_average)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_is_deterministic_and_its_distributions_are_proper() {
        // Filled once per process on a metal's first use; the time is printed, not
        // asserted (shared machines are noisy).
        let start = std::time::Instant::now();
        let fresh = LossTable::integrate();
        eprintln!("table filled in {:.3} s", start.elapsed().as_secs_f64());
        let shared = table();
        assert_eq!(
            fresh.lost, shared.lost,
            "the fill depends on the thread schedule"
        );
        assert_eq!(fresh.lost_average, shared.lost_average);
        for j in 0..ROUGHNESS_NODES {
            assert!(
                fresh.lost[j].iter().all(|&l| (0.0..=1.0).contains(&l)),
                "row {j}"
            );
            assert!(fresh.density[j].iter().all(|&d| d >= 0.0 && d.is_finite()));
            let cdf = &fresh.cdf[j];
            assert_eq!((cdf[0], cdf[SAMPLING_BINS]), (0.0, 1.0), "row {j}");
            assert!(
                cdf.windows(2).all(|w| w[0] <= w[1]),
                "row {j}: cdf decreases"
            );
        }
        // Rougher lobes lose more on average.
        assert!(fresh.lost_average.windows(2).all(|w| w[0] <= w[1] + 1e-6));
    }

    #[test]
    fn the_table_matches_a_finer_integration_between_its_nodes() {
        // Off-node roughnesses and angles, against a 256 x 256 grid.
        let mut worst = 0.0f64;
        for r in [0.13f32, 0.37, 0.55, 0.81, 0.97] {
            let ggx = Ggx::from_roughness(r);
            let ms = MultipleScattering::new(ggx);
            for mu in [0.04f32, 0.21, 0.5, 0.77, 0.99] {
                let reference = single_scattering_albedo(ggx, mu, 256);
                let error = (ms.albedo(mu) as f64 - reference).abs();
                worst = worst.max(error);
                assert!(
                    error < 4e-3,
                    "r {r} mu {mu}: {} against {reference}",
                    ms.albedo(mu)
                );
            }
        }
        eprintln!("worst table error {worst:.2e}");
    }

    #[test]
    fn a_white_metal_loses_nothing_once_compensated() {
        // The compensation lobe's albedo from wo, integrated over mu_i, is 1 - E(mu_o).
        for r in [0.2f32, 0.5, 0.8, 1.0] {
            let ms = MultipleScattering::new(Ggx::from_roughness(r));
            for mu_o in [0.1f32, 0.5, 0.9] {
                // 2 pi integral f_ms mu_i dmu_i (isotropic), by a fine midpoint sum.
                let n = 20_000;
                let albedo: f64 = (0..n)
                    .map(|k| {
                        let mu_i = (k as f32 + 0.5) / n as f32;
                        ms.eval(mu_o, mu_i) as f64 * mu_i as f64
                    })
                    .sum::<f64>()
                    * 2.0
                    * std::f64::consts::PI
                    / n as f64;
                let expected = ms.lost(mu_o) as f64;
                assert!(
                    (albedo - expected).abs() < 2e-3,
                    "r {r} mu_o {mu_o}: {albedo} against {expected}"
                );
            }
        }
    }

    #[test]
    fn sampling_follows_the_lobe_and_its_density_integrates_to_one() {
        for r in [0.05f32, 0.1, 0.2, 0.5, 1.0] {
            let ms = MultipleScattering::new(Ggx::from_roughness(r));
            assert!(ms.is_on(), "r {r}");
            // integral pdf dw = 2 pi integral pdf(mu) dmu, summed over t (dmu = dt / t_per_mu)
            // so that the grazing band of a smooth lobe is resolved.
            let n = 200_000;
            let total: f64 = (0..n)
                .map(|k| {
                    let t = (k as f32 + 0.5) / n as f32;
                    let mu = view_cosine(t, ms.alpha);
                    let jacobian = t_per_mu(mu, ms.alpha);
                    if jacobian > 0.0 && jacobian.is_finite() {
                        (ms.pdf(mu) / jacobian) as f64
                    } else {
                        0.0
                    }
                })
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI
                / n as f64;
            assert!((total - 1.0).abs() < 2e-3, "r {r}: integral of pdf {total}");
            // f_ms cos / pdf by the lobe's own samples: its mean is 1 - E(mu_o), and no
            // sample weighs much more than that: the density is linear across bins in
            // which the lobe is not (the first bin of a nearly smooth lobe spans most of
            // the hemisphere), which allows about ten times the mean there.
            for mu_o in [0.02f32, 0.3, 0.9] {
                let side = 400;
                let mut sum = 0.0f64;
                let mut largest = 0.0f32;
                for u in midpoint_grid(side) {
                    let wi = ms.sample(u);
                    let weight = ms.eval(mu_o, wi.z) * wi.z / ms.pdf(wi.z);
                    sum += weight as f64;
                    largest = largest.max(weight);
                }
                let mean = sum / (side * side) as f64;
                let expected = ms.lost(mu_o) as f64;
                eprintln!("r {r} mu_o {mu_o}: mean weight {mean:.5} of {expected:.5}, largest {largest:.5}");
                assert!(
                    (mean - expected).abs() < 2e-3 + 0.01 * expected,
                    "r {r} mu_o {mu_o}: mean weight {mean} against {expected}"
                );
                assert!(
                    largest <= 12.0 * ms.lost(mu_o) + 1e-4,
                    "r {r} mu_o {mu_o}: a weight of {largest} (lost {})",
                    ms.lost(mu_o)
                );
            }
        }
    }

    #[test]
    fn smooth_metals_need_no_compensation_and_rough_ones_do() {
        let smooth = MultipleScattering::new(Ggx::from_roughness(0.0));
        assert!(smooth.lost(0.5) < 1e-3, "{}", smooth.lost(0.5));
        assert!(smooth.eval(0.5, 0.5) < 1e-3);
        let rough = MultipleScattering::new(Ggx::from_roughness(1.0));
        // docs/materials.md: the single-scattering white metal keeps about 0.31 at normal
        // incidence for roughness 1.
        assert!(
            (rough.albedo(1.0) - 0.31).abs() < 0.02,
            "{}",
            rough.albedo(1.0)
        );
        assert!(rough.average_albedo() < 0.6);
        // The colour: white stays white; darker metals lose more to every extra bounce.
        assert!(
            (rough.schlick_colour(Vec3::ONE) - Vec3::ONE)
                .abs()
                .max_element()
                < 1e-6
        );
        let gold = rough.schlick_colour(Vec3::new(1.0, 0.78, 0.34));
        assert!(gold.x > gold.y && gold.y > gold.z && gold.z > 0.0, "{gold}");
        assert!(gold.z < 0.34, "{gold}");
    }
}
