//! Absorption inside a transmissive medium by Beer's law.
//!
//! Seed 004, "Beer's Law": light travelling a distance `d` through an absorbing medium is
//! multiplied by `exp(-sigma d)` per colour channel, where `sigma` (seed 004's
//! `OBJECT_ABSORB`) is the absorption coefficient. Materials specify absorption the way
//! glTF's `KHR_materials_volume` does: the colour `c` left after `attenuation_distance`,
//! from which `sigma = -ln(c) / attenuation_distance` (so `exp(-sigma d) = c^(d / distance)`).

use glam::Vec3;

/// The largest absorption coefficient produced: a channel with no light left (`c = 0`)
/// absorbs this strongly instead of infinitely, so `sigma * 0` stays 0 and never NaN.
pub const MAX_SIGMA: f32 = 1.0e30;

/// Absorption coefficient from "colour `color` remains after travelling `distance`".
///
/// Per channel: `sigma = -ln(c) / distance`; `c >= 1` or an infinite `distance` give 0 (no
/// absorption); `c <= 0` (or `distance <= 0` with `c < 1`) gives the large finite
/// [`MAX_SIGMA`]. NaN inputs give 0.
#[inline]
pub fn sigma_from_attenuation(color: Vec3, distance: f32) -> Vec3 {
    let channel = |c: f32| -> f32 {
        if c.is_nan() || c >= 1.0 || distance.is_nan() || distance == f32::INFINITY {
            return 0.0;
        }
        if c <= 0.0 || distance <= 0.0 {
            return MAX_SIGMA;
        }
        (-c.ln() / distance).min(MAX_SIGMA)
    };
    Vec3::new(channel(color.x), channel(color.y), channel(color.z))
}

/// Fraction of light left after travelling `distance` through a medium with absorption
/// coefficient `sigma`: `exp(-sigma distance)` per channel (seed 004, "Beer's Law").
/// A channel with `sigma == 0` transmits fully at any distance, even an infinite one.
#[inline]
pub fn transmittance(sigma: Vec3, distance: f32) -> Vec3 {
    let distance = distance.max(0.0);
    let channel = |s: f32| -> f32 {
        if s <= 0.0 {
            1.0
        } else {
            (-s * distance).exp()
        }
    };
    Vec3::new(channel(sigma.x), channel(sigma.y), channel(sigma.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attenuation_colour_is_reached_at_the_attenuation_distance() {
        let color = Vec3::new(0.9, 0.5, 0.1);
        let sigma = sigma_from_attenuation(color, 2.0);
        let t = transmittance(sigma, 2.0);
        assert!((t - color).abs().max_element() < 1e-6);
        // Twice as far: the colour squared.
        let t2 = transmittance(sigma, 4.0);
        assert!((t2 - color * color).abs().max_element() < 1e-6);
    }

    #[test]
    fn transmittance_matches_exp_of_known_sigma() {
        // Seed 004's example absorption (8, 2, 0.1) over a distance of 0.25.
        let sigma = Vec3::new(8.0, 2.0, 0.1);
        let t = transmittance(sigma, 0.25);
        let expected = Vec3::new((-2.0f32).exp(), (-0.5f32).exp(), (-0.025f32).exp());
        assert!((t - expected).abs().max_element() < 1e-7);
        assert_eq!(transmittance(sigma, 0.0), Vec3::ONE);
    }

    #[test]
    fn no_absorption_cases() {
        assert_eq!(
            sigma_from_attenuation(Vec3::splat(0.5), f32::INFINITY),
            Vec3::ZERO
        );
        assert_eq!(sigma_from_attenuation(Vec3::ONE, 1.0), Vec3::ZERO);
        assert_eq!(sigma_from_attenuation(Vec3::splat(1.5), 1.0), Vec3::ZERO);
        assert_eq!(transmittance(Vec3::ZERO, f32::INFINITY), Vec3::ONE);
    }

    #[test]
    fn black_attenuation_is_large_but_finite() {
        let sigma = sigma_from_attenuation(Vec3::new(0.0, -1.0, 0.5), 1.0);
        assert_eq!(sigma.x, MAX_SIGMA);
        assert_eq!(sigma.y, MAX_SIGMA);
        assert!(sigma.is_finite());
        let t = transmittance(sigma, 1e-3);
        assert_eq!(t.x, 0.0);
        assert!(t.z > 0.99);
        // Zero distance through a black medium: nothing absorbed, and no NaN.
        assert_eq!(transmittance(sigma, 0.0), Vec3::ONE);
        // A vanishing attenuation distance saturates instead of overflowing.
        assert!(sigma_from_attenuation(Vec3::splat(0.5), 1e-38).is_finite());
    }
}
