//! Emissive surfaces light the scene through the voxels: a Lambert floor under a uniform
//! emissive rectangle, with no other light, must get `albedo * radiance * F`, where `F` is
//! the closed-form form factor from the floor's centre to the rectangle.

mod common;

use std::path::Path;

use common::*;

const ALBEDO: f32 = 0.5;
const RADIANCE: f32 = 2.0;

/// The form factor from a point to a parallel `2a x 2b` rectangle centred `c` above it:
/// the sum of four rectangles with a corner over the point, each
/// `(1 / 2 pi) (X / sqrt(1 + X^2) atan(Y / sqrt(1 + X^2)) + (X <-> Y))` with `X = a / c`,
/// `Y = b / c` (Howell's catalogue of configuration factors, differential area to a
/// parallel rectangle).
fn form_factor(a: f64, b: f64, c: f64) -> f64 {
    let (x, y) = (a / c, b / c);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    let corner =
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI);
    4.0 * corner
}

/// A `2 half` square floor of albedo [`ALBEDO`] under a same-sized ceiling of emission
/// [`RADIANCE`] facing down at `height`, both turned `yaw` degrees about the vertical, seen
/// from straight above its centre through a narrow pinhole.
fn room(dir: &Path, half: f32, height: f32, yaw: f32) -> std::path::PathBuf {
    let obj = write(dir, "quad.obj", &square_obj(1.0, 0.0));
    let text = format!(
        r#"
[render]
width = 4
height = 4
spp = 1
integrator = "vct"

[camera]
type = "pinhole"
eye = [0.0, {eye}, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
fov = 2

[[material]]
name = "floor"
base_color = [{ALBEDO}, {ALBEDO}, {ALBEDO}]

[[material]]
name = "lamp"
base_color = [0.0, 0.0, 0.0]
emission = [{RADIANCE}, {RADIANCE}, {RADIANCE}]

[[mesh]]
file = "{obj}"
material = "floor"
scale = [{half}, 1, {half}]
rotate = [0.0, {yaw}, 0.0]

[[mesh]]
file = "{obj}"
material = "lamp"
scale = [{half}, 1, {half}]
rotate = [180.0, {yaw}, 0.0]
translate = [0.0, {height}, 0.0]
"#,
        eye = 0.5 * height,
        obj = obj.display(),
    );
    write(dir, "room.toml", &text)
}

/// The mean red radiance of a vct render of `scene` with `extra` options.
fn vct_mean(dir: &Path, scene: &Path, extra: &[&str]) -> f32 {
    let exr = dir.join("out.exr");
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--no-png",
        "--quiet",
    ];
    args.extend_from_slice(extra);
    let out = run_in(dir, &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = read_exr(&exr);
    let mut sum = 0.0;
    for y in 0..image.height {
        for x in 0..image.width {
            sum += image.at("R", x, y);
        }
    }
    sum / (image.width * image.height) as f32
}

#[test]
fn a_floor_under_an_emissive_ceiling_gets_light_through_directional_voxels() {
    // An open 10 x 10 room 4 high (F = 0.659), the same room turned 20 degrees (the cones'
    // azimuths then meet the ceiling's edges elsewhere), a room 2 high (F = 0.883), and a
    // ceiling 0.5 above a 10 x 10 floor, which fills 99.2 % of the floor centre's
    // cosine-weighted hemisphere: all within the issue's 10 % of the exact value. With seed
    // 003's six cones the 4-high room got 63.9 % (docs/vct.md).
    let cases = [
        (5.0f32, 4.0f32, 0.0f32),
        (5.0, 4.0, 20.0),
        (5.0, 2.0, 0.0),
        (5.0, 0.5, 0.0),
    ];
    for (half, height, yaw) in cases {
        let dir = temp_dir();
        let scene = room(dir.path(), half, height, yaw);
        let f = form_factor(f64::from(half), f64::from(half), f64::from(height)) as f32;
        let exact = ALBEDO * RADIANCE * f;
        let directional = vct_mean(dir.path(), &scene, &[]);
        let isotropic = vct_mean(dir.path(), &scene, &["--vct-voxels", "isotropic"]);
        let side = 2.0 * half;
        println!(
            "ceiling {height} above a {side}x{side} floor turned {yaw}: exact {exact:.4} \
             (F {f:.4}), directional {directional:.4} ({:.1} %), isotropic {isotropic:.4} \
             ({:.1} %)",
            100.0 * directional / exact,
            100.0 * isotropic / exact
        );
        assert!(
            (directional - exact).abs() < 0.1 * exact,
            "height {height}, yaw {yaw}: {directional} vs {exact}"
        );
        assert!(
            directional > isotropic.max(0.1 * directional) * 1.3,
            "{directional} vs {isotropic}"
        );
    }
}
