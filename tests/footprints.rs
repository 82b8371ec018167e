//! Whole-program tests of ray footprints through curved mirrors (seed 000, figures 5 and 6):
//! a concave mirror lowers the level of detail of what it magnifies, and the two-cone
//! envelope removes the zero-width contours a single cone shows after a concave bounce.
//!
//! The `lod` AOV is clamped to the pyramid (>= 0), so these tests measure an *unclamped*
//! level from the `tex.dsdx/dtdx/dsdy/dtdy` AOV channels: log2 of the footprint ellipse's
//! minor axis in texels (raised to major / max_aniso), the quantity OpenImageIO's level choice
//! compares against 1 (see docs/footprints.md).

mod common;

use std::path::{Path, PathBuf};

use common::*;

/// Level-0 size of assets/textures/miplevels.exr.
const MIPLEVELS_SIZE: f32 = 1024.0;
const MAX_ANISO: f32 = 16.0;

fn asset(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// Minor axis (in level-0 texels) of the ellipse spanned by the screen-space derivatives
/// of one lookup, after OpenImageIO's conservative anisotropy clamp (reference notes, steps
/// 2 and 4). `None` where no lookup happened.
fn minor_axis_texels(image: &ExrImage, pixel: usize, size: f32) -> Option<f32> {
    if image.channel("texcolor.A")[pixel] < 0.5 {
        return None;
    }
    let a = image.channel("tex.dsdx")[pixel] * size;
    let b = image.channel("tex.dsdy")[pixel] * size;
    let c = image.channel("tex.dtdx")[pixel] * size;
    let d = image.channel("tex.dtdy")[pixel] * size;
    // Singular values of the Jacobian [[a, b], [c, d]]: the ellipse's semi-axes.
    let s1 = a * a + b * b + c * c + d * d;
    let det = (a * d - b * c).abs();
    let root = (s1 * s1 - 4.0 * det * det).max(0.0).sqrt();
    let major = ((s1 + root) / 2.0).sqrt();
    let minor = ((s1 - root) / 2.0).max(0.0).sqrt();
    Some(if major > minor * MAX_ANISO {
        (major + minor * MAX_ANISO) / 2.0 / MAX_ANISO
    } else {
        minor
    })
}

/// Unclamped level of detail of one lookup: log2 of the minor axis in texels (the level
/// whose texels match the footprint; below 0 means magnification). `None` without lookup.
fn unclamped_lod(image: &ExrImage, pixel: usize, size: f32) -> Option<f32> {
    minor_axis_texels(image, pixel, size).map(|minor| {
        if minor > 0.0 {
            minor.log2()
        } else {
            f32::NEG_INFINITY
        }
    })
}

/// OpenImageIO's fractional level for a minor axis of `x` level-0 texels (step 5): level m
/// is the first with x / 2^m <= 1, blended with m - 1 by weight 2 x / 2^m - 1 (linear in
/// the filter width, so it differs from log2 x by up to 0.09 between integers).
fn oiio_fractional_level(x: f32) -> f32 {
    if x <= 1.0 {
        return 0.0;
    }
    let m = x.log2().ceil();
    (m - 1.0) + (2.0 * x / m.exp2() - 1.0).clamp(0.0, 1.0)
}

/// Render `scene` with `lod` and all AOVs into `dir`, return the EXR.
fn render(dir: &Path, scene: &Path, lod: &str, size: (u32, u32)) -> ExrImage {
    let exr = dir.join(format!("{lod}.exr"));
    let (w, h) = (size.0.to_string(), size.1.to_string());
    let out = run_in(
        dir,
        &[
            "render",
            scene.to_str().expect("utf-8 path"),
            "-o",
            exr.to_str().expect("utf-8 path"),
            "--no-png",
            "--quiet",
            "--width",
            &w,
            "--height",
            &h,
            "--lod",
            lod,
            "--filter",
            "aniso",
            "--aov",
            "all",
        ],
    );
    assert!(
        out.status.success(),
        "render {} --lod {lod}: {}",
        scene.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    read_exr(&exr)
}

/// A concave mirror (the cap of fp_concave.toml, radius of curvature 3, focal length 1.5)
/// and a textured ball 1 unit in front of it, inside the focal length, with nothing else: every
/// mirror pixel with a texture lookup sees the ball, magnified.
fn write_magnifying_mirror_scene(dir: &Path) -> PathBuf {
    let scene = format!(
        r#"
[camera]
type = "pinhole"
eye = [0.0, 2.6, 4.0]
target = [0.0, 1.6, -1.5]
fov = 30

[[light]]
type = "directional"
direction = [-0.3, -1.0, -0.6]
intensity = 2.5

[environment]
color = [0.25, 0.27, 0.32]

[[texture]]
name = "miplevels"
file = "{texture}"
color_space = "linear"

[[material]]
name = "ball"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "miplevels"
texture_scale = [2.0, 1.0]

[[material]]
name = "mirror"
base_color = [0.0, 0.0, 0.0]
mirror = 0.95

[[mesh]]
file = "{dish}"
material = "mirror"
translate = [0.0, 2.0, 1.0]
scale = 3.0

[[sphere]]
center = [0.0, 1.9, -1.0]
radius = 0.3
material = "ball"
"#,
        texture = asset("assets/textures/miplevels.exr").display(),
        dish = asset("assets/models/dish.obj").display()
    );
    write(dir, "magnifying_mirror.toml", &scene)
}

/// Pixels whose first hit has zero albedo (the untextured black mirror) and whose path
/// made a texture lookup after the bounce.
fn mirror_pixels(image: &ExrImage) -> Vec<usize> {
    let (r, g, b) = (
        image.channel("albedo.R"),
        image.channel("albedo.G"),
        image.channel("albedo.B"),
    );
    let looked_up = image.channel("texcolor.A");
    (0..image.width * image.height)
        .filter(|&i| r[i] + g[i] + b[i] == 0.0 && looked_up[i] > 0.5)
        .collect()
}

/// A concave mirror magnifies the ball in front of it: after the bounce the ray cone
/// converges, so the cone strategy picks finer levels than the distance metric (which is
/// what a flat mirror at the same place would give) on the mirror's pixels, while on the
/// ball seen directly both agree.
#[test]
fn concave_mirror_lowers_the_lod_of_what_it_magnifies() {
    let dir = temp_dir();
    let scene = write_magnifying_mirror_scene(dir.path());
    let size = (160, 120);
    let cone = render(dir.path(), &scene, "cone", size);
    let distance = render(dir.path(), &scene, "distance", size);

    let mirror = mirror_pixels(&cone);
    let mut lowered = 0usize;
    let mut sum_difference = 0.0f64;
    for &i in &mirror {
        let (Some(c), Some(d)) = (
            unclamped_lod(&cone, i, MIPLEVELS_SIZE),
            unclamped_lod(&distance, i, MIPLEVELS_SIZE),
        ) else {
            panic!("pixel {i}: a lookup under one strategy only");
        };
        sum_difference += (d - c) as f64;
        if c < d - 0.25 {
            lowered += 1;
        }
    }
    let compared = mirror.len();
    assert!(
        compared > 300,
        "too few mirror pixels see the ball: {compared}"
    );
    let mean_difference = sum_difference / compared as f64;
    eprintln!(
        "concave mirror: {compared} pixels see the ball, cone LOD below the distance metric's by {mean_difference:.2} levels on average, {lowered} by more than 0.25"
    );
    assert!(
        mean_difference > 0.5,
        "cone LOD only {mean_difference:.2} levels below the distance metric's"
    );
    assert!(
        lowered * 10 >= compared * 9,
        "only {lowered} of {compared} mirror pixels got a finer level"
    );

    // Control: the ball seen directly has the same footprint under both strategies.
    let albedo = cone.channel("albedo.R");
    let mut direct = 0usize;
    for (i, &a) in albedo.iter().enumerate().take(cone.width * cone.height) {
        if a > 0.0 {
            let (Some(c), Some(d)) = (
                unclamped_lod(&cone, i, MIPLEVELS_SIZE),
                unclamped_lod(&distance, i, MIPLEVELS_SIZE),
            ) else {
                continue;
            };
            direct += 1;
            assert!(
                (c - d).abs() < 0.05,
                "ball pixel {i}: cone {c} vs distance {d}"
            );
        }
    }
    assert!(direct > 100, "too few direct ball pixels: {direct}");
}

/// Seed 000's figure 6: behind a concave mirror's focus a single cone passes through zero
/// width, and pixels along that contour ask for levels far below 0; the two-cone envelope
/// keeps a width there. Counted over the whole image: pixels with unclamped LOD < -1.
#[test]
fn two_cone_envelope_removes_zero_width_contours() {
    let dir = temp_dir();
    let scene = asset("assets/scenes/fp_two_cones.toml");
    let size = (320, 180);
    let cone1 = render(dir.path(), &scene, "cone1", size);
    let cone = render(dir.path(), &scene, "cone", size);
    let below = |image: &ExrImage| {
        (0..image.width * image.height)
            .filter_map(|i| unclamped_lod(image, i, MIPLEVELS_SIZE))
            .filter(|&lod| lod < -1.0)
            .count()
    };
    let (single, envelope) = (below(&cone1), below(&cone));
    eprintln!("pixels with LOD < -1: cone1 {single}, cone {envelope}");
    assert!(
        single >= 20,
        "cone1 shows no zero-width contour ({single} pixels below -1)"
    );
    assert!(
        envelope * 10 <= single,
        "the envelope leaves {envelope} pixels below -1 (cone1: {single})"
    );
}

/// The `lod` AOV (clamped to the pyramid) agrees with the unclamped level computed from
/// the `tex.*` channels wherever that lies inside the pyramid.
#[test]
fn lod_aov_matches_the_footprint_channels() {
    let dir = temp_dir();
    let scene = asset("assets/scenes/fp_concave.toml");
    let image = render(dir.path(), &scene, "cone", (96, 54));
    let lod = image.channel("lod");
    let footprint = image.channel("footprint");
    let mut checked = 0;
    for i in 0..image.width * image.height {
        let Some(minor) = minor_axis_texels(&image, i, MIPLEVELS_SIZE) else {
            continue;
        };
        assert!(footprint[i] > 0.0, "pixel {i}: footprint {}", footprint[i]);
        let expected = oiio_fractional_level(minor);
        if minor > 1.1 && expected < 9.9 {
            checked += 1;
            assert!(
                (lod[i] - expected).abs() < 0.02,
                "pixel {i}: lod AOV {} vs {expected} from tex.*",
                lod[i]
            );
        } else if minor < 0.9 {
            assert_eq!(
                lod[i], 0.0,
                "pixel {i}: magnified lookup should read level 0"
            );
        }
    }
    assert!(checked > 1000, "only {checked} pixels checked");
}
