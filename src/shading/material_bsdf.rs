//! The BSDF of a scene material at one hit: its opaque lobe ([`OpaqueLobe`]), its mirror
//! ([`SmoothMirror`]) and its dielectric boundary ([`SmoothDielectric`], or
//! [`RoughDielectric`] for rough glass), with the weights the material gives them
//! (`crate::scene::Material`): `(1 - mirror)(1 - transmission)` for the opaque part,
//! `mirror` and `transmission` for the other two, the weights of seed 001's recursion
//! `local + k_r * reflected + k_t * refracted`.
//!
//! The opaque lobe is the classic Lambert plus Blinn-Phong ([`OpaqueBsdf`]) for the
//! material's classic model, and the glTF 2.0 metallic-roughness lobe
//! ([`MetallicRoughnessBsdf`]) for its metallic-roughness model. The dielectric boundary of a
//! material with `transmission > 0` is rough when that model's roughness at the hit is at least
//! [`ROUGH_DIELECTRIC_MIN_ROUGHNESS`], the media are not index-matched (`ior != 1`) and
//! Fresnel reflection is on; otherwise it is smooth.
//!
//! Whitted follows each weighted lobe: it evaluates the opaque lobe for every light and
//! follows the mirror and the *smooth* boundary's two directions (it can follow only delta
//! directions, so rough glass renders as smooth glass there). A path tracer samples the
//! mixture through [`Bsdf`] for [`MaterialBsdf`], choosing a lobe with probability
//! proportional to its weight; there the rough boundary replaces the smooth one.

use glam::{Vec2, Vec3};

use super::brdf::OpaqueBsdf;
use super::bsdf::{Bsdf, BsdfSample, LobeFlags};
use super::dielectric::SmoothDielectric;
use super::metallic_roughness::MetallicRoughnessBsdf;
use super::mirror::SmoothMirror;
use super::rough_dielectric::RoughDielectric;
use super::surface_inputs::SurfaceInputs;
use crate::scene::{FresnelMode, Material, MaterialModel};

/// Below this perceptual roughness a transmissive material keeps the smooth (delta)
/// boundary: at `alpha = 0.05^2` the rough lobe is a mirror for every practical purpose,
/// and the delta lobe is exact and cheaper for every integrator.
pub const ROUGH_DIELECTRIC_MIN_ROUGHNESS: f32 = 0.05;

/// The opaque lobe of a material: classic, or glTF metallic-roughness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OpaqueLobe {
    /// Lambert plus normalised Blinn-Phong ([`MaterialModel::Classic`]).
    Classic(OpaqueBsdf),
    /// The glTF 2.0 metallic-roughness lobe ([`MaterialModel::MetallicRoughness`]).
    MetallicRoughness(MetallicRoughnessBsdf),
}

impl OpaqueLobe {
    /// The shading normal, on the viewer's side.
    #[inline]
    pub fn normal(&self) -> Vec3 {
        match self {
            OpaqueLobe::Classic(lobe) => lobe.n,
            OpaqueLobe::MetallicRoughness(lobe) => lobe.normal(),
        }
    }
}

impl Bsdf for OpaqueLobe {
    #[inline]
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match self {
            OpaqueLobe::Classic(lobe) => lobe.eval(wo, wi),
            OpaqueLobe::MetallicRoughness(lobe) => lobe.eval(wo, wi),
        }
    }

    #[inline]
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        match self {
            OpaqueLobe::Classic(lobe) => lobe.sample(wo, u_lobe, u),
            OpaqueLobe::MetallicRoughness(lobe) => lobe.sample(wo, u_lobe, u),
        }
    }

    #[inline]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            OpaqueLobe::Classic(lobe) => lobe.pdf(wo, wi),
            OpaqueLobe::MetallicRoughness(lobe) => lobe.pdf(wo, wi),
        }
    }

    fn flags(&self) -> LobeFlags {
        match self {
            OpaqueLobe::Classic(lobe) => lobe.flags(),
            OpaqueLobe::MetallicRoughness(lobe) => lobe.flags(),
        }
    }
}

