//! Defaults for scenes that lack a camera or lights: a pinhole camera that frames the
//! geometry's bounding sphere, and a key light with a grey-blue environment.

use glam::Vec3;

use crate::scene::{CameraDesc, Environment, Light, Projection, SceneDescription};

/// Vertical field of view of a framing camera, in degrees.
pub const FRAMING_FOV_DEGREES: f32 = 40.0;
/// Direction from the bounds' centre towards a framing camera (before normalisation).
const VIEW_DIRECTION: Vec3 = Vec3::new(0.5, 0.4, 1.0);
/// Environment colour added along with the default key light.
pub const DEFAULT_ENVIRONMENT: Vec3 = Vec3::new(0.3, 0.32, 0.38);

/// Centre and radius of the sphere around the scene's bounds (a unit sphere at the origin
/// for an empty scene).
fn bounding_sphere(scene: &SceneDescription) -> (Vec3, f32) {
    match scene.bounds() {
        Some((lo, hi)) if lo.is_finite() && hi.is_finite() => {
            ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3))
        }
        _ => (Vec3::ZERO, 1.0),
    }
}

/// A pinhole camera (fov 40 degrees) looking at the centre of the scene's bounds from the
/// direction (0.5, 0.4, 1), just far enough that the bounding sphere fits both the vertical
/// and (for `aspect` = width / height below 1) the horizontal field of view.
pub fn frame_camera(scene: &SceneDescription, aspect: f32) -> CameraDesc {
    let (center, radius) = bounding_sphere(scene);
    let aspect = if aspect.is_finite() && aspect > 0.0 {
        aspect
    } else {
        1.0
    };
    let half_v = (FRAMING_FOV_DEGREES * 0.5).to_radians();
    let half_h = (aspect * half_v.tan()).atan();
    let distance = radius / half_v.min(half_h).sin();
    CameraDesc {
        eye: center + VIEW_DIRECTION.normalize() * distance,
        target: center,
        up: Vec3::Y,
        projection: Projection::Pinhole {
            vfov_degrees: FRAMING_FOV_DEGREES,
        },
    }
}

/// Which emissive geometry counts as the scene's lighting when deciding whether it needs the
/// default key light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum EmitterRule {
    /// A TOML scene: its author wrote every emission, so any emitter lights it.
    AnyEmitter,
    /// A model file (OBJ, glTF) rendered as it is: only a lamp lights it, an emitter whose
    /// radiance exceeds [`LAMP_RADIANCE`] in some channel. Models mark glowing surfaces
    /// (labels, screens, indicators) emissive at radiance 1 or less (glTF's
    /// `emissiveFactor` cannot exceed 1 without `KHR_materials_emissive_strength`) and
    /// expect the viewer to light them.
    LampsOnly,
}

/// The radiance above which a model's emitter is a lamp: a white diffuse surface under the
/// default key light has radiance 1, so a dimmer emitter glows without lighting its
/// surroundings noticeably.
pub const LAMP_RADIANCE: f32 = 1.0;

/// Whether anything lights the scene besides punctual lights: a non-black environment, or
/// geometry (a mesh, sphere or patch) whose material emits, as `rule` counts emitters.
fn lit_without_lights(scene: &SceneDescription, rule: EmitterRule) -> bool {
    let environment = match &scene.environment {
        Environment::Color(c) => c.max_element() > 0.0,
        Environment::LatLong { intensity, .. } => *intensity > 0.0,
    };
    let threshold = match rule {
        EmitterRule::AnyEmitter => 0.0,
        EmitterRule::LampsOnly => LAMP_RADIANCE,
    };
    let emits = |material: usize| {
        scene
            .materials
            .get(material)
            .is_some_and(|m| m.emission.max_element() > threshold)
    };
    environment || scene.geometry_materials().any(emits)
}

/// Whether some geometry emits at all (any radiance above 0).
fn has_emitters(scene: &SceneDescription) -> bool {
    scene.geometry_materials().any(|material| {
        scene
            .materials
            .get(material)
            .is_some_and(crate::shading::material_features::emits)
    })
}

