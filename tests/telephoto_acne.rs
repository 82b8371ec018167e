//! Self-intersection at realistic camera distances: a smooth-shaded unit sphere (a 64x32 UV
//! mesh with vertex normals) resting on a ground quad, lit by a directional light from above
//! and in front, seen through a narrow pinhole camera 1e2, 1e3 and 1e4 units away. Each view
//! is compared with an orthographic view of the same framing from 4 units away, where hit
//! points are accurate to a few ULPs of 1.
//!
//! Unlike the far/tiny scale tests (which move camera and scene together), the scene stays
//! at the origin and only the camera recedes: camera-ray hit points carry rounding errors of
//! the camera's distance, so secondary rays must start from a point whose error does not
//! depend on the ray that found it (`conetrace::shading::ray_offset`); and the intersector's
//! own rounding grows with the ray origin's distance until a camera ray slips between two
//! triangles of the closed sphere and hits its far side, so camera rays start tracing where
//! they enter the scene's bounds (`conetrace::shading::entry_distance`).
//!
//! Two measures per distance, printed and checked:
//! - PSNR over the colour image (values clamped to [0, 1], peak 1): at least 40 dB. The
//!   perspective of a 1e2-unit pinhole differs from the orthographic projection by about 1%
//!   in scale across the sphere's depth, which moves smooth shading by far less than that.
//! - Speckles: a pixel is a speckle when the orthographic reference is lit and uniform
//!   around it (the reference pixel and its 8 neighbours are all at least `LIT` and within
//!   10% of each other, so edges of the silhouette and of the shadow, which perspective may
//!   move by a fraction of a pixel, are excluded) and the pinhole pixel is darker than
//!   `SPECKLE_RATIO` times the reference. A shadow ray that hits the surface it starts on
//!   leaves only the ambient term, about 7% of the lit value. No speckle is allowed.

mod common;

use std::path::Path;
use std::sync::Arc;

use conetrace::film::AovSelection;
use conetrace::film::Film;
use conetrace::footprint::LodStrategy;
use conetrace::integrator::Whitted;
use conetrace::render::{self, RenderControl, RenderOptions};
use conetrace::scene::load::load_toml_str;
use conetrace::scene::FresnelMode;
use conetrace::texture::FilterOptions;

const SIZE: u32 = 128;
/// Height of the view rectangle at the sphere's centre, in world units.
const FRAME_HEIGHT: f64 = 3.2;
/// Camera direction (from the target towards the eye): azimuth and elevation in degrees.
const CAMERA_AZIMUTH: f64 = 25.0;
const CAMERA_ELEVATION: f64 = 30.0;
/// The light comes from the camera's direction (above and in front of the sphere), so the
/// sphere's shadow lies hidden behind it in every view: a visible shadow edge would move by
/// a fraction of a pixel between perspective and orthographic projection, and the
/// comparison is about self-intersection, not perspective.
const LIGHT_AZIMUTH: f64 = 25.0;
const LIGHT_ELEVATION: f64 = 30.0;
/// A reference pixel at least this bright (linear) is lit: the lit ground is about 0.55, the
/// ambient-only (shadowed) value 0.04.
const LIT: f32 = 0.2;
/// A pinhole pixel darker than this fraction of a lit, uniform reference pixel is a speckle.
const SPECKLE_RATIO: f32 = 0.75;
const MIN_PSNR_DB: f64 = 40.0;

/// Unit vector of azimuth `az` (about +y, from +z towards +x) and elevation `el`, degrees.
fn direction(az: f64, el: f64) -> [f64; 3] {
    let (az, el) = (az.to_radians(), el.to_radians());
    [el.cos() * az.sin(), el.sin(), el.cos() * az.cos()]
}

/// The scene's TOML with the given `[camera]` table.
fn scene_toml(camera: &str) -> String {
    let light = direction(LIGHT_AZIMUTH, LIGHT_ELEVATION);
    format!(
        r#"
{camera}

[[light]]
type = "directional"
direction = [{lx:.9}, {ly:.9}, {lz:.9}]
intensity = 3

[environment]
color = [0.05, 0.05, 0.05]

[[material]]
name = "matte"
base_color = [0.8, 0.8, 0.8]

[[mesh]]
file = "ground.obj"
material = "matte"

[[mesh]]
file = "sphere.obj"
material = "matte"
"#,
        lx = -light[0],
        ly = -light[1],
        lz = -light[2],
    )
}

/// Camera table looking at the sphere's centre from `distance` units away.
fn camera_toml(distance: f64, orthographic: bool) -> String {
    let back = direction(CAMERA_AZIMUTH, CAMERA_ELEVATION);
    let target = [0.0, 1.0, 0.0];
    let eye = [
        target[0] + distance * back[0],
        target[1] + distance * back[1],
        target[2] + distance * back[2],
    ];
    let projection = if orthographic {
        format!("type = \"orthographic\"\nheight = {FRAME_HEIGHT}")
    } else {
        // The vertical field of view that frames FRAME_HEIGHT at the target's distance.
        let fov = 2.0 * (0.5 * FRAME_HEIGHT / distance).atan().to_degrees();
        format!("type = \"pinhole\"\nfov = {fov:.12e}")
    };
    format!(
        "[camera]\n{projection}\neye = [{:.9}, {:.9}, {:.9}]\ntarget = [{}, {}, {}]\n",
        eye[0], eye[1], eye[2], target[0], target[1], target[2]
    )
}

