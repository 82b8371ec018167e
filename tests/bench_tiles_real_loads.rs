//! `conetrace bench tiles` with real loads: the scene's textures made into `.tx` files,
//! every LOD strategy rendered with them read tile by tile under a fresh cache, on a small
//! `fp_` scene. The tiles read from disk must be the distinct tiles the counting pass
//! counted (plus each texture's 1x1 tile read on opening when the render did not touch
//! it), and the ray-cone orderings the counts show must hold for the real loads.

use std::path::Path;
use std::process::Command;

/// One row of the table: strategy, filter, and the numeric columns after them.
struct Row {
    strategy: String,
    filter: String,
    unique_tiles: u64,
    tiles_loaded: u64,
    expected: u64,
    evicted: u64,
    mib_read: f64,
    peak_mib: f64,
}

fn rows(table: &str) -> Vec<Row> {
    table
        .lines()
        .filter(|line| line.starts_with("| ") && !line.starts_with("| strategy"))
        .map(|line| {
            let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
            assert_eq!(cells.len(), 15, "{line}");
            let int = |i: usize| -> u64 { cells[i].parse().unwrap_or_else(|_| panic!("{line}")) };
            let float = |i: usize| -> f64 { cells[i].parse().unwrap_or_else(|_| panic!("{line}")) };
            Row {
                strategy: cells[0].to_string(),
                filter: cells[1].to_string(),
                unique_tiles: int(2),
                tiles_loaded: int(9),
                expected: int(10),
                evicted: int(11),
                mib_read: float(12),
                peak_mib: float(13),
            }
        })
        .collect()
}

fn bench_tiles(scene: &str, extra: &[&str]) -> Vec<Row> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("assets/scenes").join(scene);
    assert!(scene.is_file(), "{} is missing", scene.display());
    let dir = tempfile::tempdir().unwrap();
    let markdown = dir.path().join("tiles.md");
    let out = Command::new(env!("CARGO_BIN_EXE_conetrace"))
        .args(["bench", "tiles"])
        .arg(&scene)
        .args([
            "--width", "160", "--height", "90", "--spp", "1", "--runs", "1",
        ])
        .args(["--integrator", "whitted", "--threads", "2", "--markdown"])
        .arg(&markdown)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "bench tiles failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows = rows(&std::fs::read_to_string(&markdown).unwrap());
    assert_eq!(rows.len(), 7, "a row per strategy x filter");
    rows
}

fn row<'a>(rows: &'a [Row], strategy: &str, filter: &str) -> &'a Row {
    rows.iter()
        .find(|r| r.strategy == strategy && r.filter == filter)
        .unwrap_or_else(|| panic!("no {strategy} {filter} row"))
}

#[test]
fn real_loads_are_the_counted_tiles_and_keep_the_cone_orderings() {
    let rows = bench_tiles("fp_two_cones.toml", &[]);
    for r in &rows {
        assert_eq!(
            r.evicted, 0,
            "{} {}: the default cap evicts nothing here",
            r.strategy, r.filter
        );
        assert_eq!(
            r.tiles_loaded, r.expected,
            "{} {}: tiles read from disk vs distinct tiles counted",
            r.strategy, r.filter
        );
        assert!(r.tiles_loaded >= r.unique_tiles);
        assert!(r.mib_read > 0.0 && r.peak_mib > 0.0);
    }
    let mip0 = row(&rows, "mip0", "bilinear");
    let distance = row(&rows, "distance", "trilinear");
    let cone1 = row(&rows, "cone1", "trilinear");
    let cone = row(&rows, "cone", "trilinear");
    // Level 0 everywhere reads the most; at the mirror the single cone converges to zero
    // width after the bounce and reads fine levels the two-cone envelope does not.
    for other in [distance, cone1, cone] {
        assert!(
            mip0.tiles_loaded > other.tiles_loaded,
            "mip0 vs {}",
            other.strategy
        );
        assert!(mip0.mib_read > other.mib_read, "mip0 vs {}", other.strategy);
    }
    assert!(
        cone.tiles_loaded < cone1.tiles_loaded,
        "two cones {} vs one cone {}",
        cone.tiles_loaded,
        cone1.tiles_loaded
    );
}

#[test]
fn under_a_tiny_cap_tiles_are_read_again_and_the_peak_stays_under_it() {
    // 4 float tiles of 64 KiB.
    let rows = bench_tiles("fp_two_cones.toml", &["--cache", "256K"]);
    let mip0 = row(&rows, "mip0", "bilinear");
    assert!(mip0.evicted > 0, "mip0 reads more than 4 tiles");
    assert!(
        mip0.tiles_loaded > mip0.expected,
        "evicted tiles are read again"
    );
    for r in &rows {
        assert!(
            r.peak_mib <= 0.25 + 1e-9,
            "{} {}: peak {} MiB",
            r.strategy,
            r.filter,
            r.peak_mib
        );
    }
}
