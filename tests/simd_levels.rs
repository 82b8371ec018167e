//! The vector level the lane loops run at (`CONETRACE_SIMD`) changes nothing but the time:
//! the binary forced to each level this processor supports writes the same EXR bytes, and
//! `--stats` names the level. A level that cannot run is refused before any work.

mod common;

use std::path::Path;

use conetrace::simd::Level;

/// Renders `scene` at `level` into `dir`, returning the EXR's bytes and the `simd` field of
/// `--stats`.
fn render_at(dir: &Path, scene: &Path, level: Level, extra: &[&str]) -> (Vec<u8>, String) {
    let exr = dir.join(format!("{}.exr", level.name()));
    let stats = dir.join(format!("{}.json", level.name()));
    let output = common::conetrace()
        .env("CONETRACE_SIMD", level.name())
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(&exr)
        .args(["--no-png", "--quiet", "--width", "96", "--height", "64"])
        .arg("--stats")
        .arg(&stats)
        .args(extra)
        .output()
        .expect("the conetrace binary runs");
    assert!(
        output.status.success(),
        "{} at {level:?}: {}",
        scene.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&stats).expect("stats written")).unwrap();
    let named = stats["simd"]
        .as_str()
        .expect("stats name the level")
        .to_string();
    (std::fs::read(&exr).expect("EXR written"), named)
}

const THIN_LENS_SCENE: &str = r#"
[camera]
type = "thin_lens"
eye = [0, 1.5, 3]
target = [0, 0.5, 0]
fov = 45
aperture_radius = 0.15

[[light]]
type = "point"
position = [1, 3, 2]
intensity = 20

[[material]]
name = "grey"
base_color = [0.6, 0.6, 0.6]

[[mesh]]
file = "floor.obj"
material = "grey"

[[sphere]]
center = [0, 0.5, 0]
radius = 0.5
material = "grey"
"#;

#[test]
fn every_vector_level_writes_the_baseline_image() {
    let dir = common::temp_dir();
    common::write(dir.path(), "floor.obj", &common::square_obj(4.0, 0.0));
    let thin_lens = common::write(dir.path(), "thin_lens.toml", THIN_LENS_SCENE);
    let textured = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/teapot_textured.toml");
    // One sample (pixel centres), several (the position draws), a lens, and the path tracer.
    let cases: [(&Path, &[&str]); 4] = [
        (&textured, &["--spp", "1"]),
        (&textured, &["--spp", "5"]),
        (&thin_lens, &["--spp", "4"]),
        (&thin_lens, &["--spp", "3", "--integrator", "path"]),
    ];
    for (scene, extra) in cases {
        let (baseline, named) = render_at(dir.path(), scene, Level::Baseline, extra);
        assert_eq!(named, "baseline");
        for level in Level::supported() {
            let (image, named) = render_at(dir.path(), scene, level, extra);
            assert_eq!(named, level.name());
            assert!(
                image == baseline,
                "{} {extra:?}: {level:?} differs from the baseline",
                scene.display()
            );
        }
    }
}

#[test]
fn a_level_that_cannot_run_is_refused_in_one_line() {
    let dir = common::temp_dir();
    let exr = dir.path().join("never.exr");
    let mut refused = vec!["avx3".to_string(), String::new()];
    refused.extend(
        Level::ALL
            .iter()
            .filter(|level| !level.is_supported())
            .map(|level| level.name().to_string()),
    );
    for value in refused {
        let output = common::conetrace()
            .env("CONETRACE_SIMD", &value)
            .arg("render")
            .arg("-o")
            .arg(&exr)
            .args(["--no-png", "--quiet", "--width", "8", "--height", "8"])
            .output()
            .expect("the conetrace binary runs");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{value:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains("CONETRACE_SIMD"), "{stderr}");
        assert!(!exr.exists(), "{value:?} wrote an image");
    }
}
