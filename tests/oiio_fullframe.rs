//! Full-frame cross-check against OpenImageIO: a textured scene is rendered with the
//! `footprint` AOVs (the st coordinates and derivatives of each camera path's first texture
//! lookup and its filtered colour); OpenImageIO's TextureSystem looks up the same coordinates
//! in the same texture (mip-mapped by `maketx --filter box`), and the two texture images must
//! agree at PSNR >= 60 dB.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::*;

const SETUP_HINT: &str = "run `bash scripts/setup.sh` (installs python3-openimageio and maketx)";

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

fn fullframe_psnr(dir: &Path, frame: &Path, texture: &Path, filter: &str) -> (usize, f64) {
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/oiio/fullframe.py");
    let out = Command::new("/usr/bin/python3")
        .arg(&script)
        .arg(frame)
        .arg(texture)
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
        let (pixels, psnr) = fullframe_psnr(dir.path(), &frame, &texture, filter);
        // Most of the frame shows the ground directly or in the mirror.
        assert!(pixels > 96 * 64 / 3, "only {pixels} textured pixels");
        assert!(
            psnr >= 60.0,
            "{filter} with {lod}: PSNR {psnr} dB over {pixels} pixels"
        );
    }
}
