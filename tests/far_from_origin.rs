//! Far from the origin, a lit surface keeps its brightness. A diffuse plane (albedo 0.5)
//! lies 1 unit under a light, seen straight down from 0.5 above it through a narrow
//! camera, with the whole scene moved 8192 units along every axis or 131072 along the
//! normal. The light is a point light (intensity pi: the plane's radiance is exactly 0.5)
//! for Whitted and the path tracer, or a one-sided 2 x 2 emissive quad (radiance 2) for the
//! path tracer, whose answer is Lambert's formula for the square seen from under its centre.
//!
//! Secondary rays start off the surface by a bound on the hit point's rounding, which grows
//! with the coordinates (about 0.1 units at 131072); the light must still be seen from the
//! surface itself, with only the shadow ray starting from the offset point. Measured from
//! the offset point, the light came 0.1 units closer: under the point light +1.8 % at 8192
//! and +35 % at 131072, under the quad +0.42 % and +6.3 %. Now the point light is within
//! 0.01 % at every offset. Under the quad +0.08 % and +1.35 % remain: a BSDF-sampled ray
//! leaves from the offset point too (0.09 units off at 131072, with the triangle's point
//! computed in f64), and from there the lamp's edges subtend a little more (64 f32 steps of
//! 131072 separate the lamp from the plane).

mod common;

use common::*;

/// Moves `p` by `offset` and formats it for TOML.
fn at(p: [f64; 3], offset: [f64; 3]) -> String {
    format!(
        "[{:?}, {:?}, {:?}]",
        p[0] + offset[0],
        p[1] + offset[1],
        p[2] + offset[2]
    )
}

fn scene(offset: [f64; 3], light: &str) -> String {
    let light = match light {
        "point" => format!(
            "[[light]]\ntype = \"point\"\nposition = {}\nintensity = {:?}\n",
            at([0.0, 1.0, 0.0], offset),
            std::f64::consts::PI
        ),
        _ => format!(
            "[[mesh]]\nfile = \"lamp.obj\"\nmaterial = \"lamp\"\nrotate = [180, 0, 0]\n\
             translate = {}\n",
            at([0.0, 1.0, 0.0], offset)
        ),
    };
    format!(
        r#"[render]
width = 16
height = 16
spp = 256

[camera]
type = "pinhole"
eye = {eye}
target = {target}
up = [0, 0, -1]
fov = 2

[[material]]
name = "grey"
base_color = [0.5, 0.5, 0.5]

[[material]]
name = "lamp"
base_color = [0, 0, 0]
emission = [2, 2, 2]

[[mesh]]
file = "floor.obj"
material = "grey"
translate = {floor}

{light}"#,
        eye = at([0.0, 0.5, 0.0], offset),
        target = at([0.0, 0.0, 0.0], offset),
        floor = at([0.0, 0.0, 0.0], offset),
    )
}

/// `integral of cos theta d omega` over the square of half-size 1 at height 1 above the
/// point under its centre (Lambert's formula for a polygon).
fn projected_solid_angle_of_the_lamp() -> f64 {
    let corners = [
        [-1.0, 1.0, -1.0],
        [1.0, 1.0, -1.0],
        [1.0, 1.0, 1.0],
        [-1.0, 1.0, 1.0],
    ];
    let unit = |p: [f64; 3]| {
        let l = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        [p[0] / l, p[1] / l, p[2] / l]
    };
    let mut sum = 0.0;
    for i in 0..4 {
        let (a, b) = (unit(corners[i]), unit(corners[(i + 1) % 4]));
        let cross = [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ];
        let length = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
        let angle = length.atan2(a[0] * b[0] + a[1] * b[1] + a[2] * b[2]);
        sum += angle * cross[1] / length;
    }
    sum.abs() / 2.0
}

