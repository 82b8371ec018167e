//! Scene analysis: which effects a scene needs, and why.
//!
//! Before rendering, the scene is reduced to an [`EffectSet`]. The integrator hoists every
//! per-effect branch on these flags, so a scene pays nothing for an effect it does not use:
//! no shadow rays without lights, no secondary rays without specular materials, no footprint
//! math without filtered textures, no absorption without media. `--all-effects` forces the
//! general path (every flag on) for comparison. What each material does (its lobes,
//! absorption, cut-out, textures) is `crate::shading::MaterialFeatures`'s answer.

use crate::footprint::LodStrategy;
use crate::render::stats::EffectReason;
use crate::scene::{Environment, Material, Projection, SceneDescription};
use crate::shading::MaterialFeatures;

/// The effects a render switches on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EffectSet {
    /// Shadow rays towards punctual lights.
    pub shadows: bool,
    /// Shadow rays that pass through transmissive occluders (seed 001).
    pub transmissive_shadows: bool,
    /// Perfect-mirror reflection rays.
    pub mirror_reflection: bool,
    /// Dielectric boundaries: Snell refraction rays (seed 004).
    pub refraction: bool,
    /// Fresnel reflectance at dielectric boundaries with an index contrast (seed 004): the
    /// reflected share of a refraction event. Off for index-matched media (ior 1), which
    /// reflect nothing.
    pub fresnel: bool,
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
    /// Fog volumes: every segment attenuated and blended by its exact optical depth.
    pub fog: bool,
}

