//! How much light a smooth dielectric boundary reflects; the rest is transmitted.
//!
//! Seed 004 ("Fresnel", "Total Internal Reflection", "Putting it All Together"): at every
//! dielectric hit the reflected ray is weighted by the Fresnel reflectance `R` and the
//! refracted ray by `T = 1 - R`, and when leaving a denser medium beyond the critical angle
//! `R = 1`. Two ways of computing `R` are offered, selected by [`FresnelMode`]:
//! - [`fresnel_dielectric`]: the exact Fresnel equations for unpolarised light, the average
//!   of the s- and p-polarised reflectances
//!   `r_s = (n1 cos_i - n2 cos_t) / (n1 cos_i + n2 cos_t)`,
//!   `r_p = (n2 cos_i - n1 cos_t) / (n2 cos_i + n1 cos_t)`, `R = (r_s^2 + r_p^2) / 2`,
//!   with `cos_t` from Snell's law (seed 001, "Refraction Direction (2)").
//! - [`fresnel_schlick`]: seed 004's Schlick approximation `R = R0 + (1 - R0)(1 - cos)^5`,
//!   `R0 = ((n1 - n2) / (n1 + n2))^2`, where `cos` is the cosine on the *less dense* side
//!   (the transmitted cosine when `n1 > n2`), and `R = 1` under total internal reflection.
//!
//! Both return only `R`, clamped to `[0, 1]`; the transmitted weight is `1 - R` by
//! construction (energy conservation at a non-absorbing boundary).
//!
//! Both take `eta = n_incident / n_transmitted` for the ray at hand, exactly like
//! [`crate::shading::refract`]; the sign of `cos_i` is ignored, so the cosine may be taken
//! against either side's normal. [`DielectricBoundary`] works out which side a ray arrives
//! from and the matching `eta`, normal and cosine, so the caller does that in one place.

use glam::Vec3;

use crate::scene::FresnelMode;

/// Fresnel reflectance of a smooth dielectric boundary with the chosen formula.
/// `cos_i`: cosine of the angle of incidence (sign ignored); `eta = n_incident / n_transmitted`.
#[inline]
pub fn fresnel(mode: FresnelMode, cos_i: f32, eta: f32) -> f32 {
    match mode {
        FresnelMode::Exact => fresnel_dielectric(cos_i, eta),
        FresnelMode::Schlick => fresnel_schlick(cos_i, eta),
    }
}

/// Exact unpolarised Fresnel reflectance (average of the s and p polarisations).
///
/// `cos_i` is the cosine of the angle between the incident ray and the normal (its sign is
/// ignored); `eta = n_incident / n_transmitted`. Returns `R` in `[0, 1]`, `1` under total
/// internal reflection; the transmitted fraction is `1 - R`. A non-finite or non-positive
/// `eta` is treated as a perfect mirror (`1`).
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    if !(eta > 0.0 && eta.is_finite()) {
        return 1.0;
    }
    let cos_i = cos_i.abs().min(1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    // The Fresnel amplitude ratios with n1 = eta and n2 = 1 (only the ratio matters).
    let s_den = eta * cos_i + cos_t;
    let p_den = cos_i + eta * cos_t;
    if s_den <= 0.0 || p_den <= 0.0 {
        // Exactly grazing into an index-matched medium: no light enters.
        return 1.0;
    }
    let r_s = (eta * cos_i - cos_t) / s_den;
    let r_p = (cos_i - eta * cos_t) / p_den;
    (0.5 * (r_s * r_s + r_p * r_p)).clamp(0.0, 1.0)
}

