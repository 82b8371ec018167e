//! Rendering allocates nothing per tile: each worker keeps its tile image and its
//! integrator's buffers from one tile to the next. A counting allocator measures the
//! allocations of whole renders whose only difference is the number of tiles (one test, so
//! that nothing else in this process allocates while it counts).

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use conetrace::film::AovSelection;
use conetrace::integrator::{PathTracer, Whitted};
use conetrace::render::{self, Integrator, RenderControl, RenderOptions};

/// The system allocator, counting every allocation and reallocation.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded unchanged to the system allocator.
#[allow(unsafe_code)]
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by one render of `scene` at `width` x `height` (one worker thread, so
/// that one worker renders every tile), scene preparation excluded.
fn render_allocations<I: Integrator>(
    scene: &str,
    integrator: &I,
    width: u32,
    height: u32,
) -> usize {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(scene);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    pool.install(|| {
        let scene = conetrace::scene::load::load_scene(&path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let options = RenderOptions {
            width,
            height,
            spp: 2,
            aovs: AovSelection::ALL,
            seed: 0,
            ..RenderOptions::from_settings(&scene.settings)
        };
        let context = render::prepare(Arc::new(scene), options).expect("scene prepares");
        // One render first, so that lazily built state is not counted against either size.
        render::render(&context, integrator, &RenderControl::default()).expect("warm-up");
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        let result = render::render(&context, integrator, &RenderControl::default())
            .expect("render succeeds");
        let after = ALLOCATIONS.load(Ordering::Relaxed);
        assert!(result.stats.complete);
        after - before
    })
}

/// 16 tiles against 256 tiles: at most a few allocations per row of tiles and per doubling
/// of the finished-tile list may differ, far fewer than one per extra tile.
fn check<I: Integrator>(scene: &str, integrator: &I) {
    let few = render_allocations(scene, integrator, 64, 64);
    let many = render_allocations(scene, integrator, 256, 256);
    let extra_tiles = 256 - 16;
    println!("{scene}: {few} allocations for 16 tiles, {many} for 256 tiles");
    assert!(
        many.saturating_sub(few) < extra_tiles / 4,
        "{scene}: {few} allocations for 16 tiles but {many} for 256: allocation per tile"
    );
}

/// One test for every integrator: the counter is global, so no other test of this file may
/// allocate while one measures.
#[test]
fn rendering_allocates_nothing_per_tile() {
    check("default.toml", &Whitted::default());
    check("teapot_textured.toml", &Whitted::default());
    check("cornell.toml", &PathTracer::default());
}
