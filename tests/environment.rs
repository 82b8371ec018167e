//! Lat-long environments rendered by the binary: what a camera looking straight at a pole
//! sees. The map's top row is red and its bottom row blue, so any blue seen at the +Y pole
//! (or red at the -Y pole) has bled across the map's t = 0 / t = 1 seam.

mod common;

use common::{read_exr, run_in, temp_dir, write};
use std::path::Path;

/// A 16 x 8 linear map: row 0 (the +Y pole) red, row 7 (the -Y pole) blue, grey between.
fn write_pole_map(dir: &Path) {
    let image = image::RgbImage::from_fn(16, 8, |_, y| match y {
        0 => image::Rgb([255, 0, 0]),
        7 => image::Rgb([0, 0, 255]),
        _ => image::Rgb([128, 128, 128]),
    });
    image
        .save(dir.join("poles.png"))
        .expect("write the pole map");
}

/// Renders a 9 x 9 view with a 10 degree field of view looking along `look` (+1 up, -1 down)
/// and returns every pixel's (R, G, B).
fn render_pole(dir: &Path, look: f32, texture_extra: &str) -> Vec<[f32; 3]> {
    write_pole_map(dir);
    let scene = format!(
        "[render]\nwidth = 9\nheight = 9\nspp = 1\n\n\
         [camera]\ntype = \"pinhole\"\neye = [0, 0, 0]\ntarget = [0, {look}, 0]\n\
         up = [0, 0, -1]\nfov = 10\n\n\
         [[texture]]\nname = \"sky\"\nfile = \"poles.png\"\ncolor_space = \"linear\"\n\
         {texture_extra}\n\n\
         [environment]\ntexture = \"sky\"\n"
    );
    write(dir, "poles.toml", &scene);
    let output = run_in(
        dir,
        &[
            "render",
            "poles.toml",
            "-o",
            "poles.exr",
            "--no-png",
            "--quiet",
        ],
    );
    assert!(
        output.status.success(),
        "render failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let image = read_exr(&dir.join("poles.exr"));
    let (r, g, b) = (image.channel("R"), image.channel("G"), image.channel("B"));
    (0..image.width * image.height)
        .map(|i| [r[i], g[i], b[i]])
        .collect()
}

/// The largest share of the opposite pole's colour among the pixels: blue / red looking up,
/// red / blue looking down.
fn worst_bleed(pixels: &[[f32; 3]], look: f32) -> f32 {
    pixels
        .iter()
        .map(|p| {
            let (own, other) = if look > 0.0 {
                (p[0], p[2])
            } else {
                (p[2], p[0])
            };
            assert!(own > 0.2, "the pole's own colour is missing: {p:?}");
            other / own
        })
        .fold(0.0, f32::max)
}

#[test]
fn lat_long_poles_do_not_bleed_into_each_other_by_default() {
    for look in [1.0f32, -1.0] {
        let dir = temp_dir();
        let pixels = render_pole(dir.path(), look, "");
        let bleed = worst_bleed(&pixels, look);
        let centre = pixels[4 * 9 + 4];
        eprintln!(
            "looking {}: centre pixel {centre:?}, worst opposite-pole share {bleed:.4}",
            if look > 0.0 { "up" } else { "down" }
        );
        assert!(
            bleed < 1e-3,
            "looking {look}: the opposite pole's colour leaks in ({bleed:.4} of the pole's own)"
        );
    }
}

#[test]
fn an_explicit_wrap_t_still_applies_to_the_environment() {
    // Asked for, periodic t joins the two poles: the centre pixel straight up sits on the
    // seam between row 0 and row 7 and sees both.
    let dir = temp_dir();
    let pixels = render_pole(dir.path(), 1.0, "wrap_t = \"periodic\"");
    let centre = pixels[4 * 9 + 4];
    eprintln!("explicit periodic t, looking up: centre pixel {centre:?}");
    assert!(
        centre[2] > 0.25 * centre[0],
        "explicit wrap_t = periodic was not honoured: {centre:?}"
    );
}

/// A scene of one floor under the environment `environment` (TOML of the `[environment]`
/// table's body), seen looking straight up from below it at the sky, path traced.
fn sky_scene(environment: &str, texture: &str) -> String {
    format!(
        "[render]\nwidth = 4\nheight = 4\nspp = 4\nintegrator = \"path\"\n\n\
         [camera]\ntype = \"pinhole\"\neye = [0, 0, 0]\ntarget = [0, 1, 0]\n\
         up = [0, 0, -1]\nfov = 10\n\n\
         [[material]]\nname = \"floor\"\nbase_color = [0.5, 0.5, 0.5]\n\n\
         [[sphere]]\ncenter = [0, -5, 0]\nradius = 1\nmaterial = \"floor\"\n\n\
         {texture}\n[environment]\n{environment}\n"
    )
}

/// Renders `scene` into `out.exr` (which holds `previous` bytes before) and returns the exit
/// status, the error text and whether `out.exr` still holds `previous`.
fn render_over(dir: &Path, scene: &str, previous: &[u8]) -> (bool, String, bool) {
    write(dir, "s.toml", scene);
    std::fs::write(dir.join("out.exr"), previous).unwrap();
    let output = run_in(
        dir,
        &["render", "s.toml", "-o", "out.exr", "--no-png", "--quiet"],
    );
    let kept = std::fs::read(dir.join("out.exr")).unwrap() == previous;
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
        kept,
    )
}

