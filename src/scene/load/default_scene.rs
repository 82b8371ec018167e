//! The built-in default scene: `assets/scenes/default.toml` and the files it references,
//! compiled into the binary so it renders from any working directory.

use super::files::Files;
use super::framing::EmitterRule;
use super::toml_format;
use crate::scene::{Environment, Material, SceneDescription, Sphere};

/// `SceneDescription::source` of the built-in scene.
pub const DEFAULT_SCENE_LABEL: &str = "<built-in default scene>";

/// The scene text; its relative paths resolve against `assets/scenes` in [`EMBEDDED`].
const SCENE_TEXT: &str = include_str!("../../../assets/scenes/default.toml");

/// Every file the default scene references, keyed by its path in the repository.
static EMBEDDED: &[(&str, &[u8])] = &[
    (
        "assets/models/ground.obj",
        include_bytes!("../../../assets/models/ground.obj"),
    ),
    (
        "assets/models/crate.obj",
        include_bytes!("../../../assets/models/crate.obj"),
    ),
    (
        "assets/models/crate.mtl",
        include_bytes!("../../../assets/models/crate.mtl"),
    ),
    (
        "assets/textures/checker.png",
        include_bytes!("../../../assets/textures/checker.png"),
    ),
    (
        "assets/textures/crate.png",
        include_bytes!("../../../assets/textures/crate.png"),
    ),
    (
        "assets/textures/sky.png",
        include_bytes!("../../../assets/textures/sky.png"),
    ),
];

/// The built-in default scene, identical to loading `assets/scenes/default.toml` except that
/// textures are `TextureSource::Encoded` (labelled with their repository paths).
///
/// The embedded files are checked by this module's tests; should they ever fail to load,
/// a single grey sphere is returned with the error in `notes` rather than panicking.
pub fn default_scene() -> SceneDescription {
    let files = Files::embedded("assets/scenes", EMBEDDED);
    match toml_format::parse(SCENE_TEXT, &files, DEFAULT_SCENE_LABEL)
        .and_then(|scene| super::finish(scene, EmitterRule::AnyEmitter))
    {
        Ok(scene) => scene,
        Err(e) => {
            let mut scene = SceneDescription {
                source: DEFAULT_SCENE_LABEL.into(),
                materials: vec![Material::default()],
                spheres: vec![Sphere {
                    center: glam::Vec3::ZERO,
                    radius: 1.0,
                    material: 0,
                }],
                environment: Environment::Color(glam::Vec3::splat(0.5)),
                notes: vec![format!(
                    "the built-in scene failed to load ({e}); showing a sphere"
                )],
                ..Default::default()
            };
            super::framing::add_missing_camera_and_lights(&mut scene, EmitterRule::AnyEmitter);
            scene
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Light, Projection, TextureSource};
    use std::path::{Path, PathBuf};

    fn assets_dir() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets")
    }

    #[test]
    fn default_scene_loads_without_notes() {
        let scene = default_scene();
        assert!(scene.notes.is_empty(), "{:?}", scene.notes);
        assert_eq!(scene.source, DEFAULT_SCENE_LABEL);
        assert_eq!((scene.settings.width, scene.settings.height), (640, 360));
        let camera = scene.camera.as_ref().unwrap();
        assert!(
            matches!(camera.projection, Projection::Pinhole { vfov_degrees } if vfov_degrees == 45.0)
        );
        assert!(matches!(scene.lights[..], [Light::Point { .. }]));
        assert!(matches!(scene.environment, Environment::LatLong { .. }));
        // Ground plane (400 x 400) and crate (24 vertices, 12 triangles).
        assert_eq!(scene.meshes.len(), 2);
        let (lo, hi) = scene.bounds().unwrap();
        assert_eq!(hi.x - lo.x, 400.0);
        assert_eq!(scene.meshes[1].triangles.len(), 12);
        assert!(scene.meshes.iter().all(|m| m.st.len() == m.positions.len()));
        let glass = scene
            .materials
            .iter()
            .find(|m| m.transmission == 1.0)
            .unwrap();
        assert_eq!(glass.ior, 1.5);
        assert!(glass.attenuation_distance.is_finite());
        assert!(scene.materials.iter().any(|m| m.mirror > 0.0));
        assert_eq!(scene.textures.len(), 3);
    }

    #[test]
    fn embedded_table_matches_the_asset_files() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        for (name, bytes) in EMBEDDED {
            assert_eq!(std::fs::read(root.join(name)).unwrap(), *bytes, "{name}");
        }
        assert_eq!(
            std::fs::read_to_string(root.join("assets/scenes/default.toml")).unwrap(),
            SCENE_TEXT
        );
    }

    /// Loading the asset file from disk gives the same scene, with file textures whose
    /// contents equal the embedded bytes.
    #[test]
    fn default_scene_equals_loading_the_asset_file() {
        let path = assets_dir().join("scenes/default.toml");
        let built_in = default_scene();
        let loaded = super::super::load_scene(&path).unwrap();
        assert_eq!(built_in.camera, loaded.camera);
        assert_eq!(built_in.lights, loaded.lights);
        assert_eq!(built_in.materials, loaded.materials);
        assert_eq!(built_in.spheres, loaded.spheres);
        assert_eq!(built_in.environment, loaded.environment);
        assert_eq!(built_in.settings, loaded.settings);
        assert_eq!(built_in.notes, loaded.notes);
        assert_eq!(built_in.meshes.len(), loaded.meshes.len());
        for (a, b) in built_in.meshes.iter().zip(&loaded.meshes) {
            assert_eq!(
                (&a.positions, &a.normals, &a.st, &a.triangles, a.material),
                (&b.positions, &b.normals, &b.st, &b.triangles, b.material)
            );
        }
        assert_eq!(built_in.textures.len(), loaded.textures.len());
        for (a, b) in built_in.textures.iter().zip(&loaded.textures) {
            assert_eq!(
                (&a.name, a.color_space, a.wrap_s, a.wrap_t),
                (&b.name, b.color_space, b.wrap_s, b.wrap_t)
            );
            let (TextureSource::Encoded { bytes, .. }, TextureSource::File(file)) =
                (&a.source, &b.source)
            else {
                panic!(
                    "unexpected texture sources {:?} / {:?}",
                    a.source.label(),
                    b.source.label()
                );
            };
            assert_eq!(**bytes, std::fs::read(file).unwrap());
        }
    }
}