/// What the opaque lobe takes from the hit: the (textured) albedo, and the
/// metallic-roughness model's roughness and metallic (unread by the classic model).
#[derive(Clone, Copy, Debug)]
struct LobeInputs {
    albedo: Vec3,
    roughness: f32,
    metallic: f32,
}

/// A lobe of the mixture with its weight in the material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weighted<'a, L> {
    pub weight: f32,
    pub lobe: &'a L,
}

/// The lobes Whitted follows at a hit, each present only with a positive weight: the opaque
/// lobe it evaluates for every light (diffuse, and glossy with the classic highlight or the
/// metallic-roughness GGX lobe), the mirror (specular reflection) and the smooth boundary
/// (specular reflection and transmission), whose single directions it traces. It follows a
/// rough boundary as the smooth one: it traces delta directions only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WhittedLobes<'a> {
    pub opaque: Option<Weighted<'a, OpaqueLobe>>,
    pub mirror: Option<Weighted<'a, SmoothMirror>>,
    pub boundary: Option<Weighted<'a, SmoothDielectric>>,
}

impl WhittedLobes<'_> {
    /// The lobes present.
    pub fn flags(&self) -> LobeFlags {
        let opaque = self.opaque.map(|o| o.lobe.flags());
        let mirror = self.mirror.map(|m| m.lobe.flags());
        let boundary = self.boundary.map(|b| b.lobe.flags());
        [opaque, mirror, boundary]
            .into_iter()
            .flatten()
            .fold(LobeFlags::NONE, |all, flags| all | flags)
    }
}

/// A material's lobes at one hit, with their weights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaterialBsdf {
    pub opaque_weight: f32,
    pub opaque: OpaqueLobe,
    pub mirror_weight: f32,
    pub mirror: SmoothMirror,
    pub dielectric_weight: f32,
    /// The smooth boundary (Whitted always follows this one).
    pub dielectric: SmoothDielectric,
    /// The rough boundary that replaces the smooth one when sampling (see the module doc).
    pub rough_dielectric: Option<RoughDielectric>,
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
        let (roughness, metallic) = match material.model.metallic_roughness() {
            Some(model) => (model.roughness, model.metallic),
            None => (0.0, 0.0),
        };
        let inputs = LobeInputs {
            albedo,
            roughness,
            metallic,
        };
        MaterialBsdf::with_inputs(
            material,
            inputs,
            d,
            outward_geometric,
            outward_shading,
            fresnel,
        )
    }

    /// [`MaterialBsdf::new`] with the (textured) shading inputs of the hit
    /// (`crate::shading::surface_inputs`): its albedo, roughness, metallic and normal-mapped
    /// shading normal.
    #[inline(always)]
    pub fn from_surface_inputs(
        material: &Material,
        inputs: &SurfaceInputs,
        d: Vec3,
        outward_geometric: Vec3,
        fresnel: Option<FresnelMode>,
    ) -> MaterialBsdf {
        let lobe = LobeInputs {
            albedo: inputs.albedo,
            roughness: inputs.roughness.unwrap_or(0.0),
            metallic: inputs.metallic,
        };
        MaterialBsdf::with_inputs(
            material,
            lobe,
            d,
            outward_geometric,
            inputs.shading_normal,
            fresnel,
        )
    }

    #[inline(always)]
    fn with_inputs(
        material: &Material,
        inputs: LobeInputs,
        d: Vec3,
        outward_geometric: Vec3,
        outward_shading: Vec3,
        fresnel: Option<FresnelMode>,
    ) -> MaterialBsdf {
        let LobeInputs {
            albedo,
            roughness,
            metallic,
        } = inputs;
        // The viewer's side decides which way the normals face (the geometric normal's rule,
        // as for dielectric boundaries).
        let (ng, ns) = if d.dot(outward_geometric) < 0.0 {
            (outward_geometric, outward_shading)
        } else {
            (-outward_geometric, -outward_shading)
        };
        let (opaque, rough_dielectric) = match &material.model {
            MaterialModel::Classic(classic) => {
                let lobe = OpaqueBsdf {
                    n: ns,
                    albedo,
                    specular: classic.specular,
                    shininess: classic.shininess,
                };
                (OpaqueLobe::Classic(lobe), None)
            }
            MaterialModel::MetallicRoughness(_) => {
                let lobe = MetallicRoughnessBsdf::new(ns, albedo, roughness, metallic);
                let rough = material.transmission > 0.0
                    && roughness >= ROUGH_DIELECTRIC_MIN_ROUGHNESS
                    && material.ior != 1.0
                    && fresnel.is_some();
                let boundary =
                    rough.then(|| RoughDielectric::new(outward_shading, roughness, material.ior));
                (OpaqueLobe::MetallicRoughness(lobe), boundary)
            }
        };
        MaterialBsdf {
            opaque_weight: (1.0 - material.mirror) * (1.0 - material.transmission),
            opaque,
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
            rough_dielectric,
        }
    }

    /// Whether the BSDF transmits light through the surface with a density (a weighted
    /// rough boundary), which light sampling can then reach from the far side.
    #[inline]
    pub fn transmits_with_density(&self) -> bool {
        self.flags().contains(LobeFlags::GLOSSY_TRANSMISSION)
    }

    /// The lobes Whitted follows (see [`WhittedLobes`]).
    #[inline]
    pub fn whitted_lobes(&self) -> WhittedLobes<'_> {
        fn weighted<L>(weight: f32, lobe: &L) -> Option<Weighted<'_, L>> {
            (weight > 0.0).then_some(Weighted { weight, lobe })
        }
        WhittedLobes {
            opaque: weighted(self.opaque_weight, &self.opaque),
            mirror: weighted(self.mirror_weight, &self.mirror),
            boundary: weighted(self.dielectric_weight, &self.dielectric),
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

    /// Probabilities of choosing the opaque lobe and the dielectric lobe when sampling.
    fn probabilities(&self) -> (f32, f32) {
        let w = self.weights();
        let total = w[0] + w[1] + w[2];
        if total > 0.0 {
            (w[0] / total, w[2] / total)
        } else {
            (0.0, 0.0)
        }
    }
}

