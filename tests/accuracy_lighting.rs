//! `conetrace accuracy --mode lighting` end to end at a tiny size (64 pixels, a 64-sample
//! path-traced reference, path at 1 and 16 samples, vct on a 32-voxel grid): the files are
//! written and parse, the path tracer's error falls as its samples grow, vct beats Whitted's
//! constant ambient on the vct Cornell box, every time is positive and the Pareto front holds
//! the cheapest and the most accurate row. A scene file that is missing stops the command.

mod common;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use common::*;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name)
}

/// The CSV's rows, each a map from column name to cell.
fn rows(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{}: {line}", path.display());
            header
                .iter()
                .cloned()
                .zip(cells.iter().map(|c| c.to_string()))
                .collect()
        })
        .collect()
}

fn number(row: &HashMap<String, String>, column: &str) -> f64 {
    let cell = row
        .get(column)
        .unwrap_or_else(|| panic!("no column {column} in {row:?}"));
    cell.parse()
        .unwrap_or_else(|e| panic!("{column} = '{cell}' is not a number: {e}"))
}

/// The one row of `method` with `spp` samples (path) or `resolution` and `bounces` (vct).
fn find<'a>(
    rows: &'a [HashMap<String, String>],
    method: &str,
    key: &[(&str, &str)],
) -> &'a HashMap<String, String> {
    let matching: Vec<&HashMap<String, String>> = rows
        .iter()
        .filter(|r| r["method"] == method && key.iter().all(|(k, v)| r[*k] == *v))
        .collect();
    assert_eq!(matching.len(), 1, "{method} {key:?} in {rows:?}");
    matching[0]
}

fn lighting_args<'a>(out: &'a str, scenes: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "accuracy",
        "--mode",
        "lighting",
        "--out",
        out,
        "--lighting-size",
        "64",
        "--lighting-reference-spp",
        "64",
        "--lighting-path-spp",
        "1,16",
        "--lighting-vct-resolutions",
        "32",
        "--lighting-spp",
        "1",
        "--runs",
        "1",
        "--threads",
        "2",
        "--quiet",
    ];
    args.extend_from_slice(scenes);
    args
}

#[test]
fn lighting_report_ranks_path_vct_and_whitted() {
    let scenes = [asset("cornell.toml"), asset("vct_cornell.toml")];
    for scene in &scenes {
        assert!(
            scene.is_file(),
            "{} is missing: the test needs it",
            scene.display()
        );
    }
    let dir = temp_dir();
    let out = dir.path().join("out");
    let out_text = out.to_str().unwrap().to_string();
    let scene_args: Vec<&str> = scenes.iter().map(|s| s.to_str().unwrap()).collect();
    let result = run_in(dir.path(), &lighting_args(&out_text, &scene_args));
    assert_eq!(
        result.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&result.stderr)
    );

    let report = out.join("lighting");
    for name in ["cornell", "vct_cornell"] {
        for suffix in [".csv", ".md", "_error_vs_time.png", "_crop.png"] {
            let path = report.join(format!("{name}{suffix}"));
            let size = std::fs::metadata(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
                .len();
            assert!(size > 0, "{} is empty", path.display());
        }
        let markdown = std::fs::read_to_string(report.join(format!("{name}.md"))).unwrap();
        assert!(markdown.contains("| vct 32 b3 |"), "{markdown}");

        let rows = rows(&report.join(format!("{name}.csv")));
        eprintln!("{name}: {rows:#?}");
        assert_eq!(
            rows.len(),
            6,
            "{name}: whitted, path 1 and 16, vct 32 with 1 and 3 bounces, isotropic vct 32"
        );
        assert!(
            rows.iter().any(|r| r["method"] == "vct_isotropic"),
            "{name}: {rows:?}"
        );

        let path_1 = number(find(&rows, "path", &[("spp", "1")]), "rmse");
        let path_16 = number(find(&rows, "path", &[("spp", "16")]), "rmse");
        assert!(
            path_16 < 0.6 * path_1,
            "{name}: path RMSE should fall with samples: 1 spp {path_1}, 16 spp {path_16}"
        );

        for row in &rows {
            assert!(number(row, "render_seconds") > 0.0, "{row:?}");
            assert!(number(row, "total_seconds") > 0.0, "{row:?}");
            assert!(number(row, "rays") > 0.0, "{row:?}");
            let flip = number(row, "flip");
            assert!((0.0..=1.0).contains(&flip), "{row:?}");
            if row["method"].starts_with("vct") {
                assert!(number(row, "build_seconds") > 0.0, "{row:?}");
            }
        }
        let on_front: Vec<&HashMap<String, String>> =
            rows.iter().filter(|r| r["pareto"] == "true").collect();
        assert!(!on_front.is_empty(), "{name}: empty Pareto front: {rows:?}");
        let cheapest = rows
            .iter()
            .min_by(|a, b| number(a, "total_seconds").total_cmp(&number(b, "total_seconds")))
            .unwrap();
        assert_eq!(
            cheapest["pareto"], "true",
            "{name}: the cheapest row is always on the front: {cheapest:?}"
        );
        let most_accurate = rows
            .iter()
            .min_by(|a, b| number(a, "rmse").total_cmp(&number(b, "rmse")))
            .unwrap();
        assert_eq!(most_accurate["pareto"], "true", "{most_accurate:?}");
    }

    // The vct Cornell box: Whitted has the point light but only a constant ambient for the
    // rest; the voxels carry the emissive panel's light and the first bounce.
    let rows = rows(&report.join("vct_cornell.csv"));
    let whitted = number(find(&rows, "whitted", &[]), "rmse");
    for bounces in ["1", "3"] {
        let vct = number(
            find(
                &rows,
                "vct",
                &[("vct_resolution", "32"), ("vct_bounces", bounces)],
            ),
            "rmse",
        );
        assert!(
            vct < 0.9 * whitted,
            "vct ({bounces} bounces) RMSE {vct} should be well below Whitted+ambient {whitted}"
        );
    }
}

