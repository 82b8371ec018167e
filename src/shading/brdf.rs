//! The opaque material lobe, evaluated at every hit for every light (seed 001, "Apply local
//! illumination model"): a Lambertian diffuse lobe plus an energy-normalised Blinn-Phong
//! highlight, as a [`Bsdf`].
//!
//! `f(wo, wi) = albedo / pi + specular * (shininess + 8) / (8 pi) * max(n . h, 0)^shininess`
//! with `h = normalize(wo + wi)`. The `(s + 8) / (8 pi)` factor keeps the highlight's
//! reflected energy roughly independent of the exponent, so `specular` and `albedo` are
//! comparable weights. Directions are sampled by the cosine (the diffuse lobe's shape);
//! the highlight is evaluated, not importance-sampled.

use glam::{Vec2, Vec3};

use std::f32::consts::PI;

use super::bsdf::{sample_cosine_hemisphere, Bsdf, BsdfSample, LobeFlags};

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

/// The opaque lobe at one shading point: Lambert plus a normalised Blinn-Phong highlight
/// about the unit shading normal `n`, which faces the viewer's side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpaqueBsdf {
    pub n: Vec3,
    pub albedo: Vec3,
    pub specular: f32,
    pub shininess: f32,
}

impl OpaqueBsdf {
    /// [`Bsdf::sample`] once its direction `wi` is drawn (`bsdf::sample_cosine_hemisphere`
    /// about `n`), for lanes that draw many directions in loops of their own.
    #[inline(always)]
    pub fn sample_along(&self, wo: Vec3, wi: Vec3) -> Option<BsdfSample> {
        let pdf = self.pdf(wo, wi);
        if pdf <= 0.0 {
            return None;
        }
        // Drawn by the diffuse lobe's cosine, whatever the highlight adds to its value.
        let weight = self.eval(wo, wi) * self.n.dot(wi) / pdf;
        Some(BsdfSample::reflected(
            wi,
            weight,
            pdf,
            LobeFlags::DIFFUSE_REFLECTION,
        ))
    }
}

