//! The rough conductor lobe: a metal's microfacet reflection with the GGX distribution
//! ([`super::microfacet`]), the glTF 2.0 metal of its Appendix B.
//!
//! `f(wo, wi) = F(wo . h) D(h) G2(wo, wi) / (4 cos(theta_o) cos(theta_i))` with
//! `h = normalize(wo + wi)` (Walter et al. 2007, eq. 20) and Schlick's Fresnel with the
//! reflectance at normal incidence `F0` (the glTF base colour):
//! `F(c) = F0 + (1 - F0)(1 - c)^5`. Directions are sampled through the visible normals:
//! `h ~ D_wo`, `wi = reflect(wo, h)`, so `pdf = D_wo(h) / (4 wo . h)` (the reflection's
//! Jacobian, Walter et al. 2007, eq. 14) and the weight `f cos / pdf` reduces to
//! `F G2 / G1(wo)`, close to `F` whatever the roughness.
//!
//! That lobe is single-scattering: light that would bounce between microfacets is lost,
//! which darkens rough metals (to 0.31 of white at normal incidence for roughness 1). The
//! lost energy comes back through [`super::multiple_scattering`]'s compensation lobe
//! `F_ms f_ms`, added to `f`; the figures are in docs/materials.md. Sampling then picks the
//! visible normals or the compensation's own directions with probabilities proportional
//! to the two lobes' albedos seen from `wo`,
//! `mean(F(cos_o)) E(cos_o)` and `mean(F_ms) (1 - E(cos_o))`; the density is their
//! mixture and the weight `f cos / pdf` (one-sample multiple importance sampling with the
//! balance heuristic, Veach 1997, section 9.2.4). Roughness near zero is kept finite by
//! [`super::microfacet::MIN_ALPHA`].

use glam::{Vec2, Vec3};

use super::bsdf::{Bsdf, BsdfSample, LobeFlags};
use super::frame::ShadingFrame;
use super::microfacet::Ggx;
use super::multiple_scattering::MultipleScattering;

/// Schlick's Fresnel `F0 + (1 - F0)(1 - cos)^5` for a colour `F0` (glTF 2.0 Appendix B,
/// "fresnel_mix" and "conductor_fresnel").
#[inline]
pub fn schlick_f0(f0: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.abs()).clamp(0.0, 1.0);
    let m2 = m * m;
    f0 + (Vec3::ONE - f0) * (m2 * m2 * m)
}

/// A rough metal about the shading normal `frame.n` (on the viewer's side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor {
    pub frame: ShadingFrame,
    pub ggx: Ggx,
    /// Reflectance at normal incidence.
    pub f0: Vec3,
    /// The multiple-scattering compensation and its colour `F_ms` for `f0`.
    pub multiple: MultipleScattering,
    pub multiple_colour: Vec3,
}

impl RoughConductor {
    /// The conductor about the unit normal `n` with glTF perceptual `roughness` and `f0`.
    pub fn new(n: Vec3, roughness: f32, f0: Vec3) -> RoughConductor {
        let ggx = Ggx::from_roughness(roughness);
        let multiple = MultipleScattering::new(ggx);
        RoughConductor {
            frame: ShadingFrame::from_normal(n),
            ggx,
            f0,
            multiple,
            multiple_colour: multiple.schlick_colour(f0),
        }
    }

    /// The probability of sampling the visible normals rather than the compensation's
    /// cosine lobe from the local `wo` (see the module doc).
    #[inline]
    fn specular_probability(&self, wo: Vec3) -> f32 {
        let lost = self.multiple.lost(wo.z);
        if lost == 0.0 {
            return 1.0;
        }
        let mean = Vec3::splat(1.0 / 3.0);
        let specular = schlick_f0(self.f0, wo.z).dot(mean) * (1.0 - lost);
        let compensation = self.multiple_colour.dot(mean) * lost;
        let total = specular + compensation;
        if total > 0.0 {
            (specular / total).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    /// `f` in the local frame; zero unless both directions are above the surface.
    #[inline]
    pub(crate) fn eval_local(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let scale = self.ggx.d(h) * self.ggx.g2(wo, wi) / (4.0 * wo.z * wi.z);
        schlick_f0(self.f0, wo.dot(h)) * scale
            + self.multiple_colour * self.multiple.eval(wo.z, wi.z)
    }

    /// The sampling density in the local frame.
    #[inline]
    pub(crate) fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p_specular = self.specular_probability(wo);
        let h = (wo + wi).normalize_or_zero();
        let wo_dot_h = wo.dot(h);
        let specular = if h != Vec3::ZERO && wo_dot_h > 0.0 {
            self.ggx.visible_normal_pdf(wo, h) / (4.0 * wo_dot_h)
        } else {
            0.0
        };
        if p_specular >= 1.0 {
            return specular;
        }
        p_specular * specular + (1.0 - p_specular) * self.multiple.pdf(wi.z)
    }

    /// A local sample (`wi`, weight, pdf).
    #[inline]
    pub(crate) fn sample_local(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.specular_probability(wo) {
            self.ggx.sample_reflection(wo, u)?.0
        } else {
            self.multiple.sample(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf_local(wo, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        Some((wi, self.eval_local(wo, wi) * (wi.z / pdf), pdf))
    }
}

impl Bsdf for RoughConductor {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.eval_local(self.frame.to_local(wo), self.frame.to_local(wi))
    }

    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let (wi, weight, pdf) = self.sample_local(self.frame.to_local(wo), u_lobe, u)?;
        let wi = self.frame.to_world(wi);
        Some(BsdfSample::reflected(
            wi,
            weight,
            pdf,
            LobeFlags::GLOSSY_REFLECTION,
        ))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_local(self.frame.to_local(wo), self.frame.to_local(wi))
    }

    fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schlick_goes_from_f0_to_one() {
        let f0 = Vec3::new(0.9, 0.6, 0.3);
        assert_eq!(schlick_f0(f0, 1.0), f0);
        assert_eq!(schlick_f0(f0, 0.0), Vec3::ONE);
        let mid = schlick_f0(f0, 0.5);
        assert!(mid.cmpgt(f0).all() && mid.cmplt(Vec3::ONE).all());
    }

    #[test]
    fn the_peak_sits_at_the_mirror_direction() {
        let metal = RoughConductor::new(Vec3::Z, 0.3, Vec3::ONE);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let mirror = Vec3::new(-0.6, 0.0, 0.8);
        let off = Vec3::new(-0.3, 0.4, 0.866).normalize();
        assert!(metal.eval(wo, mirror).x > 5.0 * metal.eval(wo, off).x);
        assert_eq!(metal.eval(wo, Vec3::new(0.0, 0.6, -0.8)), Vec3::ZERO);
        assert!(metal.sample(-wo, 0.5, Vec2::splat(0.5)).is_none());
    }

    #[test]
    fn a_mirror_like_metal_stays_finite() {
        let metal = RoughConductor::new(Vec3::Z, 0.0, Vec3::splat(0.9));
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let s = metal
            .sample(wo, 0.5, Vec2::new(0.4, 0.7))
            .expect("reflects");
        assert!(
            (s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-2,
            "{}",
            s.wi
        );
        assert!(s.weight.is_finite() && s.pdf.is_finite() && s.pdf > 0.0);
        assert!(s.weight.max_element() <= 1.0 + 1e-4);
        assert!(metal.eval(wo, s.wi).is_finite());
    }
}
