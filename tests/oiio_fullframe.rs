//! Full-frame cross-check against OpenImageIO: a textured scene is rendered with the
//! `footprint` AOVs (the st coordinates and derivatives of each camera path's first texture
//! lookup and its filtered colour); OpenImageIO's TextureSystem looks up the same coordinates
//! in the same texture (mip-mapped by `maketx --filter box`), and the two texture images must
//! agree at PSNR >= 60 dB.
//!
//! That check hands OpenImageIO the renderer's own coordinates, so it cannot see an error in
//! them. The second test computes st and its screen derivatives for every pixel whose camera
//! ray meets the ground directly, from the scene's pinhole camera and the ground plane alone
//! (ray-plane intersection and its exact Jacobian, in f64), hands those to OpenImageIO and
//! compares with the colour the renderer's ray differentials looked up.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::*;

const SETUP_HINT: &str = "run `bash scripts/setup.sh` (installs python3-openimageio and maketx)";

/// Least PSNR between the rendered lookups and OpenImageIO's on analytic footprints: the
/// same limit as the check on the renderer's own coordinates. Measured: 105.7 dB (aniso) and
/// 112.6 dB (trilinear) over 3129 pixels; a footprint off by a mip level costs tens of dB,
/// while one lookup whose anisotropic probe count rounds the other way still passes.
const ANALYTIC_PSNR_DB: f64 = 60.0;

/// A 256x256 float texture with high-frequency content (a fine grid over smooth colour).
fn write_texture(path: &Path) {
    let size = 256usize;
    exr::prelude::write_rgba_file(path, size, size, |x, y| {
        let fx = x as f32 / size as f32;
        let fy = y as f32 / size as f32;
        let line = if x % 8 == 0 || y % 8 == 0 { 1.0 } else { 0.0 };
        let checker = if (x / 32 + y / 32) % 2 == 0 { 0.8 } else { 0.2 };
        (
            0.5 * line + 0.5 * checker * fx,
            0.3 + 0.6 * checker * fy,
            0.9 * line + 0.1 * (1.0 - fx),
            1.0,
        )
    })
    .expect("write texture");
}

fn scene(texture: &Path) -> String {
    format!(
        r#"
[render]
width = 96
height = 64

[camera]
type = "pinhole"
eye = [0.0, 1.0, 6.0]
target = [0.0, 0.6, 0.0]
fov = 50

[environment]
color = [0.2, 0.3, 0.4]

[[light]]
type = "point"
position = [3.0, 6.0, 4.0]
intensity = 60.0

[[texture]]
name = "grid"
file = "{}"
color_space = "linear"

[[material]]
name = "ground"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "grid"
texture_scale = [12.0, 12.0]

[[material]]
name = "mirror"
base_color = [0.0, 0.0, 0.0]
mirror = 1.0

[[mesh]]
file = "ground.obj"
material = "ground"

[[sphere]]
center = [0.8, 0.8, 0.0]
radius = 0.8
material = "mirror"
"#,
        texture.display()
    )
}

/// Runs tests/oiio/fullframe.py on `frame`; with `lookups`, OpenImageIO gets the lookups of
/// that CSV instead of the frame's `tex.*` channels. Returns (pixels compared, PSNR in dB).
fn fullframe_psnr(
    dir: &Path,
    frame: &Path,
    texture: &Path,
    filter: &str,
    lookups: Option<&Path>,
) -> (usize, f64) {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/oiio/fullframe.py");
    let mut command = Command::new("/usr/bin/python3");
    command.arg(&script).arg(frame).arg(texture);
    if let Some(lookups) = lookups {
        command.arg("--lookups").arg(lookups);
    }
    let out = command
        .args([
            "--maketx",
            "--filter",
            filter,
            "--wrap",
            "periodic",
            "--max-aniso",
            "16",
        ])
        .current_dir(dir)
        .output()
        .unwrap_or_else(|e| panic!("/usr/bin/python3 not runnable ({e}): {SETUP_HINT}"));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "fullframe.py failed: {}{} — {SETUP_HINT}",
        stdout,
        String::from_utf8_lossy(&out.stderr)
    );
    // "pixels N psnr P max_abs_diff D"
    let fields: Vec<&str> = stdout.split_whitespace().collect();
    let pixels: usize = fields[1].parse().expect("pixel count");
    let psnr: f64 = if fields[3] == "inf" {
        f64::INFINITY
    } else {
        fields[3].parse().expect("psnr")
    };
    println!("{filter}: {stdout}");
    (pixels, psnr)
}

