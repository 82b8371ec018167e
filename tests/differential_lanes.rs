//! Ray differentials in the shading lanes: a hit whose footprint is a ray differential is
//! shaded in lanes (`integrator::lanes::differentials` transfers it to the hit) wherever a
//! hit under cones is, in Whitted and in the path tracer, and gives the scalar path's image.

mod common;

use common::{assert_same_bits, render_small};
use conetrace::film::Film;
use conetrace::footprint::LodStrategy;
use conetrace::integrator::{PathTracer, Whitted};
use conetrace::render::Integrator;

/// Textured scenes, on meshes and on spheres, whose first hits the lanes cover.
const TEXTURED_SCENES: [&str; 3] = [
    "assets/scenes/path_textured.toml",
    "assets/scenes/teapot_textured.toml",
    "assets/scenes/bench/env_lit_textured.toml",
];

/// The film of `scene` rendered small by `integrator` with footprints `lod` and at most
/// `max_depth` bounces, and how many hits the lanes shaded.
fn render_with<I: Integrator>(
    scene: &str,
    integrator: &I,
    lod: LodStrategy,
    max_depth: u32,
) -> (Film, u64) {
    let (film, counters) = render_small(scene, integrator, |options| {
        options.lod = lod;
        options.max_depth = max_depth;
    });
    (film, counters.lane_hits)
}

#[test]
fn whitted_lanes_shade_the_hits_of_ray_differentials_as_those_of_cones() {
    // Whitted's rays do not depend on the footprint: the same hits reach the lanes.
    for scene in TEXTURED_SCENES {
        let (_, cone_hits) = render_with(scene, &Whitted::default(), LodStrategy::Cone, 4);
        let (_, differential_hits) =
            render_with(scene, &Whitted::default(), LodStrategy::Differential, 4);
        assert!(cone_hits > 0, "{scene}: no hit took the lanes");
        assert_eq!(differential_hits, cone_hits, "{scene}");
    }
}

#[test]
fn path_lanes_shade_the_camera_hits_of_ray_differentials_as_those_of_cones() {
    // No bounce beyond the camera's hit: the hits do not depend on the textures the
    // footprints filter.
    for scene in TEXTURED_SCENES {
        let tracer = PathTracer::default();
        let (_, cone_hits) = render_with(scene, &tracer, LodStrategy::Cone, 0);
        let (_, differential_hits) = render_with(scene, &tracer, LodStrategy::Differential, 0);
        assert!(cone_hits > 0, "{scene}: no hit took the lanes");
        assert_eq!(differential_hits, cone_hits, "{scene}");
    }
}

#[test]
fn path_lanes_give_the_scalar_image_under_ray_differentials_over_bounces() {
    // Several bounces: differentials reflected and refracted by delta lobes, and replaced
    // by the camera's footprint after rough ones, all moved to their hits in the lanes.
    for scene in TEXTURED_SCENES {
        let lanes = PathTracer::default();
        let scalar = PathTracer {
            shade_in_lanes: false,
            ..lanes
        };
        let (lane_film, lane_hits) = render_with(scene, &lanes, LodStrategy::Differential, 5);
        let (scalar_film, scalar_hits) = render_with(scene, &scalar, LodStrategy::Differential, 5);
        assert_eq!(scalar_hits, 0, "{scene}: the scalar render used the lanes");
        assert!(lane_hits > 0, "{scene}: no hit took the lanes");
        assert_same_bits(scene, &lane_film, &scalar_film);
    }
}
