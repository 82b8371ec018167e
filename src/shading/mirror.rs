//! The smooth mirror lobe: all the light it reflects leaves in the mirror direction (seed
//! 001, "Reflection Direction"), a delta lobe.

use glam::{Vec2, Vec3};

use super::bsdf::{Bsdf, BsdfSample, LobeFlags};
use super::reflection::reflect_above;

/// A perfect mirror reflecting `reflectance` of the light, about the unit shading normal
/// `ns` kept above the unit geometric normal `ng` (both on the viewer's side).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothMirror {
    pub ns: Vec3,
    pub ng: Vec3,
    pub reflectance: Vec3,
}

impl SmoothMirror {
    /// The direction the light seen from `wo` comes from ([`reflect_above`] of the incident
    /// direction `-wo`).
    #[inline]
    pub fn direction(&self, wo: Vec3) -> Vec3 {
        reflect_above(-wo, self.ns, self.ng)
    }
}

impl Bsdf for SmoothMirror {
    fn eval(&self, _wo: Vec3, _wi: Vec3) -> Vec3 {
        Vec3::ZERO
    }

    fn sample(&self, wo: Vec3, _u_lobe: f32, _u: Vec2) -> Option<BsdfSample> {
        if wo.dot(self.ng) <= 0.0 || self.reflectance.max_element() <= 0.0 {
            return None;
        }
        Some(BsdfSample::reflected(
            self.direction(wo),
            self.reflectance,
            1.0,
            LobeFlags::SPECULAR_REFLECTION,
        ))
    }

    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    fn flags(&self) -> LobeFlags {
        LobeFlags::SPECULAR_REFLECTION
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_samples_the_reflection_and_has_no_density() {
        let mirror = SmoothMirror {
            ns: Vec3::Z,
            ng: Vec3::Z,
            reflectance: Vec3::new(0.9, 0.8, 0.7),
        };
        let wo = Vec3::new(0.6, 0.0, 0.8);
        let s = mirror.sample(wo, 0.3, Vec2::new(0.1, 0.9)).expect("above");
        assert!((s.wi - Vec3::new(-0.6, 0.0, 0.8)).length() < 1e-6);
        assert_eq!(s.weight, mirror.reflectance);
        assert_eq!((s.flags, s.eta), (LobeFlags::SPECULAR_REFLECTION, 1.0));
        assert!(s.is_specular() && mirror.flags().is_specular());
        assert_eq!(mirror.eval(wo, s.wi), Vec3::ZERO);
        assert_eq!(mirror.pdf(wo, s.wi), 0.0);
        // Never more light than arrives.
        assert!(s.weight.max_element() <= 1.0);
        assert!(mirror.sample(-wo, 0.3, Vec2::ZERO).is_none());
    }
}