impl Bsdf for MaterialBsdf {
    /// The opaque lobe and a rough boundary have values; the delta lobes have none.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let opaque = self.opaque_weight.max(0.0) * self.opaque.eval(wo, wi);
        match &self.rough_dielectric {
            Some(rough) if self.dielectric_weight > 0.0 => {
                opaque + self.dielectric_weight * rough.eval(wo, wi)
            }
            _ => opaque,
        }
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
                _ => match &self.rough_dielectric {
                    Some(rough) => rough.sample(wo, u_inner, u)?,
                    None => self.dielectric.sample(wo, u_inner, u)?,
                },
            };
            if !sample.is_specular() {
                // A lobe with a density: the sample could have come from every smooth lobe
                // of the mixture, so it carries the mixture's value and density (one-sample
                // MIS, balance heuristic), which is what eval and pdf report.
                sample.pdf = self.pdf(wo, sample.wi);
                if sample.pdf.is_nan() || sample.pdf <= 0.0 {
                    return None;
                }
                let cos = sample.wi.dot(self.opaque.normal()).abs();
                sample.weight = self.eval(wo, sample.wi) * (cos / sample.pdf);
                return Some(sample);
            }
            sample.weight *= weight / p;
            sample.pdf *= p;
            return Some(sample);
        }
        None
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (p_opaque, p_dielectric) = self.probabilities();
        let opaque = p_opaque * self.opaque.pdf(wo, wi);
        match &self.rough_dielectric {
            Some(rough) if p_dielectric > 0.0 => opaque + p_dielectric * rough.pdf(wo, wi),
            _ => opaque,
        }
    }

    /// The lobes with a positive weight.
    fn flags(&self) -> LobeFlags {
        let mut flags = LobeFlags::NONE;
        if self.opaque_weight > 0.0 {
            flags |= self.opaque.flags();
        }
        if self.mirror_weight > 0.0 {
            flags |= self.mirror.flags();
        }
        if self.dielectric_weight > 0.0 {
            flags |= match &self.rough_dielectric {
                Some(rough) => rough.flags(),
                None => self.dielectric.flags(),
            };
        }
        flags
    }
}

