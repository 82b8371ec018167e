//! Rays that leave the scene, their environment looked up together (`integrator::lanes::
//! misses`): Whitted and the path tracer take a wave's misses there, fog or not, and the
//! images are their scalar paths', bit for bit, with a lat-long sky and a constant colour,
//! under cones and ray differentials, BSDF-sampled rays weighted against light sampling of
//! the sky, and fog on the misses' way out.

mod common;

use common::{assert_same_bits, render_small};
use conetrace::film::{AovSelection, Film};
use conetrace::footprint::LodStrategy;
use conetrace::integrator::{PathTracer, Whitted};
use conetrace::render::stats::WorkCounters;
use conetrace::render::Integrator;

/// Scenes with sky around them: a lat-long map (lit by it as a light in the path tracer)
/// and a constant colour.
const SKY_SCENES: [&str; 4] = [
    "assets/scenes/default.toml",
    "assets/scenes/bench/env_lit_textured.toml",
    "assets/scenes/teapot_mirror.toml",
    "assets/scenes/fp_magnifier.toml",
];

/// The film of `scene` rendered small by `integrator` with footprints `lod` and every AOV,
/// and the render's counters.
fn render_with<I: Integrator>(
    scene: &str,
    integrator: &I,
    lod: LodStrategy,
) -> (Film, WorkCounters) {
    render_small(scene, integrator, |options| {
        options.lod = lod;
        options.aovs = AovSelection::ALL;
    })
}

#[test]
fn whitted_looks_up_the_environment_of_its_misses_together() {
    for scene in SKY_SCENES {
        let (_, counters) = render_with(scene, &Whitted::default(), LodStrategy::Cone);
        assert!(counters.lane_misses > 0, "{scene}: no miss took the lanes");
    }
}

#[test]
fn path_lanes_give_the_scalar_image_of_misses_bit_for_bit() {
    for lod in [LodStrategy::Cone, LodStrategy::Differential] {
        for scene in SKY_SCENES {
            let lanes = PathTracer::default();
            let scalar = PathTracer {
                shade_in_lanes: false,
                ..lanes
            };
            let (lane_film, lane_counters) = render_with(scene, &lanes, lod);
            let (scalar_film, scalar_counters) = render_with(scene, &scalar, lod);
            assert!(
                lane_counters.lane_misses > 0,
                "{scene}: no miss took the lanes"
            );
            assert_eq!(
                scalar_counters.lane_misses, 0,
                "{scene}: the scalar render used them"
            );
            // Every lookup is counted once, whichever path made it.
            assert_eq!(
                lane_counters.texture_lookups, scalar_counters.texture_lookups,
                "{scene} ({lod:?})"
            );
            assert_same_bits(&format!("{scene} ({lod:?})"), &lane_film, &scalar_film);
        }
    }
}

/// Scenes with fog: over a ground in front of spheres, and bounded by a mesh.
const FOG_SCENES: [&str; 2] = ["assets/scenes/fog.toml", "assets/scenes/fog_mesh.toml"];

#[test]
fn misses_through_fog_take_the_lanes_with_the_scalar_path_s_bits() {
    for scene in FOG_SCENES {
        // Whitted fogs each miss's way out as it adds the miss's light, in the wave's order.
        let (film, counters) = render_with(scene, &Whitted::default(), LodStrategy::Cone);
        let scalar = Whitted {
            shade_in_lanes: false,
        };
        let (scalar_film, _) = render_with(scene, &scalar, LodStrategy::Cone);
        assert_same_bits(&format!("{scene} (Whitted)"), &film, &scalar_film);
        assert!(counters.lane_misses > 0, "{scene}: no miss took the lanes");
        // The path tracer's rays that fog lets escape are misses; those it stops scatter.
        let tracer = PathTracer::default();
        let scalar = PathTracer {
            shade_in_lanes: false,
            ..tracer
        };
        let (film, counters) = render_with(scene, &tracer, LodStrategy::Cone);
        let (scalar_film, _) = render_with(scene, &scalar, LodStrategy::Cone);
        assert_same_bits(&format!("{scene} (path)"), &film, &scalar_film);
        assert!(counters.lane_misses > 0, "{scene}: no miss took the lanes");
        assert!(
            counters.fog_scatter_events > 0,
            "{scene}: nothing scattered"
        );
    }
}

#[test]
fn every_whitted_ray_through_fog_takes_the_lanes() {
    // Each camera, reflection and refraction ray's hit or miss is the lanes'.
    let (_, counters) = render_with(
        "assets/scenes/fog.toml",
        &Whitted::default(),
        LodStrategy::Cone,
    );
    assert_eq!(
        counters.lane_hits + counters.lane_misses,
        counters.camera_rays + counters.reflection_rays + counters.refraction_rays
    );
}
