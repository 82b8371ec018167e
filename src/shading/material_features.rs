//! What a material does, answered once for every reader: the lobes its BSDF can have at some
//! hit ([`LobeFlags`], per layer), whether it emits, absorbs, cuts out, bends its normals
//! and which textures shading reads. The effect analysis (`crate::render::effects`),
//! integrator selection (`crate::integrator::selection`), the area lights
//! (`crate::shading::area_lights`) and the integrators read these answers rather than the
//! material's fields.
//!
//! The lobes mirror what [`super::MaterialBsdf`] builds at a hit: the opaque part with weight
//! `(1 - mirror)(1 - transmission)`, the mirror with `mirror`, the dielectric boundary with
//! `transmission`, rough when the metallic-roughness model's roughness reaches
//! [`ROUGH_DIELECTRIC_MIN_ROUGHNESS`] and the media are not index-matched. A textured
//! roughness can fall below that threshold at some hits, so such a boundary has both the
//! rough and the smooth lobes.

use super::bsdf::LobeFlags;
use super::material_bsdf::ROUGH_DIELECTRIC_MIN_ROUGHNESS;
use crate::scene::{Material, MaterialModel, MetallicRoughnessModel};

/// What a material does (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialFeatures {
    /// The opaque part's lobes; empty when a full mirror or full transmission hides it.
    pub opaque: LobeFlags,
    /// The perfect mirror: [`LobeFlags::SPECULAR_REFLECTION`], or empty.
    pub mirror: LobeFlags,
    /// The dielectric boundary's lobes as a sampling integrator meets them; empty when the
    /// material is opaque. Reflection appears only with an index contrast (`ior != 1`),
    /// which both Fresnel reflection and total internal reflection need.
    pub boundary: LobeFlags,
    /// Lobes shaped by a microfacet roughness (the metallic-roughness model, and its rough
    /// glass): they reflect the surroundings, which only a sampling integrator gathers. The
    /// classic Blinn-Phong highlight is a highlight of the lights by design and does not
    /// count.
    pub rough: bool,
    /// Emits light (a positive emission factor).
    pub emits: bool,
    /// Absorbs light inside by Beer's law (a transmissive material with a finite
    /// attenuation distance and a colour other than white).
    pub absorbs: bool,
    /// Alpha cut-out decided per hit: a cutoff with an alpha texture. A constant alpha
    /// keeps or drops the whole surface before tracing.
    pub cutout: bool,
    /// Bends its shading normals by a normal map.
    pub normal_mapped: bool,
    /// Shading reads a texture ([`reads_textures`]).
    pub reads_textures: bool,
}

impl MaterialFeatures {
    pub fn of(material: &Material) -> MaterialFeatures {
        let opaque_weight = (1.0 - material.mirror) * (1.0 - material.transmission);
        let opaque = if opaque_weight > 0.0 {
            opaque_lobes(&material.model)
        } else {
            LobeFlags::NONE
        };
        let mirror = if material.mirror > 0.0 {
            LobeFlags::SPECULAR_REFLECTION
        } else {
            LobeFlags::NONE
        };
        let boundary = boundary_lobes(material);
        MaterialFeatures {
            opaque,
            mirror,
            boundary,
            rough: material.model.metallic_roughness().is_some(),
            emits: emits(material),
            absorbs: material.transmission > 0.0
                && material.attenuation_distance.is_finite()
                && material.attenuation_color != glam::Vec3::ONE,
            cutout: material.alpha_cutoff.is_some() && material.alpha_texture.is_some(),
            normal_mapped: material.normal_texture.is_some(),
            reads_textures: reads_textures(material),
        }
    }

    /// Every lobe the material's BSDF can have.
    pub fn lobes(&self) -> LobeFlags {
        self.opaque | self.mirror | self.boundary
    }

    /// Whether it refracts: light crosses its boundary.
    pub fn refracts(&self) -> bool {
        self.boundary.is_transmissive()
    }

    /// Whether its boundary reflects part of the light (an index contrast).
    pub fn boundary_reflects(&self) -> bool {
        self.boundary.is_reflective()
    }
}

/// The opaque part's lobes under its model.
fn opaque_lobes(model: &MaterialModel) -> LobeFlags {
    match model {
        MaterialModel::Classic(classic) if classic.specular > 0.0 => {
            LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
        }
        MaterialModel::Classic(_) => LobeFlags::DIFFUSE_REFLECTION,
        MaterialModel::MetallicRoughness(model) if model.metallic >= 1.0 => {
            LobeFlags::GLOSSY_REFLECTION
        }
        MaterialModel::MetallicRoughness(_) => {
            LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
        }
    }
}

