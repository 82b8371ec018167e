//! The opaque lobe of the glTF 2.0 metallic-roughness material (its Appendix B, "BRDF
//! Implementation"): a mix by `metallic` of a GGX metal and a GGX-coated diffuse
//! dielectric.
//!
//! With `h = normalize(wo + wi)`, `c = wo . h` and the GGX specular term
//! `S = D(h) G2(wo, wi) / (4 cos_o cos_i)` ([`super::microfacet`]):
//! - metal: `F_m(c) S` with `F_m(c) = base + (1 - base)(1 - c)^5` (Schlick, `F0` = the
//!   base colour; `conductor_fresnel` in the specification);
//! - dielectric: `(1 - F_d(cos_o))(1 - F_d(cos_i)) base / pi + F_d(c) S` with
//!   `F_d(x) = 0.04 + 0.96 (1 - x)^5` (`fresnel_mix` with ior 1.5);
//! - `f = (1 - metallic) dielectric + metallic metal`.
//!
//! The metal also gets the energy its single-scattering lobe loses between microfacets
//! back, as [`super::multiple_scattering`]'s compensation `F_ms(base) f_ms` (as
//! [`super::conductor`] does): a white metal of any roughness reflects everything.
//!
//! The diffuse weight departs from the specification's example, which weights the diffuse
//! term by `1 - F_d(c)` at the half vector: that lets a white dielectric reflect more than
//! it receives at grazing views (an albedo of 1.20 at 75 degrees and roughness 0.05,
//! measured by `bsdf_properties`' furnace), because the specular layer reflects `F_d(cos_o)`
//! of the light while the diffuse part under it keeps almost all of it. Weighting by what
//! the layer transmits on the way in and on the way out, `(1 - F_d(cos_i))(1 - F_d(cos_o))`
//! (Shirley et al. 1997, "A Practitioners' Assessment of Light Reflection Models", the
//! coupled diffuse term's Fresnel factors), keeps the lobe reciprocal and its albedo at most
//! 1; at normal incidence the two differ by 4 % of the diffuse term.
//!
//! Sampling picks the specular lobe (visible-normal sampling, [`super::conductor`]'s
//! density) or the diffuse one (cosine) with probabilities proportional to their
//! approximate albedos seen from `wo`: `(1 - metallic) F_d(cos_o) + metallic mean(F_m(cos_o))`
//! for the specular, `(1 - metallic)(1 - F_d(cos_o)) mean(base)` for the diffuse, and
//! `metallic mean(F_ms) (1 - E(cos_o))` for the metal's compensation (sampled by its own
//! density). The density is the mixture
//! `p_s pdf_specular + p_d cos_i / pi + p_ms pdf_ms` whichever lobe drew the sample, and the weight `f cos_i / pdf` (one-sample multiple importance sampling
//! with the balance heuristic, Veach 1997, section 9.2.4).

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::bsdf::{sample_cosine_hemisphere, Bsdf, BsdfSample, LobeFlags};
use super::conductor::schlick_f0;
use super::frame::ShadingFrame;
use super::microfacet::Ggx;
use super::multiple_scattering::MultipleScattering;

/// The glTF dielectric's reflectance at normal incidence (ior 1.5: `((1.5 - 1) / 2.5)^2`).
pub const DIELECTRIC_F0: f32 = 0.04;

/// The metallic-roughness lobe about the shading normal `frame.n` (viewer's side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetallicRoughnessBsdf {
    pub frame: ShadingFrame,
    pub ggx: Ggx,
    pub base_color: Vec3,
    pub metallic: f32,
    /// The metal's multiple-scattering compensation ([`MultipleScattering::NONE`] when
    /// `metallic` is 0) and its colour `F_ms` for the base colour.
    pub multiple: MultipleScattering,
    pub multiple_colour: Vec3,
}

impl MetallicRoughnessBsdf {
    /// The lobe about the unit normal `n` with glTF perceptual `roughness`, `metallic`
    /// (clamped to [0, 1]) and `base_color`.
    pub fn new(n: Vec3, base_color: Vec3, roughness: f32, metallic: f32) -> Self {
        let metallic = if metallic.is_finite() {
            metallic.clamp(0.0, 1.0)
        } else {
            0.0
        };
        let ggx = Ggx::from_roughness(roughness);
        let multiple = if metallic > 0.0 {
            MultipleScattering::new(ggx)
        } else {
            MultipleScattering::NONE
        };
        MetallicRoughnessBsdf {
            frame: ShadingFrame::from_normal(n),
            ggx,
            base_color,
            metallic,
            multiple,
            multiple_colour: multiple.schlick_colour(base_color),
        }
    }

