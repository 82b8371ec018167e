//! Scene analysis: which effects a scene needs, and why.
//!
//! Before rendering, the scene is reduced to an [`EffectSet`]. The integrator hoists every
//! per-effect branch on these flags, so a scene pays nothing for an effect it does not use:
//! no shadow rays without lights, no secondary rays without specular materials, no footprint
//! math without filtered textures, no absorption without media. `--all-effects` forces the
//! general path (every flag on) for comparison.

use crate::footprint::LodStrategy;
use crate::render::stats::EffectReason;
use crate::scene::{Environment, Projection, SceneDescription};

/// The effects a render switches on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EffectSet {
    /// Shadow rays towards punctual lights.
    pub shadows: bool,
    /// Shadow rays that pass through transmissive occluders (seed 001).
    pub transmissive_shadows: bool,
    /// Perfect-mirror reflection rays.
    pub mirror_reflection: bool,
    /// Dielectric boundaries: Fresnel-weighted reflection and Snell refraction.
    pub refraction: bool,
    /// Beer's-law absorption inside media.
    pub absorption: bool,
    /// Textures filtered by a ray footprint (cones or differentials).
    pub footprints: bool,
    /// Alpha cut-out filter callbacks.
    pub alpha_cutout: bool,
    /// Environment light (ambient term from a non-black environment).
    pub environment: bool,
    /// Thin-lens depth of field (lens sampling).
    pub depth_of_field: bool,
}

impl EffectSet {
    /// Every effect on: the general path.
    pub fn all() -> EffectSet {
        EffectSet {
            shadows: true,
            transmissive_shadows: true,
            mirror_reflection: true,
            refraction: true,
            absorption: true,
            footprints: true,
            alpha_cutout: true,
            environment: true,
            depth_of_field: true,
        }
    }

    /// Analyse `scene` (rendered with footprint strategy `lod`) into the effects it needs,
    /// with a reason for each.
    pub fn analyse(scene: &SceneDescription, lod: LodStrategy) -> (EffectSet, Vec<EffectReason>) {
        let mut set = EffectSet::default();
        let mut reasons = Vec::new();
        let mut because = |effect: &str, why: String| {
            reasons.push(EffectReason {
                effect: effect.to_string(),
                because: why,
            })
        };
        let used: Vec<bool> = {
            let mut used = vec![false; scene.materials.len()];
            for mesh in &scene.meshes {
                if let Some(u) = used.get_mut(mesh.material) {
                    *u = true;
                }
            }
            for sphere in &scene.spheres {
                if let Some(u) = used.get_mut(sphere.material) {
                    *u = true;
                }
            }
            used
        };
        let materials = || {
            scene
                .materials
                .iter()
                .zip(&used)
                .filter(|(_, used)| **used)
                .map(|(m, _)| m)
        };
        if let Some(light) = scene.lights.first() {
            set.shadows = true;
            because(
                "shadows",
                format!(
                    "{} light(s), e.g. {}",
                    scene.lights.len(),
                    light_kind(light)
                ),
            );
        }
        if let Some(m) = materials().find(|m| m.mirror > 0.0) {
            set.mirror_reflection = true;
            because(
                "mirror reflection",
                format!("material '{}' has mirror {}", m.name, m.mirror),
            );
        }
        if let Some(m) = materials().find(|m| m.transmission > 0.0) {
            set.refraction = true;
            because(
                "refraction + Fresnel",
                format!("material '{}' has transmission {}", m.name, m.transmission),
            );
            if set.shadows {
                set.transmissive_shadows = true;
                because(
                    "transmissive shadows",
                    format!("lights shine through material '{}'", m.name),
                );
            }
        }
        if let Some(m) = materials().find(|m| {
            m.transmission > 0.0
                && m.attenuation_distance.is_finite()
                && m.attenuation_color != glam::Vec3::ONE
        }) {
            set.absorption = true;
            because(
                "Beer's-law absorption",
                format!(
                    "material '{}' has attenuation over {}",
                    m.name, m.attenuation_distance
                ),
            );
        }
        let textured = materials().find(|m| m.base_color_texture.is_some());
        let env_texture = matches!(scene.environment, Environment::LatLong { .. });
        if lod != LodStrategy::Mip0 {
            if let Some(m) = textured {
                set.footprints = true;
                because(
                    "ray footprints",
                    format!("material '{}' has a base-colour texture", m.name),
                );
            } else if env_texture {
                set.footprints = true;
                because(
                    "ray footprints",
                    "the environment is a lat-long texture".to_string(),
                );
            } else if let Some(m) =
                materials().find(|m| m.alpha_cutoff.is_some() && m.alpha_texture.is_some())
            {
                // Alpha cut-outs filter their mask over the ray cone (no shimmering leaves).
                set.footprints = true;
                because(
                    "ray footprints",
                    format!("material '{}' has an alpha texture", m.name),
                );
            }
        }
        if let Some(m) = materials().find(|m| m.alpha_cutoff.is_some()) {
            set.alpha_cutout = true;
            because(
                "alpha cut-out",
                format!("material '{}' has an alpha cutoff", m.name),
            );
        }
        let env_lit = match &scene.environment {
            Environment::Color(c) => c.max_element() > 0.0,
            Environment::LatLong { intensity, .. } => *intensity > 0.0,
        };
        if env_lit {
            set.environment = true;
            because(
                "environment light",
                "the environment is not black".to_string(),
            );
        }
        if let Some(camera) = &scene.camera {
            if let Projection::ThinLens {
                aperture_radius, ..
            } = camera.projection
            {
                if aperture_radius > 0.0 {
                    set.depth_of_field = true;
                    because(
                        "depth of field",
                        format!("thin-lens aperture radius {aperture_radius}"),
                    );
                }
            }
        }
        (set, reasons)
    }

    /// Names of the effects switched on.
    pub fn names(&self) -> Vec<&'static str> {
        let mut names = Vec::new();
        let flags = [
            (self.shadows, "shadows"),
            (self.transmissive_shadows, "transmissive shadows"),
            (self.mirror_reflection, "mirror reflection"),
            (self.refraction, "refraction + Fresnel"),
            (self.absorption, "Beer's-law absorption"),
            (self.footprints, "ray footprints"),
            (self.alpha_cutout, "alpha cut-out"),
            (self.environment, "environment light"),
            (self.depth_of_field, "depth of field"),
        ];
        for (on, name) in flags {
            if on {
                names.push(name);
            }
        }
        names
    }
}

fn light_kind(light: &crate::scene::Light) -> &'static str {
    match light {
        crate::scene::Light::Point { .. } => "a point light",
        crate::scene::Light::Directional { .. } => "a directional light",
        crate::scene::Light::Spot { .. } => "a spot light",
    }
}