/// Schlick's approximation of the Fresnel reflectance with total internal reflection
/// (seed 004, "Fresnel": `FresnelReflectAmount` without the object-reflectivity blend).
///
/// Same arguments and result range as [`fresnel_dielectric`]; the transmitted fraction is
/// `1 - R`.
#[inline]
pub fn fresnel_schlick(cos_i: f32, eta: f32) -> f32 {
    if !(eta > 0.0 && eta.is_finite()) {
        return 1.0;
    }
    let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let mut cos = cos_i.abs().min(1.0);
    if eta > 1.0 {
        // Leaving the denser medium: Schlick is evaluated with the transmitted angle.
        let sin2_t = eta * eta * (1.0 - cos * cos).max(0.0);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        cos = (1.0 - sin2_t).sqrt();
    }
    let x = 1.0 - cos;
    let x2 = x * x;
    (r0 + (1.0 - r0) * x2 * x2 * x).clamp(0.0, 1.0)
}

/// A ray meeting the boundary of a dielectric object, resolved into the quantities
/// [`fresnel`] and [`crate::shading::refract`] expect.
///
/// One rule decides the side: the geometric normal. Whether the ray enters or leaves, hence
/// `eta`, total internal reflection and (in the integrator) the medium a refracted ray
/// travels in, all follow it. A smooth-shading normal only tilts the boundary the ray
/// refracts through, and only while it faces the incident ray: at silhouettes of coarse
/// meshes an interpolated normal can face away from a ray that geometrically arrives from
/// outside, and taking the side from it would treat that ray as leaving the glass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricBoundary {
    /// True when the ray arrives from outside the object (against the outward geometric
    /// normal).
    pub entering: bool,
    /// The normal the ray refracts and reflects about, facing the incident ray (the side
    /// reflections leave from; refractions leave from the other side).
    pub normal: Vec3,
    /// `n_incident / n_transmitted` for this ray.
    pub eta: f32,
    /// Cosine of the angle of incidence against `normal`, in `[0, 1]`.
    pub cos_i: f32,
}

impl DielectricBoundary {
    /// Resolves the boundary for the unit incident direction `d`, the unit
    /// `outward_normal` of the object's surface and the object's index of refraction `ior`
    /// (the outside has index 1, as in `crate::scene::Material::ior`).
    #[inline]
    pub fn new(d: Vec3, outward_normal: Vec3, ior: f32) -> Self {
        Self::with_shading_normal(d, outward_normal, outward_normal, ior)
    }

