//! Fog as a participating medium in the path tracer, against known answers: a pure
//! absorber in front of a white environment passes `exp(-sigma d)`, shadow rays through an
//! absorbing slab pass the exact transmittance, a box of non-absorbing fog in a uniform
//! environment returns the environment (the medium furnace), light sampling and phase
//! sampling at medium vertices agree with their MIS combination, the same seed gives the
//! same image on any number of threads, and a scene without fog does no fog work.

mod common;

use std::path::Path;
use std::sync::Arc;

use common::*;
use conetrace::integrator::path::{LightStrategy, PathTracer};
use conetrace::render::{self, RenderControl, RenderOptions, RenderStats};
use conetrace::scene::load::load_toml_str;
use conetrace::scene::SceneDescription;

fn load(dir: &Path, text: &str) -> SceneDescription {
    load_toml_str(text, dir, "test.toml").unwrap_or_else(|e| panic!("scene: {e}"))
}

/// Renders `scene` with the path tracer on the current thread pool; returns the RGB of
/// every pixel and the statistics.
fn render_path(scene: SceneDescription) -> (Vec<[f32; 3]>, RenderStats) {
    let tracer = PathTracer::for_settings(&scene.settings);
    render_with(scene, &tracer)
}

fn render_with(scene: SceneDescription, tracer: &PathTracer) -> (Vec<[f32; 3]>, RenderStats) {
    let options = RenderOptions::from_settings(&scene.settings);
    let context = render::prepare(Arc::new(scene), options).expect("prepare");
    let result = render::render(&context, tracer, &RenderControl::default()).expect("render");
    let film = &result.film;
    let [r, g, b] = ["R", "G", "B"].map(|c| film.channel(c).expect("colour").to_vec());
    let pixels = (0..r.len()).map(|i| [r[i], g[i], b[i]]).collect();
    (pixels, result.stats)
}

fn mean(pixels: &[[f32; 3]]) -> [f64; 3] {
    let mut sum = [0.0f64; 3];
    for p in pixels {
        for c in 0..3 {
            sum[c] += f64::from(p[c]);
        }
    }
    sum.map(|s| s / pixels.len() as f64)
}

fn worst_error(pixels: &[[f32; 3]], expected: f64) -> f64 {
    pixels
        .iter()
        .flat_map(|p| p.iter())
        .map(|&v| (f64::from(v) - expected).abs())
        .fold(0.0, f64::max)
}

/// The absorber scene: an orthographic camera looking along -z at a white environment
/// through constant fog of extinction `sigma` and albedo 0 filling `bounds`; the only
/// surface lies outside the view and the fog.
fn absorber_scene(sigma: f64, bounds: &str) -> String {
    format!(
        r#"
[render]
width = 8
height = 8
spp = 1024
max_depth = 8

[camera]
type = "orthographic"
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
height = 2.0

[environment]
color = [1.0, 1.0, 1.0]

[[material]]
name = "black"
base_color = [0.0, 0.0, 0.0]

[[sphere]]
center = [50.0, 0.0, -50.0]
radius = 0.1
material = "black"

[[fog]]
density = "constant"
sigma = {sigma}
albedo = [0.0, 0.0, 0.0]
bounds = {bounds}
"#
    )
}

/// (a) An orthographic camera looks along -z through a slab of constant fog 2 units thick
/// (`z` in [-1, 1], sigma 0.5) that absorbs everything it collides with (albedo 0), in front
/// of a white environment. A path either collides (and ends: nothing is scattered) or
/// passes with weight 1, so each sample is a Bernoulli draw of mean `exp(-sigma d) =
/// exp(-1)`; 8x8 pixels at 1024 spp put the image's mean within 4 standard deviations,
/// `4 sqrt(T (1 - T) / 65536) = 0.0075`.
#[test]
fn a_pure_absorber_passes_exp_minus_sigma_d() {
    let dir = temp_dir();
    let scene = load(
        dir.path(),
        &absorber_scene(
            0.5,
            "{ min = [-10.0, -10.0, -1.0], max = [10.0, 10.0, 1.0] }",
        ),
    );
    let (pixels, stats) = render_path(scene);
    let expected = (-1.0f64).exp();
    let m = mean(&pixels);
    let tolerance = 4.0 * (expected * (1.0 - expected) / 65536.0).sqrt();
    eprintln!(
        "absorber: mean {m:?}, expected {expected:.6} +- {tolerance:.4}, worst pixel error {:.4}",
        worst_error(&pixels, expected)
    );
    for (c, value) in m.iter().enumerate() {
        assert!(
            (value - expected).abs() < tolerance,
            "channel {c}: mean {value}, expected exp(-1) = {expected}"
        );
    }
    let counters = &stats.counters;
    // Every camera ray is one fog segment crossing the slab; about 1 - exp(-1) of them
    // collide, and no path scatters on (albedo 0 leaves nothing to carry).
    assert_eq!(counters.fog_segments, 65536, "{counters:?}");
    assert_eq!(counters.fog_volume_crossings, 65536, "{counters:?}");
    let collided = counters.fog_scatter_events as f64 / 65536.0;
    assert!((collided - (1.0 - expected)).abs() < 0.01, "{collided}");
    assert_eq!(counters.path_bounces, 0, "{counters:?}");
}

