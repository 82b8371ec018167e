//! Textured area lights in the path tracer: next-event estimation reads the emission
//! texture at the sampled point, as a BSDF-sampled ray does where it hits the light, so
//! light sampling alone, BSDF sampling alone and their MIS combination estimate the same
//! image (docs/path-tracing.md).

mod common;

use std::path::Path;
use std::sync::Arc;

use common::*;
use conetrace::integrator::path::{LightStrategy, PathTracer};
use conetrace::render::{self, RenderControl, RenderOptions};
use conetrace::scene::load::load_toml_str;

/// A 64x64 PNG whose left half (s < 0.5) is black and right half white.
fn write_half_texture(dir: &Path) {
    let image = image::RgbImage::from_fn(64, 64, |x, _| {
        if x < 32 {
            image::Rgb([0, 0, 0])
        } else {
            image::Rgb([255, 255, 255])
        }
    });
    image
        .save(dir.join("half.png"))
        .expect("write the half-black texture");
}

/// Mean RGB of the image `strategy` renders of `text`.
fn mean_with(dir: &Path, text: &str, strategy: LightStrategy) -> [f64; 3] {
    let scene = load_toml_str(text, dir, "test.toml").unwrap_or_else(|e| panic!("scene: {e}"));
    let options = RenderOptions::from_settings(&scene.settings);
    let context = render::prepare(Arc::new(scene), options).expect("prepare");
    let tracer = PathTracer {
        strategy,
        ..PathTracer::default()
    };
    let result = render::render(&context, &tracer, &RenderControl::default()).expect("render");
    let film = &result.film;
    let mut sum = [0.0f64; 3];
    let mut count = 0;
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let channel = film.channel(name).expect("colour");
        count = channel.len();
        sum[c] = channel.iter().map(|&v| f64::from(v)).sum();
    }
    sum.map(|s| s / count as f64)
}

/// The three estimators of one scene agree within `tolerance` (relative).
fn assert_strategies_agree(dir: &Path, text: &str, tolerance: f64) {
    let light = mean_with(dir, text, LightStrategy::LightSampling);
    let bsdf = mean_with(dir, text, LightStrategy::BsdfSampling);
    let mis = mean_with(dir, text, LightStrategy::MultipleImportance);
    eprintln!("means: light sampling {light:?}, BSDF sampling {bsdf:?}, MIS {mis:?}");
    for c in 0..3 {
        assert!(
            (light[c] - bsdf[c]).abs() < tolerance * bsdf[c],
            "light sampling {light:?} vs BSDF sampling {bsdf:?}"
        );
        assert!(
            (mis[c] - bsdf[c]).abs() < tolerance * bsdf[c],
            "MIS {mis:?} vs BSDF sampling {bsdf:?}"
        );
    }
}

const HEADER: &str = r#"
[render]
width = 24
height = 16
spp = 256
max_depth = 2

[camera]
type = "pinhole"
eye = [0.0, 1.2, 3.0]
target = [0.0, 0.3, 0.0]
fov = 50

[[texture]]
name = "half"
file = "half.png"

[[material]]
name = "matte"
base_color = [0.6, 0.6, 0.6]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [4.0, 4.0, 4.0]
emission_texture = "half"

[[mesh]]
file = "plane.obj"
material = "matte"
"#;

/// A quad light whose emission texture is half black: with the constant emission in
/// next-event estimation, light sampling saw twice the light BSDF sampling found.
#[test]
fn a_half_black_textured_quad_light_is_estimated_alike_by_light_and_bsdf_sampling() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(5.0, 0.0));
    write(dir.path(), "lamp.obj", &square_obj(0.8, 0.0));
    write_half_texture(dir.path());
    let text = format!(
        "{HEADER}
[[mesh]]
file = \"lamp.obj\"
material = \"lamp\"
rotate = [180.0, 0.0, 0.0]
translate = [0.0, 1.6, 0.0]
"
    );
    assert_strategies_agree(dir.path(), &text, 0.03);
}

/// The same with a sphere light, whose texture is read at the lat-long st of the point.
#[test]
fn a_half_black_textured_sphere_light_is_estimated_alike_by_light_and_bsdf_sampling() {
    let dir = temp_dir();
    write(dir.path(), "plane.obj", &square_obj(5.0, 0.0));
    write_half_texture(dir.path());
    let text = format!(
        "{HEADER}
[[sphere]]
center = [0.0, 1.2, 0.0]
radius = 0.5
material = \"lamp\"
"
    );
    assert_strategies_agree(dir.path(), &text, 0.04);
}
