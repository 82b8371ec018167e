//! The smooth dielectric lobe: a boundary between media that splits light into a reflected
//! and a refracted direction, both delta (seed 001, "Refraction Direction"; seed 004,
//! "Fresnel" and "Total Internal Reflection").
//!
//! [`SmoothDielectric::split`] gives both directions with the reflected share; an
//! integrator that follows every branch (Whitted) weights each one, a sampling one picks a
//! branch with probability equal to its share ([`Bsdf::sample`]), so the weight is 1.
//! Radiance is carried across the boundary unscaled (no `1 / eta^2` factor), as in the
//! Whitted recursion of seed 001.

use glam::{Vec2, Vec3};

use super::bsdf::{Bsdf, BsdfSample, LobeFlags};
use super::fresnel::{fresnel, DielectricBoundary};
use super::reflection::reflect_above;
use super::refraction::refract;
use crate::scene::FresnelMode;

/// A smooth boundary of an object with index of refraction `ior` (the outside has 1), with
/// the unit outward geometric and shading normals of the hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothDielectric {
    pub outward_geometric: Vec3,
    pub outward_shading: Vec3,
    pub ior: f32,
    /// The Fresnel equations, or `None` when the media are index-matched (no reflection
    /// except total internal reflection).
    pub fresnel: Option<FresnelMode>,
}

/// How a boundary splits one incident ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricSplit {
    /// The side the ray arrives from, its `eta` and the normal it refracts about.
    pub boundary: DielectricBoundary,
    /// The geometric normal on the incident side (reflections leave along it, refractions
    /// against it).
    pub incident_normal: Vec3,
    /// The shading normal on the incident side.
    pub incident_shading_normal: Vec3,
    /// The refracted direction; `None` under total internal reflection or when the
    /// refracted ray would stay on the incident side.
    pub refracted: Option<Vec3>,
    /// Share of the light reflected (1 without a refracted ray); the refracted ray carries
    /// `1 - reflectance`.
    pub reflectance: f32,
}

impl SmoothDielectric {
    /// Splits the unit incident direction `d` (pointing towards the surface).
    #[inline]
    pub fn split(&self, d: Vec3) -> DielectricSplit {
        // Which side the ray comes from, eta = n_incident / n_transmitted (outside = 1): the
        // geometric normal decides, as it decides the medium a refracted ray enters.
        let boundary = DielectricBoundary::with_shading_normal(
            d,
            self.outward_geometric,
            self.outward_shading,
            self.ior,
        );
        let (ng, ns) = if d.dot(self.outward_geometric) < 0.0 {
            (self.outward_geometric, self.outward_shading)
        } else {
            (-self.outward_geometric, -self.outward_shading)
        };
        let refracted = refract(d, boundary.normal, boundary.eta).filter(|t| t.dot(ng) < 0.0);
        // Total internal reflection (or a refracted ray that would stay on the incident side)
        // reflects everything; otherwise the Fresnel share (seed 004), which is zero for
        // index-matched media.
        let reflectance = if refracted.is_none() {
            1.0
        } else if let Some(mode) = self.fresnel {
            fresnel(mode, boundary.cos_i, boundary.eta)
        } else {
            0.0
        };
        DielectricSplit {
            boundary,
            incident_normal: ng,
            incident_shading_normal: ns,
            refracted,
            reflectance,
        }
    }
}

impl Bsdf for SmoothDielectric {
    fn eval(&self, _wo: Vec3, _wi: Vec3) -> Vec3 {
        Vec3::ZERO
    }

