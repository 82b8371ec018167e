//! `conetrace accuracy --mode patches` end to end at a tiny size: the mirror teapot's table
//! has the exact row and one row per tessellation bound, the height patch's one row per
//! march step, the images are written, and the error against the exact render falls as
//! the bound tightens and the step shrinks.

mod common;

use std::path::{Path, PathBuf};

use common::*;

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name)
}

/// The CSV's rows as `(mode, parameter, rmse, triangles)`.
fn rows(path: &Path) -> Vec<(String, String, f64, u64)> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let column = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    let (mode, parameter, rmse, triangles) = (
        column("mode"),
        column("bound_or_step"),
        column("rmse"),
        column("triangles"),
    );
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            (
                cells[mode].to_string(),
                cells[parameter].to_string(),
                cells[rmse].parse().expect("rmse is a number"),
                cells[triangles].parse().expect("triangles is a count"),
            )
        })
        .collect()
}

/// The numbers of one CSV column, row by row.
fn column_values(path: &Path, name: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    let index = header
        .iter()
        .position(|h| *h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"));
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            cells[index].parse().expect("a number")
        })
        .collect()
}

/// Each error at most the one before it (up to `slack`), and the last well below the first.
fn assert_falls(what: &str, errors: &[f64], slack: f64) {
    for pair in errors.windows(2) {
        assert!(
            pair[1] <= pair[0] + slack,
            "{what}: error rises from {} to {} ({errors:?})",
            pair[0],
            pair[1]
        );
    }
    let (first, last) = (errors[0], errors[errors.len() - 1]);
    assert!(
        first > 0.0 && last < 0.5 * first,
        "{what}: errors {errors:?} do not fall"
    );
}

#[test]
fn patch_accuracy_rows_exist_and_error_falls_as_the_bound_tightens() {
    let dir = temp_dir();
    let out = dir.path().join("out");
    let result = run_in(
        dir.path(),
        &[
            "accuracy",
            "--mode",
            "patches",
            asset("teapot_mirror.toml").to_str().unwrap(),
            asset("height_patch.toml").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--width",
            "96",
            "--height",
            "54",
            "--patch-spp",
            "2",
            "--patch-reference-spp",
            "16",
            "--runs",
            "1",
            "--threads",
            "2",
            "--quiet",
        ],
    );
    assert_eq!(
        result.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&result.stderr)
    );

    // The report goes to `--out`/patches, as the lighting report goes to `--out`/lighting.
    let out = out.join("patches");
    let teapot = rows(&out.join("teapot_mirror_patches.csv"));
    eprintln!("teapot: {teapot:?}");
    let modes: Vec<(&str, &str)> = teapot
        .iter()
        .map(|(m, p, _, _)| (m.as_str(), p.as_str()))
        .collect();
    assert_eq!(
        modes,
        [
            ("exact", ""),
            ("tessellate", "0.1"),
            ("tessellate", "0.03"),
            ("tessellate", "0.01"),
            ("tessellate", "0.001"),
            ("tessellate", "0.0001"),
        ]
    );
    assert_eq!(teapot[0].2, 0.0, "the exact row is the reference");
    let triangles: Vec<u64> = teapot[1..].iter().map(|r| r.3).collect();
    assert!(
        triangles.windows(2).all(|w| w[1] > w[0]),
        "triangles grow as the bound tightens: {triangles:?}"
    );
    let errors: Vec<f64> = teapot[1..].iter().map(|r| r.2).collect();
    assert_falls("teapot tessellation", &errors, 1e-3);

    // Against the high-sample reference the exact row shows the noise of 2 spp alone, and the
    // coarsest tessellation adds its geometric error to it.
    let reference = column_values(&out.join("teapot_mirror_patches.csv"), "rmse_reference");
    eprintln!("teapot against the reference: {reference:?}");
    assert!(
        reference[0] > 0.0,
        "2 spp differ from 16 spp: {reference:?}"
    );
    assert!(
        reference[1] > reference[0],
        "E=0.1 is further from the reference than exact: {reference:?}"
    );

    let height = rows(&out.join("height_patch_patches.csv"));
    eprintln!("height patch: {height:?}");
    let modes: Vec<(&str, &str)> = height
        .iter()
        .map(|(m, p, _, _)| (m.as_str(), p.as_str()))
        .collect();
    assert_eq!(
        modes,
        [
            ("exact", ""),
            ("march", "0.5"),
            ("march", "0.2"),
            ("march", "0.1"),
            ("march", "0.03"),
            ("march", "0.01"),
        ]
    );
    let errors: Vec<f64> = height[1..].iter().map(|r| r.2).collect();
    assert_falls("height patch marching", &errors, 1e-3);

    for stem in ["teapot_mirror_patches", "height_patch_patches"] {
        for suffix in [".md", "_error_vs_time.png", "_crop.png"] {
            let path = out.join(format!("{stem}{suffix}"));
            assert!(path.is_file(), "{} was not written", path.display());
        }
    }
}
