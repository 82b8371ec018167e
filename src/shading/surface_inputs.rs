//! A material's shading inputs at one hit: albedo, alpha, metallic, roughness, emission and
//! the shading normal after normal mapping, from the material's factors and its textures.
//!
//! Every integrator shades from the same inputs, so a textured or normal-mapped material
//! looks the same under each. The texels come from the caller (`crate::render::surface_textures`
//! filters each binding over the hit's ray footprint, the lookup the base colour has always
//! used); this file only combines them, as glTF 2.0 defines it:
//! - albedo = base colour factor x base-colour texture (RGB);
//! - alpha = alpha factor x alpha texture (A);
//! - metallic = factor x metallic-roughness texture's blue channel, roughness = factor x its
//!   green channel (glTF 2.0, section 3.9.2), the texture read only by the metallic-roughness
//!   model; separate roughness and metalness maps (MTL's greyscale
//!   `map_Pr`, `map_Pm`) multiply in their green and blue channels the same way;
//! - emission = emissive factor (times `KHR_materials_emissive_strength`, folded in by the
//!   loader) x emission texture (RGB);
//! - normal: the normal texture's texel `c` gives the tangent-space normal
//!   `normalize((2c - 1) * (scale, scale, 1))` (glTF 2.0, section 3.9.3), placed in the
//!   frame tangent = dP/ds, bitangent = -dP/dt, normal = the interpolated shading normal
//!   (see [`perturb_normal`]).

use glam::{Vec3, Vec4};

use crate::hit::SurfaceHit;
use crate::scene::{Material, TextureBinding};

/// Which of a material's textures a lookup is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureSlot {
    BaseColor,
    Alpha,
    MetallicRoughness,
    /// The separate roughness map (green channel).
    Roughness,
    /// The separate metalness map (blue channel).
    Metallic,
    Emission,
    Normal,
}

/// What shading needs of a material at one hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceInputs {
    /// Linear RGB base colour (diffuse albedo, or a metal's reflectance).
    pub albedo: Vec3,
    /// Coverage (1 = opaque); the alpha texture is read only when asked for.
    pub alpha: f32,
    /// Metalness in [0, 1] (metallic-roughness model).
    pub metallic: f32,
    /// Perceptual roughness in [0, 1]; `None` for the classic model.
    pub roughness: Option<f32>,
    /// Emitted radiance.
    pub emission: Vec3,
    /// Unit shading normal after normal mapping, facing the side of the hit's outward normals.
    pub shading_normal: Vec3,
}

/// The inputs of `material` at `surface`, with `sample` giving the (filtered) texel of each
/// bound texture. `with_alpha` reads the alpha texture: integrators that resolve alpha
/// cut-outs while tracing (Whitted, the path tracer) pass `false` and get the constant alpha.
pub fn surface_inputs(
    material: &Material,
    surface: &SurfaceHit,
    with_alpha: bool,
    mut sample: impl FnMut(TextureSlot, &TextureBinding) -> Vec4,
) -> SurfaceInputs {
    let albedo = match &material.base_color_texture {
        Some(binding) => material.base_color * sample(TextureSlot::BaseColor, binding).truncate(),
        None => material.base_color,
    };
    let alpha = match (&material.alpha_texture, with_alpha) {
        (Some(binding), true) => material.alpha * sample(TextureSlot::Alpha, binding).w,
        _ => material.alpha,
    };
    let (mut metallic, mut roughness) = (0.0, None);
    if let Some(model) = material.model.metallic_roughness() {
        metallic = model.metallic;
        let mut r = model.roughness;
        if let Some(binding) = &model.metallic_roughness_texture {
            let texel = sample(TextureSlot::MetallicRoughness, binding);
            metallic *= texel.z;
            r *= texel.y;
        }
        if let Some(binding) = &model.roughness_texture {
            r *= sample(TextureSlot::Roughness, binding).y;
        }
        if let Some(binding) = &model.metallic_texture {
            metallic *= sample(TextureSlot::Metallic, binding).z;
        }
        roughness = Some(r);
    }
    // A black emissive factor emits nothing whatever the texture says: no lookup.
    let emission = match &material.emission_texture {
        Some(binding) if material.emission != Vec3::ZERO => {
            // Never negative, though a filtered lookup of stored levels made with a ringing
            // filter (`maketx --filter lanczos3`) can be.
            (material.emission * sample(TextureSlot::Emission, binding).truncate()).max(Vec3::ZERO)
        }
        _ => material.emission,
    };
    let shading_normal = match &material.normal_texture {
        Some(binding) if surface.dpds != Vec3::ZERO && surface.dpdt != Vec3::ZERO => {
            let texel = sample(TextureSlot::Normal, binding).truncate();
            perturb_normal(
                surface.shading_normal,
                surface.dpds,
                surface.dpdt,
                texel,
                material.normal_scale,
            )
        }
        _ => surface.shading_normal,
    };
    SurfaceInputs {
        albedo,
        alpha,
        metallic,
        roughness,
        emission,
        shading_normal,
    }
}

