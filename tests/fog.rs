//! Fog volumes end to end: `[[fog]]` parsing and its errors (exit 2, one line naming the
//! file), and Whitted's fogged pixels against the closed forms: a camera ray through
//! constant, linear and exponential fog onto an unlit emissive surface, a shadow ray through
//! a fog slab, escaping rays, and the counters of a scene without fog.

mod common;

use std::path::Path;

use common::*;

/// A scene seen straight down by an orthographic camera at height `eye_y`: an emissive
/// white square at y = 0 (no albedo, so nothing but its emission and the fog reaches the
/// camera), no lights, a black environment, and the fog tables `fog`; Whitted renders it
/// (the emissive square would otherwise make `auto` pick the path tracer).
fn emissive_floor_scene(eye_y: f32, fog: &str) -> String {
    format!(
        r#"
[render]
integrator = "whitted"
width = 5
height = 5
spp = 1

[camera]
type = "orthographic"
eye = [0, {eye_y}, 0]
target = [0, 0, 0]
up = [0, 0, -1]
height = 0.5

[[material]]
name = "glow"
base_color = [0, 0, 0]
emission = [1, 1, 1]

[[mesh]]
file = "floor.obj"
material = "glow"

{fog}
"#
    )
}

/// Renders `scene` in `dir` and returns the EXR and the statistics JSON.
fn render(dir: &Path, scene: &str, extra: &[&str]) -> (ExrImage, serde_json::Value) {
    write(dir, "floor.obj", &square_obj(10.0, 0.0));
    write(dir, "s.toml", scene);
    let mut args = vec![
        "render", "s.toml", "-o", "o.exr", "--no-png", "--quiet", "--stats", "s.json",
    ];
    args.extend_from_slice(extra);
    let out = run_in(dir, &args);
    assert!(
        out.status.success(),
        "render failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).expect("stats"))
            .expect("stats JSON");
    (read_exr(&dir.join("o.exr")), stats)
}

/// Every pixel is `T * 1 + (1 - T) * color` with `T = exp(-tau)`.
fn assert_blend(image: &ExrImage, tau: f64, color: [f64; 3], what: &str) {
    let t = (-tau).exp();
    for (channel, c) in ["R", "G", "B"].into_iter().zip(color) {
        let expected = t + (1.0 - t) * c;
        for &v in image.channel(channel) {
            let error = (f64::from(v) - expected).abs();
            assert!(
                error < 2e-6,
                "{what}: channel {channel} = {v}, expected {expected} (tau {tau})"
            );
        }
    }
    println!("{what}: tau {tau:.6}, transmittance {t:.6}, pixels within 2e-6 of the closed form");
}

#[test]
fn constant_fog_attenuates_a_camera_ray_by_exp_minus_sigma_d() {
    let dir = temp_dir();
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 0.1\ncolor = [0.2, 0.4, 0.6]\n";
    let (image, stats) = render(dir.path(), &emissive_floor_scene(5.0, fog), &[]);
    // 5 units of fog between the camera and the floor.
    assert_blend(&image, 0.1 * 5.0, [0.2, 0.4, 0.6], "constant fog");
    let counters = &stats["counters"];
    assert_eq!(counters["fog_segments"], 25, "{counters}");
    assert_eq!(counters["fog_volume_crossings"], 25, "{counters}");
}

#[test]
fn the_linear_blend_model_is_the_seeds_clamped_amount() {
    let dir = temp_dir();
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 0.1\ncolor = [0.2, 0.4, 0.6]\n";
    let scene =
        emissive_floor_scene(5.0, fog).replace("spp = 1", "spp = 1\nfog_model = \"linear-blend\"");
    let (image, _) = render(dir.path(), &scene, &[]);
    // Seed 004: fog amount min(1, 0.1 * 5) = 0.5 blended towards the colour.
    for (channel, c) in ["R", "G", "B"].into_iter().zip([0.2f32, 0.4, 0.6]) {
        let expected = 0.5 + 0.5 * c;
        for &v in image.channel(channel) {
            assert!(
                (v - expected).abs() < 1e-6,
                "{channel} = {v}, expected {expected}"
            );
        }
    }
}

#[test]
fn linear_fog_below_a_plane_matches_its_triangle() {
    let dir = temp_dir();
    // Fog below y = 2, growing by 0.3 per unit of depth (the plane is normalised: [0, 2, 0,
    // -4] is the same plane). From y = 5 down to 0: integral of 0.3 (2 - y) over [0, 2] = 0.6.
    let fog =
        "[[fog]]\ndensity = \"linear\"\nsigma = 0.3\nplane = [0, 2, 0, -4]\ncolor = [1, 0, 0]\n";
    let (image, _) = render(dir.path(), &emissive_floor_scene(5.0, fog), &[]);
    assert_blend(&image, 0.6, [1.0, 0.0, 0.0], "linear fog");
}

#[test]
fn exponential_height_fog_matches_its_integral() {
    let dir = temp_dir();
    let fog = "[[fog]]\ndensity = \"exponential\"\nsigma = 0.2\nheight = 1.0\nfalloff = 0.7\ncolor = [0.5, 0.5, 1]\n";
    let (image, _) = render(dir.path(), &emissive_floor_scene(4.0, fog), &[]);
    // integral over y in [0, 4] of 0.2 exp(-0.7 (y - 1)) = 0.2 / 0.7 (e^0.7 - e^-2.1).
    let tau = 0.2 / 0.7 * ((0.7f64).exp() - (-2.1f64).exp());
    assert_blend(&image, tau, [0.5, 0.5, 1.0], "exponential fog");
}

#[test]
fn bounded_fog_counts_only_the_segments_that_cross_its_box() {
    let dir = temp_dir();
    // A box beside the view: no camera ray crosses it, so every pixel is the clear floor.
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 5\nbounds = { min = [3, 0, -1], max = [4, 1, 1] }\n";
    let (image, stats) = render(dir.path(), &emissive_floor_scene(5.0, fog), &[]);
    assert!(image.channel("G").iter().all(|&v| v == 1.0));
    assert_eq!(stats["counters"]["fog_segments"], 25);
    assert_eq!(stats["counters"]["fog_volume_crossings"], 0);
    // A box on the view: a 0.5-unit slab of sigma 5 between y = 1 and 1.5.
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 5\ncolor = [0, 0, 0]\nbounds = { min = [-1, 1, -1], max = [1, 1.5, 1] }\n";
    let (image, stats) = render(dir.path(), &emissive_floor_scene(5.0, fog), &[]);
    assert_blend(&image, 2.5, [0.0, 0.0, 0.0], "fog box");
    assert_eq!(stats["counters"]["fog_volume_crossings"], 25);
}

#[test]
fn escaping_rays_are_fogged_to_the_volumes_exit_or_fully() {
    let dir = temp_dir();
    // No floor in view: a camera looking up into a white environment.
    let scene = |fog: &str| {
        format!(
            "[render]\nwidth = 3\nheight = 3\n[camera]\ntype = \"orthographic\"\neye = [0, 0, 0]\n\
             target = [0, 1, 0]\nup = [0, 0, -1]\nheight = 0.5\n[environment]\ncolor = [1, 1, 1]\n\
             [[material]]\nname = \"m\"\n[[sphere]]\ncenter = [0, -50, 0]\nradius = 1\nmaterial = \"m\"\n{fog}"
        )
    };
    // Height fog above y = 0 thinning upwards: finite depth sigma / falloff to infinity.
    let fog = "[[fog]]\ndensity = \"exponential\"\nsigma = 0.3\nheight = 0\nfalloff = 0.5\ncolor = [0, 0, 0]\n";
    let (image, _) = render(dir.path(), &scene(fog), &[]);
    assert_blend(&image, 0.6, [0.0, 0.0, 0.0], "escaping through height fog");
    // Unbounded constant fog: infinitely deep, the fog colour alone.
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 0.01\ncolor = [0.3, 0.3, 0.3]\n";
    let (image, _) = render(dir.path(), &scene(fog), &[]);
    assert!(image.channel("R").iter().all(|&v| (v - 0.3).abs() < 1e-7));
}

#[test]
fn shadow_rays_through_fog_pass_exp_minus_tau_of_the_light() {
    let dir = temp_dir();
    let scene = |fog: &str| {
        format!(
            r#"
[render]
width = 5
height = 5
[camera]
type = "orthographic"
eye = [0, 5, 0]
target = [0, 0, 0]
up = [0, 0, -1]
height = 0.2
[[light]]
type = "directional"
direction = [-1, -1, 0]
intensity = 2
[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]
[[mesh]]
file = "floor.obj"
material = "matte"
{fog}
"#
        )
    };
    let (clear, clear_stats) = render(dir.path(), &scene(""), &[]);
    assert_eq!(clear_stats["counters"]["fog_segments"], 0);
    // A slab 0.5 <= y <= 1.5 starting at x = 0.2: the camera rays (|x| <= 0.1) miss it, the
    // shadow rays towards the light at 45 degrees cross it over sqrt(2).
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 0.4\nbounds = { min = [0.2, 0.5, -10], max = [10, 1.5, 10] }\n";
    let (fogged, stats) = render(dir.path(), &scene(fog), &[]);
    let expected = (-0.4 * 2f64.sqrt()).exp();
    for (c, f) in clear.channel("R").iter().zip(fogged.channel("R")) {
        assert!(*c > 0.0);
        let ratio = f64::from(*f) / f64::from(*c);
        assert!(
            (ratio - expected).abs() < 2e-6,
            "ratio {ratio}, expected {expected}"
        );
    }
    // 25 camera segments (no crossing) and 25 shadow segments (crossing).
    assert_eq!(stats["counters"]["fog_segments"], 50);
    assert_eq!(stats["counters"]["fog_volume_crossings"], 25);
}

#[test]
fn a_scene_without_fog_does_no_fog_work() {
    let dir = temp_dir();
    let (_, stats) = render(dir.path(), &emissive_floor_scene(5.0, ""), &[]);
    assert_eq!(stats["counters"]["fog_segments"], 0);
    assert_eq!(stats["counters"]["fog_volume_crossings"], 0);
    let effects = stats["effects"].as_array().expect("effects");
    assert!(effects.iter().all(|e| e["effect"] != "fog"), "{effects:?}");
    // Forced on, the general path evaluates every segment (and finds no volume).
    let (_, forced) = render(
        dir.path(),
        &emissive_floor_scene(5.0, ""),
        &["--all-effects"],
    );
    assert!(forced["counters"]["fog_segments"].as_u64().unwrap() >= 25);
    assert_eq!(forced["counters"]["fog_volume_crossings"], 0);
}

#[test]
fn fog_tables_parse_with_every_key() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(1.0, 0.0));
    let text = emissive_floor_scene(
        5.0,
        r#"
[[fog]]
density = "exponential"
sigma = 0.04
color = [0.7, 0.75, 0.8]
height = 0.0
falloff = 0.5
bounds = { min = [-5, 0, -5], max = [5, 3, 5] }
absorption = [0.1, 0.2, 0.3]
g = 0.6

[[fog]]
density = "linear"
sigma = 0.5
plane = [0, 4, 0, -8]
albedo = [0.9, 0.9, 0.9]
"#,
    );
    let scene = conetrace::scene::load::load_toml_str(&text, dir.path(), "s.toml").expect("parses");
    assert_eq!(scene.fog.len(), 2);
    let height = &scene.fog[0];
    assert_eq!(height.density.kind(), "exponential");
    assert_eq!(height.color, glam::Vec3::new(0.7, 0.75, 0.8));
    assert!(
        (height.albedo - glam::Vec3::new(0.9, 0.8, 0.7))
            .abs()
            .max_element()
            < 1e-6
    );
    assert_eq!(height.g, 0.6);
    let Some(conetrace::medium::FogBounds::Box(bounds)) = height.bounds else {
        panic!("not a box: {:?}", height.bounds)
    };
    assert_eq!(bounds.max, glam::DVec3::new(5.0, 3.0, 5.0));
    let conetrace::medium::Density::Linear(plane) = scene.fog[1].density else {
        panic!("not linear")
    };
    // Normalised: [0, 4, 0, -8] is y = 2 with a unit normal.
    assert_eq!((plane.normal, plane.offset), (glam::DVec3::Y, -2.0));
    assert_eq!(scene.fog[1].color, glam::Vec3::splat(0.8));
}

