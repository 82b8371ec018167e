//! The path tracer against known answers: a white furnace, a plane under an emissive quad,
//! the three light strategies agreeing, Whitted's image when diffuse interreflection is off,
//! the automatic choice of integrator, determinism, and coarser texture lookups after a
//! diffuse bounce.

mod common;

use std::path::Path;
use std::sync::Arc;

use common::*;
use conetrace::footprint::LodStrategy;
use conetrace::integrator::path::{LightStrategy, PathTracer};
use conetrace::integrator::selection::{self, IntegratorChoice, IntegratorKind};
use conetrace::integrator::Whitted;
use conetrace::render::{self, Integrator, RenderControl, RenderOptions, RenderStats};
use conetrace::scene::load::load_toml_str;
use conetrace::scene::{MaterialModel, MetallicRoughnessModel, SceneDescription};

fn load(dir: &Path, text: &str) -> SceneDescription {
    load_toml_str(text, dir, "test.toml").unwrap_or_else(|e| panic!("scene: {e}"))
}

/// Renders `scene` with `integrator`; returns the RGB of every pixel and the statistics.
fn render_with<I: Integrator>(
    scene: SceneDescription,
    integrator: &I,
    options: impl FnOnce(&mut RenderOptions),
) -> (Vec<[f32; 3]>, RenderStats) {
    let mut render_options = RenderOptions::from_settings(&scene.settings);
    options(&mut render_options);
    let context = render::prepare(Arc::new(scene), render_options).expect("prepare");
    let result = render::render(&context, integrator, &RenderControl::default()).expect("render");
    let film = &result.film;
    let [r, g, b] = ["R", "G", "B"].map(|c| film.channel(c).expect("colour").to_vec());
    let pixels = (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect();
    (pixels, result.stats)
}

fn mean(pixels: &[[f32; 3]]) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for p in pixels {
        for c in 0..3 {
            sum[c] += p[c] as f64;
        }
    }
    sum.map(|s| s / pixels.len() as f64)
}

/// Renders `text` with `integrator` and checks the red channel's mean over the image is
/// `want` within `tolerance` (absolute), printing it under `label`.
fn assert_mean_red<I: Integrator>(
    dir: &Path,
    text: &str,
    integrator: &I,
    want: f64,
    tolerance: f64,
    label: &str,
) {
    let (pixels, _) = render_with(load(dir, text), integrator, |_| {});
    let value = mean(&pixels)[0];
    eprintln!("{label}: {value} (expected {want})");
    assert!(
        (value - want).abs() < tolerance,
        "{label}: {value}, expected {want}"
    );
}

/// Materials the white furnace holds to "reflects everything": one line each.
/// The rough conductors are white (F0 = 1) GGX metals from nearly smooth to glTF's roughest;
/// their single-scattering lobes alone keep as little as 0.31 of the light at roughness 1
/// (docs/materials.md), and the multiple-scattering compensation gives the rest back.
const FURNACE_MATERIALS: &[(&str, &str)] = &[
    ("lambert", "base_color = [1.0, 1.0, 1.0]"),
    (
        "rough_conductor",
        "base_color = [1.0, 1.0, 1.0]\nmetallic = 1.0\nroughness = 0.2",
    ),
    (
        "rougher_conductor",
        "base_color = [1.0, 1.0, 1.0]\nmetallic = 1.0\nroughness = 0.5",
    ),
    (
        "roughest_conductor",
        "base_color = [1.0, 1.0, 1.0]\nmetallic = 1.0\nroughness = 1.0",
    ),
];