/// The shading normal `n` (unit) bent by a tangent-space normal-map texel `texel` (RGB in
/// [0, 1]) with X/Y scale `scale`.
///
/// The tangent frame: T = dP/ds made orthogonal to `n`; B = -dP/dt made orthogonal to `n` and
/// T (texture t grows down the image, while a normal map's +Y points up it, as in glTF and
/// OpenGL-style maps). Taking B from the parameterisation rather than `n x T` keeps mirrored
/// texture coordinates right, the role MikkTSpace's handedness sign plays; for the
/// per-triangle derivatives here it gives MikkTSpace's frame whenever the st mapping is not
/// sheared. Degenerate frames, texels that give no direction and results below the surface
/// leave `n` unchanged.
pub fn perturb_normal(n: Vec3, dpds: Vec3, dpdt: Vec3, texel: Vec3, scale: f32) -> Vec3 {
    let Some(tangent) = (dpds - n * n.dot(dpds)).try_normalize() else {
        return n;
    };
    let up = -dpdt;
    let bitangent = (up - n * n.dot(up) - tangent * tangent.dot(up))
        .try_normalize()
        .unwrap_or_else(|| n.cross(tangent));
    let m = (texel * 2.0 - Vec3::ONE) * Vec3::new(scale, scale, 1.0);
    match (tangent * m.x + bitangent * m.y + n * m.z).try_normalize() {
        Some(mapped) if mapped.dot(n) > 0.0 => mapped,
        _ => n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hit::Patch;
    use crate::scene::{MaterialModel, MetallicRoughnessModel};
    use glam::Vec2;

    /// A hit on the z = 0 plane facing +z, with s along +x and t along -y (t grows down the
    /// image, so the image's "up" is +y).
    fn plane_hit() -> SurfaceHit {
        SurfaceHit {
            t: 1.0,
            position: Vec3::ZERO,
            geometric_normal: Vec3::Z,
            shading_normal: Vec3::Z,
            barycentric: Vec2::ZERO,
            st: Vec2::new(0.25, 0.75),
            dpds: Vec3::X * 2.0,
            dpdt: Vec3::NEG_Y * 3.0,
            material: 0,
            patch: Patch::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
            },
        }
    }

    fn binding(texture: usize) -> Option<TextureBinding> {
        Some(TextureBinding {
            texture,
            transform: glam::Affine2::IDENTITY,
        })
    }

    /// Inputs of `material` with every texture answering `texel`, and the slots looked up.
    fn inputs_with(material: &Material, texel: Vec4) -> (SurfaceInputs, Vec<TextureSlot>) {
        let mut slots = Vec::new();
        let inputs = surface_inputs(material, &plane_hit(), true, |slot, _| {
            slots.push(slot);
            texel
        });
        (inputs, slots)
    }

    #[test]
    fn a_flat_normal_map_leaves_the_normal_unchanged() {
        let material = Material {
            normal_texture: binding(0),
            normal_scale: 3.0,
            ..Material::default()
        };
        let (inputs, slots) = inputs_with(&material, Vec4::new(0.5, 0.5, 1.0, 1.0));
        assert_eq!(slots, [TextureSlot::Normal]);
        assert!(
            (inputs.shading_normal - Vec3::Z).length() < 1e-6,
            "{}",
            inputs.shading_normal
        );
        // The same for a slanted shading normal and a skewed st frame.
        let n = Vec3::new(0.3, -0.2, 0.9).normalize();
        let bent = perturb_normal(
            n,
            Vec3::new(1.0, 0.4, 0.1),
            Vec3::new(0.2, -1.0, 0.3),
            Vec3::new(0.5, 0.5, 1.0),
            1.0,
        );
        assert!((bent - n).length() < 1e-6);
    }

    #[test]
    fn a_tilted_constant_normal_tilts_by_its_angle() {
        let angle = 25f32.to_radians();
        // Tangent-space normal tilted towards +X (the s direction) and towards +Y (up the
        // image, -t, which is world +y here).
        for (m, expected_axis) in [
            (Vec3::new(angle.sin(), 0.0, angle.cos()), Vec3::X),
            (Vec3::new(0.0, angle.sin(), angle.cos()), Vec3::Y),
        ] {
            let texel = m * 0.5 + Vec3::splat(0.5);
            let material = Material {
                normal_texture: binding(0),
                ..Material::default()
            };
            let (inputs, _) = inputs_with(&material, texel.extend(1.0));
            let n = inputs.shading_normal;
            let tilt = n.dot(Vec3::Z).clamp(-1.0, 1.0).acos();
            assert!(
                (tilt - angle).abs() < 1e-5,
                "tilt {} deg",
                tilt.to_degrees()
            );
            assert!(
                n.dot(expected_axis) > 0.4,
                "{n} not towards {expected_axis}"
            );
            // The scale multiplies the tangent-plane part: tan(tilt) scales with it.
            let scaled = Material {
                normal_scale: 0.5,
                ..material
            };
            let (inputs, _) = inputs_with(&scaled, texel.extend(1.0));
            let tilt = inputs.shading_normal.dot(Vec3::Z).acos();
            assert!((tilt.tan() - 0.5 * angle.tan()).abs() < 1e-5);
        }
    }

    #[test]
    fn mirrored_texture_coordinates_flip_the_bitangent() {
        // t growing up the world (+y) instead of down: the image's "up" is now world -y.
        let texel = Vec3::new(0.5, 0.5 + 0.5 * 0.3f32.sin(), 0.5 + 0.5 * 0.3f32.cos());
        let bent = perturb_normal(Vec3::Z, Vec3::X, Vec3::Y, texel, 1.0);
        assert!(bent.y < -0.25, "{bent}");
    }

    #[test]
    fn surfaces_without_texture_coordinates_are_not_normal_mapped() {
        let material = Material {
            normal_texture: binding(0),
            ..Material::default()
        };
        let hit = SurfaceHit {
            dpds: Vec3::ZERO,
            dpdt: Vec3::ZERO,
            ..plane_hit()
        };
        let inputs = surface_inputs(&material, &hit, false, |_, _| panic!("no lookup expected"));
        assert_eq!(inputs.shading_normal, Vec3::Z);
    }

    #[test]
    fn emission_is_factor_times_strength_times_texture() {
        // The loader folds KHR_materials_emissive_strength (here 6) into the factor.
        let material = Material {
            emission: Vec3::new(1.0, 0.5, 0.25) * 6.0,
            emission_texture: binding(0),
            ..Material::default()
        };
        let (inputs, slots) = inputs_with(&material, Vec4::new(0.5, 0.2, 1.0, 1.0));
        assert_eq!(slots, [TextureSlot::Emission]);
        assert!(
            (inputs.emission - Vec3::new(3.0, 0.6, 1.5)).length() < 1e-6,
            "{}",
            inputs.emission
        );
        // A black factor reads no texture.
        let dark = Material {
            emission: Vec3::ZERO,
            ..material
        };
        let (inputs, slots) = inputs_with(&dark, Vec4::ONE);
        assert!(slots.is_empty() && inputs.emission == Vec3::ZERO);
    }

    #[test]
    fn metallic_roughness_channels_are_blue_and_green() {
        let model = MetallicRoughnessModel {
            metallic_roughness_texture: binding(0),
            ..MetallicRoughnessModel::new(0.8, 0.5)
        };
        let material = Material {
            model: MaterialModel::MetallicRoughness(model.clone()),
            ..Material::default()
        };
        let (inputs, slots) = inputs_with(&material, Vec4::new(0.9, 0.25, 0.6, 1.0));
        assert_eq!(slots, [TextureSlot::MetallicRoughness]);
        assert!((inputs.metallic - 0.3).abs() < 1e-6);
        assert!((inputs.roughness.unwrap() - 0.2).abs() < 1e-6);
        // Separate greyscale maps multiply in the same channels.
        let separate = Material {
            model: MaterialModel::MetallicRoughness(MetallicRoughnessModel {
                metallic_roughness_texture: None,
                roughness_texture: binding(1),
                metallic_texture: binding(2),
                ..model
            }),
            ..material.clone()
        };
        let (inputs, slots) = inputs_with(&separate, Vec4::new(0.9, 0.25, 0.6, 1.0));
        assert_eq!(slots, [TextureSlot::Roughness, TextureSlot::Metallic]);
        assert!((inputs.metallic - 0.3).abs() < 1e-6);
        assert!((inputs.roughness.unwrap() - 0.2).abs() < 1e-6);
        // The classic model has neither.
        let classic = Material {
            model: MaterialModel::default(),
            ..material
        };
        let (inputs, slots) = inputs_with(&classic, Vec4::ZERO);
        assert!(slots.is_empty());
        assert_eq!((inputs.metallic, inputs.roughness), (0.0, None));
    }

    #[test]
    fn albedo_and_alpha_multiply_their_textures() {
        let material = Material {
            base_color: Vec3::new(0.5, 1.0, 0.8),
            base_color_texture: binding(0),
            alpha: 0.5,
            alpha_texture: binding(1),
            ..Material::default()
        };
        let (inputs, slots) = inputs_with(&material, Vec4::new(0.5, 0.5, 0.5, 0.4));
        assert_eq!(slots, [TextureSlot::BaseColor, TextureSlot::Alpha]);
        assert_eq!(inputs.albedo, Vec3::new(0.25, 0.5, 0.4));
        assert!((inputs.alpha - 0.2).abs() < 1e-7);
        let constant = surface_inputs(&material, &plane_hit(), false, |_, _| Vec4::splat(0.5));
        assert_eq!(constant.alpha, 0.5);
    }
}
