//! `conetrace accuracy` end to end on a tiny footprint scene: the CSV's rows and columns,
//! errors that fall with more samples, PSNR consistent with RMSE, decodable images of the
//! expected sizes, and bad input rejected before anything is written.

mod common;

use std::path::{Path, PathBuf};

use common::*;

fn concave_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/fp_concave.toml")
}

/// Runs `conetrace accuracy SCENE` at `width` x `height` against a 256-sample ground truth,
/// one timing run, into `out`; asserts it succeeded.
fn run_accuracy(dir: &Path, scene: &str, out: &Path, width: &str, height: &str) {
    let result = run_in(
        dir,
        &[
            "accuracy",
            scene,
            "--out",
            out.to_str().unwrap(),
            "--width",
            width,
            "--height",
            height,
            "--ground-truth-spp",
            "256",
            "--runs",
            "1",
            "--quiet",
        ],
    );
    assert_eq!(
        result.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&result.stderr)
    );
}

/// The CSV as (header, rows of cells).
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).expect("the CSV exists");
    let mut lines = text.lines();
    let header = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

#[test]
fn a_tiny_run_writes_consistent_tables_and_images() {
    let dir = temp_dir();
    let out = dir.path().join("acc");
    let scene = concave_scene();
    run_accuracy(dir.path(), scene.to_str().unwrap(), &out, "48", "27");

    let (header, rows) = read_csv(&out.join("fp_concave.csv"));
    let column = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    for name in [
        "strategy",
        "filter",
        "spp",
        "seconds",
        "rays",
        "texture_lookups",
        "tiles_touched",
        "rmse",
        "psnr_db",
        "flip",
        "rmse_textured",
        "psnr_textured_db",
        "flip_textured",
        "relative_time",
    ] {
        column(name);
    }
    // The ground truth and the sixteen compared methods.
    assert_eq!(rows.len(), 17, "{rows:?}");
    assert!(rows.iter().all(|r| r.len() == header.len()));
    let method = |r: &Vec<String>| {
        format!(
            "{}+{} {}",
            r[column("strategy")],
            r[column("filter")],
            r[column("spp")]
        )
    };
    let expected = [
        "mip0+bilinear 256",
        "mip0+bilinear 1",
        "distance+trilinear 1",
        "cone1+trilinear 1",
        "cone+trilinear 1",
        "cone+aniso 1",
        "cone+ewa 1",
        "differential+trilinear 1",
        "differential+aniso 1",
        "differential+ewa 1",
        "mip0+bilinear 4",
        "mip0+bilinear 16",
        "mip0+bilinear 64",
        "cone+aniso 4",
        "cone+aniso 16",
        "differential+ewa 4",
        "differential+ewa 16",
    ];
    let methods: Vec<String> = rows.iter().map(method).collect();
    assert_eq!(methods, expected);
    // The reference row has no error of its own.
    assert_eq!(rows[0][column("rmse")], "");

    let number = |r: &Vec<String>, name: &str| -> f64 {
        r[column(name)]
            .parse()
            .unwrap_or_else(|_| panic!("{name} of {} is '{}'", method(r), r[column(name)]))
    };
    for row in &rows[1..] {
        for name in ["rmse", "flip", "rmse_textured", "flip_textured"] {
            let v = number(row, name);
            assert!(v > 0.0 && v < 1.0, "{name} of {}: {v}", method(row));
        }
        // PSNR = 10 log10(1 / MSE), MSE = RMSE^2 (RMSE printed to 6 decimals).
        for (rmse, psnr) in [("rmse", "psnr_db"), ("rmse_textured", "psnr_textured_db")] {
            let expected = 10.0 * (1.0 / number(row, rmse).powi(2)).log10();
            let got = number(row, psnr);
            assert!(
                (got - expected).abs() < 0.01,
                "{} {psnr} {got} vs {expected}",
                method(row)
            );
        }
        assert!(number(row, "seconds") > 0.0);
        assert!(number(row, "relative_time") >= 1.0 - 1e-9);
        assert!(number(row, "rays") >= 48.0 * 27.0);
        assert!(number(row, "texture_lookups") > 0.0);
        assert!(number(row, "tiles_touched") > 0.0);
    }
    // Supersampling converges: 1 -> 4 -> 16 -> 64 samples, error falls (all pixels and
    // textured pixels).
    for name in ["rmse", "rmse_textured", "flip"] {
        let errors: Vec<f64> = [1, 10, 11, 12].map(|i| number(&rows[i], name)).to_vec();
        assert!(
            errors.windows(2).all(|w| w[1] < w[0]),
            "{name} does not fall with spp: {errors:?}"
        );
        // So do the footprint-filtered rows: 1 -> 4 -> 16 samples, each filtering its
        // share of the pixel.
        for (one, four, sixteen) in [(5, 13, 14), (9, 15, 16)] {
            let errors: Vec<f64> = [one, four, sixteen]
                .map(|i| number(&rows[i], name))
                .to_vec();
            assert!(
                errors.windows(2).all(|w| w[1] < w[0]),
                "{name} of {} does not fall with spp: {errors:?}",
                method(&rows[one])
            );
        }
    }
    // The fastest row has relative time 1.
    let fastest = rows
        .iter()
        .map(|r| number(r, "relative_time"))
        .fold(f64::INFINITY, f64::min);
    assert!((fastest - 1.0).abs() < 1e-3, "{fastest}");

    // The images decode and have the layout's sizes.
    // The layout of src/cli/accuracy (plot.rs, crop.rs): a 1100x460 plot; crop panels of a
    // quarter of the shorter side (48x27: 8 pixels, the minimum) enlarged by an integer
    // factor to at least 176 pixels, five per row, 4-pixel gaps, 34-pixel labels.
    let plot_image = image::open(out.join("fp_concave_error_vs_time.png")).expect("plot decodes");
    assert_eq!((plot_image.width(), plot_image.height()), (1100, 460));
    let crop_image = image::open(out.join("fp_concave_crop.png")).expect("crop decodes");
    let (panel_target, columns, gap, label_height) = (176u32, 5u32, 4u32, 34u32);
    let side = 8u32;
    let panel = side * panel_target.div_ceil(side);
    let cells = 18u32; // overview, ground truth, sixteen methods
    assert_eq!(
        (crop_image.width(), crop_image.height()),
        (
            columns * (panel + gap) + gap,
            cells.div_ceil(columns) * (panel + label_height + gap) + gap
        )
    );
    let markdown = std::fs::read_to_string(out.join("fp_concave.md")).unwrap();
    assert_eq!(
        markdown.lines().filter(|l| l.starts_with("| ")).count(),
        18,
        "header and 17 rows:\n{markdown}"
    );
    let index = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(
        index.contains("fp_concave_crop.png") && index.contains("Command: `conetrace accuracy")
    );
    // No temporary files are left behind.
    let leftovers: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// Status 2, one stderr line containing `names`, and nothing created at `out`.
fn assert_rejected(args: &[&str], out: &Path, names: &str) {
    let dir = temp_dir();
    let result = run_in(dir.path(), args);
    let stderr = String::from_utf8_lossy(&result.stderr);
    assert_eq!(result.status.code(), Some(2), "{args:?}: {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].contains(names),
        "'{}' does not name '{names}'",
        lines[0]
    );
    assert!(!out.exists(), "{} was created", out.display());
}

#[test]
fn bad_input_is_rejected_before_anything_is_written() {
    let dir = temp_dir();
    let out = dir.path().join("never");
    let out_arg = out.to_str().unwrap();
    let scene = concave_scene();
    let scene_arg = scene.to_str().unwrap();
    let missing = dir.path().join("missing_scene.toml");
    // A missing scene, even after a good one.
    assert_rejected(
        &[
            "accuracy",
            scene_arg,
            missing.to_str().unwrap(),
            "--out",
            out_arg,
        ],
        &out,
        "missing_scene.toml",
    );
    // Zero timed runs, zero ground-truth samples, a zero-area image.
    assert_rejected(
        &["accuracy", scene_arg, "--out", out_arg, "--runs", "0"],
        &out,
        "--runs",
    );
    assert_rejected(
        &[
            "accuracy",
            scene_arg,
            "--out",
            out_arg,
            "--ground-truth-spp",
            "0",
        ],
        &out,
        "--ground-truth-spp",
    );
    assert_rejected(
        &["accuracy", scene_arg, "--out", out_arg, "--width", "0"],
        &out,
        "0 is not in 1..=65536",
    );
    // An output directory that cannot be created (its parent is a file).
    let blocker = write(dir.path(), "blocker", "a file, not a directory");
    let under_file = blocker.join("acc");
    assert_rejected(
        &[
            "accuracy",
            scene_arg,
            "--out",
            under_file.to_str().unwrap(),
            "--width",
            "16",
            "--height",
            "16",
        ],
        &under_file,
        "blocker",
    );
}

/// The README's headline: on the built-in default scene, ray differentials with the
/// anisotropic filter at one sample per pixel come closer to the ground truth on textured
/// pixels than plain 4-sample supersampling.
///
/// Run at 160x90 (half the documented 320x180, so texture minification is stronger, not
/// weaker) against a 256-sample ground truth (instead of 1024): the 256-sample reference's
/// own error is a fraction of the gap between the two rows compared (docs/accuracy.md gives
/// the 64-sample row's error as under a third of the 4-sample row's).
#[test]
fn differential_aniso_at_one_sample_beats_four_sample_supersampling_on_the_default_scene() {
    let dir = temp_dir();
    let out = dir.path().join("acc");
    run_accuracy(dir.path(), "default", &out, "160", "90");
    let (header, rows) = read_csv(&out.join("default.csv"));
    let column = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
    };
    let textured_rmse = |strategy: &str, filter: &str, spp: &str| -> f64 {
        let row = rows
            .iter()
            .find(|r| {
                r[column("strategy")] == strategy
                    && r[column("filter")] == filter
                    && r[column("spp")] == spp
            })
            .unwrap_or_else(|| panic!("no row {strategy}+{filter} {spp} in {rows:?}"));
        row[column("rmse_textured")]
            .parse()
            .expect("rmse_textured is a number")
    };
    let footprint = textured_rmse("differential", "aniso", "1");
    let supersampled = textured_rmse("mip0", "bilinear", "4");
    println!(
        "default scene 160x90, textured RMSE vs 256 spp: differential+aniso 1 spp {footprint:.6}, \
         mip0+bilinear 4 spp {supersampled:.6}"
    );
    assert!(
        footprint < supersampled,
        "differential+aniso at 1 spp (textured RMSE {footprint}) does not beat 4-sample \
         supersampling ({supersampled})"
    );
}