    /// The shading normal.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        self.frame.n
    }

    /// Probabilities of sampling the specular lobe and the diffuse one for the local `wo`
    /// (the metal's compensation takes the rest).
    #[inline]
    fn lobe_probabilities(&self, wo: Vec3) -> (f32, f32) {
        let m = self.metallic;
        let mean = Vec3::splat(1.0 / 3.0);
        let fd = schlick_f0(Vec3::splat(DIELECTRIC_F0), wo.z).x;
        let fm = schlick_f0(self.base_color, wo.z).dot(mean);
        let specular = (1.0 - m) * fd + m * fm;
        let diffuse = (1.0 - m) * (1.0 - fd) * self.base_color.dot(mean);
        let compensation = m * self.multiple_colour.dot(mean) * self.multiple.lost(wo.z);
        let total = specular + diffuse + compensation;
        if total > 0.0 {
            (
                (specular / total).clamp(0.0, 1.0),
                (diffuse / total).clamp(0.0, 1.0),
            )
        } else {
            (1.0, 0.0)
        }
    }

    pub(crate) fn eval_local(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let c = wo.dot(h);
        let specular = self.ggx.d(h) * self.ggx.g2(wo, wi) / (4.0 * wo.z * wi.z);
        let fresnel = |x: f32| schlick_f0(Vec3::splat(DIELECTRIC_F0), x).x;
        let transmitted = (1.0 - fresnel(wo.z)) * (1.0 - fresnel(wi.z));
        let dielectric =
            transmitted * self.base_color * (1.0 / PI) + Vec3::splat(fresnel(c) * specular);
        let metal = schlick_f0(self.base_color, c) * specular
            + self.multiple_colour * self.multiple.eval(wo.z, wi.z);
        (1.0 - self.metallic) * dielectric + self.metallic * metal
    }

    pub(crate) fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let (p_specular, p_diffuse) = self.lobe_probabilities(wo);
        let h = (wo + wi).normalize_or_zero();
        let wo_dot_h = wo.dot(h);
        let specular = if h != Vec3::ZERO && wo_dot_h > 0.0 {
            self.ggx.visible_normal_pdf(wo, h) / (4.0 * wo_dot_h)
        } else {
            0.0
        };
        let p_compensation = (1.0 - p_specular - p_diffuse).max(0.0);
        let compensation = if p_compensation > 0.0 {
            p_compensation * self.multiple.pdf(wi.z)
        } else {
            0.0
        };
        p_specular * specular + p_diffuse * wi.z / PI + compensation
    }

    /// A local sample, flagged by the lobe that drew it: the GGX highlight and the metal's
    /// compensation are glossy, the coated base diffuse.
    pub(crate) fn sample_local(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let (p_specular, p_diffuse) = self.lobe_probabilities(wo);
        let (wi, flags) = if u_lobe < p_specular {
            let wi = self.ggx.sample_reflection(wo, u)?.0;
            (wi, LobeFlags::GLOSSY_REFLECTION)
        } else if u_lobe < p_specular + p_diffuse || !self.multiple.is_on() {
            let wi = sample_cosine_hemisphere(Vec3::Z, u);
            (wi, LobeFlags::DIFFUSE_REFLECTION)
        } else {
            (self.multiple.sample(u), LobeFlags::GLOSSY_REFLECTION)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf_local(wo, wi);
        if !(pdf > 0.0 && pdf.is_finite()) {
            return None;
        }
        let weight = self.eval_local(wo, wi) * (wi.z / pdf);
        Some(BsdfSample::reflected(wi, weight, pdf, flags))
    }
}

impl Bsdf for MetallicRoughnessBsdf {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.eval_local(self.frame.to_local(wo), self.frame.to_local(wi))
    }

    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let local = self.sample_local(self.frame.to_local(wo), u_lobe, u)?;
        Some(BsdfSample {
            wi: self.frame.to_world(local.wi),
            ..local
        })
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_local(self.frame.to_local(wo), self.frame.to_local(wi))
    }

    /// A fully metallic lobe has no diffuse base.
    fn flags(&self) -> LobeFlags {
        if self.metallic < 1.0 {
            LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
        } else {
            LobeFlags::GLOSSY_REFLECTION
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metallic_one_is_the_conductor_and_zero_keeps_the_diffuse() {
        let base = Vec3::new(0.9, 0.5, 0.2);
        let wo = Vec3::new(0.5, 0.1, 0.86).normalize();
        let wi = Vec3::new(-0.3, 0.4, 0.87).normalize();
        let metal = MetallicRoughnessBsdf::new(Vec3::Z, base, 0.4, 1.0);
        let conductor = super::super::conductor::RoughConductor::new(Vec3::Z, 0.4, base);
        assert!(
            (metal.eval(wo, wi) - conductor.eval(wo, wi))
                .abs()
                .max_element()
                < 1e-6
        );
        // A dielectric at grazing-free angles is mostly its diffuse base.
        let plastic = MetallicRoughnessBsdf::new(Vec3::Z, base, 1.0, 0.0);
        let f = plastic.eval(Vec3::Z, Vec3::Z);
        assert!(f.x > 0.25 && f.x < 0.35, "{f}");
        assert_eq!(plastic.eval(wo, -wi), Vec3::ZERO);
    }

    #[test]
    fn lobe_choice_follows_the_albedos() {
        let wo = Vec3::Z;
        let metal = MetallicRoughnessBsdf::new(Vec3::Z, Vec3::splat(0.5), 0.5, 1.0);
        // F_m(1) = 0.5 against the compensation's mean(F_ms) (1 - E(1)); no diffuse.
        let compensation = metal.multiple_colour.x * metal.multiple.lost(1.0);
        assert!(compensation > 0.0 && compensation < 0.05, "{compensation}");
        let (p, p_diffuse) = metal.lobe_probabilities(wo);
        assert!((p - 0.5 / (0.5 + compensation)).abs() < 1e-5, "{p}");
        assert_eq!(p_diffuse, 0.0);
        let smooth_metal = MetallicRoughnessBsdf::new(Vec3::Z, Vec3::splat(0.5), 0.0, 1.0);
        assert!(smooth_metal.lobe_probabilities(wo).0 > 0.9999);
        let plastic = MetallicRoughnessBsdf::new(Vec3::Z, Vec3::splat(0.5), 0.5, 0.0);
        // 0.04 against 0.96 * 0.5.
        let (p, p_diffuse) = plastic.lobe_probabilities(wo);
        assert!((p - 0.04 / (0.04 + 0.48)).abs() < 1e-5, "{p}");
        assert!((p + p_diffuse - 1.0).abs() < 1e-6);
    }
}
