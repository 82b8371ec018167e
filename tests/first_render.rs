//! What a new user's first render of a scene or model decides on their behalf, and says so
//! on the summary line: the path tracer's sample count when none was given, a key light for
//! models whose only emitters are glowing labels, and a note when the chosen integrator
//! cannot light the scene with the lights it has.

mod common;

use std::path::Path;

use common::*;

const MODELS: &str = "/usr/share/assimp/models";
const CORNELL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/cornell.toml");

/// Renders `args` (plus a small size and no PNG) in `dir`; the printed summary and the EXR's
/// mean red.
fn render(dir: &Path, args: &[&str]) -> (String, f64) {
    let mut all = vec![
        "render", "--width", "24", "--height", "16", "--no-png", "-o", "out.exr",
    ];
    all.extend_from_slice(args);
    let out = run_in(dir, &all);
    let printed =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{args:?}: {printed}");
    let image = read_exr(&dir.join("out.exr"));
    let red = image.channel("R");
    let mean = red.iter().map(|&v| f64::from(v)).sum::<f64>() / red.len() as f64;
    (printed, mean)
}

const ROUGH_SCENE: &str = r#"
[[material]]
name = "rough"
base_color = [0.5, 0.5, 0.5]
roughness = 0.5

[[sphere]]
center = [0, 0, 0]
radius = 1
material = "rough"
"#;

#[test]
fn the_path_tracer_takes_its_default_sample_count_when_none_is_given() {
    let dir = temp_dir();
    write(dir.path(), "rough.toml", ROUGH_SCENE);
    let (printed, _) = render(dir.path(), &["rough.toml"]);
    assert!(printed.contains("integrator path"), "{printed}");
    assert!(printed.contains(", 16 spp,"), "{printed}");
    assert!(
        printed.contains("16 spp: the path integrator's default"),
        "{printed}"
    );
    // The EXR records the count the render took.
    let (_, attributes) = conetrace::film::read_exr(&dir.path().join("out.exr")).unwrap();
    assert_eq!(
        attributes
            .strings
            .get("conetrace.option.spp")
            .map(String::as_str),
        Some("16")
    );

    // A count from the command line or the scene is taken as given, without the note.
    let (printed, _) = render(dir.path(), &["rough.toml", "--spp", "2"]);
    assert!(
        printed.contains(", 2 spp,") && !printed.contains("integrator's default"),
        "{printed}"
    );
    write(
        dir.path(),
        "rough3.toml",
        &format!("[render]\nspp = 3\n{ROUGH_SCENE}"),
    );
    let (printed, _) = render(dir.path(), &["rough3.toml"]);
    assert!(
        printed.contains(", 3 spp,") && !printed.contains("integrator's default"),
        "{printed}"
    );
    // Whitted keeps one sample.
    let (printed, _) = render(dir.path(), &["rough.toml", "--integrator", "whitted"]);
    assert!(printed.contains(", 1 spp,"), "{printed}");
}

#[test]
fn a_debian_gltf_model_renders_at_the_path_tracer_s_default_count() {
    let model = Path::new(MODELS).join("glTF2/BoxTextured-glTF/BoxTextured.gltf");
    assert!(
        model.is_file(),
        "{} is missing: run scripts/setup.sh (installs assimp-testmodels)",
        model.display()
    );
    let dir = temp_dir();
    let (printed, _) = render(dir.path(), &[model.to_str().unwrap()]);
    assert!(printed.contains(", 16 spp,"), "{printed}");
}

#[test]
fn integrators_that_cannot_use_the_scene_s_emitters_say_so() {
    let dir = temp_dir();
    for integrator in ["whitted", "vct"] {
        let (printed, _) = render(
            dir.path(),
            &[CORNELL, "--spp", "1", "--integrator", integrator],
        );
        assert!(
            printed.contains(&format!(
                "{integrator}: the scene is lit only by emissive geometry"
            )) && printed.contains("--integrator path"),
            "{integrator}: {printed}"
        );
    }
    // The path tracer uses them: no note.
    let (printed, _) = render(dir.path(), &[CORNELL, "--spp", "1"]);
    assert!(!printed.contains("lit only by"), "{printed}");
    assert!(!printed.contains("default key light"), "{printed}");
}

/// An OBJ floor under a small emissive quad of radiance `ke` (MTL `Ke`), nothing else.
fn floor_under_emitter(dir: &Path, ke: f32) -> String {
    write(
        dir,
        "m.mtl",
        &format!("newmtl floor\nKd 0.5 0.5 0.5\nnewmtl glow\nKd 0 0 0\nKe {ke} {ke} {ke}\n"),
    );
    // The emitter faces down (-y) from y = 1, over the floor at y = 0.
    let obj = "mtllib m.mtl\n\
        v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\n\
        v -0.5 1 -0.5\nv 0.5 1 -0.5\nv 0.5 1 0.5\nv -0.5 1 0.5\n\
        usemtl floor\nf 1 4 3 2\n\
        usemtl glow\nf 5 6 7 8\n";
    write(dir, "m.obj", obj);
    "m.obj".to_string()
}

#[test]
fn a_model_s_glowing_surfaces_get_the_default_light_and_its_lamps_light_it_alone() {
    let dir = temp_dir();
    let model = floor_under_emitter(dir.path(), 1.0);
    let (printed, _) = render(dir.path(), &[&model, "--spp", "1"]);
    assert!(
        printed.contains("glow but are not lamps") && printed.contains("default key light"),
        "{printed}"
    );
    let model = floor_under_emitter(dir.path(), 17.0);
    let (printed, _) = render(dir.path(), &[&model, "--spp", "1"]);
    assert!(!printed.contains("default key light"), "{printed}");
}

#[test]
fn khronos_clearcoat_test_is_lit() {
    let model = Path::new(MODELS).join("glTF2/ClearCoat-glTF/ClearCoatTest.gltf");
    assert!(
        model.is_file(),
        "{} is missing: run scripts/setup.sh (installs assimp-testmodels)",
        model.display()
    );
    let dir = temp_dir();
    let (printed, mean) = render(dir.path(), &[model.to_str().unwrap(), "--spp", "4"]);
    assert!(printed.contains("default key light"), "{printed}");
    // Lit by the key light and the grey-blue environment, not by its labels alone.
    assert!(mean > 0.05, "mean red {mean}: {printed}");
}