/// (a) A white (albedo 1) sphere under a uniform environment of radiance 0.5 and no other
/// light returns the environment: every pixel of a small orthographic view, all on the
/// sphere, is 0.5 within 1% at 1024 spp.
#[test]
fn white_furnace_returns_the_environment() {
    let dir = temp_dir();
    for (name, material) in FURNACE_MATERIALS {
        let scene = load(
            dir.path(),
            &format!(
                r#"
[render]
width = 12
height = 12
spp = 1024
max_depth = 16

[camera]
type = "orthographic"
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
height = 1.2

[environment]
color = [0.5, 0.5, 0.5]

[[material]]
name = "{name}"
{material}

[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "{name}"
"#
            ),
        );
        assert!(scene.lights.is_empty(), "{name}: a key light was added");
        let (pixels, stats) = render_with(scene, &PathTracer::default(), |_| {});
        let m = mean(&pixels);
        for (c, value) in m.iter().enumerate() {
            assert!(
                (value - 0.5).abs() < 0.005,
                "{name}: channel {c} mean {value} (expected 0.5)"
            );
        }
        let worst = pixels
            .iter()
            .flat_map(|p| p.iter())
            .map(|v| (v - 0.5).abs())
            .fold(0.0f32, f32::max);
        eprintln!("furnace {name}: mean {m:?}, worst pixel error {worst}");
        assert!(worst < 0.05, "{name}: a pixel is {worst} off");
        assert_eq!(stats.counters.nonfinite_samples, 0);
    }
}

/// An opaque surface hides what is behind it from the path tracer, however tilted its
/// shading normals: a metal quad whose smooth vertex normals lean 60 degrees off its face,
/// in front of an emissive sphere, against a black environment, shows black. Before the
/// fix a rough reflection about the leaning normal that left below the face was traced as
/// a transmission and saw the lamp (mean 0.008, pixels up to 0.25).
#[test]
fn an_opaque_surface_with_leaning_normals_does_not_leak_light_from_behind() {
    let dir = temp_dir();
    for (name, material) in [
        (
            "metal",
            "base_color = [1.0, 1.0, 1.0]\nmetallic = 1.0\nroughness = 0.3",
        ),
        ("plastic", "base_color = [0.8, 0.8, 0.8]\nroughness = 0.5"),
        (
            "classic",
            "base_color = [0.8, 0.8, 0.8]\nspecular = 0.5\nshininess = 20.0",
        ),
    ] {
        write(
            dir.path(),
            "quad.obj",
            "v -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\n\
             vn 0.866 0 0.5\n\
             f 1//1 2//1 3//1\nf 1//1 3//1 4//1\n",
        );
        let scene = load(
            dir.path(),
            &format!(
                r#"
[render]
width = 16
height = 16
spp = 64
max_depth = 4

[camera]
type = "orthographic"
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
height = 2.0

[[material]]
name = "{name}"
{material}

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [10.0, 10.0, 10.0]

[[mesh]]
file = "quad.obj"
material = "{name}"

[[sphere]]
center = [0.0, 0.0, -3.0]
radius = 1.5
material = "lamp"
"#
            ),
        );
        let (pixels, stats) = render_with(scene, &PathTracer::default(), |_| {});
        let brightest = pixels
            .iter()
            .flat_map(|p| p.iter())
            .fold(0.0f32, |m, &v| m.max(v));
        eprintln!("{name}: brightest pixel {brightest}");
        assert_eq!(brightest, 0.0, "{name}: light leaks through the quad");
        assert_eq!(stats.counters.nonfinite_samples, 0);
    }
}

/// Irradiance fraction (form factor) from a differential area to a parallel rectangle
/// `a` x `b` at height `h` whose corner is straight above it (Howell's catalogue, B-3).
fn corner_form_factor(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
}

/// A diffuse plane of albedo 0.5 under a black, emissive 2x2 quad facing down 1 unit above
/// it, seen between them by an orthographic camera over a 0.02-wide patch at the centre.
fn quad_lit_plane(dir: &Path, width: u32, spp: u32) -> SceneDescription {
    write(dir, "plane.obj", &square_obj(5.0, 0.0));
    write(dir, "lamp.obj", &square_obj(1.0, 0.0));
    load(
        dir,
        &format!(
            r#"
[render]
width = {width}
height = {width}
spp = {spp}
max_depth = 4

[camera]
type = "orthographic"
eye = [0.0, 0.5, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 0.02

[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [2.0, 2.0, 2.0]

[[mesh]]
file = "plane.obj"
material = "matte"

[[mesh]]
file = "lamp.obj"
material = "lamp"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.0, 0.0]
"#
        ),
    )
}

/// (b) Lit by an emissive quad alone (no key light): radiance = albedo / pi * E with
/// E = pi L F, F the form factor of the quad from the plane's centre; within 2%.
#[test]
fn a_plane_under_an_emissive_quad_matches_the_form_factor() {
    let dir = temp_dir();
    let scene = quad_lit_plane(dir.path(), 8, 256);
    assert!(scene.lights.is_empty(), "a key light was added");
    let (pixels, stats) = render_with(scene, &PathTracer::default(), |_| {});
    let form_factor = 4.0 * corner_form_factor(1.0, 1.0, 1.0);
    let expected = 0.5 / std::f64::consts::PI * (std::f64::consts::PI * 2.0 * form_factor);
    let m = mean(&pixels);
    eprintln!("quad-lit plane: mean {m:?}, expected {expected}");
    for value in m {
        assert!(
            (value - expected).abs() < 0.02 * expected,
            "mean {value}, expected {expected}"
        );
    }
    assert!(stats.counters.shadow_rays > 0 && stats.counters.paths == 8 * 8 * 256);
}

/// (b) A sphere light: irradiance straight below it is E = pi L sin^2(theta_max), so a
/// plane of albedo 0.5 under a black sphere of radius 0.5 emitting L = 4, 2 units above, has
/// radiance 0.5 * 4 / 16 = 0.125; within 2%. Exercises the cone sampling of spheres and its
/// density in the MIS weights.
#[test]
fn a_plane_under_a_sphere_light_matches_l_pi_sin2() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(5.0, 0.0));
    let scene = load(
        dir.path(),
        r#"
[render]
width = 8
height = 8
spp = 256
max_depth = 4

[camera]
type = "orthographic"
eye = [0.0, 0.5, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 0.02

[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]

[[material]]
name = "bulb"
base_color = [0.0, 0.0, 0.0]
emission = [4.0, 4.0, 4.0]

[[mesh]]
file = "plane.obj"
material = "matte"

[[sphere]]
center = [0.0, 2.0, 0.0]
radius = 0.5
material = "bulb"
"#,
    );
    assert!(scene.lights.is_empty(), "a key light was added");
    let (pixels, _) = render_with(scene, &PathTracer::default(), |_| {});
    let expected = 0.125;
    let m = mean(&pixels);
    eprintln!("sphere-lit plane: mean {m:?}, expected {expected}");
    for value in m {
        assert!((value - expected).abs() < 0.02 * expected, "mean {value}");
    }
}

/// Samples whose radiance overflows to infinity are counted and dropped: two facing quads
/// emitting near the largest finite float light each other beyond it, and every pixel of
/// the film stays finite.
/// A point light over a large grey ground under a dim sky. How often the light is sampled
/// must not hang on the ground's size: when the sky's share grew with the scene's bounding
/// radius, it took 96 % of the samples here, and with stratified choices each pixel got
/// either two or three of its 64 light samples, an image of pixels 0.6 or 1.3 times the
/// converged value. Now every pixel of the 64-spp image lies near the 1024-spp one.
#[test]
fn a_point_light_over_a_large_ground_is_sampled_evenly() {
    let dir = temp_dir();
    write(dir.path(), "ground.obj", &square_obj(80.0, 0.0));
    let scene = |spp: u32| {
        load(
            dir.path(),
            &format!(
                r#"
[render]
width = 32
height = 18
spp = {spp}
max_depth = 4

[camera]
type = "pinhole"
eye = [0.0, 2.2, 5.5]
target = [0.0, 0.0, 0.0]
fov = 40

[environment]
color = [0.25, 0.3, 0.4]

[[light]]
type = "point"
position = [3.0, 6.0, 4.0]
intensity = 120.0

[[material]]
name = "grey"
base_color = [0.5, 0.5, 0.5]

[[mesh]]
file = "ground.obj"
material = "grey"
"#
            ),
        )
    };
    let render = |spp| {
        let scene = scene(spp);
        let tracer = PathTracer::for_settings(&scene.settings);
        render_with(scene, &tracer, |_| {}).0
    };
    let (image, reference) = (render(64), render(1024));
    let errors: Vec<f64> = image
        .iter()
        .zip(&reference)
        .map(|(a, b)| f64::from(a[0] - b[0]) / f64::from(b[0]))
        .collect();
    let rms = (errors.iter().map(|e| e * e).sum::<f64>() / errors.len() as f64).sqrt();
    let worst = errors.iter().fold(0.0f64, |w, e| w.max(e.abs()));
    eprintln!("64 spp against 1024 spp: relative error rms {rms:.4}, worst {worst:.4}");
    assert!(rms < 0.05, "relative error rms {rms}");
    assert!(worst < 0.2, "worst relative error {worst}");
}

#[test]
fn non_finite_samples_are_counted_and_never_reach_the_film() {
    let dir = temp_dir();
    write(dir.path(), "lamp.obj", &square_obj(1.0, 0.0));
    let scene = load(
        dir.path(),
        r#"
[render]
width = 4
height = 4
spp = 4

[camera]
type = "orthographic"
eye = [0.0, 0.5, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 0.5

[[material]]
name = "blinding"
base_color = [1.0, 1.0, 1.0]
emission = [3.0e38, 3.0e38, 3.0e38]

[[mesh]]
file = "lamp.obj"
material = "blinding"

[[mesh]]
file = "lamp.obj"
material = "blinding"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.0, 0.0]
"#,
    );
    let (pixels, stats) = render_with(scene, &PathTracer::default(), |_| {});
    eprintln!(
        "{} of {} samples dropped",
        stats.counters.nonfinite_samples,
        4 * 4 * 4
    );
    assert!(stats.counters.nonfinite_samples > 0, "no sample overflowed");
    assert!(
        pixels.iter().flatten().all(|v| v.is_finite()),
        "a non-finite value reached the film"
    );
}

/// The image means of the scene `text` under multiple importance sampling, light sampling
/// alone and BSDF sampling alone, in that order (printed).
fn strategy_means(dir: &Path, text: &str) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let estimate = |strategy| {
        let tracer = PathTracer {
            strategy,
            ..PathTracer::default()
        };
        mean(&render_with(load(dir, text), &tracer, |_| {}).0)
    };
    let mis = estimate(LightStrategy::MultipleImportance);
    let light = estimate(LightStrategy::LightSampling);
    let bsdf = estimate(LightStrategy::BsdfSampling);
    eprintln!("means: MIS {mis:?}, light sampling {light:?}, BSDF sampling {bsdf:?}");
    (mis, light, bsdf)
}