#[test]
fn fog_in_a_closed_mesh_is_clipped_to_the_mesh() {
    let dir = temp_dir();
    write(
        dir.path(),
        "cube.obj",
        &boxes_obj(&[([-0.5, -0.5, -0.5], [0.5, 0.5, 0.5])]),
    );
    // The unit cube placed as the box [-1, 1] x [1, 1.5] x [-1, 1]: the same 0.5-unit slab
    // of sigma 5 as `bounded_fog_counts_only_the_segments_that_cross_its_box`.
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 5\ncolor = [0, 0, 0]\n\
               bounds = { mesh = \"cube.obj\", translate = [0, 1.25, 0], scale = [2, 0.5, 2] }\n";
    let (image, stats) = render(dir.path(), &emissive_floor_scene(5.0, fog), &[]);
    assert_blend(&image, 2.5, [0.0, 0.0, 0.0], "fog in a placed cube mesh");
    assert_eq!(stats["counters"]["fog_volume_crossings"], 25);
    // Two slabs in one mesh, with clear air between and around them: every camera ray
    // crosses both, 0.5 + 0.25 units of linear fog growing downwards from y = 4.
    write(
        dir.path(),
        "slabs.obj",
        &boxes_obj(&[
            ([-2.0, 1.0, -2.0], [2.0, 1.5, 2.0]),
            ([-2.0, 2.5, -2.0], [2.0, 2.75, 2.0]),
        ]),
    );
    let fog = "[[fog]]\ndensity = \"linear\"\nsigma = 0.4\nplane = [0, 1, 0, -4]\n\
               color = [0.2, 0.3, 0.4]\nbounds = { mesh = \"slabs.obj\" }\n";
    let (image, stats) = render(dir.path(), &emissive_floor_scene(5.0, fog), &[]);
    // density 0.4 (4 - y): integral over [1, 1.5] is 0.4 * 0.5 * 2.75 = 0.55, over
    // [2.5, 2.75] 0.4 * 0.25 * 1.375 = 0.1375.
    assert_blend(
        &image,
        0.55 + 0.1375,
        [0.2, 0.3, 0.4],
        "linear fog in two slabs",
    );
    assert_eq!(stats["counters"]["fog_volume_crossings"], 25);
    // Beside the view: no camera ray crosses the mesh.
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 5\n\
               bounds = { mesh = \"cube.obj\", translate = [3.5, 0.5, 0] }\n";
    let (image, stats) = render(dir.path(), &emissive_floor_scene(5.0, fog), &[]);
    assert!(image.channel("G").iter().all(|&v| v == 1.0));
    assert_eq!(stats["counters"]["fog_volume_crossings"], 0);
}

#[test]
fn fog_meshes_that_bound_nothing_exit_2_with_one_line() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(1.0, 0.0));
    let cube = boxes_obj(&[([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])]);
    let open: String = cube
        .lines()
        .take(8 + 11)
        .map(|l| format!("{l}\n"))
        .collect();
    write(dir.path(), "open.obj", &open);
    write(dir.path(), "cube.obj", &cube);
    let cases = [
        (
            "bounds = { mesh = \"open.obj\" }",
            "open.obj' is not closed",
        ),
        (
            "bounds = { mesh = \"missing.obj\" }",
            "cannot read fog bounds mesh",
        ),
        (
            "bounds = { mesh = \"cube.obj\", scale = 0 }",
            "scale must not be zero",
        ),
        (
            "bounds = { mesh = \"cube.obj\", min = [0, 0, 0], max = [1, 1, 1] }",
            "a box { min",
        ),
        (
            "bounds = { min = [0, 0, 0], translate = [1, 0, 0] }",
            "a box { min",
        ),
    ];
    for (bounds, message) in cases {
        let text = emissive_floor_scene(
            5.0,
            &format!("[[fog]]\ndensity = \"constant\"\nsigma = 1\n{bounds}\n"),
        );
        write(dir.path(), "bad.toml", &text);
        let out = run_in(
            dir.path(),
            &["render", "bad.toml", "-o", "bad.exr", "--quiet"],
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bounds}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{bounds}: {stderr}");
        assert!(
            stderr.contains("bad.toml") && stderr.contains(message),
            "{bounds}: expected '{message}' in: {stderr}"
        );
        assert!(
            !dir.path().join("bad.exr").exists(),
            "{bounds}: an image was written"
        );
    }
}