/// The BSDF of a material whose only lobe is its opaque lobe `L` (`mirror` and
/// `transmission` both zero): [`MaterialBsdf`]'s mixture with the weights (1, 0, 0), with the
/// operations its methods then perform, so every value has the same bits, but without the
/// matches over lobes and models. The path tracer's lanes run one `OpaqueOnly` per
/// material group (`integrator::path::lane_bsdf`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OpaqueOnly<L> {
    pub lobe: L,
    /// The lobe's shading normal, on the viewer's side ([`OpaqueLobe::normal`]).
    pub normal: Vec3,
}

impl OpaqueOnly<OpaqueBsdf> {
    #[inline(always)]
    pub fn classic(lobe: OpaqueBsdf) -> Self {
        OpaqueOnly {
            normal: lobe.n,
            lobe,
        }
    }

    /// [`Bsdf::sample`] once the lobe's cosine has drawn `wi`
    /// (`bsdf::sample_cosine_hemisphere` about the lobe's normal): what the classic lobe's
    /// sample does with it (`OpaqueBsdf::sample_along`), then the mixture's density and
    /// weight.
    #[inline(always)]
    pub fn sample_along(&self, wo: Vec3, wi: Vec3) -> Option<BsdfSample> {
        self.as_mixture(wo, self.lobe.sample_along(wo, wi)?)
    }
}

impl<L: Bsdf> OpaqueOnly<L> {
    /// The lobe's sample as the mixture's, the density and weight recomputed as
    /// [`MaterialBsdf::sample`] does for a lobe chosen with probability 1.
    #[inline(always)]
    fn as_mixture(&self, wo: Vec3, mut sample: BsdfSample) -> Option<BsdfSample> {
        if !sample.is_specular() {
            sample.pdf = self.lobe.pdf(wo, sample.wi);
            if sample.pdf.is_nan() || sample.pdf <= 0.0 {
                return None;
            }
            let cos = sample.wi.dot(self.normal).abs();
            sample.weight = self.lobe.eval(wo, sample.wi) * (cos / sample.pdf);
        }
        Some(sample)
    }
}

impl OpaqueOnly<MetallicRoughnessBsdf> {
    #[inline(always)]
    pub fn metallic_roughness(lobe: MetallicRoughnessBsdf) -> Self {
        OpaqueOnly {
            normal: lobe.normal(),
            lobe,
        }
    }
}