/// (c) Light sampling alone, BSDF sampling alone and their combination estimate the same
/// image: a plane lit by the quad, seen obliquely with a diffuse sphere on it.
#[test]
fn light_bsdf_and_mis_estimates_agree() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(5.0, 0.0));
    write(dir.path(), "lamp.obj", &square_obj(0.8, 0.0));
    let text = r#"
[render]
width = 24
height = 16
spp = 256
max_depth = 3

[camera]
type = "pinhole"
eye = [0.0, 1.2, 3.0]
target = [0.0, 0.3, 0.0]
fov = 50

[environment]
color = [0.05, 0.07, 0.1]

[[material]]
name = "matte"
base_color = [0.6, 0.5, 0.4]

[[material]]
name = "ball"
base_color = [0.3, 0.6, 0.3]
specular = 0.3
shininess = 20.0

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [4.0, 4.0, 4.0]

[[mesh]]
file = "plane.obj"
material = "matte"

[[sphere]]
center = [0.0, 0.4, 0.0]
radius = 0.4
material = "ball"

[[mesh]]
file = "lamp.obj"
material = "lamp"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.6, 0.0]
"#;
    let (m, l, b) = strategy_means(dir.path(), text);
    for c in 0..3 {
        assert!(
            (m[c] - l[c]).abs() < 0.02 * m[c],
            "light sampling: {l:?} vs {m:?}"
        );
        assert!(
            (m[c] - b[c]).abs() < 0.03 * m[c],
            "BSDF sampling: {b:?} vs {m:?}"
        );
    }
}

/// (d) A Whitted scene (point light, diffuse floor and spheres, a mirror sphere, black
/// environment) rendered by the path tracer with no diffuse bounces gives Whitted's image
/// in expectation.
#[test]
fn without_diffuse_bounces_the_path_tracer_gives_whitteds_image() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(6.0, 0.0));
    let text = r#"
[render]
width = 32
height = 18
spp = 256
max_depth = 4
diffuse_bounces = 0

[camera]
type = "pinhole"
eye = [0.0, 1.5, 5.0]
target = [0.0, 0.6, 0.0]
fov = 40

[[light]]
type = "point"
position = [3.0, 6.0, 4.0]
intensity = 120.0

[[material]]
name = "floor"
base_color = [0.7, 0.7, 0.7]

[[material]]
name = "red"
base_color = [0.8, 0.2, 0.15]
specular = 0.2
shininess = 40.0

[[material]]
name = "chrome"
base_color = [0.5, 0.5, 0.5]
mirror = 0.85

[[mesh]]
file = "plane.obj"
material = "floor"

[[sphere]]
center = [-1.1, 0.7, 0.0]
radius = 0.7
material = "red"

[[sphere]]
center = [0.9, 0.7, 0.3]
radius = 0.7
material = "chrome"
"#;
    let scene = load(dir.path(), text);
    assert_eq!(scene.settings.diffuse_bounces, Some(0));
    let tracer = PathTracer::for_settings(&scene.settings);
    assert_eq!(tracer.diffuse_bounces, 0);
    let (path, _) = render_with(scene, &tracer, |_| {});
    let (whitted, _) = render_with(load(dir.path(), text), &Whitted::default(), |_| {});
    let (mp, mw) = (mean(&path), mean(&whitted));
    let mut squared = 0.0f64;
    for (p, w) in path.iter().zip(&whitted) {
        for c in 0..3 {
            squared += ((p[c] - w[c]) as f64).powi(2);
        }
    }
    let rmse = (squared / (3 * path.len()) as f64).sqrt();
    let brightness = (mw[0] + mw[1] + mw[2]) / 3.0;
    eprintln!("path {mp:?}, Whitted {mw:?}, per-pixel RMSE {rmse} (mean {brightness})");
    for c in 0..3 {
        assert!(
            (mp[c] - mw[c]).abs() < 0.01 * mw[c],
            "channel {c}: path {} vs Whitted {}",
            mp[c],
            mw[c]
        );
    }
    assert!(rmse < 0.05 * brightness, "RMSE {rmse}");
}