#[test]
fn intensity_scales_a_constant_environment_colour() {
    // Radiance = colour x intensity, as for a map; the sky straight up shows it directly.
    let dir = temp_dir();
    for (intensity, expected) in [(2.0f32, 0.5f32), (0.5, 0.125)] {
        let scene = sky_scene(
            &format!("color = [0.25, 0.25, 0.25]\nintensity = {intensity}"),
            "",
        );
        write(dir.path(), "s.toml", &scene);
        let output = run_in(
            dir.path(),
            &["render", "s.toml", "-o", "sky.exr", "--no-png", "--quiet"],
        );
        assert!(output.status.success(), "{output:?}");
        let image = read_exr(&dir.path().join("sky.exr"));
        for channel in ["R", "G", "B"] {
            for &value in image.channel(channel) {
                assert!(
                    (value - expected).abs() < 1e-6,
                    "intensity {intensity}: sky {value}, expected {expected}"
                );
            }
        }
    }
    // Alone, or making the colour overflow, it is refused, naming the file.
    let previous = b"previous output";
    for (environment, problem) in [
        ("intensity = 2", "neither is given"),
        (
            "color = [1e38, 1e38, 1e38]\nintensity = 1e10",
            "overflows to infinity",
        ),
        ("color = [1, 1, 1]\nintensity = -1", "must be >= 0"),
    ] {
        let (success, stderr, kept) =
            render_over(dir.path(), &sky_scene(environment, ""), previous);
        assert!(!success && kept, "{environment}: {stderr}");
        assert!(
            stderr.contains("s.toml")
                && stderr.contains(problem)
                && stderr.trim().lines().count() == 1,
            "{environment}: {stderr}"
        );
    }
}

#[test]
fn an_environment_map_with_an_infinite_nan_or_negative_texel_is_refused() {
    // A sun brighter than 65504 saved as half floats is stored as inf; a NaN; a negative
    // radiance. Each used to render without a word (the infinite sun switched light
    // sampling of the environment off and was dropped as non-finite samples).
    let dir = temp_dir();
    let (width, height) = (16usize, 8usize);
    exr::prelude::write_rgba_file(dir.path().join("half_sun.exr"), width, height, |x, y| {
        let value = if (x, y) == (3, 2) { 1.0e5f32 } else { 0.25 };
        let half = exr::prelude::f16::from_f32(value);
        (half, half, half, exr::prelude::f16::ONE)
    })
    .expect("half_sun.exr");
    let single = |name: &str, bad: f32| {
        exr::prelude::write_rgba_file(dir.path().join(name), width, height, |x, y| {
            let value = if (x, y) == (5, 6) { bad } else { 0.25 };
            (0.25f32, value, 0.25f32, 1.0f32)
        })
        .expect(name);
    };
    single("nan.exr", f32::NAN);
    single("negative.exr", -100.0);
    let previous = b"previous output";
    for (file, problem) in [
        ("half_sun.exr", "texel (3, 2) of level 0 has R = inf"),
        ("nan.exr", "texel (5, 6) of level 0 has G = NaN"),
        ("negative.exr", "texel (5, 6) has G = -100"),
    ] {
        let texture = format!("[[texture]]\nname = \"sky\"\nfile = \"{file}\"\n");
        let scene = sky_scene("texture = \"sky\"", &texture);
        let (success, stderr, kept) = render_over(dir.path(), &scene, previous);
        assert!(!success && kept, "{file}: {stderr}");
        assert!(
            stderr.contains(file) && stderr.contains(problem) && stderr.trim().lines().count() == 1,
            "{file}: {stderr}"
        );
    }
}

/// An emission texture with a negative texel is refused like a negative environment map,
/// naming the file, the material and the texel, with the previous output kept; the same
/// texture as a base colour is accepted. (It rendered pixels of -1 below a lamp.)
#[test]
fn an_emission_texture_with_a_negative_texel_is_refused() {
    let dir = temp_dir();
    exr::prelude::write_rgba_file(dir.path().join("minus.exr"), 8, 4, |x, y| {
        let value = if (x, y) == (6, 1) { -1.0f32 } else { 0.5 };
        (0.5f32, 0.5f32, value, 1.0f32)
    })
    .expect("minus.exr");
    let scene = |key: &str| {
        format!(
            r#"
[render]
width = 4
height = 4
[camera]
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]
fov = 30.0
[[texture]]
name = "t"
file = "minus.exr"
color_space = "linear"
[[material]]
name = "glow"
emission = [1.0, 1.0, 1.0]
{key} = "t"
[[sphere]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "glow"
"#
        )
    };
    let previous = b"previous output";
    let (success, stderr, kept) = render_over(dir.path(), &scene("emission_texture"), previous);
    assert!(!success && kept, "{stderr}");
    assert!(
        stderr.contains("minus.exr")
            && stderr.contains("material 'glow'")
            && stderr.contains("texel (6, 1) has B = -1")
            && stderr.trim().lines().count() == 1,
        "{stderr}"
    );
    let (success, stderr, _) = render_over(dir.path(), &scene("base_color_texture"), previous);
    assert!(success, "{stderr}");
}
