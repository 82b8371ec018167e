//! Texture tiles under the path tracer: lookups are recorded at every bounce, and on the
//! textured path-traced scene (assets/scenes/path_textured.toml) the cone footprints read
//! fewer distinct 64x64 tiles of the finest level than point samples of level 0 do
//! (`conetrace bench tiles`, docs/path-tracing.md).

use std::path::PathBuf;
use std::sync::Arc;

mod common;
use common::{run_in, temp_dir};

use conetrace::footprint::LodStrategy;
use conetrace::integrator::path::PathTracer;
use conetrace::render::{self, RenderControl, RenderOptions, TextureTileUsage};
use conetrace::scene::load::load_scene;
use conetrace::scene::SceneDescription;
use conetrace::texture::FilterMode;

fn textured_scene() -> SceneDescription {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/path_textured.toml");
    load_scene(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Options of a small, quick render of the textured scene.
fn small_options(scene: &SceneDescription) -> RenderOptions {
    let mut options = RenderOptions::from_settings(&scene.settings);
    options.width = 96;
    options.height = 64;
    options.spp = 2;
    options
}

/// One row of `bench tiles`' table: strategy, filter, unique tiles, unique level-0 tiles,
/// touches, lookups.
struct TableRow {
    lod: String,
    filter: String,
    unique: u64,
    level0: u64,
    touches: u64,
    lookups: u64,
}

fn table_rows(text: &str) -> Vec<TableRow> {
    text.lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| strategy"))
        .map(|line| {
            let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
            let number = |i: usize| -> u64 {
                cells[i]
                    .parse()
                    .unwrap_or_else(|e| panic!("cell {i} of {line:?}: {e}"))
            };
            TableRow {
                lod: cells[0].to_string(),
                filter: cells[1].to_string(),
                unique: number(2),
                level0: number(3),
                touches: number(4),
                lookups: number(5),
            }
        })
        .collect()
}

/// `conetrace bench tiles` on the textured scene under the path tracer: every row counts
/// tiles, and the cone rows read fewer distinct level-0 tiles than mip0.
#[test]
fn cone_footprints_touch_fewer_fine_tiles_than_mip0_under_path() {
    let dir = temp_dir();
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/path_textured.toml");
    let table = dir.path().join("tiles.md");
    let output = run_in(
        dir.path(),
        &[
            "bench",
            "tiles",
            scene.to_str().expect("utf-8 path"),
            "--integrator",
            "path",
            "--width",
            "96",
            "--height",
            "64",
            "--spp",
            "2",
            "--runs",
            "1",
            "--markdown",
            table.to_str().expect("utf-8 path"),
        ],
    );
    assert!(
        output.status.success(),
        "bench tiles failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = std::fs::read_to_string(&table).expect("the table was written");
    println!("{text}");
    assert!(text.contains("integrator path"), "{text}");
    let rows = table_rows(&text);
    assert_eq!(rows.len(), 7, "{text}");
    for row in &rows {
        assert!(
            row.lookups > 0 && row.unique > 0,
            "{}: nothing counted",
            row.lod
        );
        assert!(row.touches >= row.unique && row.unique >= row.level0);
    }
    let mip0 = rows.iter().find(|r| r.lod == "mip0").expect("a mip0 row");
    let cone_rows: Vec<&TableRow> = rows.iter().filter(|r| r.lod.starts_with("cone")).collect();
    assert_eq!(cone_rows.len(), 3, "{text}");
    for row in cone_rows {
        assert!(
            row.level0 < mip0.level0,
            "{}+{}: {} level-0 tiles, mip0 {}",
            row.lod,
            row.filter,
            row.level0,
            mip0.level0
        );
    }
}

fn tile_usage(max_depth: u32) -> (TextureTileUsage, u64) {
    let scene = textured_scene();
    let mut options = small_options(&scene);
    options.max_depth = max_depth;
    options.lod = LodStrategy::Cone;
    options.filter.filter = FilterMode::Trilinear;
    options.count_texture_tiles = true;
    let context = render::prepare(Arc::new(scene), options).expect("prepare");
    let result = render::render(&context, &PathTracer::default(), &RenderControl::default())
        .expect("render");
    let usage = result.stats.texture_tiles.expect("tiles were counted");
    (usage, result.stats.counters.texture_lookups)
}

/// The coarsest mip level any texture had a tile read from.
fn coarsest_level(usage: &TextureTileUsage) -> usize {
    usage
        .per_texture
        .iter()
        .filter_map(|(_, levels)| levels.iter().rposition(|&n| n > 0))
        .max()
        .unwrap_or(0)
}

/// Lookups after diffuse bounces are recorded too: with bounces there are more lookups,
/// touches and distinct tiles than with camera hits alone. (Most bounced rays of this
/// open-topped scene escape to the environment, so about a third more lookups.)
#[test]
fn texture_tiles_are_counted_at_every_bounce() {
    let (camera_only, camera_lookups) = tile_usage(0);
    let (bounced, bounced_lookups) = tile_usage(4);
    println!(
        "max_depth 0: {camera_lookups} lookups, {} touches, {} tiles, coarsest level {}; \
         max_depth 4: {bounced_lookups} lookups, {} touches, {} tiles, coarsest level {}",
        camera_only.touches,
        camera_only.total,
        coarsest_level(&camera_only),
        bounced.touches,
        bounced.total,
        coarsest_level(&bounced)
    );
    assert!(camera_only.touches > 0 && camera_lookups > 0);
    assert!(bounced_lookups > camera_lookups * 5 / 4);
    assert!(bounced.touches > camera_only.touches * 5 / 4);
    assert!(bounced.total > camera_only.total);
    // Cones widen at every diffuse bounce, so bounced lookups reach coarser levels.
    assert!(coarsest_level(&bounced) >= coarsest_level(&camera_only));
}