/// (e) `auto` picks the path tracer for emissive geometry, rough materials and `gi = true`,
/// and Whitted otherwise, each with its reason.
#[test]
fn auto_selection_names_the_integrator_and_why() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let load_file = |relative: &str| {
        conetrace::scene::load::load_scene(&root.join(relative))
            .unwrap_or_else(|e| panic!("{relative}: {e}"))
    };
    let cornell = selection::resolve(
        IntegratorChoice::Auto,
        &load_file("assets/scenes/cornell.toml"),
    );
    assert_eq!(cornell.kind, IntegratorKind::Path);
    assert_eq!(cornell.to_string(), "path: emissive geometry (2 triangles)");

    let matte = load_file("assets/scenes/bench/matte_lit.toml");
    let whitted = selection::resolve(IntegratorChoice::Auto, &matte);
    assert_eq!(whitted.kind, IntegratorKind::Whitted, "{whitted}");
    assert_eq!(
        whitted.to_string(),
        "whitted: no emissive geometry, rough materials or gi"
    );

    let mut rough = matte.clone();
    let metallic_roughness =
        || MaterialModel::MetallicRoughness(MetallicRoughnessModel::new(0.4, 0.0));
    rough.materials[1].model = metallic_roughness();
    let chosen = selection::resolve(IntegratorChoice::Auto, &rough);
    assert_eq!(
        chosen.to_string(),
        "path: rough or glossy materials (1 with roughness)"
    );
    // A rough material that no geometry wears changes no image, and does not count.
    let mut unworn = matte.clone();
    unworn.materials.push(conetrace::scene::Material {
        name: "unworn".into(),
        model: metallic_roughness(),
        ..Default::default()
    });
    let chosen = selection::resolve(IntegratorChoice::Auto, &unworn);
    assert_eq!(chosen.kind, IntegratorKind::Whitted, "{chosen}");

    let dir = temp_dir();
    let gi = load(
        dir.path(),
        "[render]\ngi = true\n[[material]]\nname = \"m\"\n[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n",
    );
    assert_eq!(
        selection::resolve(IntegratorChoice::Auto, &gi).to_string(),
        "path: [render] gi = true"
    );
    let forced = selection::resolve(IntegratorChoice::Fixed(IntegratorKind::Whitted), &gi);
    assert_eq!(forced.to_string(), "whitted: requested");
    assert_eq!(
        "path".parse(),
        Ok(IntegratorChoice::Fixed(IntegratorKind::Path))
    );
    assert!("mlt".parse::<IntegratorChoice>().is_err());
}

/// (e) The command line prints the choice on the summary line and in `--stats`, and
/// `--integrator` overrides it; an unknown `[render] integrator` is a one-line error.
#[test]
fn the_summary_line_and_stats_say_which_integrator() {
    let dir = temp_dir();
    let scene =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cornell.toml");
    let scene = scene.to_str().expect("utf-8 path");
    let out = run_in(
        dir.path(),
        &[
            "render",
            scene,
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "2",
            "--no-png",
            "-o",
            "c.exr",
            "--stats",
            "stats.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(
        printed.contains("integrator path: emissive geometry (2 triangles)"),
        "{printed}"
    );
    assert!(printed.contains("paths"), "{printed}");
    let stats = std::fs::read_to_string(dir.path().join("stats.json")).expect("stats");
    assert!(
        stats.contains("\"integrator\": \"path: emissive geometry (2 triangles)\"")
            || stats.contains("\"integrator\":\"path: emissive geometry (2 triangles)\""),
        "{stats}"
    );
    assert!(stats.contains("roulette_terminations"), "{stats}");

    let out = run_in(
        dir.path(),
        &[
            "render",
            scene,
            "--width",
            "16",
            "--height",
            "16",
            "--no-png",
            "-o",
            "w.exr",
            "--integrator",
            "whitted",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let printed =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(
        printed.contains("integrator whitted: requested"),
        "{printed}"
    );

    write(dir.path(), "bad.toml", "[render]\nintegrator = \"mlt\"\n");
    let out = run_in(dir.path(), &["render", "bad.toml", "-o", "bad.exr"]);
    assert_eq!(out.status.code(), Some(2));
    let message = String::from_utf8_lossy(&out.stderr);
    assert!(message.contains("unknown integrator 'mlt'"), "{message}");
    assert!(!dir.path().join("bad.exr").exists());
}

/// (f) Equal seeds give bit-identical images, whatever the thread count; another seed
/// gives another image.
#[test]
fn a_seed_determines_the_image() {
    let root = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let scene = conetrace::scene::load::load_scene(&root.join("assets/scenes/cornell.toml"))
        .expect("cornell");
    let run = |seed: u32, threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            render_with(scene.clone(), &PathTracer::default(), |o| {
                o.width = 24;
                o.height = 24;
                o.spp = 4;
                o.seed = seed;
            })
            .0
        })
    };
    let first = run(7, 1);
    assert_eq!(first, run(7, 2), "the same seed gave another image");
    assert_ne!(first, run(8, 1), "another seed gave the same image");
}

/// Seed 000's spread through a diffuse bounce: the texture lookups of rays that bounced off
/// a diffuse ceiling onto a textured floor use coarser mip levels than the camera's own
/// lookups of that floor from the same height.
#[test]
fn texture_lookups_after_a_diffuse_bounce_use_coarser_levels() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(4.0, 0.0));
    let checker =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/textures/checker.png");
    let scene = |look_up: bool| {
        let (target, up) = if look_up {
            ("[0.0, 1.0, 0.0]", "[0.0, 0.0, -1.0]")
        } else {
            ("[0.0, 0.0, 0.0]", "[0.0, 0.0, -1.0]")
        };
        load(
            dir.path(),
            &format!(
                r#"
[render]
width = 32
height = 32
spp = 4
max_depth = 1

[camera]
type = "pinhole"
eye = [0.0, 0.5, 0.0]
target = {target}
up = {up}
fov = 60

[environment]
color = [0.2, 0.2, 0.2]

[[texture]]
name = "checker"
file = "{checker}"

[[material]]
name = "floor"
base_color_texture = "checker"
texture_scale = [4.0, 4.0]

[[material]]
name = "ceiling"
base_color = [0.8, 0.8, 0.8]

[[mesh]]
file = "plane.obj"
material = "floor"

[[mesh]]
file = "plane.obj"
material = "ceiling"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.0, 0.0]
"#,
                checker = checker.display()
            ),
        )
    };
    let mean_level = |look_up: bool, lod: LodStrategy| {
        let (_, stats) = render_with(scene(look_up), &PathTracer::default(), |o| {
            o.count_texture_tiles = true;
            o.lod = lod;
        });
        let usage = stats.texture_tiles.expect("tiles counted");
        let levels = &usage.per_texture[0].1;
        let (weighted, total) = levels
            .iter()
            .enumerate()
            .fold((0.0, 0.0), |(w, t), (level, &n)| {
                (w + level as f64 * n as f64, t + n as f64)
            });
        assert!(total > 0.0, "no lookups");
        (weighted / total, stats.counters.texture_lookups)
    };
    for lod in [LodStrategy::Cone, LodStrategy::Cone1] {
        let (camera_level, camera_lookups) = mean_level(false, lod);
        let (bounce_level, bounce_lookups) = mean_level(true, lod);
        eprintln!(
            "{}: mean mip level: camera hits {camera_level:.2} ({camera_lookups} lookups), \
             after a diffuse bounce {bounce_level:.2} ({bounce_lookups} lookups)",
            lod.name()
        );
        assert!(camera_lookups > 0 && bounce_lookups > 0);
        assert!(
            bounce_level > camera_level + 1.0,
            "{}: camera {camera_level}, bounce {bounce_level}",
            lod.name()
        );
    }
    // Differentials take the camera's footprint at the bounced hit (pbrt-v4's
    // approximation): filtered like a camera hit at that distance, not point-sampled.
    let (camera_level, _) = mean_level(false, LodStrategy::Differential);
    let (bounce_level, _) = mean_level(true, LodStrategy::Differential);
    eprintln!(
        "differential: camera hits {camera_level:.2}, after a diffuse bounce {bounce_level:.2}"
    );
    assert!(
        bounce_level > 1.0 && (bounce_level - camera_level).abs() < 1.0,
        "differential: camera {camera_level}, bounce {bounce_level}"
    );
}