#[test]
fn rendered_texture_lookups_match_openimageio() {
    let dir = temp_dir();
    let texture = dir.path().join("grid.exr");
    write_texture(&texture);
    write(dir.path(), "ground.obj", &square_obj(20.0, 0.0));
    write(dir.path(), "scene.toml", &scene(&texture));
    for (filter, lod) in [
        ("aniso", "cone"),
        ("trilinear", "cone"),
        ("aniso", "differential"),
    ] {
        let frame = dir.path().join(format!("{filter}-{lod}.exr"));
        let out = run_in(
            dir.path(),
            &[
                "render",
                "scene.toml",
                "-o",
                frame.to_str().unwrap(),
                "--no-png",
                "--quiet",
                "--aov",
                "footprint",
                "--filter",
                filter,
                "--lod",
                lod,
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (pixels, psnr) = fullframe_psnr(dir.path(), &frame, &texture, filter, None);
        // Most of the frame shows the ground directly or in the mirror.
        assert!(pixels > 96 * 64 / 3, "only {pixels} textured pixels");
        assert!(
            psnr >= 60.0,
            "{filter} with {lod}: PSNR {psnr} dB over {pixels} pixels"
        );
    }
}

// ---- The same lookups from the camera and the plane alone. ----

/// The scene's pinhole camera (eye, target, vertical field of view, up +Y), in f64.
struct Pinhole {
    eye: [f64; 3],
    /// Eye to the centre of the view rectangle, and half its width and height.
    w: [f64; 3],
    u: [f64; 3],
    v: [f64; 3],
    width: f64,
    height: f64,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: [f64; 3], k: f64) -> [f64; 3] {
    [a[0] * k, a[1] * k, a[2] * k]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn unit(a: [f64; 3]) -> [f64; 3] {
    scale(a, 1.0 / dot(a, a).sqrt())
}

impl Pinhole {
    /// The view rectangle at the target's distance: half height tan(fov / 2) times that
    /// distance, half width that times the aspect ratio; x right, y down in pixels.
    fn new(eye: [f64; 3], target: [f64; 3], fov_degrees: f64, width: f64, height: f64) -> Self {
        let to_target = sub(target, eye);
        let distance = dot(to_target, to_target).sqrt();
        let forward = unit(to_target);
        let right = unit(cross(forward, [0.0, 1.0, 0.0]));
        let up = cross(right, forward);
        let half_height = (fov_degrees.to_radians() / 2.0).tan() * distance;
        Pinhole {
            eye,
            w: scale(forward, distance),
            u: scale(right, half_height * width / height),
            v: scale(up, half_height),
            width,
            height,
        }
    }

    /// Direction (not normalised) through image point (px, py), and its derivatives along
    /// px and py.
    fn direction(&self, px: f64, py: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let x = 2.0 * px / self.width - 1.0;
        let y = 1.0 - 2.0 * py / self.height;
        let d = add(self.w, add(scale(self.u, x), scale(self.v, y)));
        (
            d,
            scale(self.u, 2.0 / self.width),
            scale(self.v, -2.0 / self.height),
        )
    }
}

/// Where the ray (eye, d) meets the plane y = 0, and how that point moves when d moves by
/// dd: p = e + t d with t = -e_y / d_y, so dp = t (dd - d dd_y / d_y).
fn hit_ground(eye: [f64; 3], d: [f64; 3], dds: [[f64; 3]; 2]) -> Option<([f64; 3], [[f64; 3]; 2])> {
    if d[1] >= 0.0 {
        return None;
    }
    let t = -eye[1] / d[1];
    let p = add(eye, scale(d, t));
    let dp = dds.map(|dd| scale(sub(dd, scale(d, dd[1] / d[1])), t));
    Some((p, dp))
}

/// Whether the ray (eye, d) passes within `radius` of `center` in front of the eye before
/// travelling `t_max` (in units of d).
fn ray_meets_sphere(eye: [f64; 3], d: [f64; 3], center: [f64; 3], radius: f64, t_max: f64) -> bool {
    let oc = sub(center, eye);
    let t_closest = (dot(oc, d) / dot(d, d)).clamp(0.0, t_max);
    let closest = sub(add(eye, scale(d, t_closest)), center);
    dot(closest, closest) <= radius * radius
}

/// st and its x/y derivatives for every pixel whose centre ray meets the ground plane
/// directly (not first the mirror sphere, which it must miss by a margin of 2 % of its
/// radius so that rounding cannot decide), as "x,y,s,t,dsdx,dtdx,dsdy,dtdy" lines.
///
/// The ground is `square_obj(20.0, 0.0)` with `texture_scale = [12, 12]`: the OBJ's vt runs
/// 0..1 over x and z from -20 to 20, with v flipped into t (OpenImageIO's convention), so
/// s = 12 (x + 20) / 40 and t = 12 (z + 20) / 40.
fn analytic_lookups() -> (String, usize) {
    let camera = Pinhole::new([0.0, 1.0, 6.0], [0.0, 0.6, 0.0], 50.0, 96.0, 64.0);
    let (sphere_center, sphere_radius) = ([0.8, 0.8, 0.0], 0.8);
    let st_per_unit = 12.0 / 40.0;
    let mut csv = String::from("x,y,s,t,dsdx,dtdx,dsdy,dtdy\n");
    let mut count = 0;
    for y in 0..64 {
        for x in 0..96 {
            let (d, ddx, ddy) = camera.direction(x as f64 + 0.5, y as f64 + 0.5);
            let Some((p, [dpdx, dpdy])) = hit_ground(camera.eye, d, [ddx, ddy]) else {
                continue;
            };
            if p[0].abs() >= 20.0 || p[2].abs() >= 20.0 {
                continue;
            }
            let t_hit = -camera.eye[1] / d[1];
            if ray_meets_sphere(camera.eye, d, sphere_center, sphere_radius * 1.02, t_hit) {
                continue;
            }
            let s = st_per_unit * (p[0] + 20.0);
            let t = st_per_unit * (p[2] + 20.0);
            let [dsdx, dtdx] = [st_per_unit * dpdx[0], st_per_unit * dpdx[2]];
            let [dsdy, dtdy] = [st_per_unit * dpdy[0], st_per_unit * dpdy[2]];
            csv.push_str(&format!("{x},{y},{s},{t},{dsdx},{dtdx},{dsdy},{dtdy}\n"));
            count += 1;
        }
    }
    (csv, count)
}

#[test]
fn openimageio_given_analytic_footprints_matches_the_rendered_lookups() {
    let dir = temp_dir();
    let texture = dir.path().join("grid.exr");
    write_texture(&texture);
    write(dir.path(), "ground.obj", &square_obj(20.0, 0.0));
    write(dir.path(), "scene.toml", &scene(&texture));
    let (csv, direct) = analytic_lookups();
    // The ground fills most of the lower two thirds of the frame.
    assert!(
        direct > 96 * 64 / 3,
        "only {direct} pixels see the ground directly"
    );
    let lookups = write(dir.path(), "analytic.csv", &csv);
    for filter in ["aniso", "trilinear"] {
        let frame = dir.path().join(format!("{filter}-analytic.exr"));
        let out = run_in(
            dir.path(),
            &[
                "render",
                "scene.toml",
                "-o",
                frame.to_str().unwrap(),
                "--no-png",
                "--quiet",
                "--spp",
                "1",
                "--aov",
                "footprint",
                "--filter",
                filter,
                "--lod",
                "differential",
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (pixels, psnr) = fullframe_psnr(dir.path(), &frame, &texture, filter, Some(&lookups));
        assert_eq!(pixels, direct);
        println!("{filter} with analytic footprints: PSNR {psnr:.2} dB over {pixels} pixels");
        assert!(
            psnr >= ANALYTIC_PSNR_DB,
            "{filter}: rendered lookups vs OpenImageIO on analytic footprints: PSNR {psnr} dB \
             over {pixels} pixels (limit {ANALYTIC_PSNR_DB} dB)"
        );
    }
}
