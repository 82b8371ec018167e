//! Normal-mapped materials and emission-textured emitters shaded in lanes
//! (`integrator::lanes`): their hits take the lanes in both integrators, and the path
//! tracer's lanes give its scalar path's image and AOVs bit for bit.
//!
//! The scene is written here: a normal-mapped diffuse ground and sphere, a normal-mapped
//! glossy (metallic-roughness) panel and sphere, a normal-mapped classic material with a
//! highlight, and an emission-textured lamp quad and sphere, lit by them and a point light.

mod common;

use std::f32::consts::TAU;
use std::path::Path;
use std::sync::Arc;

use common::*;
use conetrace::film::{AovSelection, Film};
use conetrace::footprint::LodStrategy;
use conetrace::integrator::{PathTracer, Whitted};
use conetrace::render::{self, RenderControl, RenderOptions, RenderStats};
use conetrace::scene::load::load_toml_str;

const SCENE: &str = r#"
[render]
width = 48
height = 36
spp = 2
max_depth = 4

[camera]
type = "pinhole"
eye = [0.0, 2.2, 4.5]
target = [0.0, 0.4, 0.0]
fov = 50

[environment]
color = [0.1, 0.12, 0.15]

[[light]]
type = "point"
position = [2.0, 4.0, 3.0]
intensity = 40

[[texture]]
name = "bumps"
file = "bumps.png"
color_space = "linear"

[[texture]]
name = "glow"
file = "glow.png"

[[material]]
name = "bumpy_diffuse"
base_color = [0.7, 0.6, 0.5]
normal_texture = "bumps"
texture_scale = [4.0, 4.0]

[[material]]
name = "bumpy_glossy"
base_color = [0.8, 0.5, 0.3]
roughness = 0.3
metallic = 0.6
normal_texture = "bumps"
normal_scale = 1.5

[[material]]
name = "bumpy_highlight"
base_color = [0.4, 0.6, 0.7]
specular = 0.3
shininess = 40
normal_texture = "bumps"
normal_scale = 0.7

[[material]]
name = "lamp"
base_color = [0.8, 0.8, 0.8]
emission = [4.0, 3.5, 3.0]
emission_texture = "glow"

[[mesh]]
file = "ground.obj"
material = "bumpy_diffuse"

[[mesh]]
file = "panel.obj"
material = "bumpy_glossy"
rotate = [70.0, 25.0, 0.0]
translate = [1.6, 0.9, -1.2]

# Facing down, under the ceiling the scene has not.
[[mesh]]
file = "panel.obj"
material = "lamp"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 2.6, 0.0]

[[sphere]]
center = [-0.9, 0.6, 0.0]
radius = 0.6
material = "bumpy_glossy"

[[sphere]]
center = [0.9, 0.5, 0.3]
radius = 0.5
material = "bumpy_diffuse"

[[sphere]]
center = [0.1, 0.3, 1.3]
radius = 0.3
material = "bumpy_highlight"

[[sphere]]
center = [-1.9, 1.3, -1.2]
radius = 0.35
material = "lamp"
"#;

/// Writes the scene's meshes and textures into `dir`: a tangent-space normal map of
/// bumps (some steep enough at scale 1.5 to bend below the surface, where the normal is
/// left alone) and a striped emission texture.
fn write_scene_files(dir: &Path) {
    write(dir, "ground.obj", &square_obj(4.0, 0.0));
    write(dir, "panel.obj", &square_obj(0.6, 0.0));
    let bumps = image::RgbImage::from_fn(64, 64, |x, y| {
        let slope_x = 0.9 * (TAU * x as f32 / 16.0).sin();
        let slope_y = 0.9 * (TAU * y as f32 / 8.0).cos();
        let n = glam::Vec3::new(slope_x, slope_y, 1.0).normalize();
        let texel = (n * 0.5 + glam::Vec3::splat(0.5)) * 255.0;
        image::Rgb(texel.to_array().map(|c| c.round() as u8))
    });
    bumps.save(dir.join("bumps.png")).expect("write bumps.png");
    let glow = image::RgbImage::from_fn(32, 32, |x, y| match (x / 4 + y / 8) % 3 {
        0 => image::Rgb([255, 240, 200]),
        1 => image::Rgb([60, 120, 255]),
        _ => image::Rgb([10, 10, 10]),
    });
    glow.save(dir.join("glow.png")).expect("write glow.png");
}

/// The scene prepared with its own settings, changed by `options`.
fn context(dir: &Path, options: impl Fn(&mut RenderOptions)) -> render::RenderContext {
    let scene = load_toml_str(SCENE, dir, "scene.toml").unwrap_or_else(|e| panic!("{e}"));
    let mut render_options = RenderOptions::from_settings(&scene.settings);
    options(&mut render_options);
    render::prepare(Arc::new(scene), render_options).expect("prepare")
}

/// The path tracer's film and statistics, shaded in lanes or by the scalar path alone.
fn render_path(
    dir: &Path,
    in_lanes: bool,
    options: impl Fn(&mut RenderOptions),
) -> (Film, RenderStats) {
    let tracer = PathTracer {
        shade_in_lanes: in_lanes,
        ..PathTracer::default()
    };
    let result =
        render::render(&context(dir, options), &tracer, &RenderControl::default()).expect("render");
    (result.film, result.stats)
}

/// A render's name, how it changes the scene's options, and the least share of the camera
/// rays' count the lanes must shade: every material is normal-mapped or an
/// emission-textured emitter, so the lanes took no hit before.
type Variant = (&'static str, fn(&mut RenderOptions), f64);

#[test]
fn path_lanes_shade_normal_maps_and_emission_textures_with_the_scalar_bits() {
    let dir = temp_dir();
    write_scene_files(dir.path());
    let variants: [Variant; 3] = [
        ("default", |_| {}, 0.6),
        ("mip0", |o| o.lod = LodStrategy::Mip0, 0.6),
        // First samples record their pixel's first lookup by the scalar path: the lanes
        // take the second samples and the bounces.
        ("every AOV", |o| o.aovs = AovSelection::ALL, 0.3),
    ];
    for (variant, options, least_share) in variants {
        let (lanes, stats) = render_path(dir.path(), true, options);
        let (scalar, scalar_stats) = render_path(dir.path(), false, options);
        assert_eq!(scalar_stats.counters.lane_hits, 0, "{variant}");
        assert_same_bits(variant, &lanes, &scalar);
        let counters = &stats.counters;
        assert!(
            counters.lane_hits as f64 > least_share * counters.camera_rays as f64,
            "{variant}: {} lane hits of {} camera rays",
            counters.lane_hits,
            counters.camera_rays
        );
        assert_eq!(
            counters.texture_lookups, scalar_stats.counters.texture_lookups,
            "{variant}"
        );
    }
}

#[test]
fn whitted_lanes_shade_normal_mapped_hits() {
    let dir = temp_dir();
    write_scene_files(dir.path());
    let context = context(dir.path(), |_| {});
    let result =
        render::render(&context, &Whitted::default(), &RenderControl::default()).expect("render");
    let counters = &result.stats.counters;
    // Whitted's lanes leave the emitters to the scalar path; the normal-mapped rest is
    // most of the camera's hits.
    assert!(
        counters.lane_hits > counters.camera_rays / 2,
        "{} lane hits of {} camera rays",
        counters.lane_hits,
        counters.camera_rays
    );
}