/// The depth limit counts paths whatever their last vertex: with `max_depth` 0 (direct
/// light only, a path of at most two segments), a mirror shows the lamp it reflects, as a
/// diffuse surface shows the lamp's light by light sampling (pbrt-v4's `maxDepth` 1,
/// Mitsuba 3's `max_depth` 2). The path tracer used to end every path at the last hit
/// without the delta lobe's ray, leaving the mirror black there.
#[test]
fn at_the_depth_limit_a_mirror_still_shows_the_light_it_reflects() {
    let dir = temp_dir();
    let text = |max_depth: u32| {
        format!(
            r#"
[render]
width = 16
height = 16
spp = 4
max_depth = {max_depth}

[camera]
type = "pinhole"
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fov = 4

[[material]]
name = "mirror"
base_color = [0.0, 0.0, 0.0]
mirror = 1.0

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [3.0, 2.0, 1.0]

# The mirror fills the view; straight back from it, behind the camera, the lamp.
[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "mirror"

[[sphere]]
center = [0.0, 0.0, 20.0]
radius = 12.0
material = "lamp"
"#
        )
    };
    for max_depth in [0, 1, 3] {
        let scene = load(dir.path(), &text(max_depth));
        let (pixels, _) = render_with(scene, &PathTracer::default(), |_| {});
        for (index, pixel) in pixels.iter().enumerate() {
            for (c, expected) in [3.0f32, 2.0, 1.0].into_iter().enumerate() {
                assert!(
                    (pixel[c] - expected).abs() <= 1e-4 * expected,
                    "max_depth {max_depth}, pixel {index}: {pixel:?}, expected the lamp's \
                     [3, 2, 1]"
                );
            }
        }
    }
}

/// Light sampling reaches a viewer through a rough glass pane too: below the pane (its
/// back, inside the glass), a camera looks up through it at a lamp and a uniform sky, and
/// light sampling alone, BSDF sampling alone and their combination agree. Light sampling
/// used to look only on the viewer's side of a surface, so that with light sampling alone
/// the pane showed the reflected sky only, and the power heuristic dropped part of the
/// transmitted light; and a point light behind frosted glass, which only light sampling can
/// reach, rendered black.
#[test]
fn light_through_rough_glass_is_found_by_every_strategy() {
    let dir = temp_dir();
    write(dir.path(), "pane.obj", &square_obj(3.0, 0.0));
    write(dir.path(), "lamp.obj", &square_obj(0.8, 0.0));
    let text = r#"
[render]
width = 24
height = 16
spp = 1024
max_depth = 3

[camera]
type = "pinhole"
eye = [0.0, -2.0, 0.5]
target = [0.0, 0.0, 0.0]
fov = 50

[environment]
color = [0.2, 0.25, 0.3]

[[material]]
name = "frosted"
base_color = [1.0, 1.0, 1.0]
transmission = 1.0
ior = 1.5
roughness = 0.6

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [4.0, 4.0, 4.0]

[[mesh]]
file = "pane.obj"
material = "frosted"

[[mesh]]
file = "lamp.obj"
material = "lamp"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.5, 0.0]
"#;
    let (m, l, b) = strategy_means(dir.path(), text);
    // Light sampling alone is the noisy one here (a uniform sky sampled over the sphere,
    // seen through a lobe that scales radiance by ior^2): 5 seeds at 256 spp spread over
    // 1.09-1.16 against 1.10-1.11 for the other two.
    for c in 0..3 {
        assert!(
            (m[c] - b[c]).abs() < 0.01 * m[c],
            "BSDF sampling: {b:?} vs {m:?}"
        );
        assert!(
            (m[c] - l[c]).abs() < 0.04 * m[c],
            "light sampling: {l:?} vs {m:?}"
        );
    }

    // A point light behind frosted glass: only light sampling can reach it.
    let point_lit = r#"
[render]
width = 8
height = 8
spp = 16
max_depth = 2

[camera]
type = "pinhole"
eye = [0.0, -3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, 1.0]
fov = 10

[[light]]
type = "point"
position = [0.0, 1.0, 0.0]
intensity = 1.0

[[material]]
name = "frosted"
base_color = [1.0, 1.0, 1.0]
transmission = 1.0
ior = 1.5
roughness = 0.7

[[mesh]]
file = "pane.obj"
material = "frosted"
"#;
    let (pixels, _) = render_with(load(dir.path(), point_lit), &PathTracer::default(), |_| {});
    let lit = mean(&pixels);
    eprintln!("point light through frosted glass: {lit:?}");
    assert!(
        pixels.iter().flatten().all(|v| v.is_finite() && *v > 0.0),
        "a pixel of the frosted pane is black: {lit:?}"
    );
}

/// Both strategies of the power heuristic read the environment alike, and as its importance
/// sampling sees it: a diffuse floor under a sky with a small, bright sun has the same
/// brightness whether lookups are filtered by ray cones or not, and for every seed. Light
/// sampling used to read the environment through the arriving ray's footprint while a BSDF
/// ray read it through its own, widened one, so the blurred glow around the sun was counted
/// by both (cone: 1.93980 against 1.22849 here).
#[test]
fn a_sharp_sun_lights_a_diffuse_floor_alike_with_and_without_footprints() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(6.0, 0.0));
    // 256 x 128 lat-long: a sky of 0.5 above the horizon and a 2 x 2-texel sun of 4000.
    let (width, height) = (256usize, 128usize);
    exr::prelude::write_rgba_file(dir.path().join("sun.exr"), width, height, |x, y| {
        let sun = (100..102).contains(&x) && (30..32).contains(&y);
        let value = if sun {
            4000.0
        } else if y < height / 2 {
            0.5
        } else {
            0.0
        };
        (value, value, value, 1.0f32)
    })
    .expect("sun.exr");
    let text = r#"