    /// Reflects with probability `reflectance`, refracts otherwise (chosen by `u_lobe`).
    fn sample(&self, wo: Vec3, u_lobe: f32, _u: Vec2) -> Option<BsdfSample> {
        let d = -wo;
        let split = self.split(d);
        match split.refracted {
            Some(wi) if u_lobe >= split.reflectance => Some(BsdfSample {
                wi,
                weight: Vec3::ONE,
                pdf: 1.0 - split.reflectance,
                flags: LobeFlags::SPECULAR_TRANSMISSION,
                eta: split.boundary.eta,
            }),
            _ => Some(BsdfSample::reflected(
                reflect_above(d, split.incident_shading_normal, split.incident_normal),
                Vec3::ONE,
                split.reflectance,
                LobeFlags::SPECULAR_REFLECTION,
            )),
        }
    }

    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    /// Both directions: the reflection carries Fresnel's share or total internal
    /// reflection.
    fn flags(&self) -> LobeFlags {
        LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;
    use crate::shading::fresnel_dielectric;

    fn glass(fresnel: Option<FresnelMode>) -> SmoothDielectric {
        SmoothDielectric {
            outward_geometric: Vec3::Z,
            outward_shading: Vec3::Z,
            ior: 1.5,
            fresnel,
        }
    }

    #[test]
    fn entering_glass_splits_by_the_exact_fresnel_reflectance() {
        let d = Vec3::new(0.6, 0.0, -0.8);
        let split = glass(Some(FresnelMode::Exact)).split(d);
        assert!(split.boundary.entering);
        let t = split.refracted.expect("no TIR entering glass");
        // Snell: sin_t = sin_i / 1.5.
        assert!((t.x - 0.4).abs() < 1e-5 && t.z < 0.0);
        let expected = fresnel_dielectric(0.8, 1.0 / 1.5);
        assert_eq!(split.reflectance, expected);
        assert!(split.reflectance > 0.0 && split.reflectance < 0.2);
    }

    #[test]
    fn beyond_the_critical_angle_inside_everything_is_reflected() {
        // Leaving glass at 60 degrees (critical angle 41.8 degrees).
        let d = Vec3::new(0.866, 0.0, 0.5);
        let bsdf = glass(Some(FresnelMode::Exact));
        let split = bsdf.split(d);
        assert!(!split.boundary.entering && split.refracted.is_none());
        assert_eq!(split.reflectance, 1.0);
        let s = bsdf.sample(-d, 0.99, Vec2::ZERO).expect("reflects");
        assert_eq!((s.flags, s.eta), (LobeFlags::SPECULAR_REFLECTION, 1.0));
        assert_eq!(s.pdf, 1.0);
        assert!(s.wi.z < 0.0, "stays inside: {}", s.wi);
    }

    #[test]
    fn sampling_picks_each_branch_as_often_as_its_share() {
        let bsdf = glass(Some(FresnelMode::Exact));
        let wo = Vec3::new(-0.9, 0.0, 0.436).normalize();
        let reflectance = bsdf.split(-wo).reflectance;
        let mut u = Uniforms(17);
        let count = 100_000;
        let mut reflected = 0;
        for _ in 0..count {
            let s = bsdf.sample(wo, u.next(), u.vec2()).expect("scatters");
            assert!(s.is_specular() && s.weight == Vec3::ONE);
            match s.flags {
                LobeFlags::SPECULAR_REFLECTION => {
                    assert_eq!(s.eta, 1.0);
                    reflected += 1;
                    assert_eq!(s.pdf, reflectance);
                    assert!(s.wi.z > 0.0);
                }
                flags => {
                    // Entering glass: n_incident / n_transmitted = 1 / 1.5.
                    assert_eq!(
                        (flags, s.eta),
                        (LobeFlags::SPECULAR_TRANSMISSION, 1.0 / 1.5)
                    );
                    assert_eq!(s.pdf, 1.0 - reflectance);
                    assert!(s.wi.z < 0.0);
                }
            }
        }
        let share = reflected as f32 / count as f32;
        assert!(
            (share - reflectance).abs() < 0.005,
            "{share} vs {reflectance}"
        );
        assert_eq!(bsdf.eval(wo, -wo), Vec3::ZERO);
        assert_eq!(bsdf.pdf(wo, -wo), 0.0);
    }

    #[test]
    fn index_matched_media_only_refract() {
        let split = glass(None).split(Vec3::new(0.6, 0.0, -0.8));
        assert_eq!(split.reflectance, 0.0);
        assert!(split.refracted.is_some());
    }

    #[test]
    fn a_sample_leaving_glass_carries_the_inverse_ratio() {
        let bsdf = glass(Some(FresnelMode::Exact));
        // From inside at 10 degrees: below the critical angle, so u_lobe near 1 refracts.
        let wo = Vec3::new(0.1736, 0.0, -0.9848).normalize();
        let s = bsdf.sample(wo, 0.999, Vec2::ZERO).expect("scatters");
        assert_eq!((s.flags, s.eta), (LobeFlags::SPECULAR_TRANSMISSION, 1.5));
        assert!(s.wi.z > 0.0);
        assert_eq!(
            bsdf.flags(),
            LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION
        );
    }
}