/// The dielectric boundary's lobes (see [`MaterialFeatures::boundary`]).
fn boundary_lobes(material: &Material) -> LobeFlags {
    if material.transmission <= 0.0 {
        return LobeFlags::NONE;
    }
    let index_contrast = material.ior != 1.0;
    let smooth = if index_contrast {
        LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION
    } else {
        LobeFlags::SPECULAR_TRANSMISSION
    };
    let rough = LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION;
    match material.model.metallic_roughness() {
        Some(model) if index_contrast && model.roughness >= ROUGH_DIELECTRIC_MIN_ROUGHNESS => {
            if roughness_textured(model) {
                rough | smooth
            } else {
                rough
            }
        }
        _ => smooth,
    }
}

/// Whether a texture scales the model's roughness.
fn roughness_textured(model: &MetallicRoughnessModel) -> bool {
    model.metallic_roughness_texture.is_some() || model.roughness_texture.is_some()
}

/// Whether `material` emits light: a positive emission factor (an emission texture only
/// scales it).
#[inline]
pub fn emits(material: &Material) -> bool {
    material.emission.max_element() > 0.0
}

/// Whether shading `material` reads any texture (so hits need texture coordinates and
/// dP/ds, dP/dt, and lookups need the footprint's gradients): the base colour, the
/// metallic-roughness maps, an emission texture on a material that emits, a normal map.
pub fn reads_textures(material: &Material) -> bool {
    let model_maps = material.model.metallic_roughness().is_some_and(|model| {
        model.metallic_roughness_texture.is_some()
            || model.roughness_texture.is_some()
            || model.metallic_texture.is_some()
    });
    material.base_color_texture.is_some()
        || model_maps
        || (material.emission_texture.is_some() && material.emission != glam::Vec3::ZERO)
        || material.normal_texture.is_some()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ClassicModel, TextureBinding};
    use glam::Vec3;

    fn binding() -> Option<TextureBinding> {
        Some(TextureBinding {
            texture: 0,
            transform: glam::Affine2::IDENTITY,
        })
    }

    fn metallic_roughness(roughness: f32, metallic: f32) -> Material {
        Material {
            model: MaterialModel::MetallicRoughness(MetallicRoughnessModel::new(
                roughness, metallic,
            )),
            ..Material::default()
        }
    }

    #[test]
    fn a_classic_matte_material_is_diffuse_only() {
        let features = MaterialFeatures::of(&Material::default());
        assert_eq!(features.lobes(), LobeFlags::DIFFUSE_REFLECTION);
        assert!(!features.rough && !features.emits && !features.absorbs);
        assert!(!features.cutout && !features.normal_mapped && !features.reads_textures);
        assert!(!features.refracts() && !features.boundary_reflects());
    }

    #[test]
    fn the_classic_highlight_is_glossy_but_not_rough() {
        let shiny = Material {
            model: MaterialModel::Classic(ClassicModel {
                specular: 0.5,
                shininess: 40.0,
            }),
            ..Material::default()
        };
        let features = MaterialFeatures::of(&shiny);
        assert_eq!(
            features.opaque,
            LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
        );
        assert!(!features.rough);
    }

    #[test]
    fn mirror_and_glass_layers_are_specular_and_hide_the_opaque_part_when_full() {
        let mirror = Material {
            mirror: 1.0,
            ..Material::default()
        };
        let features = MaterialFeatures::of(&mirror);
        assert_eq!(features.lobes(), LobeFlags::SPECULAR_REFLECTION);
        assert!(features.opaque.is_empty() && features.boundary.is_empty());

        let glass = Material {
            transmission: 1.0,
            attenuation_color: Vec3::new(0.5, 0.9, 0.5),
            attenuation_distance: 2.0,
            ..Material::default()
        };
        let features = MaterialFeatures::of(&glass);
        assert_eq!(
            features.boundary,
            LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION
        );
        assert!(features.opaque.is_empty() && features.mirror.is_empty());
        assert!(features.refracts() && features.boundary_reflects() && features.absorbs);

        // Index-matched media reflect nothing; a white attenuation absorbs nothing.
        let matched = Material {
            ior: 1.0,
            attenuation_distance: 2.0,
            ..glass.clone()
        };
        let matched = Material {
            attenuation_color: Vec3::ONE,
            ..matched
        };
        let features = MaterialFeatures::of(&matched);
        assert_eq!(features.boundary, LobeFlags::SPECULAR_TRANSMISSION);
        assert!(!features.boundary_reflects() && !features.absorbs);

        // Half glass: the classic opaque part stays.
        let half = Material {
            transmission: 0.5,
            ..Material::default()
        };
        let features = MaterialFeatures::of(&half);
        assert_eq!(
            features.lobes(),
            LobeFlags::DIFFUSE_REFLECTION
                | LobeFlags::SPECULAR_REFLECTION
                | LobeFlags::SPECULAR_TRANSMISSION
        );
    }

    #[test]
    fn the_metallic_roughness_model_is_rough_and_a_full_metal_has_no_diffuse_base() {
        let plastic = MaterialFeatures::of(&metallic_roughness(0.4, 0.0));
        assert_eq!(
            plastic.lobes(),
            LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION
        );
        assert!(plastic.rough);
        let metal = MaterialFeatures::of(&metallic_roughness(0.4, 1.0));
        assert_eq!(metal.lobes(), LobeFlags::GLOSSY_REFLECTION);
        assert!(metal.rough);
    }

    #[test]
    fn rough_glass_is_glossy_above_the_threshold_and_smooth_below_or_index_matched() {
        let mut glass = metallic_roughness(0.3, 0.0);
        glass.transmission = 1.0;
        let rough = LobeFlags::GLOSSY_REFLECTION | LobeFlags::GLOSSY_TRANSMISSION;
        let smooth = LobeFlags::SPECULAR_REFLECTION | LobeFlags::SPECULAR_TRANSMISSION;
        let features = MaterialFeatures::of(&glass);
        assert_eq!(features.lobes(), rough);
        assert!(features.rough && features.refracts());

        let mut polished = metallic_roughness(0.5 * ROUGH_DIELECTRIC_MIN_ROUGHNESS, 0.0);
        polished.transmission = 1.0;
        assert_eq!(MaterialFeatures::of(&polished).lobes(), smooth);

        let mut matched = glass.clone();
        matched.ior = 1.0;
        assert_eq!(
            MaterialFeatures::of(&matched).lobes(),
            LobeFlags::SPECULAR_TRANSMISSION
        );

        // A roughness map can take a hit below the threshold: both boundaries.
        if let MaterialModel::MetallicRoughness(model) = &mut glass.model {
            model.roughness_texture = binding();
        }
        let features = MaterialFeatures::of(&glass);
        assert_eq!(features.boundary, rough | smooth);
        assert!(features.reads_textures);
    }

    #[test]
    fn emission_cutout_normal_map_and_textures_are_answered_from_the_shared_fields() {
        let mut m = Material {
            emission: Vec3::new(0.0, 2.0, 0.0),
            ..Material::default()
        };
        assert!(MaterialFeatures::of(&m).emits && !MaterialFeatures::of(&m).reads_textures);
        // An emission texture on a black factor is never read.
        m.emission = Vec3::ZERO;
        m.emission_texture = binding();
        let features = MaterialFeatures::of(&m);
        assert!(!features.emits && !features.reads_textures);

        let cut = Material {
            alpha_cutoff: Some(0.5),
            alpha_texture: binding(),
            ..Material::default()
        };
        assert!(MaterialFeatures::of(&cut).cutout);
        let constant = Material {
            alpha_cutoff: Some(0.5),
            alpha: 0.2,
            ..Material::default()
        };
        assert!(!MaterialFeatures::of(&constant).cutout);

        let bumpy = Material {
            normal_texture: binding(),
            ..Material::default()
        };
        let features = MaterialFeatures::of(&bumpy);
        assert!(features.normal_mapped && features.reads_textures);

        // Metallic-roughness maps are read only by that model.
        let mut orm = metallic_roughness(1.0, 1.0);
        if let MaterialModel::MetallicRoughness(model) = &mut orm.model {
            model.metallic_texture = binding();
        }
        assert!(MaterialFeatures::of(&orm).reads_textures);
        let textured = Material {
            base_color_texture: binding(),
            ..Material::default()
        };
        assert!(MaterialFeatures::of(&textured).reads_textures);
    }
}