impl<L: Bsdf> Bsdf for OpaqueOnly<L> {
    /// The mixture's `1 * f`.
    #[inline(always)]
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        self.lobe.eval(wo, wi)
    }

    /// The mixture's sample with the opaque lobe chosen with probability 1: `u_lobe`
    /// clamped as [`MaterialBsdf::sample`] rescales it, the density and weight those of the
    /// mixture (here the lobe's own).
    #[inline(always)]
    fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
        let u_inner = u_lobe.clamp(0.0, 1.0 - f32::EPSILON);
        self.as_mixture(wo, self.lobe.sample(wo, u_inner, u)?)
    }

    /// The mixture's `1 * pdf`.
    #[inline(always)]
    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.lobe.pdf(wo, wi)
    }

    #[inline(always)]
    fn flags(&self) -> LobeFlags {
        self.lobe.flags()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::bsdf::tests::Uniforms;

    fn material(mirror: f32, transmission: f32) -> Material {
        Material {
            base_color: Vec3::new(0.8, 0.6, 0.4),
            mirror,
            transmission,
            ior: 1.5,
            ..Material::default()
        }
    }

    fn metallic_roughness(roughness: f32, metallic: f32) -> MaterialModel {
        MaterialModel::MetallicRoughness(crate::scene::MetallicRoughnessModel::new(
            roughness, metallic,
        ))
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
        assert!(b.flags().is_specular());
        assert!(!bsdf_of(&material(0.0, 0.0)).flags().is_specular());
    }

    #[test]
    fn whitted_follows_the_weighted_lobes_and_rough_glass_as_smooth() {
        let b = bsdf_of(&material(0.25, 0.5));
        let lobes = b.whitted_lobes();
        assert_eq!(lobes.opaque.map(|o| o.weight), Some(0.75 * 0.5));
        assert_eq!(lobes.mirror.map(|m| m.weight), Some(0.25));
        assert_eq!(lobes.boundary.map(|d| d.weight), Some(0.5));
        assert_eq!(
            lobes.flags(),
            LobeFlags::DIFFUSE_REFLECTION
                | LobeFlags::SPECULAR_REFLECTION
                | LobeFlags::SPECULAR_TRANSMISSION
        );
        assert_eq!(b.flags(), lobes.flags());
        // A matte material: only the diffuse lobe.
        let matte = bsdf_of(&material(0.0, 0.0));
        let lobes = matte.whitted_lobes();
        assert!(lobes.mirror.is_none() && lobes.boundary.is_none());
        assert_eq!(lobes.flags(), LobeFlags::DIFFUSE_REFLECTION);
        // Full glass hides the opaque lobe.
        let glass = bsdf_of(&material(0.0, 1.0));
        assert!(glass.whitted_lobes().opaque.is_none());
        // Rough glass: sampled as a glossy boundary, followed by Whitted as the smooth one.
        let mut rough = material(0.0, 1.0);
        rough.model = metallic_roughness(0.3, 0.0);
        let b = bsdf_of(&rough);
        assert_eq!(
            b.flags(),
            LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION
        );
        assert_eq!(
            b.whitted_lobes().flags(),
            LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION
        );
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
            match s.flags {
                LobeFlags::DIFFUSE_REFLECTION => {
                    counts[0] += 1;
                    assert!((s.pdf - b.pdf(wo, s.wi)).abs() <= 1e-5 * s.pdf);
                    let expected = b.eval(wo, s.wi) * b.opaque.normal().dot(s.wi) / s.pdf;
                    assert!((s.weight - expected).abs().max_element() <= 1e-4);
                }
                LobeFlags::SPECULAR_REFLECTION => counts[1] += 1,
                LobeFlags::SPECULAR_TRANSMISSION => counts[2] += 1,
                flags => panic!("a classic mirror and glass has no {flags:?} lobe"),
            }
        }
        // The opaque lobe is chosen in proportion to its weight.
        let w = [0.7 * 0.8, 0.3, 0.2];
        let expected = w[0] / (w[0] + w[1] + w[2]);
        let share = counts[0] as f32 / count as f32;
        assert!((share - expected).abs() < 0.01, "{share} vs {expected}");
        assert!(counts[1] > 0 && counts[2] > 0);
    }

    /// `OpaqueOnly` gives [`MaterialBsdf`]'s bits for a material without mirror or
    /// transmission, for both models and a classic lobe with and without a highlight.
    #[test]
    fn an_opaque_only_material_matches_the_mixture_bit_for_bit() {
        let mut u = Uniforms(41);
        let mut classic = material(0.0, 0.0);
        let mut dull = classic.clone();
        if let MaterialModel::Classic(model) = &mut classic.model {
            model.specular = 0.4;
            model.shininess = 30.0;
        }
        if let MaterialModel::Classic(model) = &mut dull.model {
            model.specular = 0.0;
        }
        let mut metal = material(0.0, 0.0);
        metal.model = metallic_roughness(0.35, 0.6);
        for m in [&classic, &dull, &metal] {
            for _ in 0..2000 {
                let d = crate::shading::bsdf::sample_uniform_sphere(u.vec2());
                let ns = (Vec3::Z + 0.3 * crate::shading::bsdf::sample_uniform_sphere(u.vec2()))
                    .normalize();
                let mixture = MaterialBsdf::new(m, m.base_color, d, Vec3::Z, ns, None);
                let opaque = match mixture.opaque {
                    OpaqueLobe::Classic(lobe) => {
                        let only = OpaqueOnly::classic(lobe);
                        compare(&mixture, &only, d, &mut u);
                        // The lanes draw the cosine's direction apart from the sample.
                        let (wo, u_lobe, u_dir) = (-d, u.next(), u.vec2());
                        let drawn = crate::shading::bsdf::sample_cosine_hemisphere(lobe.n, u_dir);
                        same_sample(
                            mixture.sample(wo, u_lobe, u_dir),
                            only.sample_along(wo, drawn),
                        );
                        continue;
                    }
                    OpaqueLobe::MetallicRoughness(lobe) => OpaqueOnly::metallic_roughness(lobe),
                };
                compare(&mixture, &opaque, d, &mut u);
            }
        }

        fn compare(mixture: &MaterialBsdf, only: &impl Bsdf, d: Vec3, u: &mut Uniforms) {
            let (wo, wi) = (-d, crate::shading::bsdf::sample_uniform_sphere(u.vec2()));
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            assert_eq!(bits(mixture.eval(wo, wi)), bits(only.eval(wo, wi)));
            assert_eq!(mixture.pdf(wo, wi).to_bits(), only.pdf(wo, wi).to_bits());
            assert_eq!(mixture.flags(), only.flags());
            let (u_lobe, u_dir) = (u.next(), u.vec2());
            same_sample(
                mixture.sample(wo, u_lobe, u_dir),
                only.sample(wo, u_lobe, u_dir),
            );
        }

        fn same_sample(a: Option<BsdfSample>, b: Option<BsdfSample>) {
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            match (a, b) {
                (Some(a), Some(b)) => {
                    assert_eq!(bits(a.wi), bits(b.wi));
                    assert_eq!(bits(a.weight), bits(b.weight));
                    assert_eq!(a.pdf.to_bits(), b.pdf.to_bits());
                    assert_eq!((a.flags, a.eta.to_bits()), (b.flags, b.eta.to_bits()));
                }
                (None, None) => {}
                (a, b) => panic!("{a:?} against {b:?}"),
            }
        }
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

    #[test]
    fn roughness_selects_the_metallic_roughness_lobe_and_none_keeps_the_classic_one() {
        let classic = bsdf_of(&material(0.0, 0.0));
        assert!(matches!(classic.opaque, OpaqueLobe::Classic(_)));
        let mut metal = material(0.0, 0.0);
        metal.model = metallic_roughness(0.3, 1.0);
        let b = bsdf_of(&metal);
        let OpaqueLobe::MetallicRoughness(lobe) = b.opaque else {
            panic!("expected the metallic-roughness lobe, got {:?}", b.opaque);
        };
        assert_eq!(lobe.metallic, 1.0);
        assert!((lobe.ggx.alpha - 0.09).abs() < 1e-6, "{}", lobe.ggx.alpha);
        // The GGX highlight: far brighter towards the mirror direction than to the side.
        let wo = Vec3::new(-0.3, 0.0, 0.954).normalize();
        let mirror = Vec3::new(0.3, 0.0, 0.954).normalize();
        let side = Vec3::new(-0.5, 0.5, 0.707).normalize();
        assert!(b.eval(wo, mirror).x > 20.0 * b.eval(wo, side).x);
        assert!(b.rough_dielectric.is_none() && !b.flags().is_specular());
    }

    #[test]
    fn rough_transmission_replaces_the_smooth_boundary_above_the_threshold() {
        let mut glass = material(0.0, 1.0);
        glass.model = metallic_roughness(0.3, 0.0);
        let b = bsdf_of(&glass);
        assert!(b.rough_dielectric.is_some() && !b.flags().is_specular());
        // Below the threshold, index-matched, or without Fresnel: the smooth boundary.
        glass.model = metallic_roughness(0.5 * ROUGH_DIELECTRIC_MIN_ROUGHNESS, 0.0);
        assert!(bsdf_of(&glass).rough_dielectric.is_none());
        glass.model = metallic_roughness(0.3, 0.0);
        glass.ior = 1.0;
        assert!(bsdf_of(&glass).rough_dielectric.is_none());
        glass.ior = 1.5;
        let index_matched = MaterialBsdf::new(
            &glass,
            glass.base_color,
            Vec3::new(0.3, 0.0, -0.954).normalize(),
            Vec3::Z,
            Vec3::Z,
            None,
        );
        assert!(index_matched.rough_dielectric.is_none() && index_matched.flags().is_specular());
        // A rough glass scatters light through the surface with a density.
        let wo = Vec3::new(-0.3, 0.0, 0.954).normalize();
        let mut u = Uniforms(31);
        let transmitted = (0..1000)
            .filter_map(|_| b.sample(wo, u.next(), u.vec2()))
            .filter(|s| s.wi.z < 0.0 && s.flags == LobeFlags::GLOSSY_TRANSMISSION && s.pdf > 0.0)
            .count();
        assert!(transmitted > 800, "{transmitted}");
    }
}
