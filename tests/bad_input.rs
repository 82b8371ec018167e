//! Every kind of bad input gets exit status 2, one line naming the file, and no output.

mod common;

use common::*;

const GOOD_SCENE: &str = r#"
[render]
width = 8
height = 8

[camera]
type = "pinhole"
eye = [0.0, 1.0, 4.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 40.0

[[light]]
type = "point"
position = [0.0, 4.0, 0.0]
color = [1.0, 1.0, 1.0]
intensity = 10.0

[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]

[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "matte"
"#;

/// Run `render scene_file` in `dir` and check the failure contract: status 2, one line on
/// stderr mentioning `names`, no output file.
fn assert_rejected(dir: &std::path::Path, scene_file: &str, extra: &[&str], names: &str) {
    let mut args = vec!["render", scene_file, "-o", "out.exr", "--quiet"];
    args.extend_from_slice(extra);
    let out = run_in(dir, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{scene_file}: stderr {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(
        lines.len(),
        1,
        "{scene_file}: expected one line, got {stderr:?}"
    );
    assert!(
        lines[0].contains(names),
        "{scene_file}: '{}' does not name '{names}'",
        lines[0]
    );
    assert!(
        !dir.join("out.exr").exists(),
        "{scene_file}: an output was written"
    );
    assert!(
        !dir.join("out.png").exists(),
        "{scene_file}: a PNG was written"
    );
}

#[test]
fn the_good_scene_renders() {
    let dir = temp_dir();
    write(dir.path(), "good.toml", GOOD_SCENE);
    let out = run_in(
        dir.path(),
        &["render", "good.toml", "-o", "out.exr", "--quiet"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.path().join("out.exr").exists());
    assert!(dir.path().join("out.png").exists());
}

#[test]
fn missing_scene_file() {
    let dir = temp_dir();
    assert_rejected(dir.path(), "nowhere.toml", &[], "nowhere.toml");
}

#[test]
fn missing_mesh_file() {
    let dir = temp_dir();
    let text = format!("{GOOD_SCENE}\n[[mesh]]\nfile = \"absent.obj\"\nmaterial = \"matte\"\n");
    write(dir.path(), "s.toml", &text);
    assert_rejected(dir.path(), "s.toml", &[], "absent.obj");
}

#[test]
fn malformed_toml_reports_line_and_column() {
    let dir = temp_dir();
    let text = GOOD_SCENE.replace("radius = 1.0", "radius = = 1.0");
    write(dir.path(), "broken.toml", &text);
    let out = run_in(
        dir.path(),
        &["render", "broken.toml", "-o", "out.exr", "--quiet"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    let line = GOOD_SCENE
        .lines()
        .position(|l| l.contains("radius"))
        .unwrap()
        + 1;
    assert!(stderr.contains(&format!("broken.toml:{line}:")), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(!dir.path().join("out.exr").exists());
}

#[test]
fn unknown_material_name() {
    let dir = temp_dir();
    write(
        dir.path(),
        "s.toml",
        &GOOD_SCENE.replace("material = \"matte\"", "material = \"matt\""),
    );
    assert_rejected(dir.path(), "s.toml", &[], "matt");
}

#[test]
fn unknown_texture_name() {
    let dir = temp_dir();
    let text = GOOD_SCENE.replace(
        "base_color = [0.5, 0.5, 0.5]",
        "base_color = [0.5, 0.5, 0.5]\nbase_color_texture = \"nosuch\"",
    );
    write(dir.path(), "s.toml", &text);
    assert_rejected(dir.path(), "s.toml", &[], "nosuch");
}

#[test]
fn nan_and_infinite_numbers() {
    let dir = temp_dir();
    write(
        dir.path(),
        "nan.toml",
        &GOOD_SCENE.replace("radius = 1.0", "radius = nan"),
    );
    assert_rejected(dir.path(), "nan.toml", &[], "nan.toml");
    write(
        dir.path(),
        "inf.toml",
        &GOOD_SCENE.replace("intensity = 10.0", "intensity = inf"),
    );
    assert_rejected(dir.path(), "inf.toml", &[], "inf.toml");
}

#[test]
fn zero_area_image_size() {
    let dir = temp_dir();
    write(
        dir.path(),
        "zero.toml",
        &GOOD_SCENE.replace("width = 8", "width = 0"),
    );
    assert_rejected(dir.path(), "zero.toml", &[], "zero.toml");
    write(dir.path(), "good.toml", GOOD_SCENE);
    assert_rejected(dir.path(), "good.toml", &["--height", "0"], "--height");
}

#[test]
fn unreadable_texture() {
    let dir = temp_dir();
    write(dir.path(), "fake.png", "this is not a PNG file");
    let text = GOOD_SCENE
        .replace(
            "[[material]]",
            "[[texture]]\nname = \"fake\"\nfile = \"fake.png\"\n\n[[material]]",
        )
        .replace(
            "base_color = [0.5, 0.5, 0.5]",
            "base_color = [0.5, 0.5, 0.5]\nbase_color_texture = \"fake\"",
        );
    write(dir.path(), "s.toml", &text);
    assert_rejected(dir.path(), "s.toml", &[], "fake.png");
}

#[test]
fn a_corrupt_image_is_called_undecodable_not_badly_sized() {
    // A PNG signature followed by garbage, and bytes of no known format, each as a TOML
    // texture, a glTF image file and a glTF image embedded as a data URI.
    let dir = temp_dir();
    let mut corrupt_png = b"\x89PNG\r\n\x1a\n".to_vec();
    corrupt_png.extend((0..200u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
    std::fs::write(dir.path().join("corrupt.png"), &corrupt_png).unwrap();
    std::fs::write(
        dir.path().join("noise.png"),
        [7u8, 1, 200, 3, 99, 42, 0, 13, 8],
    )
    .unwrap();
    let expectations = [
        ("corrupt.png", "cannot decode image"),
        ("noise.png", "unrecognised image format"),
    ];
    for (image, problem) in expectations {
        let toml = GOOD_SCENE
            .replace(
                "[[material]]",
                &format!("[[texture]]\nname = \"t\"\nfile = \"{image}\"\n\n[[material]]"),
            )
            .replace(
                "base_color = [0.5, 0.5, 0.5]",
                "base_color = [0.5, 0.5, 0.5]\nbase_color_texture = \"t\"",
            );
        write(dir.path(), "s.toml", &toml);
        let uri = format!("\"{image}\"");
        let embedded = format!(
            "\"data:image/png;base64,{}\"",
            base64(&std::fs::read(dir.path().join(image)).unwrap())
        );
        write(dir.path(), "file.gltf", &textured_triangle_gltf(&uri));
        write(
            dir.path(),
            "embedded.gltf",
            &textured_triangle_gltf(&embedded),
        );
        for (scene, names) in [
            ("s.toml", image),
            ("file.gltf", image),
            ("embedded.gltf", "embedded.gltf"),
        ] {
            assert_rejected(dir.path(), scene, &[], names);
            let out = run_in(dir.path(), &["render", scene, "-o", "out.exr", "--quiet"]);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(
                stderr.contains(problem) && !stderr.contains("dimensions"),
                "{scene} with {image}: {stderr}"
            );
        }
    }
}

/// A glTF with one textured triangle whose base colour texture's image has the URI `uri`
/// (JSON string, quoted).
fn textured_triangle_gltf(uri: &str) -> String {
    // Positions (0,0,0) (1,0,0) (0,1,0) then texture coordinates (0,0) (1,0) (0,1), as f32.
    let floats: [f32; 15] = [
        0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0,
    ];
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
"textures":[{{"source":0}}],"images":[{{"uri":{uri}}}],
"buffers":[{{"byteLength":60,"uri":"data:application/octet-stream;base64,{}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}]}}"#,
        base64(&bytes)
    )
}

#[test]
fn a_failed_render_never_replaces_the_previous_output() {
    let dir = temp_dir();
    write(dir.path(), "good.toml", GOOD_SCENE);
    let out = run_in(
        dir.path(),
        &["render", "good.toml", "-o", "keep.exr", "--quiet"],
    );
    assert!(out.status.success());
    let before = std::fs::read(dir.path().join("keep.exr")).unwrap();
    write(
        dir.path(),
        "bad.toml",
        &GOOD_SCENE.replace("radius = 1.0", "radius = nan"),
    );
    let out = run_in(
        dir.path(),
        &["render", "bad.toml", "-o", "keep.exr", "--quiet"],
    );
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(std::fs::read(dir.path().join("keep.exr")).unwrap(), before);
}

#[test]
fn metallic_roughness_out_of_range_names_the_material() {
    let dir = temp_dir();
    for (file, key) in [
        ("rough.toml", "roughness = 1.5"),
        ("metal.toml", "metallic = nan"),
    ] {
        let text = GOOD_SCENE.replace(
            "base_color = [0.5, 0.5, 0.5]",
            &format!("base_color = [0.5, 0.5, 0.5]\n{key}"),
        );
        write(dir.path(), file, &text);
        assert_rejected(dir.path(), file, &[], file);
        assert_rejected(dir.path(), file, &[], "material 'matte'");
    }
}

#[test]
fn a_field_of_view_the_camera_cannot_compute_is_refused() {
    // The camera works from 1e-7 to 179 degrees; a value outside was clamped silently.
    let dir = temp_dir();
    for fov in ["1e-8", "179.5"] {
        let text = GOOD_SCENE.replace("fov = 40.0", &format!("fov = {fov}"));
        write(dir.path(), "s.toml", &text);
        assert_rejected(dir.path(), "s.toml", &[], "must lie in [1e-7, 179] degrees");
    }
}

/// Command-line values out of range are bad input like any other: status 2, one line (no
/// usage block) naming the option, nothing written. `--threads 100000` used to start
/// threads for minutes, deaf to signals, before failing.
#[test]
fn absurd_command_line_values_get_one_line() {
    let dir = temp_dir();
    write(dir.path(), "good.toml", GOOD_SCENE);
    assert_rejected(
        dir.path(),
        "good.toml",
        &["--threads", "100000"],
        "--threads",
    );
    assert_rejected(dir.path(), "good.toml", &["--spp", "4294967296"], "--spp");
    assert_rejected(dir.path(), "good.toml", &["--spp", "many"], "--spp");
    // A misspelt option keeps clap's tip on the same line.
    assert_rejected(
        dir.path(),
        "good.toml",
        &["--sppp", "4"],
        "a similar argument exists: '--spp'",
    );
}

/// A directory named as the scene is called one (it used to get "unknown scene format ''").
#[test]
fn a_directory_is_not_a_scene_file() {
    let dir = temp_dir();
    std::fs::create_dir(dir.path().join("scenes")).unwrap();
    std::fs::create_dir(dir.path().join("box.toml")).unwrap();
    assert_rejected(
        dir.path(),
        "scenes",
        &[],
        "scenes: is a directory, not a scene file",
    );
    assert_rejected(
        dir.path(),
        "box.toml",
        &[],
        "box.toml: is a directory, not a scene file",
    );
}

/// A scene with nothing a ray can meet (an empty file, lights alone, a plain background) is
/// bad input naming the file: it used to render a grey frame and exit 0. Fog alone and an
/// environment map alone are something to see and still render.
#[test]
fn a_scene_without_geometry_is_refused() {
    let dir = temp_dir();
    write(dir.path(), "empty.toml", "");
    assert_rejected(dir.path(), "empty.toml", &[], "empty.toml: no geometry");
    let lights_only = GOOD_SCENE.split("[[sphere]]").next().unwrap();
    write(dir.path(), "lights.toml", lights_only);
    assert_rejected(dir.path(), "lights.toml", &[], "lights.toml: no geometry");

    let fog = format!(
        "{lights_only}\n[[fog]]\ndensity = \"constant\"\nsigma = 0.5\n\
         bounds = {{ min = [-1, -1, -1], max = [1, 1, 1] }}\n"
    );
    write(dir.path(), "fog.toml", &fog);
    let out = run_in(
        dir.path(),
        &["render", "fog.toml", "-o", "fog.exr", "--no-png", "--quiet"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
