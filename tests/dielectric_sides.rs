//! One rule decides which side of a dielectric a ray is on: the geometric normal.
//!
//! A coarse (8x6) smooth-shaded glass sphere under a unit environment, no lights. At its
//! silhouettes the interpolated shading normal can face away from a ray that geometrically
//! arrives from outside. The index ratio, total internal reflection and the medium a
//! refracted ray carries must all follow the geometric side; taking the index ratio from the
//! shading normal there treats an arriving ray as one leaving the glass, and total internal
//! reflection (impossible from air) sends all of it back out.
//!
//! Checks:
//! - energy: with a clear, a tinted and an opaque-absorbing medium, every pixel lies in
//!   [0, 1] (a unit environment cannot be amplified);
//! - with a medium that absorbs everything that enters, a pixel is exactly the share
//!   reflected at the first hit: rays that never entered carry no absorption, and light
//!   that entered never comes back. Where the shading normal faces the camera ray, that
//!   share is the Fresnel reflectance for air to glass at the shading normal's cosine;
//!   where it faces away (silhouette pixels), the ray still arrives from outside, so some
//!   light must enter: the pixel is below 1 and at least the normal-incidence reflectance.

mod common;

use std::path::Path;
use std::sync::Arc;

use conetrace::film::AovSelection;
use conetrace::film::Film;
use conetrace::footprint::LodStrategy;
use conetrace::integrator::Whitted;
use conetrace::render::{self, RenderContext, RenderControl, RenderOptions};
use conetrace::scene::load::load_toml_str;
use conetrace::scene::FresnelMode;
use conetrace::shading::fresnel_dielectric;
use conetrace::texture::FilterOptions;
use glam::Vec3;

const SIZE: u32 = 64;
const IOR: f32 = 1.5;

fn options() -> RenderOptions {
    RenderOptions {
        width: SIZE,
        height: SIZE,
        spp: 1,
        max_depth: 8,
        min_throughput: 1e-4,
        lod: LodStrategy::Cone,
        filter: FilterOptions::default(),
        fresnel: FresnelMode::Exact,
        aovs: AovSelection {
            surface: true,
            ..AovSelection::default()
        },
        count_texture_tiles: false,
        all_effects: false,
        seed: 0,
        sample_clamp: None,
    }
}

/// The glass sphere scene; `medium` is the material's extra TOML lines (attenuation).
fn scene_toml(eye: [f32; 3], medium: &str) -> String {
    format!(
        r#"
[camera]
eye = [{}, {}, {}]
target = [0, 0, 0]
fov = 40

[environment]
color = [1, 1, 1]

[[material]]
name = "glass"
base_color = [0, 0, 0]
transmission = 1.0
ior = {IOR}
{medium}

[[mesh]]
file = "sphere.obj"
material = "glass"
"#,
        eye[0], eye[1], eye[2]
    )
}

fn render_in(dir: &Path, toml: &str) -> (RenderContext, Film) {
    let scene = load_toml_str(toml, dir, "glass.toml")
        .unwrap_or_else(|e| panic!("scene does not load: {e}"));
    let context = render::prepare(Arc::new(scene), options())
        .unwrap_or_else(|e| panic!("scene does not prepare: {e}"));
    let result = render::render(&context, &Whitted::default(), &RenderControl::default())
        .unwrap_or_else(|e| panic!("render failed: {e}"));
    assert!(result.stats.complete, "render incomplete");
    (context, result.film)
}

fn channel<'a>(film: &'a Film, name: &str) -> &'a [f32] {
    film.channel(name)
        .unwrap_or_else(|| panic!("channel {name} missing"))
}

const EYES: [[f32; 3]; 3] = [[0.0, 0.3, 4.0], [2.5, 1.7, 2.2], [-0.7, -2.9, 2.1]];

fn sphere_dir() -> tempfile::TempDir {
    let dir = common::temp_dir();
    common::write(
        dir.path(),
        "sphere.obj",
        &common::uv_sphere_obj([0.0, 0.0, 0.0], 1.0, 8, 6),
    );
    dir
}