impl Bsdf for OpaqueBsdf {
    /// Zero when the light is below the surface (`n . wi <= 0`) or the viewer is
    /// (`n . wo <= 0`).
    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let n = self.n;
        if n.dot(wi) <= 0.0 || n.dot(wo) <= 0.0 {
            return Vec3::ZERO;
        }
        let mut f = lambert(self.albedo);
        if self.specular > 0.0 {
            let h = (wo + wi).normalize_or_zero();
            f += Vec3::splat(self.specular * blinn_phong(n, h, self.shininess));
        }
        f
    }

    fn sample(&self, wo: Vec3, _u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if self.n.dot(wo) <= 0.0 {
            return None;
        }
        self.sample_along(wo, sample_cosine_hemisphere(self.n, u))
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let cos_i = self.n.dot(wi);
        if cos_i <= 0.0 || self.n.dot(wo) <= 0.0 {
            return 0.0;
        }
        cos_i / PI
    }

    fn flags(&self) -> LobeFlags {
        if self.specular > 0.0 {
            LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
        } else {
            LobeFlags::DIFFUSE_REFLECTION
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    fn opaque(albedo: Vec3, specular: f32, shininess: f32) -> OpaqueBsdf {
        OpaqueBsdf {
            n: Vec3::Z,
            albedo,
            specular,
            shininess,
        }
    }

    /// Integrates `f cos` over the hemisphere of `wi` with a midpoint rule in
    /// (cos theta, phi), which is uniform in solid angle.
    fn hemisphere_integral(bsdf: &OpaqueBsdf, wo: Vec3) -> Vec3 {
        let (nu, nv) = (400, 400);
        let mut sum = Vec3::ZERO;
        for i in 0..nu {
            let cos_t = (i as f32 + 0.5) / nu as f32;
            let sin_t = (1.0 - cos_t * cos_t).sqrt();
            for j in 0..nv {
                let phi = 2.0 * PI * (j as f32 + 0.5) / nv as f32;
                let wi = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
                sum += bsdf.eval(wo, wi) * bsdf.n.dot(wi);
            }
        }
        sum * (2.0 * PI / (nu * nv) as f32)
    }

    #[test]
    fn lambert_reflects_its_albedo() {
        let albedo = Vec3::new(0.8, 0.5, 0.2);
        let total = hemisphere_integral(&opaque(albedo, 0.0, 1.0), Vec3::Z);
        assert!((total - albedo).abs().max_element() < 1e-3, "{total}");
    }

    #[test]
    fn white_lambert_reflects_at_most_everything_from_any_view() {
        let white = opaque(Vec3::ONE, 0.0, 1.0);
        for wo in [
            Vec3::Z,
            Vec3::new(0.6, 0.0, 0.8),
            Vec3::new(0.0, 0.995, 0.0999),
        ] {
            let total = hemisphere_integral(&white, wo.normalize());
            assert!(total.max_element() <= 1.0 + 1e-3, "{wo}: {total}");
        }
    }

    #[test]
    fn normalised_highlight_does_not_create_energy() {
        // The (s + 8) / (8 pi) normalisation is approximate: at normal view the lobe reflects
        // about 1 (within 10 %) for any exponent, instead of growing with it.
        for &s in &[1.0f32, 16.0, 64.0, 512.0] {
            let total = hemisphere_integral(&opaque(Vec3::ZERO, 1.0, s), Vec3::Z).x;
            assert!(total > 0.5 && total < 1.1, "shininess {s}: {total}");
        }
    }

    #[test]
    fn highlight_peaks_at_the_mirror_direction() {
        let bsdf = opaque(Vec3::ZERO, 1.0, 50.0);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let mirror = Vec3::new(-0.6, 0.0, 0.8);
        let off = Vec3::new(-0.2, 0.4, 0.9).normalize();
        let peak = bsdf.eval(wo, mirror).x;
        let side = bsdf.eval(wo, off).x;
        assert!(peak > 5.0 * side, "peak {peak} side {side}");
        let expected = (50.0 + 8.0) / (8.0 * PI);
        assert!((peak - expected).abs() < 1e-4);
    }

    #[test]
    fn lights_and_viewers_below_the_surface_contribute_nothing() {
        let bsdf = opaque(Vec3::ONE, 1.0, 8.0);
        assert_eq!(bsdf.eval(Vec3::Z, Vec3::new(0.0, 0.6, -0.8)), Vec3::ZERO);
        assert_eq!(bsdf.eval(-Vec3::Z, Vec3::Z), Vec3::ZERO);
        assert_eq!(bsdf.pdf(-Vec3::Z, Vec3::Z), 0.0);
        assert!(bsdf.sample(-Vec3::Z, 0.5, Vec2::splat(0.5)).is_none());
        let diffuse = opaque(Vec3::ONE, 0.0, 8.0);
        let f = diffuse.eval(Vec3::Z, Vec3::new(0.0, 0.6, 0.8));
        assert!((f - Vec3::splat(1.0 / PI)).abs().max_element() < 1e-6);
    }

    #[test]
    fn eval_is_symmetric_in_its_directions() {
        let bsdf = opaque(Vec3::new(0.7, 0.4, 0.1), 0.6, 30.0);
        let mut u = Uniforms(3);
        for _ in 0..1000 {
            let a = sample_cosine_hemisphere(Vec3::Z, u.vec2());
            let b = sample_cosine_hemisphere(Vec3::Z, u.vec2());
            let (ab, ba) = (bsdf.eval(a, b), bsdf.eval(b, a));
            assert!(
                (ab - ba).abs().max_element() <= 1e-5 * ab.max_element(),
                "{ab} {ba}"
            );
        }
    }

    #[test]
    fn sampled_pdf_and_weight_match_pdf_and_eval() {
        let bsdf = OpaqueBsdf {
            n: Vec3::new(0.2, 0.3, 0.9).normalize(),
            albedo: Vec3::new(0.9, 0.5, 0.3),
            specular: 0.4,
            shininess: 20.0,
        };
        let wo = Vec3::new(-0.4, 0.1, 0.9).normalize();
        let mut u = Uniforms(5);
        for _ in 0..1000 {
            let s = bsdf.sample(wo, u.next(), u.vec2()).expect("wo is above");
            assert_eq!((s.flags, s.eta), (LobeFlags::DIFFUSE_REFLECTION, 1.0));
            assert!((s.pdf - bsdf.pdf(wo, s.wi)).abs() <= 1e-6);
            let expected = bsdf.eval(wo, s.wi) * bsdf.n.dot(s.wi) / s.pdf;
            assert!((s.weight - expected).abs().max_element() <= 1e-5);
        }
    }

    #[test]
    fn pdf_integrates_to_one_and_sampling_estimates_the_albedo() {
        let bsdf = opaque(Vec3::new(0.8, 0.5, 0.2), 0.0, 1.0);
        let wo = Vec3::new(0.3, 0.0, 0.95).normalize();
        // The pdf over the hemisphere (midpoint rule, uniform in solid angle).
        let (nu, nv) = (200, 200);
        let mut integral = 0.0;
        for i in 0..nu {
            let cos_t = (i as f32 + 0.5) / nu as f32;
            let sin_t = (1.0 - cos_t * cos_t).sqrt();
            for j in 0..nv {
                let phi = 2.0 * PI * (j as f32 + 0.5) / nv as f32;
                let wi = Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t);
                integral += bsdf.pdf(wo, wi);
            }
        }
        integral *= 2.0 * PI / (nu * nv) as f32;
        assert!((integral - 1.0).abs() < 1e-3, "{integral}");
        // Lambert sampled by its own cosine: every weight is the albedo.
        let mut u = Uniforms(9);
        for _ in 0..100 {
            let s = bsdf.sample(wo, u.next(), u.vec2()).expect("above");
            assert!((s.weight - bsdf.albedo).abs().max_element() < 1e-5);
        }
    }
}
