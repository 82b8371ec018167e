//! The thread count changes nothing but the time: every shipped scene rendered on one and on
//! two worker threads gives the same pixels (every layer, bit for bit) and the same work
//! counters and texture-tile counts. Workers keep their counters to themselves and write
//! their tiles straight into the film; this checks that merging them at the end loses and
//! duplicates nothing.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use conetrace::film::AovSelection;
use conetrace::integrator::Whitted;
use conetrace::render::{self, RenderControl, RenderOptions, RenderResult};

fn shipped_scenes() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap_or_else(|e| panic!("{}: {e}", root.display()))
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|x| x == "toml"))
        .collect();
    scenes.sort();
    scenes
}

/// Prepares and renders `path` at 72x40 (a partial tile column and row), 2 samples, every
/// AOV and texture-tile counting on, inside a pool of `threads` workers.
fn render_on(path: &Path, threads: usize) -> RenderResult {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    pool.install(|| {
        let scene = conetrace::scene::load::load_scene(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let options = RenderOptions {
            width: 72,
            height: 40,
            spp: 2,
            aovs: AovSelection::ALL,
            count_texture_tiles: true,
            seed: 0,
            ..RenderOptions::from_settings(&scene.settings)
        };
        let context = render::prepare(Arc::new(scene), options).expect("scene prepares");
        render::render(&context, &Whitted::default(), &RenderControl::default())
            .expect("render succeeds")
    })
}

#[test]
fn one_and_two_threads_give_identical_images_and_counters() {
    let scenes = shipped_scenes();
    assert!(scenes.len() >= 5, "{scenes:?}");
    let mut textured = 0;
    for path in &scenes {
        let name = path.file_name().unwrap().to_string_lossy();
        let one = render_on(path, 1);
        let two = render_on(path, 2);
        assert_eq!((one.stats.threads, two.stats.threads), (1, 2), "{name}");
        assert!(one.stats.complete && two.stats.complete, "{name}");
        assert_eq!(one.finished_tiles, two.finished_tiles, "{name}");
        assert_eq!(one.stats.counters, two.stats.counters, "{name}: counters");
        assert!(one.stats.counters.total_rays() >= 72 * 40 * 2, "{name}");
        assert_eq!(
            one.stats.texture_tiles, two.stats.texture_tiles,
            "{name}: texture tiles"
        );
        let tiles = one
            .stats
            .texture_tiles
            .as_ref()
            .expect("tiles were counted");
        if tiles.total > 0 {
            textured += 1;
        }
        let names = one.film.channel_names();
        assert_eq!(names, two.film.channel_names(), "{name}");
        for channel in &names {
            let (a, b) = (
                one.film.channel(channel).unwrap(),
                two.film.channel(channel).unwrap(),
            );
            let differing = a
                .iter()
                .zip(b)
                .filter(|(x, y)| x.to_bits() != y.to_bits())
                .count();
            assert_eq!(differing, 0, "{name}: {channel}: {differing} pixels differ");
        }
        // Depth is the hit distance or f32::MAX for a miss, never the film's initial 0: every
        // pixel was written.
        let depth = one.film.channel("Z").unwrap();
        assert!(
            depth.iter().all(|&z| z > 0.0),
            "{name}: a pixel was never written"
        );
    }
    assert!(
        textured >= 3,
        "only {textured} scenes touched texture tiles"
    );
}