impl EffectSet {
    /// Every effect on: the general path.
    pub fn all() -> EffectSet {
        EffectSet {
            shadows: true,
            transmissive_shadows: true,
            mirror_reflection: true,
            refraction: true,
            fresnel: true,
            absorption: true,
            footprints: true,
            alpha_cutout: true,
            environment: true,
            depth_of_field: true,
            fog: true,
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
        let used = scene.worn_materials();
        let features: Vec<MaterialFeatures> =
            scene.materials.iter().map(MaterialFeatures::of).collect();
        // The worn materials with what they do.
        let materials = || {
            scene
                .materials
                .iter()
                .zip(&features)
                .zip(&used)
                .filter(|(_, used)| **used)
                .map(|(pair, _)| pair)
        };
        let find = |test: fn(&MaterialFeatures) -> bool| -> Option<&Material> {
            materials().find(|(_, f)| test(f)).map(|(m, _)| m)
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
        if let Some(m) = find(|f| !f.mirror.is_empty()) {
            set.mirror_reflection = true;
            because(
                "mirror reflection",
                format!("material '{}' has mirror {}", m.name, m.mirror),
            );
        }
        if let Some(m) = find(MaterialFeatures::refracts) {
            set.refraction = true;
            because(
                "refraction",
                format!("material '{}' has transmission {}", m.name, m.transmission),
            );
            if let Some(m) = find(MaterialFeatures::boundary_reflects) {
                set.fresnel = true;
                because(
                    "Fresnel",
                    format!(
                        "transmissive material '{}' has ior {} (an index contrast reflects)",
                        m.name, m.ior
                    ),
                );
            }
            if set.shadows {
                set.transmissive_shadows = true;
                because(
                    "transmissive shadows",
                    format!("lights shine through material '{}'", m.name),
                );
            }
        }
        if let Some(m) = find(|f| f.absorbs) {
            set.absorption = true;
            because(
                "Beer's-law absorption",
                format!(
                    "material '{}' has attenuation over {}",
                    m.name, m.attenuation_distance
                ),
            );
        }
        let textured = materials()
            .map(|(m, _)| m)
            .find(|m| m.base_color_texture.is_some());
        let env_texture = matches!(scene.environment, Environment::LatLong { .. });
        if lod != LodStrategy::Mip0 {
            if let Some(m) = textured {
                set.footprints = true;
                because(
                    "ray footprints",
                    format!("material '{}' has a base-colour texture", m.name),
                );
            } else if let Some(m) = find(|f| f.reads_textures) {
                set.footprints = true;
                because(
                    "ray footprints",
                    format!("material '{}' has a texture", m.name),
                );
            } else if env_texture {
                set.footprints = true;
                because(
                    "ray footprints",
                    "the environment is a lat-long texture".to_string(),
                );
            } else if let Some(m) = find(|f| f.cutout) {
                // Alpha cut-outs filter their mask over the ray cone (no shimmering leaves).
                set.footprints = true;
                because(
                    "ray footprints",
                    format!("material '{}' has an alpha texture", m.name),
                );
            }
        }
        // Cut-out filters run on meshes whose material has an alpha cutoff and an alpha
        // texture (a constant alpha either keeps the whole mesh or drops it before tracing).
        if let Some(mesh) = scene.meshes.iter().find(|mesh| {
            !mesh.triangles.is_empty()
                && !mesh.st.is_empty()
                && features.get(mesh.material).is_some_and(|f| f.cutout)
        }) {
            set.alpha_cutout = true;
            let m = &scene.materials[mesh.material];
            because(
                "alpha cut-out",
                format!(
                    "material '{}' has an alpha texture and cutoff {}",
                    m.name,
                    m.alpha_cutoff.unwrap_or_default()
                ),
            );
        } else if let Some(m) = scene
            .patches
            .iter()
            .map(|p| p.material)
            .chain(scene.height_patches.iter().map(|p| p.material))
            .filter(|&index| features.get(index).is_some_and(|f| f.cutout))
            .find_map(|index| scene.materials.get(index))
        {
            // Curved patches always have texture coordinates: their alpha test runs in
            // their user geometry's callbacks.
            set.alpha_cutout = true;
            because(
                "alpha cut-out",
                format!(
                    "material '{}' (on curved patches) has an alpha texture and cutoff {}",
                    m.name,
                    m.alpha_cutoff.unwrap_or_default()
                ),
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
        if let Some(volume) = scene.fog.iter().find(|v| v.density.sigma() > 0.0) {
            set.fog = true;
            because(
                "fog",
                format!(
                    "{} fog volume(s), e.g. {} fog with sigma {}",
                    scene.fog.len(),
                    volume.density.kind(),
                    volume.density.sigma()
                ),
            );
        }
        (set, reasons)
    }

    /// Names of the effects switched on.
    pub fn names(&self) -> Vec<&'static str> {
        self.flags()
            .into_iter()
            .zip(EFFECT_NAMES)
            .filter(|(on, _)| *on)
            .map(|(_, name)| name)
            .collect()
    }

    /// Every effect on its own, with its name, in the order of [`EffectSet::names`].
    pub fn singles() -> Vec<(&'static str, EffectSet)> {
        (0..EFFECT_NAMES.len())
            .map(|i| {
                let mut flags = [false; EFFECT_NAMES.len()];
                flags[i] = true;
                (EFFECT_NAMES[i], EffectSet::from_flags(flags))
            })
            .collect()
    }

    /// The effects on in `self` or in `other`.
    pub fn union(self, other: EffectSet) -> EffectSet {
        let (a, b) = (self.flags(), other.flags());
        EffectSet::from_flags(std::array::from_fn(|i| a[i] || b[i]))
    }

    /// The effects on in `self` but not in `other`.
    pub fn without(self, other: EffectSet) -> EffectSet {
        let (a, b) = (self.flags(), other.flags());
        EffectSet::from_flags(std::array::from_fn(|i| a[i] && !b[i]))
    }

    /// Whether every effect on in `other` is also on in `self`.
    pub fn includes(&self, other: &EffectSet) -> bool {
        other.without(*self) == EffectSet::default()
    }

    /// The flags in the order of [`EFFECT_NAMES`].
    fn flags(&self) -> [bool; EFFECT_NAMES.len()] {
        [
            self.shadows,
            self.transmissive_shadows,
            self.mirror_reflection,
            self.refraction,
            self.fresnel,
            self.absorption,
            self.footprints,
            self.alpha_cutout,
            self.environment,
            self.depth_of_field,
            self.fog,
        ]
    }

    fn from_flags(flags: [bool; EFFECT_NAMES.len()]) -> EffectSet {
        let [shadows, transmissive_shadows, mirror_reflection, refraction, fresnel, absorption, footprints, alpha_cutout, environment, depth_of_field, fog] =
            flags;
        EffectSet {
            shadows,
            transmissive_shadows,
            mirror_reflection,
            refraction,
            fresnel,
            absorption,
            footprints,
            alpha_cutout,
            environment,
            depth_of_field,
            fog,
        }
    }
}

/// The effects' names, as the summary line and `--stats` print them.
const EFFECT_NAMES: [&str; 11] = [
    "shadows",
    "transmissive shadows",
    "mirror reflection",
    "refraction",
    "Fresnel",
    "Beer's-law absorption",
    "ray footprints",
    "alpha cut-out",
    "environment light",
    "depth of field",
    "fog",
];

fn light_kind(light: &crate::scene::Light) -> &'static str {
    match light {
        crate::scene::Light::Point { .. } => "a point light",
        crate::scene::Light::Directional { .. } => "a directional light",
        crate::scene::Light::Spot { .. } => "a spot light",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn singles_cover_every_effect_once() {
        let singles = EffectSet::singles();
        assert_eq!(singles.len(), EFFECT_NAMES.len());
        let mut all = EffectSet::default();
        for (name, set) in &singles {
            assert_eq!(set.names(), vec![*name]);
            all = all.union(*set);
        }
        assert_eq!(all, EffectSet::all());
    }

    #[test]
    fn union_without_and_includes() {
        let shadows = EffectSet {
            shadows: true,
            ..EffectSet::default()
        };
        let mirror = EffectSet {
            mirror_reflection: true,
            ..EffectSet::default()
        };
        let both = shadows.union(mirror);
        assert_eq!(both.names(), vec!["shadows", "mirror reflection"]);
        assert!(both.includes(&shadows) && both.includes(&mirror));
        assert!(!shadows.includes(&both));
        assert_eq!(both.without(shadows), mirror);
        assert!(EffectSet::all().includes(&both));
        assert!(shadows.includes(&EffectSet::default()));
    }
}