[render]
width = 8
height = 8
spp = 1024
max_depth = 1

[camera]
type = "pinhole"
eye = [0.3, 5.0, 0.2]
target = [0.3, 0.0, 0.2]
up = [1.0, 0.0, 0.0]
fov = 1

[[texture]]
name = "sky"
file = "sun.exr"

[environment]
texture = "sky"

[[material]]
name = "floor"
base_color = [0.6, 0.6, 0.6]

[[mesh]]
file = "plane.obj"
material = "floor"
"#;
    let brightness = |lod, seed| {
        let (pixels, _) = render_with(load(dir.path(), text), &PathTracer::default(), |o| {
            o.lod = lod;
            o.seed = seed;
        });
        mean(&pixels)[0]
    };
    let unfiltered = brightness(LodStrategy::Mip0, 0);
    for lod in [LodStrategy::Cone, LodStrategy::Cone1] {
        let filtered = brightness(lod, 0);
        eprintln!("{}: {filtered} against {unfiltered} unfiltered", lod.name());
        assert!(
            (filtered - unfiltered).abs() < 0.04 * unfiltered,
            "{}: {filtered} against {unfiltered} unfiltered",
            lod.name()
        );
    }
    // The sun is sampled where its radiance is: other seeds give the same brightness. With
    // the sun read through bilinear lookups, its light spread into texels the sampling
    // rarely visits and seeds scattered by +-7 % (0.8813, 0.9569, 1.0488 on a reviewer's
    // 1024 x 512 sky).
    for seed in [1, 2] {
        let other = brightness(LodStrategy::Cone, seed);
        eprintln!("seed {seed}: {other}");
        assert!(
            (other - unfiltered).abs() < 0.01 * unfiltered,
            "seed {seed}: {other} against {unfiltered}"
        );
    }
}

/// A floor of albedo 0.5 just under a unit sphere lamp of radiance `L = (d / r)^2`, looked
/// at (along a grazing orthographic view under the lamp) where it is nearest to the lamp:
/// the irradiance there is `L pi (r / d)^2 = pi`, so the floor shows 0.5, by light sampling
/// alone (`max_depth` 0) and with multiple importance sampling. At a gap of 1e-4 radii,
/// light sampling gave 0.295 and MIS 0.420: a point sampled on the lamp came out up to one
/// f32 rounding of the lamp's size inside it (`d cos - sqrt(r^2 - d^2 sin^2)` cancels),
/// and the shadow ray, stopping only 1e-4 of its length (1e-8) short, met the lamp itself.
#[test]
fn a_floor_just_under_a_sphere_lamp_gets_its_irradiance() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(100.0, 0.0));
    for gap in [1e-2f64, 1e-3, 1e-4] {
        let d = 1.0 + gap;
        let radiance = d * d;
        // The view passes under the lamp: slope 0.00707 towards the point under its centre.
        let eye = [10.0, 0.0707, 0.0];
        for max_depth in [0, 8] {
            let text = format!(
                r#"
[render]
width = 4
height = 4
spp = 256
max_depth = {max_depth}

[camera]
type = "orthographic"
eye = [{}, {}, {}]
target = [0, 0, 0]
height = 1e-6

[[material]]
name = "floor"
base_color = [0.5, 0.5, 0.5]

[[material]]
name = "lamp"
base_color = [0, 0, 0]
emission = [{radiance}, {radiance}, {radiance}]

[[mesh]]
file = "floor.obj"
material = "floor"

[[sphere]]
center = [0, {d}, 0]
radius = 1
material = "lamp"
"#,
                eye[0], eye[1], eye[2]
            );
            let label = format!("gap {gap}, max_depth {max_depth}");
            assert_mean_red(dir.path(), &text, &PathTracer::default(), 0.5, 2e-3, &label);
        }
    }
}

/// A two-sided emitter (`two_sided = true`, glTF's `doubleSided`) lights from its back as
/// from its front: the quad lamp of [`quad_lit_plane`] turned to face away from the plane
/// gives the plane the form-factor irradiance by light sampling, by BSDF sampling and by
/// both, and nothing when it is one-sided. Seen from behind, it shows its radiance in the
/// path tracer and in Whitted alike (Whitted used to show the back of every emitter and the
/// path tracer none, and `doubleSided` was not read).
#[test]
fn a_two_sided_emitter_lights_and_shows_from_its_back() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(5.0, 0.0));
    write(dir.path(), "lamp.obj", &square_obj(1.0, 0.0));
    let scene = |two_sided: bool, eye_y: f32| {
        format!(
            r#"
[render]
width = 8
height = 8
spp = 256
max_depth = 4

[camera]
type = "orthographic"
eye = [0.0, {eye_y}, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 0.02

[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [2.0, 2.0, 2.0]
two_sided = {two_sided}

[[mesh]]
file = "plane.obj"
material = "matte"

# Facing up, away from the plane.
[[mesh]]
file = "lamp.obj"
material = "lamp"
translate = [0.0, 1.0, 0.0]
"#
        )
    };
    let form_factor = 4.0 * corner_form_factor(1.0, 1.0, 1.0);
    let expected = 0.5 / std::f64::consts::PI * (std::f64::consts::PI * 2.0 * form_factor);
    for strategy in [
        LightStrategy::MultipleImportance,
        LightStrategy::LightSampling,
        LightStrategy::BsdfSampling,
    ] {
        let tracer = PathTracer {
            strategy,
            ..PathTracer::default()
        };
        // The camera sits between the plane and the lamp, looking down at the plane.
        for (two_sided, want) in [(true, expected), (false, 0.0)] {
            let label = format!("{strategy:?}, two-sided {two_sided}");
            let text = scene(two_sided, 0.5);
            assert_mean_red(dir.path(), &text, &tracer, want, 0.02 * expected, &label);
        }
    }
    // Below the lamp looking up at its back: its radiance, or black, in both integrators.
    for (two_sided, want) in [(true, 2.0f64), (false, 0.0)] {
        let mut text = scene(two_sided, 0.5);
        text = text.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 2.0, 0.0]");
        text = text.replace("up = [0.0, 0.0, -1.0]", "up = [0.0, 0.0, 1.0]");
        let (path, _) = render_with(load(dir.path(), &text), &PathTracer::default(), |_| {});
        let (whitted, _) = render_with(load(dir.path(), &text), &Whitted::default(), |_| {});
        for (name, pixels) in [("path", path), ("whitted", whitted)] {
            let value = mean(&pixels)[0];
            assert!(
                (value - want).abs() < 1e-6,
                "{name}, two-sided {two_sided}, seen from behind: {value}, expected {want}"
            );
        }
    }
}