/// A white-ish diffuse floor (albedo 0.5) under a directional light of irradiance 2 shining
/// straight down through an absorbing slab (`y` in [1, 3], sigma 0.3, albedo 0), seen from
/// below the slab: the floor's radiance is `0.5 / pi * 2 * exp(-0.6)`. Light sampling of a
/// delta light is exact, the environment is black and paths that leave the floor upwards
/// find nothing, so every sample of every pixel is that value: the shadow ray's fog
/// transmittance is checked to f32 precision.
fn slab_over_floor(dir: &Path, fog: &str) -> SceneDescription {
    write(dir, "floor.obj", &square_obj(10.0, 0.0));
    load(
        dir,
        &format!(
            r#"
[render]
width = 6
height = 6
spp = 4
max_depth = 4

[camera]
type = "orthographic"
eye = [0.0, 0.5, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
height = 1.0

[[material]]
name = "floor"
base_color = [0.5, 0.5, 0.5]

[[mesh]]
file = "floor.obj"
material = "floor"

[[light]]
type = "directional"
direction = [0.0, -1.0, 0.0]
intensity = 2.0

{fog}
"#
        ),
    )
}

#[test]
fn shadow_rays_through_fog_pass_the_exact_transmittance() {
    let dir = temp_dir();
    let fog = r#"
[[fog]]
density = "constant"
sigma = 0.3
albedo = [0.0, 0.0, 0.0]
bounds = { min = [-20.0, 1.0, -20.0], max = [20.0, 3.0, 20.0] }
"#;
    let (pixels, stats) = render_path(slab_over_floor(dir.path(), fog));
    let expected = 0.5 / std::f64::consts::PI * 2.0 * (-0.6f64).exp();
    let worst = worst_error(&pixels, expected);
    eprintln!("shadow through fog: expected {expected:.6}, worst pixel error {worst:.2e}");
    assert!(worst < 1e-5 * expected, "a pixel is {worst} off {expected}");
    assert!(stats.counters.fog_segments > 0);

    // The same floor without the slab: the light arrives whole.
    let (clear, _) = render_path(slab_over_floor(dir.path(), ""));
    let unfogged = 0.5 / std::f64::consts::PI * 2.0;
    assert!(worst_error(&clear, unfogged) < 1e-5 * unfogged);
}

/// (b) The medium furnace: fog that absorbs nothing (albedo 1) inside a box, in a uniform
/// environment of radiance 1, returns the environment everywhere — whatever the number of
/// scattering events, the phase function or the density — because nothing in the scene
/// absorbs or emits. Rendered with the box alone (isotropic, constant density, optical
/// thickness 3 across), and with two overlapping volumes of different kinds and phase
/// functions (constant g = 0.6 and exponential height fog g = -0.3, each volume's own
/// phase function chosen by where the collision fell) around a white diffuse sphere.
fn medium_furnace(dir: &Path, spp: u32, fog_and_surfaces: &str) -> SceneDescription {
    load(
        dir,
        &format!(
            r#"
[render]
width = 8
height = 8
spp = {spp}
max_depth = 128

[camera]
type = "orthographic"
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
height = 1.6

[environment]
color = [1.0, 1.0, 1.0]

[[material]]
name = "white"
base_color = [1.0, 1.0, 1.0]

{fog_and_surfaces}
"#
        ),
    )
}

const FURNACE_ALONE: &str = r#"
# Far outside the box and the view: the scene's only surface (white, it absorbs nothing).
[[sphere]]
center = [60.0, 0.0, -60.0]
radius = 0.1
material = "white"

[[fog]]
density = "constant"
sigma = 1.5
albedo = [1.0, 1.0, 1.0]
bounds = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }
"#;

const FURNACE_MIXED: &str = r#"
[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 0.4
material = "white"

[[fog]]
density = "constant"
sigma = 0.8
g = 0.6
bounds = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }

[[fog]]
density = "exponential"
sigma = 0.7
height = 0.0
falloff = 1.5
g = -0.3
bounds = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }
"#;

#[test]
fn a_medium_furnace_returns_the_environment() {
    let dir = temp_dir();
    for (name, fog) in [("alone", FURNACE_ALONE), ("mixed", FURNACE_MIXED)] {
        let scene = medium_furnace(dir.path(), 1024, fog);
        assert!(scene.lights.is_empty(), "{name}: a key light was added");
        let (pixels, stats) = render_path(scene);
        // Several collisions per path on average: the furnace tests multiple scattering.
        assert_furnace(name, &pixels, &stats, stats.counters.paths);
    }
}