#[test]
fn bad_fog_parameters_exit_2_with_one_line_naming_the_file() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(1.0, 0.0));
    let cases = [
        (
            "density = \"constant\"\nsigma = -0.1",
            "sigma = -0.1 must be >= 0",
        ),
        ("density = \"constant\"\nsigma = nan", "not finite"),
        (
            "density = \"linear\"\nsigma = 1\nplane = [0, 0, 0, 1]",
            "zero normal",
        ),
        ("density = \"linear\"\nsigma = 1", "needs plane"),
        ("density = \"exponential\"\nsigma = 1", "needs falloff"),
        (
            "density = \"constant\"\nsigma = 1\nfalloff = 2",
            "does not apply to constant fog",
        ),
        (
            "density = \"constant\"\nsigma = 1\nbounds = { min = [0, 2, 0], max = [1, 1, 1] }",
            "exceeds max",
        ),
        (
            "density = \"constant\"\nsigma = 1\ng = 1",
            "g = 1 must lie in (-1, 1)",
        ),
        (
            "density = \"constant\"\nsigma = 1\nalbedo = [1.5, 0, 0]",
            "must lie in [0, 1]",
        ),
        (
            "density = \"constant\"\nsigma = 1\nalbedo = [1, 1, 1]\nabsorption = [0, 0, 0]",
            "give one",
        ),
        ("density = \"fractal\"\nsigma = 1", "fractal"),
        (
            "density = \"constant\"\nsigma = 1\ncolour = [1, 1, 1]",
            "colour",
        ),
    ];
    for (table, message) in cases {
        let text = emissive_floor_scene(5.0, &format!("[[fog]]\n{table}\n"));
        write(dir.path(), "bad.toml", &text);
        let out = run_in(
            dir.path(),
            &["render", "bad.toml", "-o", "bad.exr", "--quiet"],
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{table}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{table}: {stderr}");
        assert!(
            stderr.contains("bad.toml") && stderr.contains(message),
            "{table}: expected '{message}' in: {stderr}"
        );
        assert!(
            !dir.path().join("bad.exr").exists(),
            "{table}: an image was written"
        );
    }
}

