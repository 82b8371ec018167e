//! Scene loading: TOML scenes, OBJ + MTL and glTF 2.0 files become a validated
//! [`SceneDescription`].
//!
//! [`load_scene`] picks the format from the file extension. OBJ and glTF files may be
//! rendered directly or pulled into a TOML scene with `[[mesh]]`; either way a scene
//! without a camera gets one from [`frame_camera`] and a scene without lights gets a key
//! light and an environment colour, each recorded in `SceneDescription::notes`. Every
//! problem (missing file, syntax error, unknown name, `nan`, zero image size, ...) is a
//! [`SceneError`] whose message is one line naming the file. Textures are only located
//! and checked for readability here; `crate::texture` decodes them.
//!
//! ```toml
//! [camera]
//! eye = [0, 1, 5]
//! target = [0, 1, 0]
//!
//! [[material]]
//! name = "glass"
//! transmission = 1.0
//! ior = 1.5
//!
//! [[sphere]]
//! center = [0, 1, 0]
//! radius = 1
//! material = "glass"
//! ```

mod default_scene;
mod error;
mod files;
mod fog;
mod framing;
mod gltf;
mod merge;
mod normals;
mod obj;
mod obj_text;
mod patches;
mod polygon;
mod toml_format;
mod uri;
mod validate;

use std::path::Path;

pub use default_scene::{default_scene, DEFAULT_SCENE_LABEL};
pub use error::{one_line, SceneError};
pub use framing::{frame_camera, FRAMING_FOV_DEGREES, LAMP_RADIANCE};
pub use validate::validate;

use crate::scene::SceneDescription;
use files::Files;
use framing::EmitterRule;

/// The file formats a scene can be loaded from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Toml,
    Obj,
    Gltf,
}

/// The format named by `path`'s extension (case-insensitive).
fn format_of(path: &Path) -> Result<Format, SceneError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match extension.as_str() {
        "toml" => Ok(Format::Toml),
        "obj" => Ok(Format::Obj),
        "gltf" | "glb" => Ok(Format::Gltf),
        _ => Err(SceneError::UnknownFormat {
            file: path.display().to_string(),
            extension,
        }),
    }
}

/// Loads a scene from a `.toml`, `.obj`, `.gltf` or `.glb` file (extension case-insensitive),
/// adds a camera and lights when missing, and validates the result.
pub fn load_scene(path: &Path) -> Result<SceneDescription, SceneError> {
    let label = path.display().to_string();
    if path.is_dir() {
        return Err(SceneError::invalid(
            &label,
            "is a directory, not a scene file",
        ));
    }
    let base_dir = path.parent().unwrap_or(Path::new(""));
    let files = Files::disk(base_dir);
    let format = format_of(path)?;
    let mut scene = match format {
        Format::Toml => {
            let bytes = files.read(path)?;
            let text = String::from_utf8(bytes)
                .map_err(|_| SceneError::invalid(&label, "not UTF-8 text"))?;
            toml_format::parse(&text, &files, &label)?
        }
        Format::Obj | Format::Gltf => {
            let mut scene = SceneDescription {
                source: label.clone(),
                ..Default::default()
            };
            merge::append(&mut scene, load_part(&files, path)?, None, None);
            scene
        }
    };
    scene.input_files = files.read_so_far();
    let rule = match format {
        Format::Toml => EmitterRule::AnyEmitter,
        Format::Obj | Format::Gltf => EmitterRule::LampsOnly,
    };
    finish(scene, rule)
}

/// Parses TOML scene text; relative file names resolve against `base_dir`, and messages name
/// `source_label`. Missing camera and lights are added and the result is validated.
pub fn load_toml_str(
    text: &str,
    base_dir: &Path,
    source_label: &str,
) -> Result<SceneDescription, SceneError> {
    let files = Files::disk(base_dir);
    let mut scene = toml_format::parse(text, &files, source_label)?;
    scene.input_files = files.read_so_far();
    finish(scene, EmitterRule::AnyEmitter)
}