#[test]
fn glass_never_creates_energy_under_a_unit_environment() {
    let dir = sphere_dir();
    let media = [
        "",
        "attenuation_color = [0.3, 0.6, 0.9]\nattenuation_distance = 1.0",
        "attenuation_color = [1e-30, 1e-30, 1e-30]\nattenuation_distance = 1e-6",
    ];
    for eye in EYES {
        for medium in media {
            let (_, film) = render_in(dir.path(), &scene_toml(eye, medium));
            for name in ["R", "G", "B"] {
                let plane = channel(&film, name);
                let (low, high) = plane
                    .iter()
                    .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| {
                        (l.min(v), h.max(v))
                    });
                println!("eye {eye:?} medium {medium:?} {name}: range [{low}, {high}]");
                assert!(
                    low >= 0.0 && high <= 1.0 + 1e-5,
                    "eye {eye:?}, medium {medium:?}, {name}: values in [{low}, {high}]"
                );
            }
        }
    }
}

#[test]
fn light_arriving_from_outside_is_split_as_air_to_glass() {
    let dir = sphere_dir();
    let opaque_medium = "attenuation_color = [1e-30, 1e-30, 1e-30]\nattenuation_distance = 1e-6";
    let mut facing_total = 0;
    let mut averted_total = 0;
    let mut failures = Vec::new();
    for eye in EYES {
        let (context, film) = render_in(dir.path(), &scene_toml(eye, opaque_medium));
        let red = channel(&film, "R");
        let depth = channel(&film, "Z");
        let normal = [
            channel(&film, "N.X"),
            channel(&film, "N.Y"),
            channel(&film, "N.Z"),
        ];
        let mut worst_facing = 0.0f32;
        let mut averted = Vec::new();
        for y in 0..SIZE {
            for x in 0..SIZE {
                let i = (y * SIZE + x) as usize;
                let value = red[i];
                if depth[i] == f32::MAX {
                    // The camera ray missed: it sees the environment, unabsorbed.
                    if value != 1.0 {
                        failures.push(format!("eye {eye:?} ({x}, {y}): miss shows {value}"));
                    }
                    continue;
                }
                let (_, d) = context.camera.generate_ray(
                    x as f32 + 0.5,
                    y as f32 + 0.5,
                    glam::Vec2::splat(0.5),
                );
                let ns = Vec3::new(normal[0][i], normal[1][i], normal[2][i]);
                let cos = d.dot(ns);
                if cos < 0.0 {
                    facing_total += 1;
                    let expected = fresnel_dielectric(-cos, 1.0 / IOR);
                    worst_facing = worst_facing.max((value - expected).abs());
                } else {
                    averted_total += 1;
                    averted.push(value);
                    if !(value < 1.0 - 1e-3 && value >= fresnel_dielectric(1.0, 1.0 / IOR) - 1e-4) {
                        failures.push(format!(
                            "eye {eye:?} ({x}, {y}): arrived from outside, shading normal \
                             averted, pixel {value}"
                        ));
                    }
                }
            }
        }
        let totally_reflected = averted.iter().filter(|&&v| v >= 1.0 - 1e-3).count();
        println!(
            "eye {eye:?}: worst |pixel - R(air to glass)| where the shading normal faces the \
             ray {worst_facing:.2e}; {} pixels with an averted shading normal, {} of them \
             totally reflected",
            averted.len(),
            totally_reflected
        );
        if worst_facing > 1e-3 {
            failures.push(format!(
                "eye {eye:?}: a pixel differs from the air-to-glass reflectance by {worst_facing}"
            ));
        }
    }
    assert!(
        averted_total >= 20,
        "the views should include silhouette pixels with averted shading normals, found \
         {averted_total}"
    );
    assert!(facing_total > 500, "too few sphere pixels: {facing_total}");
    assert!(
        failures.is_empty(),
        "{} failures, first ones: {:?}",
        failures.len(),
        &failures[..failures.len().min(8)]
    );
}