/// The medium furnace's checks: a mean of 1 within 1 % in every channel, no pixel 0.05
/// off, more than `min_scatter_events` collisions, no non-finite sample.
fn assert_furnace(name: &str, pixels: &[[f32; 3]], stats: &RenderStats, min_scatter_events: u64) {
    let m = mean(pixels);
    let worst = worst_error(pixels, 1.0);
    let counters = &stats.counters;
    eprintln!(
        "medium furnace {name}: mean {m:?}, worst pixel error {worst:.4}, \
         scatter events {} over {} paths",
        counters.fog_scatter_events, counters.paths
    );
    for (c, value) in m.iter().enumerate() {
        assert!(
            (value - 1.0).abs() < 0.01,
            "{name}: channel {c} mean {value} (expected 1)"
        );
    }
    assert!(worst < 0.05, "{name}: a pixel is {worst} off");
    assert!(
        counters.fog_scatter_events > min_scatter_events,
        "{name}: {counters:?}"
    );
    assert_eq!(counters.nonfinite_samples, 0);
}

/// Fog bounded by closed meshes under the path tracer: (a) the absorber of
/// `a_pure_absorber_passes_exp_minus_sigma_d` split into two slabs of one mesh with clear
/// air between them (z in [-1.5, -1] and [0.5, 1], sigma 1: again exp(-1)); (b) the medium
/// furnace in a tessellated sphere, where scattered paths start inside the mesh.
#[test]
fn fog_in_a_mesh_absorbs_and_scatters_like_fog_in_a_box() {
    let dir = temp_dir();
    write(
        dir.path(),
        "slabs.obj",
        &boxes_obj(&[
            ([-10.0, -10.0, -1.5], [10.0, 10.0, -1.0]),
            ([-10.0, -10.0, 0.5], [10.0, 10.0, 1.0]),
        ]),
    );
    write(
        dir.path(),
        "ball.obj",
        &uv_sphere_obj([0.0; 3], 1.0, 64, 32),
    );
    let absorber = absorber_scene(1.0, "{ mesh = \"slabs.obj\" }");
    let (pixels, stats) = render_path(load(dir.path(), &absorber));
    let expected = (-1.0f64).exp();
    let m = mean(&pixels);
    let tolerance = 4.0 * (expected * (1.0 - expected) / 65536.0).sqrt();
    eprintln!(
        "absorber in two slabs of a mesh: mean {m:?}, expected {expected:.6} +- {tolerance:.4}"
    );
    for value in m {
        assert!(
            (value - expected).abs() < tolerance,
            "mean {value}, expected {expected}"
        );
    }
    assert_eq!(stats.counters.fog_volume_crossings, 65536);

    let furnace = FURNACE_ALONE.replace(
        "bounds = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }",
        "bounds = { mesh = \"ball.obj\" }",
    );
    assert!(furnace.contains("ball.obj"));
    let (pixels, stats) = render_path(medium_furnace(dir.path(), 1024, &furnace));
    assert_furnace(
        "in a sphere mesh",
        &pixels,
        &stats,
        stats.counters.paths / 2,
    );
}

