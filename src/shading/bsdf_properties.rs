//! Property tests every BSDF must pass, and the numerical tools they share (test builds
//! only).
//!
//! The tools: [`sphere_integral`], a quadrature over the whole sphere with cells that
//! crowd towards both poles (narrow lobes about the normal are resolved), and
//! [`chi_square_directions`], a binned chi-square comparison of sampled directions with
//! the density the sampler claims (the bins' expected shares integrated from that density).

use std::f64::consts::PI;

use glam::{Vec2, Vec3};

use super::bsdf::tests::Uniforms;

/// The direction of the sphere cell coordinates `x` in [0, 1] (`|cos theta| = 1 - x^2`,
/// which puts many cells near the pole), `phi` and the hemisphere's sign.
#[inline]
fn cell_direction(x: f64, phi: f64, sign: f64) -> Vec3 {
    let cos = 1.0 - x * x;
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    Vec3::new(
        (sin * phi.cos()) as f32,
        (sin * phi.sin()) as f32,
        (sign * cos) as f32,
    )
}

/// `integral f(w) dw` over the unit sphere (midpoint rule in `x = sqrt(1 - |cos theta|)`
/// and `phi` on each hemisphere; `dw = 2 x dx dphi`).
pub(crate) fn sphere_integral(f: impl Fn(Vec3) -> f64) -> f64 {
    let (nx, nphi) = (1500usize, 360usize);
    let (dx, dphi) = (1.0 / nx as f64, 2.0 * PI / nphi as f64);
    let mut sum = 0.0;
    for sign in [1.0, -1.0] {
        for i in 0..nx {
            let x = (i as f64 + 0.5) * dx;
            let mut ring = 0.0;
            for j in 0..nphi {
                let phi = (j as f64 + 0.5) * dphi;
                ring += f(cell_direction(x, phi, sign));
            }
            sum += ring * 2.0 * x;
        }
    }
    sum * dx * dphi
}

/// What a chi-square comparison found.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ChiSquareReport {
    /// Pearson's statistic over the bins with enough expected samples.
    pub statistic: f64,
    /// Degrees of freedom (bins used minus one).
    pub dof: usize,
    /// The share of all samples the density claims (its integral; the rest are samples the
    /// sampler refuses).
    pub integral: f64,
}

impl ChiSquareReport {
    /// The rejection threshold: the statistic's mean plus five standard deviations
    /// (`dof + 5 sqrt(2 dof)`, a false alarm well under one in a million for these dofs).
    pub fn threshold(&self) -> f64 {
        self.dof as f64 + 5.0 * (2.0 * self.dof as f64).sqrt()
    }
    pub fn passes(&self) -> bool {
        self.dof >= 3 && self.statistic <= self.threshold()
    }
    /// Statistic over threshold (below 1 passes).
    pub fn normalised(&self) -> f64 {
        self.statistic / self.threshold()
    }
}

/// Bins `sample`'s directions (drawn with `(u_lobe, u)` from a fixed generator; `None` is
/// a refused sample) over the sphere about `+z` and compares the counts with the shares
/// `pdf` gives each bin, refused samples being one more bin with the share `pdf` leaves.
pub(crate) fn chi_square_directions(
    seed: u64,
    sample: impl Fn(f32, Vec2) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
) -> ChiSquareReport {
    const NX: usize = 12;
    const NPHI: usize = 16;
    const SUB: usize = 12;
    const SAMPLES: usize = 300_000;
    let bins = 2 * NX * NPHI;
    let bin_of = |w: Vec3| -> usize {
        let w = w.normalize();
        let hemisphere = usize::from(w.z < 0.0);
        let x = (1.0 - w.z.abs() as f64).max(0.0).sqrt();
        let i = ((x * NX as f64) as usize).min(NX - 1);
        let phi = (w.y as f64).atan2(w.x as f64).rem_euclid(2.0 * PI);
        let j = ((phi / (2.0 * PI) * NPHI as f64) as usize).min(NPHI - 1);
        (hemisphere * NX + i) * NPHI + j
    };
    // Expected shares: the density integrated over each bin with a SUB x SUB midpoint rule.
    let mut expected = vec![0.0f64; bins + 1];
    let (dx, dphi) = (1.0 / (NX * SUB) as f64, 2.0 * PI / (NPHI * SUB) as f64);
    for (hemisphere, sign) in [(0usize, 1.0), (1, -1.0)] {
        for i in 0..NX * SUB {
            let x = (i as f64 + 0.5) * dx;
            for j in 0..NPHI * SUB {
                let phi = (j as f64 + 0.5) * dphi;
                let w = cell_direction(x, phi, sign);
                let bin = (hemisphere * NX + i / SUB) * NPHI + j / SUB;
                expected[bin] += pdf(w) as f64 * 2.0 * x * dx * dphi;
            }
        }
    }
    let integral: f64 = expected[..bins].iter().sum();
    expected[bins] = (1.0 - integral).max(0.0);
    let mut observed = vec![0.0f64; bins + 1];
    let mut u = Uniforms(seed);
    for _ in 0..SAMPLES {
        let u_lobe = u.next();
        match sample(u_lobe, u.vec2()) {
            Some(w) => observed[bin_of(w)] += 1.0,
            None => observed[bins] += 1.0,
        }
    }
    // Bins expecting fewer than 5 samples are pooled (Pearson's approximation needs
    // enough per bin).
    let (mut statistic, mut used) = (0.0, 0usize);
    let (mut pooled_expected, mut pooled_observed) = (0.0, 0.0);
    for (e, o) in expected.iter().zip(&observed) {
        let e = e * SAMPLES as f64;
        if e < 5.0 {
            pooled_expected += e;
            pooled_observed += o;
        } else {
            statistic += (o - e) * (o - e) / e;
            used += 1;
        }
    }
    if pooled_expected >= 5.0 {
        statistic += (pooled_observed - pooled_expected).powi(2) / pooled_expected;
        used += 1;
    } else if pooled_observed > 10.0 + 10.0 * pooled_expected {
        // Samples where the density says there are (almost) none.
        statistic = f64::INFINITY;
    }
    ChiSquareReport {
        statistic,
        dof: used.saturating_sub(1),
        integral,
    }
}

/// A random unit vector, uniform on the sphere.
pub(crate) fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}
