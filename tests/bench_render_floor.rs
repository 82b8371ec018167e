//! `conetrace bench render`'s traversal floor traces the render's own camera rays: every
//! sample of every pixel, so that the floor at N samples per pixel is measured, not
//! extrapolated from one ray per pixel. The raw pass, the camera-plus-shadow pass and the
//! full render must all trace the same number of camera rays.

use std::path::Path;
use std::process::Command;

/// The number in `(N camera` of the table row that starts with `row`.
fn camera_rays(stdout: &str, row: &str) -> u64 {
    let line = stdout
        .lines()
        .find(|line| line.starts_with(row))
        .unwrap_or_else(|| panic!("no row {row:?} in:\n{stdout}"));
    let open = line.find('(').expect("the row names its rays");
    let count = line[open + 1..].split_whitespace().next().expect("a count");
    count
        .parse()
        .unwrap_or_else(|_| panic!("no camera-ray count in {line:?}"))
}

#[test]
fn every_pass_traces_every_samples_camera_ray() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cornell.toml");
    assert!(scene.exists(), "missing {}", scene.display());
    let (width, height, spp) = (24u64, 16u64, 4u64);
    for integrator in ["whitted", "path"] {
        let out = Command::new(env!("CARGO_BIN_EXE_conetrace"))
            .args(["bench", "render"])
            .arg(&scene)
            .args([
                "--width",
                &width.to_string(),
                "--height",
                &height.to_string(),
            ])
            .args(["--spp", &spp.to_string(), "--repeat", "1", "--threads", "1"])
            .args(["--integrator", integrator])
            .output()
            .expect("run conetrace");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{integrator}: {}\n{stdout}",
            String::from_utf8_lossy(&out.stderr)
        );
        let expected = width * height * spp;
        for row in [
            "| raw packet traversal",
            "| camera + shadow rays traced, nothing shaded",
            "| full shading",
        ] {
            assert_eq!(camera_rays(&stdout, row), expected, "{integrator}: {row}");
        }
    }
}