/// A mirrored one-sided lamp keeps its front where its normals point: an OBJ quad facing up,
/// placed with `scale = [-1, 1, 1]` (and a glTF node with a negative scale), still glows
/// seen from above and lights the plane under it, in both integrators. Its winding used to
/// be kept, which turned its front downwards: black from above.
#[test]
fn a_mirrored_lamp_keeps_its_emitting_side() {
    let dir = temp_dir();
    write(dir.path(), "lamp.obj", &square_obj(1.0, 0.0));
    let scene = |mirror: &str| {
        format!(
            r#"
[render]
width = 8
height = 8
spp = 4

[camera]
type = "orthographic"
eye = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 0.5

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [2.0, 2.0, 2.0]

[[mesh]]
file = "lamp.obj"
material = "lamp"
scale = {mirror}
"#
        )
    };
    for mirror in ["[1, 1, 1]", "[-1, 1, 1]", "[1, 1, -1]", "[-1, 2, -1]"] {
        let text = scene(mirror);
        let (path, _) = render_with(load(dir.path(), &text), &PathTracer::default(), |_| {});
        let (whitted, _) = render_with(load(dir.path(), &text), &Whitted::default(), |_| {});
        for (name, pixels) in [("path", path), ("whitted", whitted)] {
            let value = mean(&pixels)[0];
            assert!(
                (value - 2.0).abs() < 1e-6,
                "{name}, scale {mirror}, seen from the front: {value}, expected 2"
            );
        }
    }
}

/// A floor inside a two-sided emitting sphere sees the sphere's inner wall over its whole
/// upper hemisphere: a white-furnace-like check, the floor's radiance is its albedo times
/// the wall's, under every strategy. (Light sampling found no light from inside a sphere,
/// so it gave 0 and multiple importance sampling lost the light at the last bounce.)
#[test]
fn a_floor_inside_a_two_sided_emitting_sphere_sees_its_inner_wall() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(0.5, 0.0));
    let scene = |two_sided: bool| {
        format!(
            r#"
[render]
width = 8
height = 8
spp = 64
max_depth = 3

[camera]
type = "orthographic"
eye = [0.0, 0.5, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 0.2

[[material]]
name = "matte"
base_color = [0.5, 0.5, 0.5]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [3.0, 3.0, 3.0]
two_sided = {two_sided}

[[mesh]]
file = "floor.obj"
material = "matte"

[[sphere]]
center = [0.0, 0.3, 0.0]
radius = 2.0
material = "lamp"
"#
        )
    };
    for strategy in [
        LightStrategy::MultipleImportance,
        LightStrategy::LightSampling,
        LightStrategy::BsdfSampling,
    ] {
        let tracer = PathTracer {
            strategy,
            ..PathTracer::default()
        };
        for (two_sided, want) in [(true, 1.5f64), (false, 0.0)] {
            let label = format!("{strategy:?}, two-sided {two_sided}");
            assert_mean_red(dir.path(), &scene(two_sided), &tracer, want, 0.015, &label);
        }
    }
}

/// The same floor and lamps 1e4 from the origin, where f32 steps are 1e-3: a floor 0.0098
/// under a unit sphere lamp, and under a 2 x 2 quad lamp, gets by light sampling the
/// irradiance it gets at the origin. Before, sampled points rounded to f32 lay off the
/// lamp and the offset shadow-ray origin, 0.004 nearer the lamp than the surface point,
/// saw less of the sphere: shadow rays near its outline met the lamp itself, and the floor
/// showed 0.93 % (sphere) and 0.57 % (quad) too little.
#[test]
fn a_floor_close_under_a_lamp_far_from_the_origin_gets_its_irradiance() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(5.0, 0.0));
    write(dir.path(), "lamp.obj", &square_obj(1.0, 0.0));
    // 10001.01 in f32: the gap is 0.009765625.
    let lamp_y = 10001.009765625f64;
    let d = lamp_y - 10000.0;
    let camera = r#"
[render]
width = 8
height = 8
spp = 1024
max_depth = 0

[camera]
type = "orthographic"
eye = [10000.0, 10000.005, 10000.0]
target = [10000.0, 10000.0, 10000.0]
up = [0.0, 0.0, -1.0]
height = 0.001

[[material]]
name = "floor"
base_color = [0.5, 0.5, 0.5]