/// A one-triangle glTF whose root `extras` carry `fog` (JSON text of the array).
fn gltf_with_fog(fog: &str) -> String {
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extras": {{"author": "a test", "fog": {fog}}},
  "buffers": [{{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}}],
  "bufferViews": [{{"buffer": 0, "byteLength": 36}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                  "min": [0, 0, 0], "max": [1, 1, 0]}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "nodes": [{{"mesh": 0}}],
  "scenes": [{{"nodes": [0]}}],
  "scene": 0
}}"#
    )
}

#[test]
fn gltf_files_bring_fog_through_extras() {
    let dir = temp_dir();
    let path = write(
        dir.path(),
        "fog.gltf",
        &gltf_with_fog(
            r#"[{"density": "linear", "sigma": 0.5, "plane": [0, 1, 0, -2], "color": [0.1, 0.2, 0.3]}]"#,
        ),
    );
    let scene = conetrace::scene::load::load_scene(&path).expect("loads");
    assert_eq!(scene.fog.len(), 1);
    assert_eq!(scene.fog[0].density.kind(), "linear");
    assert_eq!(scene.fog[0].color, glam::Vec3::new(0.1, 0.2, 0.3));
    // A mesh bound is read relative to the glTF file.
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    write(
        &dir.path().join("sub"),
        "volume.obj",
        &boxes_obj(&[([0.0, 0.0, 0.0], [1.0, 2.0, 1.0])]),
    );
    let path = write(
        &dir.path().join("sub"),
        "meshfog.gltf",
        &gltf_with_fog(
            r#"[{"density": "constant", "sigma": 0.5, "bounds": {"mesh": "volume.obj", "translate": [1, 0, 0]}}]"#,
        ),
    );
    let scene = conetrace::scene::load::load_scene(&path).expect("loads");
    let volume = &scene.fog[0];
    assert!(matches!(
        volume.bounds,
        Some(conetrace::medium::FogBounds::Mesh(_))
    ));
    assert!(volume.contains(glam::DVec3::new(1.5, 1.5, 0.5)));
    assert!(!volume.contains(glam::DVec3::new(0.5, 1.5, 0.5)));
    // Placed by a TOML scene without a transform the fog comes along; with one, a note says
    // it was left out.
    let toml = |placement: &str| {
        format!("[[mesh]]\nfile = \"fog.gltf\"\n{placement}\n[[light]]\ntype = \"point\"\nposition = [0, 3, 3]\n")
    };
    let placed = conetrace::scene::load::load_toml_str(&toml(""), dir.path(), "s.toml").unwrap();
    assert_eq!(placed.fog.len(), 1);
    let moved =
        conetrace::scene::load::load_toml_str(&toml("translate = [1, 0, 0]"), dir.path(), "s.toml")
            .unwrap();
    assert!(moved.fog.is_empty());
    assert!(
        moved.notes.iter().any(|n| n.contains("fog volume(s)")),
        "{:?}",
        moved.notes
    );
    // A bad entry: exit 2, one line naming the file and the entry.
    write(
        dir.path(),
        "bad.gltf",
        &gltf_with_fog(
            r#"[{"density": "constant", "sigma": 0.1}, {"density": "constant", "sigma": -3}]"#,
        ),
    );
    let out = run_in(
        dir.path(),
        &["render", "bad.gltf", "-o", "bad.exr", "--quiet"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("bad.gltf")
            && stderr.contains("extras.fog[1]: fog sigma = -3 must be >= 0"),
        "{stderr}"
    );
}

/// A glTF file whose fog names the file itself as its bounding mesh: the bounds are read
/// as triangles only, so loading ends (it overflowed the stack before) and the fog fills
/// the file's closed tetrahedron.
#[test]
fn a_gltf_fog_bounded_by_its_own_file_loads() {
    let dir = temp_dir();
    let tetrahedron = r#"{
  "asset": {"version": "2.0"},
  "extras": {"fog": [{"density": "constant", "sigma": 0.5, "bounds": {"mesh": "self.gltf"}}]},
  "buffers": [{"byteLength": 72, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAACAAEAAAABAAMAAAADAAIAAQACAAMA"}],
  "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                 "min": [0, 0, 0], "max": [1, 1, 1]},
                {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "nodes": [{"mesh": 0}],
  "scenes": [{"nodes": [0]}],
  "scene": 0
}"#;
    let path = write(dir.path(), "self.gltf", tetrahedron);
    let scene = conetrace::scene::load::load_scene(&path).expect("loads");
    assert_eq!(scene.fog.len(), 1);
    assert!(scene.fog[0].contains(glam::DVec3::splat(0.2)));
    assert!(!scene.fog[0].contains(glam::DVec3::splat(0.5)));
    let out = run_in(
        dir.path(),
        &["render", "self.gltf", "-o", "o.exr", "--quiet"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The path tracer simulates fog as a medium (tests/fog_path.rs): a fog scene it renders
/// carries no note that the fog was left out, and its fog counters show the work.
#[test]
fn the_path_tracer_renders_fog_without_a_note() {
    let dir = temp_dir();
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 0.1\ncolor = [0.5, 0.5, 0.5]\n";
    let (_, stats) = render(
        dir.path(),
        &emissive_floor_scene(1.0, fog),
        &["--integrator", "path"],
    );
    let notes = stats["notes"].to_string();
    assert!(
        !notes.contains("fog is not simulated by this integrator"),
        "a note says fog is left out: {notes}"
    );
    let counters = &stats["counters"];
    assert!(counters["fog_segments"].as_u64() > Some(0), "{counters}");
}

/// `--fog-march-steps N` / `[render] fog_march_steps`: the midpoint rule on the density
/// (`conetrace::medium::integration`). Straight down through height fog from y = 4 its error
/// in `tau` is about `tau (k h)^2 / 24` (`h = 4 / N`): visible at 4 steps, below 1e-4 at 64;
/// every segment takes N density samples.
#[test]
fn ray_marched_fog_approaches_the_closed_form_and_counts_its_samples() {
    let dir = temp_dir();
    let fog = "[[fog]]\ndensity = \"exponential\"\nsigma = 0.2\nheight = 1.0\nfalloff = 0.7\ncolor = [0.5, 0.5, 1]\n";
    let tau = 0.2 / 0.7 * ((0.7f64).exp() - (-2.1f64).exp());
    let exact = 1.0 - (1.0 - (-tau).exp()) * 0.5; // the red channel: T + (1 - T) 0.5
    let mut errors = Vec::new();
    for steps in [4u32, 64] {
        let (image, stats) = render(
            dir.path(),
            &emissive_floor_scene(4.0, fog),
            &["--fog-march-steps", &steps.to_string()],
        );
        assert_eq!(
            stats["counters"]["fog_density_samples"],
            25 * u64::from(steps),
            "{}",
            stats["counters"]
        );
        let error = image
            .channel("R")
            .iter()
            .map(|&v| (f64::from(v) - exact).abs())
            .fold(0.0, f64::max);
        println!("{steps} steps: largest pixel error {error:.3e}");
        errors.push(error);
    }
    assert!(errors[0] > 1e-3, "4 steps differ visibly: {errors:?}");
    assert!(errors[1] < 1e-4, "64 steps are close: {errors:?}");
    // The scene's own setting gives the same image as the option.
    let scene = emissive_floor_scene(4.0, fog).replace("spp = 1", "spp = 1\nfog_march_steps = 4");
    let (image, _) = render(dir.path(), &scene, &[]);
    let (option, _) = render(
        dir.path(),
        &emissive_floor_scene(4.0, fog),
        &["--fog-march-steps", "4"],
    );
    assert_eq!(image.channel("R"), option.channel("R"));
    // The closed form takes no samples.
    let (_, stats) = render(dir.path(), &emissive_floor_scene(4.0, fog), &[]);
    assert_eq!(stats["counters"]["fog_density_samples"], 0);
}

#[test]
fn zero_march_steps_exit_2_with_one_line() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(1.0, 0.0));
    let fog = "[[fog]]\ndensity = \"constant\"\nsigma = 0.1\n";
    write(dir.path(), "good.toml", &emissive_floor_scene(5.0, fog));
    let bad = emissive_floor_scene(5.0, fog).replace("spp = 1", "spp = 1\nfog_march_steps = 0");
    write(dir.path(), "bad.toml", &bad);
    for (args, message) in [
        (
            vec![
                "render",
                "good.toml",
                "-o",
                "bad.exr",
                "--quiet",
                "--fog-march-steps",
                "0",
            ],
            "--fog-march-steps must be at least 1",
        ),
        (
            vec![
                "render",
                "good.toml",
                "-o",
                "bad.exr",
                "--quiet",
                "--fog-march-steps",
                "-3",
            ],
            "--fog-march-steps must be at least 1 and at most 4294967295, got -3",
        ),
        (
            vec!["render", "bad.toml", "-o", "bad.exr", "--quiet"],
            "fog_march_steps must be at least 1",
        ),
    ] {
        let out = run_in(dir.path(), &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        assert!(
            !dir.path().join("bad.exr").exists(),
            "{args:?}: an image was written"
        );
    }
    let out = run_in(
        dir.path(),
        &["render", "bad.toml", "-o", "bad.exr", "--quiet"],
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.toml"));
}
