//! The rough dielectric lobe: a GGX microfacet boundary between the outside (index 1) and
//! a material of index `ior` that reflects and transmits (Walter et al. 2007,
//! "Microfacet Models for Refraction through Rough Surfaces"; the facts as in pbrt-v4's
//! `DielectricBxDF`).
//!
//! In the local frame of the outward normal (`z > 0` outside), with `eta'` the index of
//! the side `wi` is on over that of `wo`'s side (1 for reflection) and the generalised half
//! vector `m = normalize(eta' wi + wo)` (eq. 16) turned to `z > 0`:
//! - reflection: `f = F D G2 / (4 |cos_o cos_i|)` (eq. 20);
//! - transmission: `f = (1 - F) D G2 |(wi . m)(wo . m)| / (|cos_o cos_i| (wi . m + (wo . m) / eta')^2)`
//!   (eq. 21 written with pbrt-v4's `eta'`), divided by `eta'^2`: radiance is compressed
//!   into the smaller solid angle of the denser side (pbrt-v4, section 9.5.2, "radiance
//!   transport"), so `f(wo, wi) / n_o^2 = f(wi, wo) / n_i^2` (generalised reciprocity);
//! - `F` is the exact unpolarised dielectric Fresnel reflectance at `wo . m`
//!   ([`fresnel_dielectric`]), 1 under total internal reflection.
//!
//! Sampling draws `m` from the normals visible from `wo` ([`Ggx::sample_visible_normal`]),
//! reflects with probability `F` and refracts otherwise, so the density is
//! `D_wo(m) F / (4 |wo . m|)` for reflection and
//! `D_wo(m) (1 - F) |wi . m| / (wi . m + (wo . m) / eta')^2` for transmission (eq. 17).
//! Beer's-law absorption inside stays with the integrators. An index-matched boundary
//! (`ior = 1`) has no rough refraction (every `m` transmits straight through): the
//! material mixture keeps the smooth boundary for it.

use glam::{Vec2, Vec3};

use super::bsdf::{Bsdf, BsdfSample, LobeFlags};
use super::frame::ShadingFrame;
use super::fresnel::fresnel_dielectric;
use super::microfacet::Ggx;
use super::refraction::refract;

/// A rough boundary about the unit *outward* shading normal `frame.n` of a material with
/// index of refraction `ior` (the outside has 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric {
    pub frame: ShadingFrame,
    pub ggx: Ggx,
    pub ior: f32,
}

/// The generalised half vector of a pair and the `eta'` of the pair (see the module doc).
struct HalfVector {
    m: Vec3,
    eta_prime: f32,
    reflection: bool,
}

impl RoughDielectric {
    /// The boundary about the unit outward normal `outward_n`, with glTF perceptual
    /// `roughness`.
    pub fn new(outward_n: Vec3, roughness: f32, ior: f32) -> RoughDielectric {
        RoughDielectric {
            frame: ShadingFrame::from_normal(outward_n),
            ggx: Ggx::from_roughness(roughness),
            ior,
        }
    }

    /// Fresnel reflectance for light seen along `wo` meeting a microfacet `m` (`m.z > 0`),
    /// with `wo . m` telling which side it arrives from.
    #[inline]
    fn fresnel(&self, wo_dot_m: f32) -> f32 {
        // fresnel_dielectric takes n_incident / n_transmitted.
        let eta = if wo_dot_m >= 0.0 {
            1.0 / self.ior
        } else {
            self.ior
        };
        fresnel_dielectric(wo_dot_m, eta)
    }

