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
