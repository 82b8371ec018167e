//! Numerical guards shared by the footprint code.
//!
//! Footprints must never emit NaN or infinity, whatever the geometry (grazing hits, degenerate
//! triangles, zero normals, total internal reflection). These helpers turn the few places where
//! a division or normalisation can blow up into a finite fallback, so the formulas themselves
//! stay readable.

use glam::Vec3;

/// Largest magnitude any footprint quantity is allowed to reach. Large enough to never matter
/// for a real scene, small enough that squared lengths of cross products of two such vectors
/// (a differential's area) stay finite in f32.
pub const MAX_MAGNITUDE: f32 = 1.0e9;

/// Smallest |D.N| used as a divisor: grazing hits are treated as this grazing and no more.
pub const MIN_COSINE: f32 = 1.0e-7;

/// `x` clamped to `[-MAX_MAGNITUDE, MAX_MAGNITUDE]`, with NaN mapped to 0.
#[inline(always)]
pub fn finite(x: f32) -> f32 {
    if x.is_nan() {
        0.0
    } else {
        x.clamp(-MAX_MAGNITUDE, MAX_MAGNITUDE)
    }
}

/// [`finite`] for each component of a vector.
#[inline]
pub fn finite3(v: Vec3) -> Vec3 {
    if v.is_finite() && v.abs().max_element() <= MAX_MAGNITUDE {
        v
    } else {
        Vec3::new(finite(v.x), finite(v.y), finite(v.z))
    }
}

/// `v` normalised, or `fallback` when `v` is zero, tiny or not finite.
// Always inlined, and the quotient computed either way, so that a lane loop calling it
// compiles to selects and vectorises (`integrator::lanes::footprints`).
#[inline(always)]
pub fn unit_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let len2 = v.length_squared();
    let unit = v * len2.sqrt().recip();
    if len2.is_finite() && len2 > 1.0e-30 {
        unit
    } else {
        fallback
    }
}

/// A unit ray direction from whatever the caller passed (NaN or zero becomes -Z).
#[inline(always)]
pub fn unit_direction(dir: Vec3) -> Vec3 {
    unit_or(dir, Vec3::NEG_Z)
}

/// A unit surface normal from `n`, falling back to facing the ray (`-dir`) when `n` is zero,
/// tiny or not finite: the footprint is then treated as a head-on hit.
#[inline(always)]
pub fn unit_normal(n: Vec3, dir: Vec3) -> Vec3 {
    unit_or(n, -dir)
}

/// `x` with its magnitude raised to at least `min_abs`, keeping its sign (positive for 0/NaN).
#[inline]
pub fn away_from_zero(x: f32, min_abs: f32) -> f32 {
    if x.is_nan() {
        min_abs
    } else if x.abs() >= min_abs {
        x
    } else if x < 0.0 {
        -min_abs
    } else {
        min_abs
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finite_maps_nan_and_infinity() {
        assert_eq!(finite(f32::NAN), 0.0);
        assert_eq!(finite(f32::INFINITY), MAX_MAGNITUDE);
        assert_eq!(finite(f32::NEG_INFINITY), -MAX_MAGNITUDE);
        assert_eq!(finite(1.5), 1.5);
    }

    #[test]
    fn unit_or_falls_back_on_degenerate_vectors() {
        assert_eq!(unit_or(Vec3::ZERO, Vec3::X), Vec3::X);
        assert_eq!(unit_or(Vec3::splat(f32::NAN), Vec3::Y), Vec3::Y);
        assert!(
            (unit_or(Vec3::new(3.0, 4.0, 0.0), Vec3::X) - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-6
        );
    }

    #[test]
    fn away_from_zero_keeps_sign() {
        assert_eq!(away_from_zero(-1e-9, 1e-7), -1e-7);
        assert_eq!(away_from_zero(0.0, 1e-7), 1e-7);
        assert_eq!(away_from_zero(0.5, 1e-7), 0.5);
        assert_eq!(away_from_zero(f32::NAN, 1e-7), 1e-7);
    }
}
