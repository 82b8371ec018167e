//! Scene loading against real-world files: Debian's assimp test models (glTF 2.0, OBJ),
//! including its deliberately malformed ones, which must give an error and never panic.
//! Tests that need `/usr/share/assimp/models` (package `assimp-testmodels`) fail with a
//! message naming `bash scripts/setup.sh` when it is absent.

use std::panic;
use std::path::{Path, PathBuf};

use conetrace::scene::load::{default_scene, load_scene};
use conetrace::scene::{Projection, TextureSource, WrapMode};

const MODELS: &str = "/usr/share/assimp/models";
const SETUP_HINT: &str = "run `bash scripts/setup.sh` (installs assimp-testmodels)";

/// The installed model at `relative`; a missing file fails the test.
fn model(relative: &str) -> PathBuf {
    let path = Path::new(MODELS).join(relative);
    assert!(
        path.exists(),
        "{} is not installed: {SETUP_HINT}",
        path.display()
    );
    path
}

fn all_model_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            all_model_files(&path, out);
        } else if let Some(ext) = path.extension().and_then(|e| e.to_str()) {
            if ["obj", "gltf", "glb"].contains(&ext.to_ascii_lowercase().as_str()) {
                out.push(path);
            }
        }
    }
}

#[test]
fn no_model_file_makes_the_loader_panic() {
    let mut files = Vec::new();
    all_model_files(Path::new(MODELS), &mut files);
    assert!(
        !files.is_empty(),
        "no OBJ or glTF files under {MODELS}: {SETUP_HINT}"
    );
    files.sort();
    let mut panicked = Vec::new();
    let (mut ok, mut err) = (0, 0);
    for file in &files {
        match panic::catch_unwind(|| load_scene(file)) {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(e)) => {
                let message = e.to_string();
                assert!(!message.contains('\n'), "multi-line message: {message}");
                assert!(
                    message.contains(&*file.file_name().unwrap().to_string_lossy()),
                    "{message}"
                );
                err += 1;
            }
            Err(_) => panicked.push(file.clone()),
        }
    }
    eprintln!("{} files: {ok} loaded, {err} rejected", files.len());
    assert!(panicked.is_empty(), "loader panicked on {panicked:?}");
    assert!(ok >= 10, "only {ok} files loaded");
}

#[test]
fn malformed_models_are_errors() {
    for relative in [
        "invalid/empty.obj",
        "glTF2/wrongTypes/badArray.gltf",
        "glTF2/wrongTypes/badNumber.gltf",
        "glTF2/wrongTypes/badObject.gltf",
        "glTF2/wrongTypes/badString.gltf",
        "glTF2/wrongTypes/badUint.gltf",
        "glTF2/IndexOutOfRange/IndexOutOfRange.gltf",
        "glTF2/IndexOutOfRange/AllIndicesOutOfRange.gltf",
        "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
        "glTF2/MissingBin/BoxTextured.gltf",
        "glTF2/RecursiveNodes/RecursiveNodes.gltf",
        "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf",
    ] {
        let path = model(relative);
        match load_scene(&path) {
            Ok(_) => panic!("{relative} loaded but is malformed"),
            Err(e) => eprintln!("{relative}: {e}"),
        }
    }
}

/// Every glTF 1.0 file gets the one message, whatever 1.0 construct the `gltf` crate would
/// trip over first (CesiumMilkTruck writes its version as a number).
#[test]
fn every_gltf_1_file_is_named_as_such() {
    for relative in [
        "glTF/BoxTextured-glTF/BoxTextured.gltf",
        "glTF/BoxTextured-glTF-Binary/BoxTextured.glb",
        "glTF/BoxTextured-glTF-Embedded/BoxTextured.gltf",
        "glTF/BoxTextured-glTF-MaterialsCommon/BoxTextured.gltf",
        "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf",
        "glTF/IncorrectVertexArrays/Cube_v1.gltf",
        "glTF/TwoBoxes/TwoBoxes.gltf",
    ] {
        let path = model(relative);
        let e = load_scene(&path).unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "{}: glTF 1.0 files are not supported (only glTF 2.0)",
                path.display()
            )
        );
    }
}