    /// As [`DielectricBoundary::new`] for a surface with a shading normal: the unit
    /// `outward_geometric` normal decides the side; `outward_shading` (the same side's
    /// shading normal) is the boundary's normal when it faces the incident ray, the
    /// geometric normal otherwise.
    #[inline]
    pub fn with_shading_normal(
        d: Vec3,
        outward_geometric: Vec3,
        outward_shading: Vec3,
        ior: f32,
    ) -> Self {
        // The same test as `SurfaceHit::is_front_face`: a ray exactly in the plane leaves.
        let entering = d.dot(outward_geometric) < 0.0;
        let (geometric, shading, eta) = if entering {
            (outward_geometric, outward_shading, 1.0 / ior)
        } else {
            (-outward_geometric, -outward_shading, ior)
        };
        let normal = if d.dot(shading) < 0.0 {
            shading
        } else {
            geometric
        };
        DielectricBoundary {
            entering,
            normal,
            eta,
            cos_i: d.dot(normal).abs().min(1.0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Transmittance computed independently from the Fresnel transmission amplitudes
    /// `t_s = 2 n1 cos_i / (n1 cos_i + n2 cos_t)`, `t_p = 2 n1 cos_i / (n2 cos_i + n1 cos_t)`
    /// and the beam-area/speed factor `n2 cos_t / (n1 cos_i)`.
    fn transmittance_from_amplitudes(cos_i: f32, n1: f64, n2: f64) -> f64 {
        let cos_i = cos_i as f64;
        let sin2_t = (n1 / n2).powi(2) * (1.0 - cos_i * cos_i);
        if sin2_t >= 1.0 {
            return 0.0;
        }
        let cos_t = (1.0 - sin2_t).sqrt();
        let t_s = 2.0 * n1 * cos_i / (n1 * cos_i + n2 * cos_t);
        let t_p = 2.0 * n1 * cos_i / (n2 * cos_i + n1 * cos_t);
        let factor = n2 * cos_t / (n1 * cos_i);
        0.5 * factor * (t_s * t_s + t_p * t_p)
    }

    #[test]
    fn reflectance_plus_transmittance_is_one() {
        for &(n1, n2) in &[(1.0f32, 1.5f32), (1.5, 1.0), (1.0, 2.4), (1.33, 1.0)] {
            for k in 1..=50 {
                let cos_i = k as f32 / 50.0;
                let r = fresnel_dielectric(cos_i, n1 / n2) as f64;
                let t = transmittance_from_amplitudes(cos_i, n1 as f64, n2 as f64);
                assert!(
                    (r + t - 1.0).abs() < 1e-5,
                    "n1 {n1} n2 {n2} cos {cos_i}: R {r} T {t}"
                );
            }
        }
    }

    #[test]
    fn normal_incidence_matches_r0() {
        for &(n1, n2) in &[(1.0f32, 1.5f32), (1.5, 1.0), (1.0, 1.33), (1.0, 2.4)] {
            let expected = ((n1 - n2) / (n1 + n2)).powi(2);
            assert!((fresnel_dielectric(1.0, n1 / n2) - expected).abs() < 1e-6);
            assert!((fresnel_schlick(1.0, n1 / n2) - expected).abs() < 1e-6);
        }
        // Glass: 4 %.
        assert!((fresnel_dielectric(1.0, 1.0 / 1.5) - 0.04).abs() < 1e-6);
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let eta: f32 = 1.5; // glass to air
        let cos_critical = (1.0 - 1.0 / (eta * eta)).sqrt();
        for &cos_i in &[0.0f32, 0.1, 0.5, cos_critical - 1e-3] {
            assert_eq!(fresnel_dielectric(cos_i, eta), 1.0);
            assert_eq!(fresnel_schlick(cos_i, eta), 1.0);
        }
        assert!(fresnel_dielectric(cos_critical + 1e-2, eta) < 1.0);
        assert!(fresnel_schlick(cos_critical + 1e-2, eta) < 1.0);
    }

    #[test]
    fn grazing_incidence_reflects_everything() {
        assert!((fresnel_dielectric(0.0, 1.0 / 1.5) - 1.0).abs() < 1e-6);
        assert!((fresnel_schlick(0.0, 1.0 / 1.5) - 1.0).abs() < 1e-6);
        // Index-matched: nothing reflects except exactly at grazing.
        assert_eq!(fresnel_dielectric(0.7, 1.0), 0.0);
    }

    #[test]
    fn reflectance_is_the_same_in_both_directions_along_a_light_path() {
        // Reciprocity: entering at theta_i and leaving at the matching theta_t reflect alike.
        let (n1, n2) = (1.0f32, 1.5f32);
        let cos_i: f32 = 0.6;
        let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).sqrt();
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let entering = fresnel_dielectric(cos_i, n1 / n2);
        let leaving = fresnel_dielectric(cos_t, n2 / n1);
        assert!((entering - leaving).abs() < 1e-5);
    }

    #[test]
    fn schlick_is_close_to_exact_for_glass() {
        let mut worst: f32 = 0.0;
        for &eta in &[1.0f32 / 1.5, 1.5] {
            for k in 0..=1000 {
                let cos_i = k as f32 / 1000.0;
                let diff = (fresnel_schlick(cos_i, eta) - fresnel_dielectric(cos_i, eta)).abs();
                worst = worst.max(diff);
            }
        }
        assert!(worst < 0.05, "Schlick differs from exact by {worst}");
    }

    #[test]
    fn mode_selects_the_formula() {
        let (c, e) = (0.3, 1.0 / 1.5);
        assert_eq!(fresnel(FresnelMode::Exact, c, e), fresnel_dielectric(c, e));
        assert_eq!(fresnel(FresnelMode::Schlick, c, e), fresnel_schlick(c, e));
    }

    #[test]
    fn boundary_resolves_entering_and_leaving() {
        let n = Vec3::Y;
        let d = Vec3::new(0.6, -0.8, 0.0);
        let b = DielectricBoundary::new(d, n, 1.5);
        assert!(b.entering);
        assert_eq!(b.normal, n);
        assert!((b.eta - 1.0 / 1.5).abs() < 1e-7);
        assert!((b.cos_i - 0.8).abs() < 1e-6);

        let up = Vec3::new(0.6, 0.8, 0.0);
        let b = DielectricBoundary::new(up, n, 1.5);
        assert!(!b.entering);
        assert_eq!(b.normal, -n);
        assert_eq!(b.eta, 1.5);
        assert!((b.cos_i - 0.8).abs() < 1e-6);
    }

    #[test]
    fn the_geometric_normal_decides_the_side() {
        let ng = Vec3::Y;
        // A ray arriving from above (outside) at a grazing angle, with a shading normal
        // tilted so far that it faces away from the ray.
        let d = Vec3::new(0.99, -0.141_067, 0.0).normalize();
        let ns = Vec3::new(0.8, 0.6, 0.0);
        assert!(d.dot(ns) > 0.0);
        let b = DielectricBoundary::with_shading_normal(d, ng, ns, 1.5);
        assert!(b.entering, "the ray arrives from outside");
        assert!((b.eta - 1.0 / 1.5).abs() < 1e-7);
        assert_eq!(
            b.normal, ng,
            "an averted shading normal falls back to the geometric"
        );
        assert!(
            crate::shading::refract(d, b.normal, b.eta).is_some(),
            "no TIR from air"
        );

        // A shading normal that faces the ray tilts the boundary, and the side stays.
        let ns = Vec3::new(-0.3, 0.95, 0.0).normalize();
        let b = DielectricBoundary::with_shading_normal(d, ng, ns, 1.5);
        assert!(b.entering);
        assert_eq!(b.normal, ns);
        assert!((b.cos_i - (-d.dot(ns))).abs() < 1e-6);

        // From inside: leaving, whatever the shading normal says.
        let up = Vec3::new(0.99, 0.141_067, 0.0).normalize();
        let b = DielectricBoundary::with_shading_normal(up, ng, Vec3::new(-0.8, 0.6, 0.0), 1.5);
        assert!(!b.entering);
        assert_eq!(b.eta, 1.5);
        assert_eq!(b.normal, -ng);
    }

    proptest! {
        #[test]
        fn fresnel_terms_lie_in_unit_interval_and_sum_to_one(
            cos_i in -1.0f32..=1.0, eta in 0.05f32..20.0,
        ) {
            for r in [fresnel_dielectric(cos_i, eta), fresnel_schlick(cos_i, eta)] {
                prop_assert!((0.0..=1.0).contains(&r), "R = {}", r);
                let t = 1.0 - r;
                prop_assert!((0.0..=1.0).contains(&t));
                prop_assert_eq!(r + t, 1.0);
            }
            // Exact R agrees with the independent transmittance formula, to f32 accuracy:
            // near the critical angle R is ill-conditioned (dR/dcos_t grows like
            // 1/cos_t), so the tolerance follows the conditioning.
            let c = cos_i.abs();
            prop_assume!(c > 1e-3);
            let r = fresnel_dielectric(cos_i, eta) as f64;
            let t = transmittance_from_amplitudes(c, eta as f64, 1.0);
            let sin2_t = (eta as f64).powi(2) * (1.0 - (c as f64).powi(2));
            let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
            let tolerance = 1e-5 + 1e-6 / (cos_t * cos_t).max(1e-12);
            prop_assert!((r + t - 1.0).abs() < tolerance, "R {} T {} cos_t {}", r, t, cos_t);
        }
    }
}
