//! A scene pays only for the effects it uses: for each effect, a scene without it reports
//! zero work of that kind and does not list it; a scene with it reports work and says why.

mod common;

use common::*;
use serde_json::Value;

const BASE: &str = r#"
[render]
width = 24
height = 16

[camera]
type = "pinhole"
eye = [0.0, 1.5, 5.0]
target = [0.0, 0.5, 0.0]
fov = 50

[environment]
color = [0.1, 0.1, 0.1]

[[texture]]
name = "checker"
file = "checker.exr"
color_space = "linear"

[[material]]
name = "matte"
base_color = [0.6, 0.6, 0.6]

[[material]]
name = "textured"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "checker"

[[material]]
name = "mirror"
base_color = [0.0, 0.0, 0.0]
mirror = 1.0

[[material]]
name = "glass"
base_color = [0.0, 0.0, 0.0]
transmission = 1.0
ior = 1.5

[[material]]
name = "tinted"
base_color = [0.0, 0.0, 0.0]
transmission = 1.0
ior = 1.5
attenuation_color = [0.5, 0.8, 0.6]
attenuation_distance = 1.0
"#;

const LIGHT: &str = r#"
[[light]]
type = "point"
position = [2.0, 5.0, 3.0]
intensity = 40.0
"#;

/// Render BASE + `extra` with a ground plane of material `ground`; return the stats JSON.
fn stats(ground: &str, extra: &str, args: &[&str]) -> Value {
    let dir = temp_dir();
    exr::prelude::write_rgba_file(dir.path().join("checker.exr"), 8, 8, |x, y| {
        let v = if (x + y) % 2 == 0 { 1.0 } else { 0.1 };
        (v, v, v, 1.0)
    })
    .unwrap();
    write(dir.path(), "ground.obj", &square_obj(10.0, 0.0));
    let text = format!("{BASE}{extra}\n[[mesh]]\nfile = \"ground.obj\"\nmaterial = \"{ground}\"\n");
    write(dir.path(), "s.toml", &text);
    let mut full = vec![
        "render", "s.toml", "-o", "o.exr", "--no-png", "--quiet", "--stats", "s.json",
    ];
    full.extend_from_slice(args);
    let out = run_in(dir.path(), &full);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap()
}

fn counter(stats: &Value, name: &str) -> u64 {
    stats["counters"][name]
        .as_u64()
        .unwrap_or_else(|| panic!("no counter {name}"))
}

fn effects(stats: &Value) -> Vec<String> {
    stats["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["effect"].as_str().unwrap().to_string())
        .collect()
}

fn sphere(material: &str) -> String {
    format!("\n[[sphere]]\ncenter = [0.0, 1.0, 0.0]\nradius = 1.0\nmaterial = \"{material}\"\n")
}

#[test]
fn shadows_only_with_lights() {
    let without = stats("matte", "", &[]);
    assert_eq!(counter(&without, "shadow_rays"), 0);
    assert!(!effects(&without).iter().any(|e| e == "shadows"));
    let with = stats("matte", LIGHT, &[]);
    assert!(counter(&with, "shadow_rays") > 0);
    assert!(effects(&with).iter().any(|e| e == "shadows"));
}

#[test]
fn secondary_rays_only_with_specular_materials() {
    let plain = stats("matte", &format!("{LIGHT}{}", sphere("matte")), &[]);
    assert_eq!(counter(&plain, "reflection_rays"), 0);
    assert_eq!(counter(&plain, "refraction_rays"), 0);
    let mirror = stats("matte", &format!("{LIGHT}{}", sphere("mirror")), &[]);
    assert!(counter(&mirror, "reflection_rays") > 0);
    assert_eq!(counter(&mirror, "refraction_rays"), 0);
    assert!(effects(&mirror).iter().any(|e| e == "mirror reflection"));
    let glass = stats("matte", &format!("{LIGHT}{}", sphere("glass")), &[]);
    assert!(counter(&glass, "refraction_rays") > 0);
    assert!(effects(&glass).iter().any(|e| e == "refraction + Fresnel"));
}

#[test]
fn absorption_only_with_media() {
    let clear = stats("matte", &format!("{LIGHT}{}", sphere("glass")), &[]);
    assert_eq!(counter(&clear, "absorption_evaluations"), 0);
    assert!(!effects(&clear).iter().any(|e| e == "Beer's-law absorption"));
    let tinted = stats("matte", &format!("{LIGHT}{}", sphere("tinted")), &[]);
    assert!(counter(&tinted, "absorption_evaluations") > 0);
    assert!(effects(&tinted)
        .iter()
        .any(|e| e == "Beer's-law absorption"));
}

#[test]
fn footprints_only_with_filtered_textures() {
    let untextured = stats("matte", LIGHT, &[]);
    assert_eq!(counter(&untextured, "footprint_updates"), 0);
    assert_eq!(counter(&untextured, "texture_lookups"), 0);
    let textured = stats("textured", LIGHT, &[]);
    assert!(counter(&textured, "footprint_updates") > 0);
    assert!(counter(&textured, "texture_lookups") > 0);
    assert!(effects(&textured).iter().any(|e| e == "ray footprints"));
    // mip0 filtering needs no footprint: textures are looked up, footprints are not tracked.
    let mip0 = stats("textured", LIGHT, &["--lod", "mip0"]);
    assert!(counter(&mip0, "texture_lookups") > 0);
    assert_eq!(counter(&mip0, "footprint_updates"), 0);
    assert!(!effects(&mip0).iter().any(|e| e == "ray footprints"));
}

#[test]
fn all_effects_forces_the_general_path() {
    let general = stats("matte", LIGHT, &["--all-effects"]);
    let names = effects(&general);
    for effect in [
        "shadows",
        "mirror reflection",
        "refraction + Fresnel",
        "ray footprints",
    ] {
        assert!(
            names.iter().any(|e| e == effect),
            "{effect} missing from {names:?}"
        );
    }
}