/// A required extension the loader lacks is named; a used one it ignores is a note.
#[test]
fn gltf_extensions_are_refused_or_noted_by_name() {
    for (relative, extension) in [
        (
            "glTF2/draco/2CylinderEngine.gltf",
            "KHR_draco_mesh_compression",
        ),
        (
            "glTF2/BoxTextured-glTF-techniqueWebGL/BoxTextured.gltf",
            "KHR_technique_webgl",
        ),
    ] {
        let path = model(relative);
        let e = load_scene(&path).unwrap_err().to_string();
        assert_eq!(
            e,
            format!(
                "{}: requires the glTF extension {extension}, which conetrace does not support",
                path.display()
            )
        );
    }
    for (relative, extension) in [
        (
            "glTF2/ClearCoat-glTF/ClearCoatTest.gltf",
            "KHR_materials_clearcoat",
        ),
        (
            "glTF2/BoxTextured-glTF-pbrSpecularGlossiness/BoxTextured.gltf",
            "KHR_materials_pbrSpecularGlossiness",
        ),
    ] {
        let path = model(relative);
        let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let note = format!(
            "{}: uses the glTF extension {extension}, which conetrace ignores",
            path.display()
        );
        assert!(scene.notes.contains(&note), "{:?}", scene.notes);
    }
}

/// BoxBadNormals' four zero normals are replaced by the face normal with a note, as an OBJ
/// file's `vn 0 0 0` are.
#[test]
fn zero_gltf_normals_are_repaired_with_a_note() {
    let path = model("glTF2/BoxBadNormals-glTF-Binary/BoxBadNormals.glb");
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let normals: Vec<_> = scene.meshes.iter().flat_map(|m| &m.normals).collect();
    assert_eq!(normals.len(), 24);
    assert!(normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    assert!(
        scene
            .notes
            .iter()
            .any(|n| n.contains("4 zero-length normals replaced by the surrounding faces' normal")),
        "{:?}",
        scene.notes
    );
}

#[test]
fn box_textured_loads_in_all_three_containers() {
    for (relative, expect_file) in [
        ("glTF2/BoxTextured-glTF/BoxTextured.gltf", true),
        ("glTF2/BoxTextured-glTF-Binary/BoxTextured.glb", false),
        ("glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf", false),
    ] {
        let path = model(relative);
        let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.meshes.len(), 1, "{relative}");
        let mesh = &scene.meshes[0];
        assert_eq!(mesh.triangles.len(), 12);
        assert_eq!(mesh.st.len(), mesh.positions.len());
        assert_eq!(mesh.normals.len(), mesh.positions.len());
        let binding = scene.materials[mesh.material]
            .base_color_texture
            .as_ref()
            .unwrap();
        let texture = &scene.textures[binding.texture];
        match &texture.source {
            TextureSource::File(file) => {
                assert!(expect_file);
                assert!(file.is_file());
            }
            TextureSource::Encoded { bytes, .. } => {
                assert!(!expect_file);
                assert_eq!(
                    &bytes[1..4],
                    b"PNG",
                    "{relative}: image bytes are not the encoded PNG"
                );
            }
        }
        // A file with no camera or lights gets both, with notes.
        assert!(scene.camera.is_some() && !scene.lights.is_empty());
        assert_eq!(scene.notes.len(), 2, "{:?}", scene.notes);
    }
}

#[test]
fn engine_and_obj_models_load() {
    for relative in [
        "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
        "OBJ/spider.obj",
        "OBJ/WusonOBJ.obj",
        "OBJ/box.obj",
    ] {
        let path = model(relative);
        let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
        let triangles: usize = scene.meshes.iter().map(|m| m.triangles.len()).sum();
        assert!(triangles >= 12, "{relative}: {triangles} triangles");
        assert!(scene.bounds().is_some());
    }
}

#[test]
fn texture_transform_test_model_has_transforms_and_clamp_samplers() {
    let path = model("glTF2/textureTransform/TextureTransformTest.gltf");
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let transformed = scene
        .materials
        .iter()
        .filter_map(|m| m.base_color_texture.as_ref())
        .filter(|b| b.transform != glam::Affine2::IDENTITY)
        .count();
    assert!(transformed >= 4, "{transformed} transformed bindings");
    assert!(scene.textures.iter().any(|t| t.wrap_s == WrapMode::Clamp));
}

#[test]
fn gltf_cameras_become_scene_cameras() {
    let path = model("glTF2/cameras/Cameras.gltf");
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let camera = scene.camera.unwrap();
    assert!(matches!(
        camera.projection,
        Projection::Pinhole { .. } | Projection::Orthographic { .. }
    ));
    assert!(!scene.notes.iter().any(|n| n.starts_with("no camera")));
}

#[test]
fn default_scene_has_no_notes_and_embedded_textures() {
    let scene = default_scene();
    assert!(scene.notes.is_empty(), "{:?}", scene.notes);
    assert!(scene
        .textures
        .iter()
        .all(|t| matches!(t.source, TextureSource::Encoded { .. })));
}