    /// The half vector of a local pair, or `None` for a pair no microfacet connects
    /// (grazing, degenerate, or a microfacet seen from its back by either direction).
    #[inline]
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<HalfVector> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o == 0.0 || cos_i == 0.0 {
            return None;
        }
        let reflection = cos_o * cos_i > 0.0;
        let eta_prime = if reflection {
            1.0
        } else if cos_o > 0.0 {
            self.ior
        } else {
            1.0 / self.ior
        };
        let m = (wi * eta_prime + wo).normalize_or_zero();
        if m == Vec3::ZERO {
            return None;
        }
        let m = if m.z < 0.0 { -m } else { m };
        if m.dot(wi) * cos_i < 0.0 || m.dot(wo) * cos_o < 0.0 {
            return None;
        }
        Some(HalfVector {
            m,
            eta_prime,
            reflection,
        })
    }

    /// `f` in the local frame.
    pub(crate) fn eval_local(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let Some(half) = self.half_vector(wo, wi) else {
            return Vec3::ZERO;
        };
        let m = half.m;
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        let f = self.fresnel(wo_m);
        let dg = self.ggx.d(m) * self.ggx.g2(wo, wi);
        let value = if half.reflection {
            f * dg / (4.0 * (wo.z * wi.z).abs())
        } else {
            let denom = (wi_m + wo_m / half.eta_prime).powi(2);
            if denom == 0.0 {
                return Vec3::ZERO;
            }
            let t = (1.0 - f) * dg * (wi_m * wo_m / (wi.z * wo.z * denom)).abs();
            t / (half.eta_prime * half.eta_prime)
        };
        if value.is_finite() {
            Vec3::splat(value)
        } else {
            Vec3::ZERO
        }
    }

    /// The sampling density in the local frame.
    pub(crate) fn pdf_local(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(half) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let m = half.m;
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        let f = self.fresnel(wo_m);
        let visible = self.ggx.visible_normal_pdf(wo, m);
        let pdf = if half.reflection {
            visible / (4.0 * wo_m.abs()) * f
        } else {
            let denom = (wi_m + wo_m / half.eta_prime).powi(2);
            visible * wi_m.abs() / denom * (1.0 - f)
        };
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }

    /// A local sample, flagged glossy reflection or transmission; a refraction's `eta` is
    /// the index on `wo`'s side over that on `wi`'s (the ratio it refracts with).
    pub(crate) fn sample_local(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let m = self.ggx.sample_visible_normal(wo, u);
        let wo_m = wo.dot(m);
        let f = self.fresnel(wo_m);
        let (wi, flags, eta) = if u_lobe < f {
            let wi = 2.0 * wo_m * m - wo;
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            (wi, LobeFlags::GLOSSY_REFLECTION, 1.0)
        } else {
            let eta = if wo_m >= 0.0 {
                1.0 / self.ior
            } else {
                self.ior
            };
            let wi = refract(-wo, m, eta)?;
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            (wi, LobeFlags::GLOSSY_TRANSMISSION, eta)
        };
        // Value and density from the pair itself, so the sample agrees with eval and pdf.
        let pdf = self.pdf_local(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 {
            return None;
        }
        let weight = self.eval_local(wo, wi) * (wi.z.abs() / pdf);
        Some(BsdfSample {
            wi,
            weight,
            pdf,
            flags,
            eta,
        })
    }
}

impl Bsdf for RoughDielectric {
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

    fn flags(&self) -> LobeFlags {
        LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn beyond_the_critical_angle_almost_nothing_leaves() {
        // Inside glass at 60 degrees from the normal (critical angle 41.8 degrees) with a
        // nearly smooth surface: only microfacets tilted by more than 18 degrees, in GGX's
        // long tail (~ alpha^2 / tan^2), let light out.
        let glass = RoughDielectric::new(Vec3::Z, 0.1, 1.5);
        let wo = Vec3::new(0.866, 0.0, -0.5);
        let mut u = crate::shading::bsdf::tests::Uniforms(3);
        let (count, mut left) = (20_000, 0);
        for _ in 0..count {
            if let Some(s) = glass.sample(wo, u.next(), u.vec2()) {
                left += usize::from(s.wi.z > 0.0);
            }
        }
        assert!(left * 200 < count, "{left} of {count} left the glass");
        let out = Vec3::new(-0.6, 0.0, 0.8);
        assert_eq!(glass.eval(wo, out), Vec3::ZERO);
    }

    #[test]
    fn transmission_peaks_along_snells_direction() {
        let glass = RoughDielectric::new(Vec3::Z, 0.2, 1.5);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        // Snell: sin_t = 0.6 / 1.5 = 0.4.
        let snell = Vec3::new(-0.4, 0.0, -(1.0f32 - 0.16).sqrt());
        let off = Vec3::new(-0.1, 0.3, -0.95).normalize();
        assert!(glass.eval(wo, snell).x > 5.0 * glass.eval(wo, off).x);
    }
}
