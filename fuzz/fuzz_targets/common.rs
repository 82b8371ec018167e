//! Shared by the fuzz targets: write the input to a scratch file, load it through the public
//! loader, and carry an accepted scene through to a committed Embree scene and a tiny render.

use std::path::PathBuf;
use std::sync::Arc;

use conetrace::footprint::LodStrategy;
use conetrace::integrator::{AovSelection, Whitted};
use conetrace::render::{self, RenderControl, RenderOptions};
use conetrace::scene::FresnelMode;
use conetrace::texture::FilterOptions;

/// A per-process scratch directory (libFuzzer may run several processes with `-jobs`).
pub fn scratch_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("conetrace-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    dir
}

/// Options of a 4x4, one-sample, two-bounce render with every AOV.
pub fn tiny_options() -> RenderOptions {
    RenderOptions {
        width: 4,
        height: 4,
        spp: 1,
        max_depth: 2,
        min_throughput: 1e-3,
        lod: LodStrategy::Cone,
        filter: FilterOptions::default(),
        fresnel: FresnelMode::Exact,
        aovs: AovSelection {
            surface: true,
            texture_footprint: true,
            lod: true,
        },
        count_tiles: false,
        all_effects: true,
    }
}

/// Load `file`; when the loader accepts it, build and commit the Embree scene and render
/// 4x4 pixels. Loader and preparation errors are the expected outcome of most inputs; only a
/// panic, abort or memory error is a finding.
pub fn load_prepare_render(file: &std::path::Path) {
    let Ok(mut scene) = conetrace::scene::load::load_scene(file) else {
        return;
    };
    if scene.camera.is_none() {
        scene.camera = Some(conetrace::scene::load::frame_camera(&scene, 1.0));
    }
    let Ok(context) = render::prepare(Arc::new(scene), tiny_options()) else {
        return;
    };
    let result = render::render(&context, &Whitted, &RenderControl::default())
        .expect("a validated scene renders without traversal failures");
    for name in result.film.channel_names() {
        if name == "Z" {
            continue; // f32::MAX where the camera ray missed, by design
        }
        if let Some(plane) = result.film.channel(&name) {
            assert!(
                plane.iter().all(|v| v.is_finite()),
                "channel {name} has a non-finite value"
            );
        }
    }
}