/// An OBJ or glTF file as a scene part (world-space meshes, materials, textures, lights,
/// camera), not yet completed or validated.
fn load_part(files: &Files, path: &Path) -> Result<SceneDescription, SceneError> {
    match format_of(path)? {
        Format::Obj => obj::load_obj(files, path),
        Format::Gltf => gltf::load_gltf(files, path),
        Format::Toml => Err(SceneError::UnknownFormat {
            file: path.display().to_string(),
            extension: "toml (a scene cannot be included as a mesh)".into(),
        }),
    }
}

/// The triangles of the OBJ or glTF file at `path` as a part, for a closed mesh that bounds
/// fog: like [`load_part`], but a glTF file's own fog is not read (it could name this very
/// file as its bounds, and loading would never end).
fn load_bounds_mesh(files: &Files, path: &Path) -> Result<SceneDescription, SceneError> {
    match format_of(path)? {
        Format::Gltf => gltf::load_gltf_with(files, path, false),
        _ => load_part(files, path),
    }
}

/// Adds a missing camera and lights (counting emitters by `rule`), then validates, and
/// refuses a scene with nothing to see.
fn finish(mut scene: SceneDescription, rule: EmitterRule) -> Result<SceneDescription, SceneError> {
    framing::add_missing_camera_and_lights(&mut scene, rule);
    validate(&scene)?;
    if !has_something_to_render(&scene) {
        return Err(SceneError::invalid(
            &scene.source,
            "no geometry: no mesh, sphere, patch, fog or environment map to render",
        ));
    }
    Ok(scene)
}

/// Whether `scene` holds anything a camera ray can meet: geometry (emitters included), fog,
/// or an environment map (an environment-only scene shows the map). Without any, every
/// pixel is the same colour: an empty file or a scene whose geometry was left out.
fn has_something_to_render(scene: &SceneDescription) -> bool {
    scene.meshes.iter().any(|mesh| !mesh.triangles.is_empty())
        || !scene.spheres.is_empty()
        || !scene.patches.is_empty()
        || !scene.height_patches.is_empty()
        || !scene.fog.is_empty()
        || matches!(scene.environment, crate::scene::Environment::LatLong { .. })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_dispatch_case_insensitively() {
        assert_eq!(format_of(Path::new("a/B.TOML")).unwrap(), Format::Toml);
        assert_eq!(format_of(Path::new("x.Obj")).unwrap(), Format::Obj);
        assert_eq!(format_of(Path::new("x.GLB")).unwrap(), Format::Gltf);
        let e = format_of(Path::new("x.fbx")).unwrap_err().to_string();
        assert!(e.starts_with("x.fbx: unknown scene format 'fbx'"), "{e}");
        assert!(load_scene(Path::new("noext")).is_err());
    }

    #[test]
    fn a_directory_is_not_a_scene_file() {
        let dir = std::env::temp_dir();
        let e = load_scene(&dir).unwrap_err().to_string();
        assert_eq!(
            e,
            format!("{}: is a directory, not a scene file", dir.display())
        );
    }

    #[test]
    fn a_scene_with_nothing_to_render_is_an_error_naming_it() {
        for text in [
            "",
            "[render]\nwidth = 8\n",
            "[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\n",
            "[environment]\ncolor = [0.2, 0.3, 0.4]\n",
        ] {
            let e = load_toml_str(text, Path::new("."), "empty.toml")
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("empty.toml: no geometry"), "{text:?}: {e}");
        }
        // Fog alone is something to see.
        let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 0.1\n";
        assert!(load_toml_str(fog, Path::new("."), "fog.toml").is_ok());
    }

    #[test]
    fn missing_scene_file_is_an_error_naming_it() {
        let e = load_scene(Path::new("/nonexistent/scene.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("/nonexistent/scene.toml: cannot read"), "{e}");
    }

    #[test]
    fn toml_without_camera_or_lights_gets_defaults_and_notes() {
        let text = "[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n";
        let s = load_toml_str(text, Path::new("."), "t.toml").unwrap();
        assert!(s.camera.is_some());
        assert_eq!(s.lights.len(), 1);
        assert_eq!(s.notes.len(), 2);
        assert_eq!(s.materials.len(), 1);
    }
}