fn mean_red(dir: &std::path::Path, name: &str) -> f64 {
    let image = read_exr(&dir.join(name));
    let red = image.channel("R");
    red.iter().map(|&r| f64::from(r)).sum::<f64>() / red.len() as f64
}

#[test]
fn a_lit_plane_far_from_the_origin_keeps_its_brightness() {
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(10.0, 0.0));
    write(dir.path(), "lamp.obj", &square_obj(1.0, 0.0));
    // Radiance 0.5 / pi times the lamp's 2 times its projected solid angle.
    let under_lamp = 2.0 * 0.5 / std::f64::consts::PI * projected_solid_angle_of_the_lamp();
    // Light sampling sees the light from the surface point; a BSDF-sampled ray still leaves
    // from the offset point, which sees the lamp's edges a little wider: measured +0.08 %
    // at 8192 and +1.35 % at 131072 (see the module doc), hence the last tolerance (with
    // the f32 triangle point the offset was larger and it was +1.99 %).
    let cases = [
        ("point", "whitted", 0.5, [2e-3, 2e-3]),
        ("point", "path", 0.5, [2e-3, 2e-3]),
        ("lamp", "path", under_lamp, [2e-3, 1.6e-2]),
    ];
    let mut failures = Vec::new();
    for (light, integrator, expected, tolerances) in cases {
        for offset in [[0.0; 3], [8192.0; 3], [0.0, 131072.0, 0.0], [131072.0; 3]] {
            let tolerance = tolerances[usize::from(offset[1] > 1e5)];
            write(dir.path(), "s.toml", &scene(offset, light));
            let out = run_in(
                dir.path(),
                &[
                    "render",
                    "s.toml",
                    "-o",
                    "s.exr",
                    "--quiet",
                    "--no-png",
                    "--integrator",
                    integrator,
                ],
            );
            assert!(out.status.success(), "{out:?}");
            let mean = mean_red(dir.path(), "s.exr");
            eprintln!(
                "{light}, {integrator}, offset {offset:?}: {mean:.6} (expected {expected:.6})"
            );
            if (mean / expected - 1.0).abs() > tolerance {
                failures.push(format!(
                    "{light}, {integrator}, offset {offset:?}: {mean} against {expected}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn a_camera_a_million_units_away_sees_what_a_near_one_sees() {
    // The point-lit plane, seen straight down from 0.5 units and from 1e6 units through a
    // field of view that frames the same 0.0175-unit patch (1e-6 degrees): both images are
    // the plane's radiance, 0.5, everywhere. The field of view was clamped to 1e-3 degrees
    // (a 17-unit patch, mostly far from the light: mean 0.03).
    let dir = temp_dir();
    write(dir.path(), "floor.obj", &square_obj(10.0, 0.0));
    for height in [0.5f64, 1e6] {
        let fov = 2.0 * (0.00875 / height).atan().to_degrees();
        let text = scene([0.0; 3], "point")
            .replace(
                "eye = [0.0, 0.5, 0.0]",
                &format!("eye = [0.0, {height:?}, 0.0]"),
            )
            .replace("fov = 2", &format!("fov = {fov:?}"))
            .replace("spp = 256", "spp = 4");
        write(dir.path(), "s.toml", &text);
        let out = run_in(
            dir.path(),
            &["render", "s.toml", "-o", "s.exr", "--quiet", "--no-png"],
        );
        assert!(out.status.success(), "{out:?}");
        let image = read_exr(&dir.path().join("s.exr"));
        let (lowest, highest) = image
            .channel("R")
            .iter()
            .fold((f32::INFINITY, 0.0f32), |(lo, hi), &r| {
                (lo.min(r), hi.max(r))
            });
        eprintln!("camera {height} above, fov {fov:e} degrees: {lowest} to {highest}");
        assert!(
            (lowest - 0.5).abs() < 1e-3 && (highest - 0.5).abs() < 1e-3,
            "camera {height} above: radiance {lowest} to {highest}, expected 0.5"
        );
    }
}
