//! The local illumination model evaluated at every hit for every light (seed 001,
//! "Apply local illumination model"): a Lambertian diffuse lobe plus an energy-normalised
//! Blinn-Phong highlight.
//!
//! `f(wo, wi) = albedo / pi + specular * (shininess + 8) / (8 pi) * max(n . h, 0)^shininess`
//! with `h = normalize(wo + wi)`. The `(s + 8) / (8 pi)` factor keeps the highlight's
//! reflected energy roughly independent of the exponent, so `specular` and `albedo` are
//! comparable weights. The integrator multiplies the returned `f * cos` by the light's
//! irradiance scale ([`crate::shading::LightSample::radiance_scale`]) and its shadow-ray
//! visibility.

use glam::Vec3;

use std::f32::consts::PI;

/// Lambertian BRDF value `albedo / pi`.
#[inline]
pub fn lambert(albedo: Vec3) -> Vec3 {
    albedo * (1.0 / PI)
}

/// Normalised Blinn-Phong highlight `(s + 8) / (8 pi) * max(n . h, 0)^s` for unit `n` and
/// unit half vector `h`.
#[inline]
pub fn blinn_phong(n: Vec3, h: Vec3, shininess: f32) -> f32 {
    let s = shininess.max(0.0);
    let cos_h = n.dot(h).max(0.0);
    (s + 8.0) / (8.0 * PI) * cos_h.powf(s)
}

/// BRDF times the cosine at the surface: `(albedo / pi + specular * blinn_phong) * (n . wi)`.
///
/// `n` is the unit shading normal on the viewer's side, `wo` the unit direction towards the
/// viewer, `wi` the unit direction towards the light. Zero when the light is below the
/// surface (`n . wi <= 0`) or the viewer is (`n . wo <= 0`).
#[inline]
pub fn eval_surface(
    albedo: Vec3,
    specular: f32,
    shininess: f32,
    n: Vec3,
    wo: Vec3,
    wi: Vec3,
) -> Vec3 {
    let cos_i = n.dot(wi);
    if cos_i <= 0.0 || n.dot(wo) <= 0.0 {
        return Vec3::ZERO;
    }
    let mut f = lambert(albedo);
    if specular > 0.0 {
        let h = (wo + wi).normalize_or_zero();
        f += Vec3::splat(specular * blinn_phong(n, h, shininess));
    }
    f * cos_i
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Integrates `eval_surface` over the hemisphere of `wi` with a midpoint rule in
    /// (cos theta, phi), which is uniform in solid angle.
    fn hemisphere_integral(albedo: Vec3, specular: f32, shininess: f32, wo: Vec3) -> Vec3 {
        let n = Vec3::Z;
        let (nu, nv) = (400, 400);
        let mut sum = Vec3::ZERO;
        for i in 0..nu {
            let cos_t = (i as f32 + 0.5) / nu as f32;
            let sin_t = (1.0 - cos_t * cos_t).sqrt();
            for j in 0..nv {
                let phi = 2.0 * PI * (j as f32 + 0.5) / nv as f32;
                let wi = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
                sum += eval_surface(albedo, specular, shininess, n, wo, wi);
            }
        }
        sum * (2.0 * PI / (nu * nv) as f32)
    }

    #[test]
    fn lambert_reflects_its_albedo() {
        let albedo = Vec3::new(0.8, 0.5, 0.2);
        let total = hemisphere_integral(albedo, 0.0, 1.0, Vec3::Z);
        assert!((total - albedo).abs().max_element() < 1e-3, "{total}");
    }

    #[test]
    fn normalised_highlight_does_not_create_energy() {
        // The (s + 8) / (8 pi) normalisation is approximate: at normal view the lobe reflects
        // about 1 (within 10 %) for any exponent, instead of growing with it.
        for &s in &[1.0f32, 16.0, 64.0, 512.0] {
            let total = hemisphere_integral(Vec3::ZERO, 1.0, s, Vec3::Z).x;
            assert!(total > 0.5 && total < 1.1, "shininess {s}: {total}");
        }
    }

    #[test]
    fn highlight_peaks_at_the_mirror_direction() {
        let n = Vec3::Z;
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let mirror = Vec3::new(-0.6, 0.0, 0.8);
        let off = Vec3::new(-0.2, 0.4, 0.9).normalize();
        let peak = eval_surface(Vec3::ZERO, 1.0, 50.0, n, wo, mirror).x;
        let side = eval_surface(Vec3::ZERO, 1.0, 50.0, n, wo, off).x;
        assert!(peak > 5.0 * side, "peak {peak} side {side}");
        let expected = (50.0 + 8.0) / (8.0 * PI) * 0.8;
        assert!((peak - expected).abs() < 1e-4);
    }

    #[test]
    fn lights_and_viewers_below_the_surface_contribute_nothing() {
        let n = Vec3::Z;
        let a = Vec3::ONE;
        assert_eq!(
            eval_surface(a, 1.0, 8.0, n, Vec3::Z, Vec3::new(0.0, 0.6, -0.8)),
            Vec3::ZERO
        );
        assert_eq!(eval_surface(a, 1.0, 8.0, n, -Vec3::Z, Vec3::Z), Vec3::ZERO);
        let c = eval_surface(a, 0.0, 8.0, n, Vec3::Z, Vec3::new(0.0, 0.6, 0.8));
        assert!((c - Vec3::splat(0.8 / PI)).abs().max_element() < 1e-6);
    }
}