/// Adds a framing camera when there is none and a key light (plus, when the environment is
/// black, the grey-blue environment) when nothing lights the scene: no punctual light, no
/// emissive geometry that `rule` counts as light, and a black environment. Notes each
/// addition in `scene.notes`.
pub(crate) fn add_missing_camera_and_lights(scene: &mut SceneDescription, rule: EmitterRule) {
    if scene.camera.is_none() {
        let aspect = scene.settings.width as f32 / scene.settings.height.max(1) as f32;
        scene.camera = Some(frame_camera(scene, aspect));
        scene
            .notes
            .push("no camera: placed one to frame the bounds".into());
    }
    if scene.lights.is_empty() && !lit_without_lights(scene, rule) {
        let glowing = has_emitters(scene);
        let (center, radius) = bounding_sphere(scene);
        let (eye, up) = scene
            .camera
            .as_ref()
            .map_or((center + Vec3::Z * 3.0 * radius, Vec3::Y), |c| {
                (c.eye, c.up.normalize_or_zero())
            });
        let back = (eye - center).normalize_or_zero();
        // Above and a little behind the camera, so shadows fall away from the viewer.
        let position = eye + back * (0.5 * radius) + up * (1.5 * radius);
        let distance_squared = (position - center).length_squared().max(1e-6);
        // Irradiance pi at the centre: a white diffuse surface facing the light has radiance 1.
        scene.lights.push(Light::Point {
            position,
            color: Vec3::ONE,
            intensity: std::f32::consts::PI * distance_squared,
        });
        if scene.environment == Environment::Color(Vec3::ZERO) {
            scene.environment = Environment::Color(DEFAULT_ENVIRONMENT);
        }
        scene.notes.push(if glowing {
            format!(
                "no lights (its emitters, of radiance {LAMP_RADIANCE} or less, glow but are not \
                 lamps): added a default key light and environment"
            )
        } else {
            "no lights: added a default key light and environment".into()
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Sphere};

    fn one_sphere(center: Vec3, radius: f32) -> SceneDescription {
        SceneDescription {
            materials: vec![Material::default()],
            spheres: vec![Sphere {
                center,
                radius,
                material: 0,
            }],
            ..Default::default()
        }
    }

    /// Angle between the view axis and the ray from the eye tangent to the bounding sphere.
    fn tangent_angle(camera: &CameraDesc, center: Vec3, radius: f32) -> f32 {
        (radius / (camera.eye - center).length()).asin()
    }

    #[test]
    fn framing_fits_the_bounding_sphere_vertically() {
        let center = Vec3::new(3.0, -1.0, 2.0);
        let scene = one_sphere(center, 2.0);
        let camera = frame_camera(&scene, 16.0 / 9.0);
        assert_eq!(camera.target, center);
        let bound_radius = 2.0 * 3f32.sqrt();
        let angle = tangent_angle(&camera, center, bound_radius);
        assert!((angle - 20f32.to_radians()).abs() < 1e-4, "{angle}");
        let dir = (camera.eye - center).normalize();
        assert!((dir - VIEW_DIRECTION.normalize()).length() < 1e-5);
    }

    #[test]
    fn narrow_images_frame_by_the_horizontal_fov() {
        let scene = one_sphere(Vec3::ZERO, 1.0);
        let wide = frame_camera(&scene, 2.0);
        let tall = frame_camera(&scene, 0.5);
        assert!(tall.eye.length() > wide.eye.length() * 1.5);
        let half_h = (0.5 * 20f32.to_radians().tan()).atan();
        assert!((tangent_angle(&tall, Vec3::ZERO, 3f32.sqrt()) - half_h).abs() < 1e-4);
    }

    #[test]
    fn missing_camera_and_lights_are_added_with_notes() {
        let mut scene = one_sphere(Vec3::ZERO, 1.0);
        add_missing_camera_and_lights(&mut scene, EmitterRule::AnyEmitter);
        assert!(scene.camera.is_some());
        assert_eq!(scene.lights.len(), 1);
        assert_eq!(scene.environment, Environment::Color(DEFAULT_ENVIRONMENT));
        assert_eq!(scene.notes.len(), 2);
        let Light::Point { position, .. } = scene.lights[0] else {
            panic!("not a point light")
        };
        assert!(position.y > scene.camera.as_ref().unwrap().eye.y);
        // Nothing more is added the second time.
        add_missing_camera_and_lights(&mut scene, EmitterRule::AnyEmitter);
        assert_eq!(scene.notes.len(), 2);
    }

    #[test]
    fn emissive_geometry_or_an_environment_keeps_the_key_light_away() {
        // Lit by an emissive sphere alone: no key light, no environment added.
        let mut scene = one_sphere(Vec3::ZERO, 1.0);
        scene.materials[0].emission = Vec3::splat(2.0);
        add_missing_camera_and_lights(&mut scene, EmitterRule::AnyEmitter);
        assert!(scene.lights.is_empty());
        assert_eq!(scene.environment, Environment::Color(Vec3::ZERO));
        // Lit by the environment alone.
        let mut scene = one_sphere(Vec3::ZERO, 1.0);
        scene.environment = Environment::Color(Vec3::splat(0.5));
        add_missing_camera_and_lights(&mut scene, EmitterRule::AnyEmitter);
        assert!(scene.lights.is_empty());
        // An emissive material no geometry uses lights nothing: the key light comes.
        let mut scene = one_sphere(Vec3::ZERO, 1.0);
        scene.materials.push(Material {
            emission: Vec3::ONE,
            ..Material::default()
        });
        add_missing_camera_and_lights(&mut scene, EmitterRule::AnyEmitter);
        assert_eq!(scene.lights.len(), 1);
    }

    /// An emissive marched height patch lights the scene as its exact (Bezier) form does:
    /// no key light or environment is added for either. The marched one used to be left out
    /// of the emitters, so one scene gained lights or not depending on `trace`.
    #[test]
    fn an_emissive_height_patch_keeps_the_key_light_away() {
        let tile = crate::scene::patch::height::HeightPatch {
            min: glam::Vec2::splat(-1.0),
            max: glam::Vec2::splat(1.0),
            heights: [0.0; 16],
            material: 0,
            march_step: 0.01,
        };
        let emissive = Material {
            emission: Vec3::splat(2.0),
            ..Material::default()
        };
        let marched = SceneDescription {
            materials: vec![emissive.clone()],
            height_patches: vec![tile.clone()],
            ..Default::default()
        };
        let exact = SceneDescription {
            materials: vec![emissive],
            patches: vec![tile.to_bezier()],
            ..Default::default()
        };
        for mut scene in [marched, exact] {
            add_missing_camera_and_lights(&mut scene, EmitterRule::AnyEmitter);
            assert!(scene.lights.is_empty(), "{:?}", scene.notes);
            assert_eq!(scene.environment, Environment::Color(Vec3::ZERO));
        }
    }

    #[test]
    fn a_model_s_glowing_surfaces_do_not_replace_the_key_light_but_its_lamps_do() {
        let glowing = |radiance: f32| {
            let mut scene = one_sphere(Vec3::ZERO, 1.0);
            scene.materials.push(Material {
                emission: Vec3::new(radiance, 0.5 * radiance, 0.0),
                ..Material::default()
            });
            scene.spheres.push(Sphere {
                center: Vec3::X * 3.0,
                radius: 0.1,
                material: 1,
            });
            scene
        };
        // A label of radiance 1 in a model file: the key light and environment come, and the
        // note says why its emitters did not count.
        let mut label = glowing(1.0);
        add_missing_camera_and_lights(&mut label, EmitterRule::LampsOnly);
        assert_eq!(label.lights.len(), 1);
        assert_eq!(label.environment, Environment::Color(DEFAULT_ENVIRONMENT));
        assert!(
            label.notes.iter().any(|n| n.contains("glow")),
            "{:?}",
            label.notes
        );
        // A lamp brighter than 1 lights the model alone.
        let mut lamp = glowing(1.5);
        add_missing_camera_and_lights(&mut lamp, EmitterRule::LampsOnly);
        assert!(lamp.lights.is_empty(), "{:?}", lamp.notes);
        // A TOML scene's emitters light it at any radiance.
        let mut authored = glowing(0.25);
        add_missing_camera_and_lights(&mut authored, EmitterRule::AnyEmitter);
        assert!(authored.lights.is_empty(), "{:?}", authored.notes);
    }
}
