//! `conetrace accuracy --mode fog` end to end at a small size on the three fog scenes: every
//! file is written and parses, the analytic row is the reference, the march's error falls
//! from 4 to 256 steps on the height-fog scenes (and is nil on constant fog, which the
//! midpoint rule integrates exactly), marching costs density samples the closed form does
//! not take, and a missing scene stops the command (exit 2, nothing written). The report
//! checked in under docs/accuracy/fog/ is read back too.

mod common;

use std::path::{Path, PathBuf};

use common::*;

const SCENES: [&str; 3] = [
    "fog_accuracy_inside",
    "fog_accuracy_outside",
    "fog_accuracy_edge",
];

/// The path of a shipped scene; a missing one fails the test with its name.
fn scene(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(format!("{name}.toml"));
    assert!(path.is_file(), "missing scene {}", path.display());
    path
}

/// One CSV row of a fog report.
#[derive(Debug)]
struct Row {
    mode: String,
    steps: String,
    render_seconds: f64,
    fog_segments: u64,
    fog_volume_crossings: u64,
    fog_density_samples: u64,
    rmse: f64,
    flip: f64,
}

fn rows(path: &Path) -> Vec<Row> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("{}: no column {name} in {header:?}", path.display()))
    };
    let columns = [
        "mode",
        "steps",
        "render_seconds",
        "fog_segments",
        "fog_volume_crossings",
        "fog_density_samples",
        "rmse",
        "flip",
    ]
    .map(column);
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{}: {line}", path.display());
            let number = |i: usize| -> f64 {
                cells[columns[i]]
                    .parse()
                    .unwrap_or_else(|e| panic!("{}: {line}: {e}", path.display()))
            };
            let count = |i: usize| -> u64 {
                cells[columns[i]]
                    .parse()
                    .unwrap_or_else(|e| panic!("{}: {line}: {e}", path.display()))
            };
            Row {
                mode: cells[columns[0]].to_string(),
                steps: cells[columns[1]].to_string(),
                render_seconds: number(2),
                fog_segments: count(3),
                fog_volume_crossings: count(4),
                fog_density_samples: count(5),
                rmse: number(6),
                flip: number(7),
            }
        })
        .collect()
}

/// The checks every report (fresh or checked in) passes; `height_fog` for the exponential
/// scenes, where marching is inexact.
fn check_report(dir: &Path, name: &str, height_fog: bool) {
    let csv = dir.join(format!("{name}_fog.csv"));
    let rows = rows(&csv);
    eprintln!("{name}: {rows:#?}");
    let modes: Vec<(&str, &str)> = rows
        .iter()
        .map(|r| (r.mode.as_str(), r.steps.as_str()))
        .collect();
    assert_eq!(
        modes,
        [
            ("analytic", ""),
            ("march", "4"),
            ("march", "16"),
            ("march", "64"),
            ("march", "256"),
            ("linear-blend", ""),
        ],
        "{name}"
    );
    let analytic = &rows[0];
    assert_eq!(
        (analytic.rmse, analytic.flip),
        (0.0, 0.0),
        "{name}: the reference"
    );
    assert_eq!(
        analytic.fog_density_samples, 0,
        "{name}: the closed form samples nothing"
    );
    assert!(analytic.fog_segments > 0, "{name}: fog was evaluated");
    assert!(rows.iter().all(|r| r.render_seconds > 0.0), "{name}: times");
    // Marching's work: N samples per crossed volume (every segment is finite in these
    // boxed scenes), so 256 steps take 64 times the samples of 4 steps.
    for row in &rows[1..5] {
        let steps: u64 = row.steps.parse().expect("steps");
        assert_eq!(
            row.fog_density_samples,
            steps * row.fog_volume_crossings,
            "{name}: march {steps}"
        );
    }
    assert!(rows[4].fog_density_samples > 0);
    let march: Vec<f64> = rows[1..5].iter().map(|r| r.rmse).collect();
    if height_fog {
        assert!(
            march.windows(2).all(|w| w[1] < w[0]),
            "{name}: the march's error falls with the steps: {march:?}"
        );
        assert!(
            march[3] < 0.05 * march[0],
            "{name}: 256 steps are far closer than 4: {march:?}"
        );
    } else {
        assert!(
            march.iter().all(|&e| e == 0.0),
            "{name}: constant fog is marched exactly (bit-identical images): {march:?}"
        );
    }
    assert!(rows[5].rmse > 1e-3, "{name}: the clamped blend differs");
    let markdown = std::fs::read_to_string(dir.join(format!("{name}_fog.md"))).expect("md");
    assert!(
        markdown.contains("| mode | render s |"),
        "{name}: {markdown}"
    );
    assert_eq!(
        markdown.matches("\n| march ").count(),
        4,
        "{name}: {markdown}"
    );
    for suffix in ["_error_vs_time.png", "_crop.png"] {
        let path = dir.join(format!("{name}_fog{suffix}"));
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{} is not a PNG",
            path.display()
        );
    }
}

#[test]
fn fog_accuracy_rows_exist_and_marching_converges() {
    let dir = temp_dir();
    let out = dir.path().join("out");
    let paths: Vec<String> = SCENES
        .iter()
        .map(|name| scene(name).to_string_lossy().into_owned())
        .collect();
    let mut args = vec!["accuracy", "--mode", "fog"];
    args.extend(paths.iter().map(String::as_str));
    args.extend([
        "--out",
        out.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "36",
        "--runs",
        "1",
        "--threads",
        "2",
        "--quiet",
    ]);
    let result = run_in(dir.path(), &args);
    assert_eq!(
        result.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&result.stderr)
    );
    // The report goes to `--out`/fog, as the lighting report goes to `--out`/lighting.
    let report = out.join("fog");
    check_report(&report, "fog_accuracy_inside", true);
    check_report(&report, "fog_accuracy_outside", true);
    check_report(&report, "fog_accuracy_edge", false);
}

#[test]
fn the_checked_in_fog_report_parses_and_converges() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/accuracy/fog");
    assert!(dir.is_dir(), "missing report directory {}", dir.display());
    check_report(&dir, "fog_accuracy_inside", true);
    check_report(&dir, "fog_accuracy_outside", true);
    check_report(&dir, "fog_accuracy_edge", false);
}

#[test]
fn a_missing_scene_exits_2_and_writes_nothing() {
    let dir = temp_dir();
    let out = dir.path().join("out");
    let inside = scene("fog_accuracy_inside");
    let result = run_in(
        dir.path(),
        &[
            "accuracy",
            "--mode",
            "fog",
            inside.to_str().unwrap(),
            "no_such_fog.toml",
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no_such_fog.toml"), "{stderr}");
    assert!(!out.exists(), "the output directory was created");
    // A scene without fog is refused the same way.
    let plain = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/cornell.toml");
    assert!(plain.is_file(), "missing scene {}", plain.display());
    let result = run_in(
        dir.path(),
        &[
            "accuracy",
            "--mode",
            "fog",
            plain.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("has no fog"), "{stderr}");
    assert!(!out.exists(), "the output directory was created");
}