#[test]
fn a_missing_scene_fails_before_anything_is_written() {
    let dir = temp_dir();
    let out = dir.path().join("out");
    let out_text = out.to_str().unwrap().to_string();
    let cornell = asset("cornell.toml");
    let missing = dir.path().join("no_such_scene.toml");
    let result = run_in(
        dir.path(),
        &lighting_args(
            &out_text,
            &[cornell.to_str().unwrap(), missing.to_str().unwrap()],
        ),
    );
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.contains("no_such_scene.toml"), "stderr: {stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "stderr: {stderr}");
    assert!(!out.exists(), "nothing may be written for bad input");
}

/// A grid whose voxel pyramid vct would refuse (over its memory limit) stops the command
/// before the reference renders: exit 2, one line naming the scene, nothing written.
#[test]
fn an_oversized_vct_grid_fails_before_anything_is_written() {
    let dir = temp_dir();
    let out = dir.path().join("out");
    let out_text = out.to_str().unwrap().to_string();
    let cornell = asset("cornell.toml");
    let mut args = lighting_args(&out_text, &[cornell.to_str().unwrap()]);
    args.extend_from_slice(&["--lighting-vct-resolutions", "1024"]);
    let result = run_in(dir.path(), &args);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "stderr: {stderr}");
    assert!(
        stderr.contains("cornell.toml") && stderr.contains("1024"),
        "stderr: {stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "stderr: {stderr}");
    assert!(!out.exists(), "nothing may be written for bad input");
}

/// Two scenes with the same file stem would write the same report files: refused up front.
#[test]
fn two_scenes_with_one_name_are_refused() {
    let dir = temp_dir();
    let out = dir.path().join("out");
    let out_text = out.to_str().unwrap().to_string();
    let cornell = asset("cornell.toml");
    let copy_dir = dir.path().join("copy");
    std::fs::create_dir_all(&copy_dir).unwrap();
    let copy = copy_dir.join("cornell.toml");
    std::fs::copy(&cornell, &copy).unwrap();
    let result = run_in(
        dir.path(),
        &lighting_args(
            &out_text,
            &[cornell.to_str().unwrap(), copy.to_str().unwrap()],
        ),
    );
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "stderr: {stderr}");
    assert!(stderr.contains("same name"), "stderr: {stderr}");
    assert!(!out.exists(), "nothing may be written for bad input");
}
