//! Physically meaningless values are refused like any other bad value: negative light
//! intensities and colour components, reflectances and weights outside [0, 1]. A TOML scene
//! gets exit status 2 and one line naming the file, line and column of the value; a glTF
//! file one line naming the file and the material or light (glTF has no useful lines). No
//! output is written.

mod common;

use std::path::Path;

use common::*;

/// A scene that renders; each case replaces one of its lines.
const SCENE: &str = r#"[render]
width = 8
height = 8

[camera]
eye = [0, 1, 4]
target = [0, 0, 0]

[environment]
color = [0.1, 0.1, 0.1]

[[light]]
type = "point"
position = [0, 4, 0]
color = [1, 1, 1]
intensity = 10

[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]
emission = [0, 0, 0]
mirror = 0
transmission = 0
attenuation_color = [1, 1, 1]
attenuation_distance = 2
alpha = 1
specular = 0

[[sphere]]
center = [0, 0, 0]
radius = 1
material = "matte"
"#;

/// Renders `file` in `dir`; asserts exit 2, one line on stderr containing every one of
/// `expected`, and no output. Returns the line.
fn assert_refused(dir: &Path, file: &str, expected: &[&str]) -> String {
    let out = run_in(dir, &["render", file, "-o", "out.exr", "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{file}: stderr {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{file}: expected one line, got {stderr:?}");
    for part in expected {
        assert!(
            lines[0].contains(part),
            "{file}: '{}' does not contain '{part}'",
            lines[0]
        );
    }
    assert!(!dir.join("out.exr").exists(), "{file}: an EXR was written");
    assert!(!dir.join("out.png").exists(), "{file}: a PNG was written");
    lines[0].to_owned()
}

/// `SCENE` with the line starting with `old` (the first after line `after`) replaced by
/// `new`; returns the text and the 1-based number of the replaced line.
fn scene_with(after: usize, old: &str, new: &str) -> (String, usize) {
    let mut lines: Vec<String> = SCENE.lines().map(str::to_owned).collect();
    let index = lines
        .iter()
        .enumerate()
        .position(|(i, l)| i + 1 > after && l.starts_with(old))
        .unwrap_or_else(|| panic!("no line '{old}' in the scene"));
    lines[index] = new.to_owned();
    (lines.join("\n") + "\n", index + 1)
}

#[test]
fn the_unchanged_scene_renders() {
    let dir = temp_dir();
    write(dir.path(), "s.toml", SCENE);
    let out = run_in(
        dir.path(),
        &["render", "s.toml", "-o", "out.exr", "--quiet"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn toml_values_are_refused_at_their_line_and_column() {
    // (line to replace, its new text, key = value column, words the message must contain)
    let cases: [(&str, &str, usize, &str); 13] = [
        (
            "intensity",
            "intensity = -10",
            13,
            "intensity = -10 must be >= 0",
        ),
        (
            "color = [1, 1, 1]",
            "color = [1, -1, 1]",
            9,
            "components must be >= 0",
        ),
        (
            "base_color",
            "base_color = [0.5, -0.1, 0.5]",
            14,
            "base_color",
        ),
        (
            "base_color",
            "base_color = [1.5, 0.5, 0.5]",
            14,
            "must lie in [0, 1]",
        ),
        ("emission", "emission = [0, -2, 0]", 12, "emission"),
        (
            "attenuation_color",
            "attenuation_color = [1, 1, -0.5]",
            21,
            "attenuation_color",
        ),
        (
            "attenuation_color",
            "attenuation_color = [1, 2, 1]",
            21,
            "attenuation_color",
        ),
        (
            "mirror",
            "mirror = 1.5",
            10,
            "mirror = 1.5 must lie in [0, 1]",
        ),
        ("mirror", "mirror = -0.5", 10, "mirror"),
        ("transmission", "transmission = 2", 16, "transmission"),
        ("alpha", "alpha = -1", 9, "alpha"),
        ("specular", "specular = 3", 12, "specular"),
        (
            "color = [0.1",
            "color = [-0.1, 0.1, 0.1]",
            9,
            "components must be >= 0",
        ),
    ];
    for (old, new, column, words) in cases {
        let dir = temp_dir();
        let (text, line) = scene_with(0, old, new);
        write(dir.path(), "s.toml", &text);
        let location = format!("s.toml:{line}:{column}:");
        assert_refused(dir.path(), "s.toml", &[&location, words]);
    }
}

#[test]
fn negative_environment_texture_intensity_is_refused() {
    let dir = temp_dir();
    let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/sky.png");
    std::fs::copy(&sky, dir.path().join("sky.png")).expect("assets/textures/sky.png");
    let text = SCENE.replace(
        "[environment]\ncolor = [0.1, 0.1, 0.1]",
        "[[texture]]\nname = 'sky'\nfile = 'sky.png'\n\n[environment]\ntexture = 'sky'\nintensity = -2",
    );
    write(dir.path(), "s.toml", &text);
    let line = text.lines().position(|l| l == "intensity = -2").unwrap() + 1;
    assert_refused(
        dir.path(),
        "s.toml",
        &[&format!("s.toml:{line}:13:"), "intensity = -2 must be >= 0"],
    );
}

/// A one-triangle glTF file whose material 'paint' and light 'lamp' carry `material` and
/// `light` (JSON members), embedded buffer.
fn gltf_with(material: &str, light: &str) -> String {
    // Three vec3 positions and three u16 indices (+2 bytes padding), base64 (42 bytes).
    let mut bytes = Vec::new();
    for p in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let data = base64(&bytes);
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_volume"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [{{"name": "lamp", "type": "point", {light}}}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [{{"mesh": 0}}, {{"translation": [0, 0, 3], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
  "materials": [{{"name": "paint", {material}}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}
  ]
}}"#,
        len = bytes.len()
    )
}

const GOOD_MATERIAL: &str = r#""pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0, "roughnessFactor": 0.5}"#;
const GOOD_LIGHT: &str = r#""color": [1, 1, 1], "intensity": 20"#;

#[test]
fn the_good_gltf_renders() {
    let dir = temp_dir();
    write(dir.path(), "m.gltf", &gltf_with(GOOD_MATERIAL, GOOD_LIGHT));
    let out = run_in(
        dir.path(),
        &["render", "m.gltf", "-o", "out.exr", "--quiet"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn gltf_values_outside_the_specification_are_refused_naming_the_material() {
    let cases = [
        (
            r#""pbrMetallicRoughness": {"baseColorFactor": [1.2, 0.5, 0.5, 1]}"#,
            "baseColorFactor",
        ),
        (
            r#""pbrMetallicRoughness": {"baseColorFactor": [0.5, -0.5, 0.5, 1]}"#,
            "baseColorFactor",
        ),
        (
            r#""pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.5]}"#,
            "baseColorFactor",
        ),
        (r#""emissiveFactor": [0, -1, 0]"#, "emissiveFactor"),
        (
            r#""pbrMetallicRoughness": {"metallicFactor": 1.5}"#,
            "metallicFactor 1.5",
        ),
        (
            r#""pbrMetallicRoughness": {"roughnessFactor": -0.1}"#,
            "roughnessFactor -0.1",
        ),
        (
            r#""extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.1}}"#,
            "transmissionFactor 1.1",
        ),
        (
            r#""extensions": {"KHR_materials_ior": {"ior": 0.5}}"#,
            "ior 0.5",
        ),
        (
            r#""extensions": {"KHR_materials_volume": {"attenuationDistance": -1}}"#,
            "attenuationDistance -1",
        ),
        (
            r#""extensions": {"KHR_materials_volume": {"attenuationColor": [1, 1.5, 1]}}"#,
            "attenuationColor",
        ),
    ];
    for (material, key) in cases {
        let dir = temp_dir();
        write(dir.path(), "m.gltf", &gltf_with(material, GOOD_LIGHT));
        assert_refused(
            dir.path(),
            "m.gltf",
            &["m.gltf", "material 'paint' (materials[0])", key],
        );
    }
}

#[test]
fn gltf_lights_outside_the_specification_are_refused_naming_the_light() {
    let cases = [
        (r#""intensity": -5"#, "intensity -5 must be >= 0"),
        (r#""color": [1, -0.2, 1]"#, "color"),
        (r#""color": [2, 1, 1]"#, "color"),
        (r#""intensity": 1, "range": 0"#, "range 0"),
    ];
    for (light, words) in cases {
        let dir = temp_dir();
        write(dir.path(), "m.gltf", &gltf_with(GOOD_MATERIAL, light));
        assert_refused(
            dir.path(),
            "m.gltf",
            &[
                "m.gltf",
                "light 'lamp' (KHR_lights_punctual.lights[0])",
                words,
            ],
        );
    }
}

#[test]
fn gltf_ior_zero_is_rendered_with_a_note() {
    // KHR_materials_ior admits exactly 0 (legacy "reflect at every angle").
    let dir = temp_dir();
    let material = r#""extensions": {"KHR_materials_ior": {"ior": 0}}"#;
    write(dir.path(), "m.gltf", &gltf_with(material, GOOD_LIGHT));
    let out = run_in(dir.path(), &["render", "m.gltf", "-o", "out.exr"]);
    let printed =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{printed}");
    assert!(
        printed.contains("ior 0, rendered with ior 1.5"),
        "{printed}"
    );
}

#[test]
fn radiance_above_what_the_film_holds_is_rendered_with_a_note() {
    // An emitter and an environment brighter than 2^31, the largest sample value the film's
    // exact sums hold: the render goes ahead, the summary line and --stats say they are
    // clamped, and the pixels that see them hold 2^31.
    let dir = temp_dir();
    let text = SCENE
        .replace("emission = [0, 0, 0]", "emission = [0, 5e9, 0]")
        .replace("color = [0.1, 0.1, 0.1]", "color = [4e9, 0, 0]");
    write(dir.path(), "s.toml", &text);
    let out = run_in(
        dir.path(),
        &["render", "s.toml", "-o", "out.exr", "--stats", "s.json"],
    );
    let printed =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{printed}");
    for expected in [
        "material 'matte': emission 5000000000 is above the film's largest sample value 2^31",
        "environment color 4000000000 is above the film's largest sample value 2^31",
    ] {
        assert!(printed.contains(expected), "{printed}");
        let stats = std::fs::read_to_string(dir.path().join("s.json")).unwrap();
        assert!(stats.contains(expected), "{stats}");
    }
    let image = read_exr(&dir.path().join("out.exr"));
    let limit = 2_147_483_648.0f32;
    assert_eq!(image.at("G", 4, 4), limit, "the sphere's emission");
    assert_eq!(image.at("R", 0, 0), limit, "the environment in a corner");
}

#[test]
fn an_environment_texture_brighter_than_the_film_holds_is_noted() {
    let dir = temp_dir();
    let sky = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/sky.png");
    let text = SCENE.replace(
        "[environment]\ncolor = [0.1, 0.1, 0.1]",
        &format!(
            "[[texture]]\nname = \"sky\"\nfile = \"{}\"\n\n\
             [environment]\ntexture = \"sky\"\nintensity = 5e9",
            sky.display()
        ),
    );
    assert_ne!(
        text, SCENE,
        "the scene has no environment colour to replace"
    );
    write(dir.path(), "s.toml", &text);
    let out = run_in(dir.path(), &["render", "s.toml", "-o", "out.exr"]);
    let printed =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{printed}");
    assert!(
        printed.contains(
            "environment intensity 5000000000 is above the film's largest sample value 2^31"
        ),
        "{printed}"
    );
}