[[mesh]]
file = "floor.obj"
material = "floor"
translate = [10000.0, 10000.0, 10000.0]
"#;
    let radiance = d * d;
    let sphere = format!(
        r#"{camera}
[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [{radiance}, {radiance}, {radiance}]

[[sphere]]
center = [10000.0, {lamp_y}, 10000.0]
radius = 1.0
material = "lamp"
"#
    );
    let height = d - 1.0;
    let quad = format!(
        r#"{camera}
[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [1.0, 1.0, 1.0]

# Facing down.
[[mesh]]
file = "lamp.obj"
material = "lamp"
rotate = [180.0, 0.0, 0.0]
translate = [10000.0, {}, 10000.0]
"#,
        10000.0 + height
    );
    let quad_expected = 0.5 * 4.0 * corner_form_factor(1.0, 1.0, height);
    let tracer = PathTracer {
        strategy: LightStrategy::LightSampling,
        ..PathTracer::default()
    };
    for (name, text, expected) in [("sphere", sphere, 0.5), ("quad", quad, quad_expected)] {
        assert_mean_red(
            dir.path(),
            &text,
            &tracer,
            expected,
            2.5e-3 * expected,
            name,
        );
    }
}

/// A small, very bright lamp (a sphere of emission 400, 300, 100) over a matte floor, with a
/// glass sphere that focuses it: at one sample per pixel, the lamp seen directly, through
/// the glass and in the caustic gives pixels far above 1. `extra_render` is added to
/// `[render]`.
fn firefly_scene(dir: &Path, extra_render: &str) -> std::path::PathBuf {
    write(dir, "floor.obj", &square_obj(3.0, 0.0));
    write(
        dir,
        "fireflies.toml",
        &format!(
            r#"
[render]
width = 48
height = 32
spp = 1
vct_resolution = 32
{extra_render}

[camera]
type = "pinhole"
eye = [0.0, 1.0, 3.0]
target = [0.0, 0.4, 0.0]
fov = 45

[[material]]
name = "floor"
base_color = [0.8, 0.8, 0.8]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [400.0, 300.0, 100.0]

[[material]]
name = "glass"
base_color = [1.0, 1.0, 1.0]
transmission = 1.0
ior = 1.5

[[mesh]]
file = "floor.obj"
material = "floor"

[[sphere]]
center = [0.1, 1.3, -0.2]
radius = 0.08
material = "lamp"

[[sphere]]
center = [-0.3, 0.35, 0.2]
radius = 0.35
material = "glass"
"#
        ),
    )
}

/// Renders `scene` into `dir/name` with `extra` options; panics with stderr on failure.
/// Returns the film and its header.
fn render_cli(
    dir: &Path,
    scene: &Path,
    name: &str,
    extra: &[&str],
) -> (conetrace::film::Film, conetrace::film::ExrAttributes) {
    let out = dir.join(name);
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--no-png",
        "--quiet",
        "--threads",
        "2",
    ];
    args.extend_from_slice(extra);
    let output = run_in(dir, &args);
    assert!(
        output.status.success(),
        "render {extra:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    conetrace::film::read_exr(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()))
}

/// The largest colour component of any pixel.
fn brightest(film: &conetrace::film::Film) -> f32 {
    ["R", "G", "B"]
        .iter()
        .flat_map(|c| film.channel(c).expect("colour").iter().copied())
        .fold(0.0, f32::max)
}

/// `--clamp VALUE` caps every camera sample's largest component at VALUE, for every
/// integrator; at one sample per pixel a pixel is its sample, so no pixel exceeds VALUE, and
/// the lamp seen directly keeps its hue (400 : 300 : 100 scaled to 2 : 1.5 : 0.5). The
/// header records the clamp (`conetrace.option.clamp`), "off" without one; unclamped, the
/// same renders have pixels of hundreds.
#[test]
fn a_sample_clamp_caps_every_pixel_of_every_integrator() {
    let dir = temp_dir();
    let scene = firefly_scene(dir.path(), "");
    for integrator in ["whitted", "path", "vct"] {
        let (free, attributes) = render_cli(
            dir.path(),
            &scene,
            &format!("{integrator}_free.exr"),
            &["--integrator", integrator],
        );
        assert_eq!(attributes.strings["conetrace.option.clamp"], "off");
        assert!(
            brightest(&free) > 100.0,
            "{integrator}: the unclamped lamp peaks at {}",
            brightest(&free)
        );
        let (clamped, attributes) = render_cli(
            dir.path(),
            &scene,
            &format!("{integrator}_clamped.exr"),
            &["--integrator", integrator, "--clamp", "2"],
        );
        assert_eq!(attributes.strings["conetrace.option.clamp"], "2");
        assert!(
            brightest(&clamped) <= 2.0,
            "{integrator}: a pixel of {} under --clamp 2",
            brightest(&clamped)
        );
        let [r, g, b] = ["R", "G", "B"].map(|c| clamped.channel(c).unwrap().to_vec());
        let lamp = (0..r.len())
            .find(|&i| r[i] == 2.0 && g[i] > 1.0)
            .unwrap_or_else(|| panic!("{integrator}: no clamped lamp pixel"));
        assert!(
            (g[lamp] - 1.5).abs() < 1e-5 && (b[lamp] - 0.5).abs() < 1e-5,
            "{integrator}: the lamp became {}, {}, {}",
            r[lamp],
            g[lamp],
            b[lamp]
        );
    }
}

/// `[render] clamp` clamps as `--clamp` does, and `--clamp` overrides it. A resume whose
/// clamp differs from the partial render's is refused, naming the option.
#[test]
fn the_scene_s_clamp_applies_and_a_resume_with_another_clamp_is_refused() {
    let dir = temp_dir();
    let d = dir.path();
    let scene = firefly_scene(d, "clamp = 3.5\nintegrator = \"path\"");
    let (film, attributes) = render_cli(d, &scene, "scene.exr", &[]);
    assert_eq!(attributes.strings["conetrace.option.clamp"], "3.5");
    let peak = brightest(&film);
    assert!(peak <= 3.5 && peak > 2.0, "peak {peak} under clamp = 3.5");
    let (film, attributes) = render_cli(d, &scene, "cli.exr", &["--clamp", "2"]);
    assert_eq!(attributes.strings["conetrace.option.clamp"], "2");
    assert!(brightest(&film) <= 2.0);

    // The render's file stands in for a partial one: the signature is checked first.
    std::fs::copy(d.join("cli.exr"), d.join("cli.partial.exr")).unwrap();
    for (other, now) in [(&["--clamp", "4"][..], "now: 4"), (&[][..], "now: 3.5")] {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            "cli.exr",
            "--no-png",
            "--quiet",
            "--resume",
        ];
        args.extend_from_slice(other);
        let output = run_in(d, &args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{other:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains("option --clamp changed (partial render: 2,") && stderr.contains(now),
            "{other:?}: {stderr}"
        );
    }
}

/// A clamp must be a finite number above 0: `--clamp` and `[render] clamp` refuse 0,
/// negatives, nan and inf with one line naming the option or the key, exit 2, writing
/// nothing.
#[test]
fn bad_clamp_values_are_refused() {
    let dir = temp_dir();
    let d = dir.path();
    let scene = firefly_scene(d, "");
    for value in ["0", "-1", "nan", "inf", "1e40"] {
        let output = run_in(
            d,
            &[
                "render",
                scene.to_str().unwrap(),
                "-o",
                "bad.exr",
                "--quiet",
                "--clamp",
                value,
            ],
        );
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "--clamp {value}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains("--clamp"), "--clamp {value}: {stderr}");
        assert!(!d.join("bad.exr").exists() && !d.join("bad.png").exists());
    }
    for value in ["0", "-1.5", "nan", "inf"] {
        let scene = firefly_scene(d, &format!("clamp = {value}"));
        let output = run_in(
            d,
            &[
                "render",
                scene.to_str().unwrap(),
                "-o",
                "bad.exr",
                "--quiet",
            ],
        );
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "clamp = {value}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains("fireflies.toml") && stderr.contains("render.clamp"),
            "clamp = {value}: {stderr}"
        );
        assert!(!d.join("bad.exr").exists());
    }
}
