//! Alpha cut-outs on curved patches: a card (a flat bicubic patch) with a square hole in its
//! alpha texture, in front of a wall, lit at a slant. Traced exactly and tessellated, camera
//! rays pass through the hole to the wall, and shadow rays pass through it too: the wall
//! seen through the hole is lit where the light comes through the hole and dark where the
//! card's opaque frame shades it.
//!
//! Geometry (y up, camera at z = 5 looking down -z, vertical fov 40 degrees, 64x64): the card
//! is `[-1, 1]^2` at z = 0 with (s, t) = (u, v), opaque except the hole
//! `0.3 < s, t < 0.7`; the wall is at z = -1; light travels along (0.5, 0, -1), so a wall
//! point's shadow ray reaches the card 0.5 to the left of it.

mod common;

use std::path::Path;

use common::*;

const SIDE: u32 = 64;

fn write_mask(path: &Path) {
    let side = 64u32;
    let image = image::RgbaImage::from_fn(side, side, |x, y| {
        let (s, t) = (
            (x as f32 + 0.5) / side as f32,
            (y as f32 + 0.5) / side as f32,
        );
        let hole = (0.3..0.7).contains(&s) && (0.3..0.7).contains(&t);
        image::Rgba([255, 255, 255, if hole { 0 } else { 255 }])
    });
    image.save(path).expect("the mask is written");
}

fn scene() -> String {
    format!(
        r#"
[render]
width = {SIDE}
height = {SIDE}
max_depth = 2

[camera]
type = "pinhole"
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fov = 40

[environment]
color = [0.0, 0.0, 0.0]

[[light]]
type = "directional"
direction = [0.5, 0.0, -1.0]

[[texture]]
name = "mask"
file = "mask.png"
color_space = "linear"

[[material]]
name = "card"
base_color = [1.0, 0.0, 0.0]
alpha_texture = "mask"
alpha_cutoff = 0.5

[[material]]
name = "wall"
base_color = [0.0, 0.0, 1.0]

[[patch]]
degree = [1, 1]
control_points = [[-1, -1, 0], [1, -1, 0], [-1, 1, 0], [1, 1, 0]]
material = "card"

[[mesh]]
file = "wall.obj"
material = "wall"
"#
    )
}

const WALL_OBJ: &str = "v -4 -4 -1\nv 4 -4 -1\nv 4 4 -1\nv -4 4 -1\nvn 0 0 1\n\
f 1//1 2//1 3//1\nf 1//1 3//1 4//1\n";

/// The pixel column whose centre looks at x = `x` on the plane at depth `z` (row 32 looks
/// along y = 0 to within 0.03).
fn column(x: f32, z: f32) -> usize {
    let half = (5.0 - z) * 20f32.to_radians().tan();
    ((x / half + 1.0) * 0.5 * SIDE as f32) as usize
}

fn render(dir: &Path, mode: &str) -> ExrImage {
    let out = run_in(
        dir,
        &[
            "render",
            "card.toml",
            "-o",
            &format!("{mode}.exr"),
            "--no-png",
            "--quiet",
            "--spp",
            "1",
            "--patch-mode",
            mode,
        ],
    );
    assert!(
        out.status.success(),
        "{mode}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_exr(&dir.join(format!("{mode}.exr")))
}

#[test]
fn holes_in_patches_let_camera_and_shadow_rays_through() {
    let dir = temp_dir();
    write_mask(&dir.path().join("mask.png"));
    write(dir.path(), "wall.obj", WALL_OBJ);
    write(dir.path(), "card.toml", &scene());
    let row = (SIDE / 2) as usize;
    // Through the hole (the camera ray crosses the card at s = 0.63) to the wall at
    // x = 0.3, whose shadow ray crosses the card at s = 0.40: also in the hole.
    let lit = column(0.3, -1.0);
    // Through the hole (s = 0.37) to the wall at x = -0.3, whose shadow ray crosses the
    // card at s = 0.10: the opaque frame.
    let shaded = column(-0.3, -1.0);
    // The card's opaque frame at s = 0.92.
    let frame = column(0.85, 0.0);
    for mode in ["exact", "tessellate"] {
        let image = render(dir.path(), mode);
        let rgb = |x: usize| {
            [
                image.at("R", x, row),
                image.at("G", x, row),
                image.at("B", x, row),
            ]
        };
        let (a, b, c) = (rgb(lit), rgb(shaded), rgb(frame));
        eprintln!("{mode}: lit wall {a:?}, shaded wall {b:?}, card {c:?}");
        assert!(
            a[2] > 0.2 && a[0] < 0.02,
            "{mode}: the wall behind the hole, lit through it, is {a:?}"
        );
        assert!(
            b[0] < 0.02 && b[2] < 0.1 * a[2],
            "{mode}: the wall behind the hole in the frame's shadow is {b:?}"
        );
        assert!(
            c[0] > 0.2 && c[2] < 0.02,
            "{mode}: the card's frame is {c:?}"
        );
    }
}
