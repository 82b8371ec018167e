//! Footprints through rough bounces: how a ray cone widens when a surface scatters it into a
//! sampled direction rather than a mirror one (seed 000, "BSDF scattering").
//!
//! The seed's heuristic needs only the BSDF's value: a diffuse surface spreads the cone by a
//! constant `s_max = 0.25` radians, and a glossier one by that angle scaled by the ratio of
//! the ideal diffuse value `1/pi` to the BSDF value `F_s` in the sampled direction:
//!
//! `alpha' = alpha + s_max min(1, 1 / (pi F_s))`
//!
//! so directions near a glossy peak (large `F_s`) widen little and those away from it as
//! much as diffuse ones. The distance metric has no spread of its own to widen and stays as
//! it is; ray differentials are not widened either: at the next hit after a non-specular
//! bounce they are replaced by the camera's footprint at that point
//! (`crate::camera::Camera::approximate_dp_dxy`), as pbrt-v4 does for its non-specular
//! bounces.
//!
//! A scattering event inside fog (the path tracer's medium vertices) uses the same rule
//! with the phase function's value in place of the BSDF's, as seed 000 suggests for
//! volumes ("substituting the phase function value for the BSDF"): an isotropic phase
//! function, `1 / (4 pi)`, is below the diffuse `1 / pi` and spreads by the full `s_max`;
//! a forward peak spreads less. Such a vertex has no surface to transfer the footprint
//! onto, so [`Footprint::advance`] only propagates it to the scattering distance.

use super::Footprint;

/// The spread angle a diffuse bounce adds, in radians (seed 000's `s_max`).
pub const DIFFUSE_SPREAD: f32 = 0.25;

/// The angle a non-delta bounce adds to a cone, for the BSDF value `bsdf_value` (a scalar:
/// the luminance or the largest channel of `f(wo, wi)`) in the sampled direction:
/// `s_max min(1, 1 / (pi F_s))`. A zero, negative or NaN value counts as diffuse.
#[inline]
pub fn bsdf_spread_angle(bsdf_value: f32) -> f32 {
    let scaled = std::f32::consts::PI * bsdf_value;
    if scaled.is_nan() || scaled <= 1.0 {
        DIFFUSE_SPREAD
    } else {
        DIFFUSE_SPREAD / scaled
    }
}

impl Footprint {
    /// The footprint of a ray scattered by a non-delta lobe, after [`Footprint::transfer`]
    /// to the hit: cones keep their width and widen their angle by `spread`
    /// ([`bsdf_spread_angle`]); the two-cone envelope widens both cones and stops ignoring
    /// its second cone (any bounce does). The distance metric and differentials stay as
    /// they are (see the module doc).
    #[inline]
    pub fn scatter(&self, spread: f32) -> Footprint {
        let spread = super::robust::finite(spread).max(0.0);
        match self {
            Footprint::Mip0 | Footprint::Distance(_) | Footprint::Differential(_) => *self,
            Footprint::Cone1(c) => Footprint::Cone1(super::RayCone::new(c.width, c.angle + spread)),
            Footprint::Cone(e) => Footprint::Cone(super::ConeEnvelope {
                primary: super::RayCone::new(e.primary.width, e.primary.angle + spread),
                secondary: super::RayCone::new(e.secondary.width, e.secondary.angle + spread),
                secondary_ignored: false,
            }),
        }
    }
}

impl Footprint {
    /// The footprint carried `distance` along the ray with no surface there (a scattering
    /// event inside fog): cones and the distance metric propagate (seed 000,
    /// `w' = w + alpha d`); differentials stay as they are, to be replaced by the camera's
    /// footprint at the next hit like after any non-delta bounce.
    #[inline]
    pub fn advance(&self, distance: f32) -> Footprint {
        match self {
            Footprint::Mip0 | Footprint::Differential(_) => *self,
            Footprint::Distance(f) => Footprint::Distance(f.propagate(distance)),
            Footprint::Cone1(c) => Footprint::Cone1(c.propagate(distance)),
            Footprint::Cone(e) => Footprint::Cone(e.propagate(distance)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::footprint::{ConeEnvelope, RayCone};
    use std::f32::consts::PI;

    #[test]
    fn diffuse_surfaces_spread_by_s_max() {
        // Lambert with any albedo up to 1 has F_s <= 1/pi: the full s_max.
        assert_eq!(bsdf_spread_angle(1.0 / PI), DIFFUSE_SPREAD);
        assert_eq!(bsdf_spread_angle(0.5 / PI), DIFFUSE_SPREAD);
        assert_eq!(bsdf_spread_angle(0.0), DIFFUSE_SPREAD);
        assert_eq!(bsdf_spread_angle(f32::NAN), DIFFUSE_SPREAD);
    }

    #[test]
    fn glossy_peaks_spread_by_the_ratio_to_diffuse() {
        // F_s = 10 / pi: one tenth of s_max.
        let spread = bsdf_spread_angle(10.0 / PI);
        assert!((spread - 0.025).abs() < 1e-7, "{spread}");
        // Monotone: a sharper peak spreads less.
        assert!(bsdf_spread_angle(100.0) < bsdf_spread_angle(10.0));
    }

    #[test]
    fn cones_widen_their_angle_and_keep_their_width() {
        let cone = Footprint::Cone1(RayCone::new(0.02, 0.001));
        let Footprint::Cone1(out) = cone.scatter(0.25) else {
            panic!("strategy changed")
        };
        assert_eq!(out.width, 0.02);
        assert!((out.angle - 0.251).abs() < 1e-7);
        let envelope = Footprint::Cone(ConeEnvelope::new(
            RayCone::new(0.01, 0.001),
            RayCone::new(0.03, -0.002),
            true,
        ));
        let Footprint::Cone(out) = envelope.scatter(0.1) else {
            panic!("strategy changed")
        };
        assert!(!out.secondary_ignored);
        assert!((out.primary.angle - 0.101).abs() < 1e-7);
        assert!((out.secondary.angle - 0.098).abs() < 1e-7);
        assert_eq!(Footprint::Mip0.scatter(0.25), Footprint::Mip0);
    }

    #[test]
    fn a_medium_vertex_spreads_by_the_phase_value() {
        use crate::medium::HenyeyGreenstein;
        // Isotropic scattering, 1 / (4 pi), is below diffuse: the full s_max.
        let iso = HenyeyGreenstein::new(0.0).eval_cos(0.3);
        assert_eq!(bsdf_spread_angle(iso), DIFFUSE_SPREAD);
        // A forward peak, g = 0.9, straight ahead: p = 0.19 / (4 pi 0.001) ~ 15.1, so the
        // spread is s_max / (pi p), about a fiftieth of s_max.
        let peak = HenyeyGreenstein::new(0.9).eval_cos(1.0);
        let expected = DIFFUSE_SPREAD / (PI * peak);
        assert!((bsdf_spread_angle(peak) - expected).abs() < 1e-7);
        assert!(bsdf_spread_angle(peak) < 0.025 * DIFFUSE_SPREAD);
        // The cone first travels to the scattering point: w' = w + alpha d.
        let cone = Footprint::Cone1(RayCone::new(0.01, 0.002));
        let Footprint::Cone1(moved) = cone.advance(5.0).scatter(bsdf_spread_angle(iso)) else {
            panic!("strategy changed")
        };
        assert!((moved.width - 0.02).abs() < 1e-7, "{}", moved.width);
        assert!((moved.angle - 0.252).abs() < 1e-7);
    }
}
