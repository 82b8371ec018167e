//! The BSDF of a scene material at one hit: its opaque lobe ([`OpaqueBsdf`]), its mirror
//! ([`SmoothMirror`]) and its dielectric boundary ([`SmoothDielectric`]), with the weights
//! the material gives them (`crate::scene::Material`): `(1 - mirror)(1 - transmission)`
//! for the opaque part, `mirror` and `transmission` for the other two, the weights of seed
//! 001's recursion `local + k_r * reflected + k_t * refracted`.
//!
//! Whitted follows each weighted lobe; a path tracer samples the mixture, choosing a lobe
//! with probability proportional to its weight ([`Bsdf`] for [`MaterialBsdf`]).

use glam::{Vec2, Vec3};

use super::brdf::OpaqueBsdf;
use super::bsdf::{Bsdf, BsdfSample};
use super::dielectric::SmoothDielectric;
use super::mirror::SmoothMirror;
use crate::scene::{FresnelMode, Material};

/// A material's lobes at one hit, with their weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialBsdf {
    pub opaque_weight: f32,
    pub opaque: OpaqueBsdf,
    pub mirror_weight: f32,
    pub mirror: SmoothMirror,
    pub dielectric_weight: f32,
    pub dielectric: SmoothDielectric,
}

impl MaterialBsdf {
    /// The BSDF of `material` with the (textured) `albedo`, seen along the incident
    /// direction `d`, at a hit with unit outward geometric and shading normals; `fresnel`
    /// as in [`SmoothDielectric::fresnel`].
    pub fn new(
        material: &Material,
        albedo: Vec3,
        d: Vec3,
        outward_geometric: Vec3,
        outward_shading: Vec3,
        fresnel: Option<FresnelMode>,
    ) -> MaterialBsdf {
        // The viewer's side decides which way the normals face (the geometric normal's rule,
        // as for dielectric boundaries).
        let (ng, ns) = if d.dot(outward_geometric) < 0.0 {
            (outward_geometric, outward_shading)
        } else {
            (-outward_geometric, -outward_shading)
        };
        MaterialBsdf {
            opaque_weight: (1.0 - material.mirror) * (1.0 - material.transmission),
            opaque: OpaqueBsdf {
                n: ns,
                albedo,
                specular: material.specular,
                shininess: material.shininess,
            },
            mirror_weight: material.mirror,
            mirror: SmoothMirror {
                ns,
                ng,
                reflectance: Vec3::ONE,
            },
            dielectric_weight: material.transmission,
            dielectric: SmoothDielectric {
                outward_geometric,
                outward_shading,
                ior: material.ior,
                fresnel,
            },
        }
    }

    /// The lobe weights, clamped at zero, in the order opaque, mirror, dielectric.
    fn weights(&self) -> [f32; 3] {
        [
            self.opaque_weight.max(0.0),
            self.mirror_weight.max(0.0),
            self.dielectric_weight.max(0.0),
        ]
    }

    /// Probability of choosing the opaque lobe when sampling.
    fn opaque_probability(&self) -> f32 {
        let w = self.weights();
        let total = w[0] + w[1] + w[2];
        if total > 0.0 {
            w[0] / total
        } else {
            0.0
        }
    }
}

impl Bsdf for MaterialBsdf {
    /// Only the opaque lobe has a value; the delta lobes have none.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.opaque_weight.max(0.0) * self.opaque.eval(wo, wi)
    }

    /// Picks a lobe with probability proportional to its weight (`u_lobe`, rescaled to stay
    /// uniform for the lobe's own choice), then samples it.
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let w = self.weights();
        let total = w[0] + w[1] + w[2];
        if total <= 0.0 {
            return None;
        }
        // The last lobe with a weight takes whatever rounding leaves above the others.
        let last = w.iter().rposition(|&x| x > 0.0).unwrap_or(0);
        let mut start = 0.0;
        for (index, weight) in w.into_iter().enumerate() {
            let p = weight / total;
            if p <= 0.0 || (u_lobe >= start + p && index < last) {
                start += p;
                continue;
            }
            let u_inner = ((u_lobe - start) / p).clamp(0.0, 1.0 - f32::EPSILON);
            let mut sample = match index {
                0 => self.opaque.sample(wo, u_inner, u)?,
                1 => self.mirror.sample(wo, u_inner, u)?,
                _ => self.dielectric.sample(wo, u_inner, u)?,
            };
            sample.weight *= weight / p;
            sample.pdf *= p;
            return Some(sample);
        }
        None
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.opaque_probability() * self.opaque.pdf(wo, wi)
    }

    fn has_delta(&self) -> bool {
        self.mirror_weight > 0.0 || self.dielectric_weight > 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;
    use crate::shading::bsdf::Lobe;

    fn material(mirror: f32, transmission: f32) -> Material {
        Material {
            base_color: Vec3::new(0.8, 0.6, 0.4),
            mirror,
            transmission,
            ior: 1.5,
            ..Material::default()
        }
    }

    fn bsdf_of(material: &Material) -> MaterialBsdf {
        MaterialBsdf::new(
            material,
            material.base_color,
            Vec3::new(0.3, 0.0, -0.954).normalize(),
            Vec3::Z,
            Vec3::Z,
            Some(FresnelMode::Exact),
        )
    }

    #[test]
    fn weights_follow_the_material() {
        let b = bsdf_of(&material(0.25, 0.5));
        assert_eq!(b.opaque_weight, 0.75 * 0.5);
        assert_eq!((b.mirror_weight, b.dielectric_weight), (0.25, 0.5));
        assert!(b.has_delta());
        assert!(!bsdf_of(&material(0.0, 0.0)).has_delta());
    }

    #[test]
    fn smooth_samples_match_eval_and_pdf_of_the_mixture() {
        let b = bsdf_of(&material(0.3, 0.2));
        let wo = Vec3::new(-0.3, 0.0, 0.954).normalize();
        let mut u = Uniforms(23);
        let mut counts = [0usize; 3];
        let count = 60_000;
        for _ in 0..count {
            let s = b.sample(wo, u.next(), u.vec2()).expect("scatters");
            match s.lobe {
                Lobe::Smooth => {
                    counts[0] += 1;
                    assert!((s.pdf - b.pdf(wo, s.wi)).abs() <= 1e-5 * s.pdf);
                    let expected = b.eval(wo, s.wi) * b.opaque.n.dot(s.wi) / s.pdf;
                    assert!((s.weight - expected).abs().max_element() <= 1e-4);
                }
                Lobe::DeltaReflection => counts[1] += 1,
                Lobe::DeltaTransmission => counts[2] += 1,
            }
        }
        // The opaque lobe is chosen in proportion to its weight.
        let w = [0.7 * 0.8, 0.3, 0.2];
        let expected = w[0] / (w[0] + w[1] + w[2]);
        let share = counts[0] as f32 / count as f32;
        assert!((share - expected).abs() < 0.01, "{share} vs {expected}");
        assert!(counts[1] > 0 && counts[2] > 0);
    }

    #[test]
    fn a_black_material_scatters_nothing() {
        let mut m = material(0.0, 0.0);
        m.base_color = Vec3::ZERO;
        let b = MaterialBsdf {
            opaque_weight: 0.0,
            ..bsdf_of(&m)
        };
        assert!(b.sample(Vec3::Z, 0.5, Vec2::splat(0.5)).is_none());
        assert_eq!(b.pdf(Vec3::Z, Vec3::Z), 0.0);
    }
}