fn options() -> RenderOptions {
    RenderOptions {
        width: SIZE,
        height: SIZE,
        spp: 1,
        max_depth: 4,
        min_throughput: 1e-3,
        lod: LodStrategy::Cone,
        filter: FilterOptions::default(),
        fresnel: FresnelMode::Exact,
        aovs: AovSelection::default(),
        count_texture_tiles: false,
        all_effects: false,
        seed: 0,
        sample_clamp: None,
    }
}

fn render_view(dir: &Path, camera: &str) -> Vec<f32> {
    let scene = load_toml_str(&scene_toml(camera), dir, "telephoto.toml")
        .unwrap_or_else(|e| panic!("scene does not load: {e}"));
    let context = render::prepare(Arc::new(scene), options())
        .unwrap_or_else(|e| panic!("scene does not prepare: {e}"));
    let result = render::render(&context, &Whitted::default(), &RenderControl::default())
        .unwrap_or_else(|e| panic!("render failed: {e}"));
    assert!(result.stats.complete, "render incomplete");
    luminance(&result.film)
}

/// Mean of R, G and B per pixel (the scene is grey).
fn luminance(film: &Film) -> Vec<f32> {
    let (r, g, b) = (
        film.channel("R").expect("R channel"),
        film.channel("G").expect("G channel"),
        film.channel("B").expect("B channel"),
    );
    (0..r.len()).map(|i| (r[i] + g[i] + b[i]) / 3.0).collect()
}

fn psnr(reference: &[f32], image: &[f32]) -> f64 {
    let mse = reference
        .iter()
        .zip(image)
        .map(|(&a, &b)| {
            let d = a.clamp(0.0, 1.0) as f64 - b.clamp(0.0, 1.0) as f64;
            d * d
        })
        .sum::<f64>()
        / reference.len() as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (1.0 / mse).log10()
    }
}

/// Whether the reference is lit and uniform in the 3x3 neighbourhood of (x, y).
fn lit_and_uniform(reference: &[f32], x: usize, y: usize) -> bool {
    let size = SIZE as usize;
    let centre = reference[y * size + x];
    if centre < LIT || x == 0 || y == 0 || x + 1 == size || y + 1 == size {
        return false;
    }
    (y - 1..=y + 1).all(|ny| {
        (x - 1..=x + 1).all(|nx| {
            let v = reference[ny * size + nx];
            v >= LIT && (v - centre).abs() <= 0.1 * centre
        })
    })
}

/// Speckles (see the module doc) and how many reference pixels were eligible.
fn speckles(reference: &[f32], image: &[f32]) -> (usize, usize) {
    let size = SIZE as usize;
    let mut eligible = 0;
    let mut count = 0;
    for y in 0..size {
        for x in 0..size {
            if !lit_and_uniform(reference, x, y) {
                continue;
            }
            eligible += 1;
            let i = y * size + x;
            if image[i] < SPECKLE_RATIO * reference[i] {
                count += 1;
            }
        }
    }
    (count, eligible)
}

#[test]
fn telephoto_views_match_the_orthographic_view() {
    let dir = common::temp_dir();
    common::write(dir.path(), "ground.obj", &common::square_obj(50.0, 0.0));
    common::write(
        dir.path(),
        "sphere.obj",
        &common::uv_sphere_obj([0.0, 1.0, 0.0], 1.0, 64, 32),
    );
    let reference = render_view(dir.path(), &camera_toml(4.0, true));
    let size = SIZE as usize;
    let lit = reference.iter().filter(|&&v| v >= LIT).count();
    assert!(
        lit > size * size / 2,
        "the orthographic reference should be mostly lit, {lit} lit pixels"
    );
    let mut failures = Vec::new();
    for distance in [1e2, 1e3, 1e4] {
        let image = render_view(dir.path(), &camera_toml(distance, false));
        let db = psnr(&reference, &image);
        let (count, eligible) = speckles(&reference, &image);
        println!(
            "pinhole at {distance:e}: PSNR {db:.2} dB against the orthographic view, \
             {count} speckles among {eligible} lit uniform pixels"
        );
        if db < MIN_PSNR_DB || count > 0 {
            failures.push(format!("{distance:e}: {db:.2} dB, {count} speckles"));
        }
    }
    assert!(
        failures.is_empty(),
        "telephoto views differ from the orthographic view (need >= {MIN_PSNR_DB} dB and no \
         speckles): {failures:?}"
    );
}
