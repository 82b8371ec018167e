//! Renders that write the texture-lookup AOVs (`tex`, `texcolor`, `lod`, `footprint`)
//! shade their first samples in lanes too: each pixel's first base-colour lookup is
//! recorded in the wave's order from the lanes' batched lookups, with the scalar path's
//! bits, and writing the AOVs changes none of which hits take the lanes.

mod common;

use common::{assert_same_bits, render_small};
use conetrace::film::AovSelection;
use conetrace::footprint::LodStrategy;
use conetrace::integrator::path::PathTracer;
use conetrace::integrator::Whitted;
use conetrace::render::stats::WorkCounters;
use conetrace::render::{Integrator, RenderOptions};

/// Textured meshes, spheres and patches, seen directly and through mirrors and glass.
const SCENES: [&str; 4] = [
    "assets/scenes/path_textured.toml",
    "assets/scenes/teapot_textured.toml",
    "assets/scenes/bench/env_lit_textured.toml",
    "assets/scenes/fp_magnifier.toml",
];

/// One sample per pixel, so that every ray belongs to a first sample.
fn options(lod: LodStrategy, aovs: AovSelection) -> impl Fn(&mut RenderOptions) {
    move |options| {
        options.spp = 1;
        options.lod = lod;
        options.aovs = aovs;
    }
}

/// `scene` rendered by `lanes` and by `scalar` with every AOV under `lod`: the same film
/// bit for bit, and the lanes' counters with every AOV and with the surface AOVs alone.
fn check(
    scene: &str,
    lod: LodStrategy,
    (lanes, scalar): (&impl Integrator, &impl Integrator),
) -> (WorkCounters, WorkCounters) {
    let what = format!("{scene} ({lod:?})");
    let (film, counters) = render_small(scene, lanes, options(lod, AovSelection::ALL));
    let (scalar_film, _) = render_small(scene, scalar, options(lod, AovSelection::ALL));
    assert!(
        film.channel_names().iter().any(|name| name == "tex.s")
            && film.channel_names().iter().any(|name| name == "lod"),
        "{what}: {:?}",
        film.channel_names()
    );
    assert_same_bits(&what, &film, &scalar_film);
    let surface_only = AovSelection {
        surface: true,
        ..AovSelection::default()
    };
    let (_, default_counters) = render_small(scene, lanes, options(lod, surface_only));
    (counters, default_counters)
}

#[test]
fn path_lanes_record_the_first_lookups_of_the_scalar_path() {
    let scalar = PathTracer {
        shade_in_lanes: false,
        ..PathTracer::default()
    };
    for scene in SCENES {
        for lod in [LodStrategy::Cone, LodStrategy::Differential] {
            let (counters, default_counters) = check(scene, lod, (&PathTracer::default(), &scalar));
            assert_eq!(counters.lane_hits, default_counters.lane_hits, "{scene}");
            // Every ray's hit or miss took the lanes.
            assert_eq!(
                counters.lane_hits + counters.lane_misses,
                counters.camera_rays + counters.path_bounces,
                "{scene} ({lod:?})"
            );
        }
    }
}

#[test]
fn whitted_lanes_record_the_first_lookups_of_the_scalar_path() {
    let scalar = Whitted {
        shade_in_lanes: false,
    };
    for scene in SCENES {
        for lod in [LodStrategy::Cone, LodStrategy::Differential] {
            let (counters, default_counters) = check(scene, lod, (&Whitted::default(), &scalar));
            assert_eq!(counters.lane_hits, default_counters.lane_hits, "{scene}");
            assert!(counters.lane_hits > 0, "{scene} ({lod:?})");
        }
    }
}