/// A pixel whose first camera sample collides in fog keeps the surface behind the fog in
/// its AOVs, as Whitted's does: depth, normal, texture coordinates and albedo of a textured
/// sphere seen through fog so dense (optical depth 36) that every camera ray scatters first,
/// equal to Whitted's AOVs of the same scene. Before, those pixels kept a miss's values.
#[test]
fn aovs_describe_the_surface_behind_the_fog() {
    let dir = temp_dir();
    let text = r#"
[render]
width = 12
height = 12
spp = 1
max_depth = 2

[camera]
type = "orthographic"
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
height = 1.2

[environment]
color = [0.5, 0.5, 0.5]

[[texture]]
name = "checker"
file = "checker.png"

[[material]]
name = "textured"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "checker"

[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "textured"

[[fog]]
density = "constant"
sigma = 20.0
bounds = { min = [-5.0, -5.0, 1.2], max = [5.0, 5.0, 3.0] }
"#;
    std::fs::copy(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/checker.png"),
        dir.path().join("checker.png"),
    )
    .expect("copy the checker texture");
    fn render_aovs<I: conetrace::render::Integrator>(
        dir: &Path,
        text: &str,
        integrator: &I,
    ) -> (Vec<Vec<f32>>, RenderStats) {
        let scene = load(dir, text);
        let mut options = RenderOptions::from_settings(&scene.settings);
        options.aovs = conetrace::film::AovSelection::ALL;
        let context = render::prepare(Arc::new(scene), options).expect("prepare");
        let result =
            render::render(&context, integrator, &RenderControl::default()).expect("render");
        let names = [
            "Z", "N.X", "N.Y", "N.Z", "uv.U", "uv.V", "albedo.R", "albedo.G",
        ];
        let channels = names
            .iter()
            .map(|n| result.film.channel(n).expect(n).to_vec())
            .collect();
        (channels, result.stats)
    }
    let scene = load(dir.path(), text);
    let tracer = PathTracer::for_settings(&scene.settings);
    let (path, stats) = render_aovs(dir.path(), text, &tracer);
    let (whitted, _) = render_aovs(dir.path(), text, &conetrace::integrator::Whitted::default());
    // Every camera ray scattered in the fog.
    assert!(
        stats.counters.fog_scatter_events >= 144,
        "{:?}",
        stats.counters
    );
    let on_sphere = whitted[0].iter().filter(|z| **z < 100.0).count();
    assert!(on_sphere > 100, "{on_sphere} pixels on the sphere");
    for (index, (p, w)) in path.iter().zip(&whitted).enumerate() {
        for (pixel, (a, b)) in p.iter().zip(w).enumerate() {
            assert!(
                (a - b).abs() <= 1e-5 * b.abs().max(1.0),
                "AOV channel {index}, pixel {pixel}: path {a}, Whitted {b}"
            );
        }
    }
}

/// Light sampling alone, phase-function sampling alone and their MIS combination estimate
/// the same image at medium vertices: a box of coloured, forward-scattering fog (albedo
/// [0.9, 0.7, 0.5], g = 0.4) under an emissive quad (an area light) in a dim environment,
/// seen by a pinhole camera.
#[test]
fn light_phase_and_mis_estimates_agree_in_fog() {
    let dir = temp_dir();
    write(dir.path(), "lamp.obj", &square_obj(0.8, 0.0));
    let text = r#"
[render]
width = 24
height = 16
spp = 256
max_depth = 6

[camera]
type = "pinhole"
eye = [0.0, 0.3, 4.0]
target = [0.0, 0.0, 0.0]
fov = 45

[environment]
color = [0.05, 0.07, 0.1]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [4.0, 4.0, 4.0]

[[mesh]]
file = "lamp.obj"
material = "lamp"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.6, 0.0]

[[fog]]
density = "constant"
sigma = 1.2
albedo = [0.9, 0.7, 0.5]
g = 0.4
bounds = { min = [-1.0, -1.0, -1.0], max = [1.0, 1.0, 1.0] }
"#;
    let estimate = |strategy| {
        let tracer = PathTracer {
            strategy,
            ..PathTracer::default()
        };
        render_with(load(dir.path(), text), &tracer)
    };
    let (mis, stats) = estimate(LightStrategy::MultipleImportance);
    let (light, _) = estimate(LightStrategy::LightSampling);
    let (phase, _) = estimate(LightStrategy::BsdfSampling);
    let (m, l, p) = (mean(&mis), mean(&light), mean(&phase));
    eprintln!("fog means: MIS {m:?}, light sampling {l:?}, phase sampling {p:?}");
    assert!(stats.counters.fog_scatter_events > 0);
    for c in 0..3 {
        assert!(
            (m[c] - l[c]).abs() < 0.02 * m[c],
            "light sampling: {l:?} vs {m:?}"
        );
        assert!(
            (m[c] - p[c]).abs() < 0.03 * m[c],
            "phase sampling: {p:?} vs {m:?}"
        );
    }
}

/// (d) The image is a pure function of the seed: the mixed furnace on one thread and on two
/// is bit for bit the same, and another seed differs.
#[test]
fn fog_renders_are_deterministic() {
    let dir = temp_dir();
    let scene = medium_furnace(dir.path(), 8, FURNACE_MIXED);
    let run = |threads: usize, seed: u32| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let mut scene = scene.clone();
        scene.settings.seed = seed;
        pool.install(|| render_path(scene).0)
    };
    let one = run(1, 7);
    let two = run(2, 7);
    assert_eq!(one, two, "thread count changed the image");
    assert_ne!(one, run(2, 8), "the seed is not used");
}

/// (e) A scene without fog does no fog work under the path tracer: all three fog counters
/// stay zero.
#[test]
fn a_scene_without_fog_counts_no_fog_work() {
    let dir = temp_dir();
    let (_, stats) = render_path(slab_over_floor(dir.path(), ""));
    let counters = &stats.counters;
    assert!(counters.paths > 0);
    assert_eq!(counters.fog_segments, 0, "{counters:?}");
    assert_eq!(counters.fog_volume_crossings, 0, "{counters:?}");
    assert_eq!(counters.fog_scatter_events, 0, "{counters:?}");
}
