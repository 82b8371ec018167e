//! The path tracer's hits shaded in lanes (`PathTracer::shade_in_lanes`) against its scalar
//! path: shipped scenes give the same image and AOVs, bit for bit, under the default
//! footprints, with every AOV, and with ray differentials.

mod common;

use common::{assert_same_bits, render_small};
use conetrace::film::{AovSelection, Film};
use conetrace::footprint::LodStrategy;
use conetrace::integrator::path::{LightStrategy, PathTracer};
use conetrace::render::RenderOptions;

/// Scenes with textured, untextured, metallic-roughness, mirror and glass materials (a
/// glass lens mesh, whose hits the lanes shade with the whole mixture of lobes), on meshes
/// and on spheres (diffuse, textured, mirror and glass spheres), emissive quads seen
/// directly, through delta lobes and by BSDF-sampled rays, point, area and environment
/// lights, and absorbing glass: what the lanes cover and what they leave to the scalar
/// path.
const SCENES: [&str; 10] = [
    "assets/scenes/path_textured.toml",
    "assets/scenes/teapot_textured.toml",
    "assets/scenes/teapot_mirror.toml",
    "assets/scenes/cornell.toml",
    "assets/scenes/bench/env_lit_textured.toml",
    "assets/scenes/bench/untextured_specular.toml",
    "assets/scenes/default.toml",
    "assets/scenes/fp_magnifier.toml",
    "assets/scenes/fp_convex.toml",
    "assets/scenes/bench/near_light.toml",
];

/// The film of `scene` rendered small by the path tracer with the settings `tracer`, in
/// lanes or not, and how many hits the lanes shaded.
fn render_film_with(
    scene: &str,
    tracer: PathTracer,
    in_lanes: bool,
    options: impl Fn(&mut RenderOptions),
) -> (Film, u64) {
    let tracer = PathTracer {
        shade_in_lanes: in_lanes,
        ..tracer
    };
    let (film, counters) = render_small(scene, &tracer, options);
    (film, counters.lane_hits)
}

/// Renders every scene both ways and compares them; returns how many hits the lanes shaded
/// in all.
fn check_every_scene(variant: &str, options: impl Fn(&mut RenderOptions)) -> u64 {
    check_every_scene_with(variant, PathTracer::default(), options)
}

/// [`check_every_scene`] with the path tracer's settings `tracer`.
fn check_every_scene_with(
    variant: &str,
    tracer: PathTracer,
    options: impl Fn(&mut RenderOptions),
) -> u64 {
    let mut lane_hits = 0;
    for scene in SCENES {
        let (lanes, hits) = render_film_with(scene, tracer, true, &options);
        let (scalar, scalar_hits) = render_film_with(scene, tracer, false, &options);
        assert_eq!(scalar_hits, 0, "{scene}: the scalar render used the lanes");
        assert_same_bits(&format!("{scene} ({variant})"), &lanes, &scalar);
        lane_hits += hits;
    }
    lane_hits
}

#[test]
fn lanes_give_the_scalar_path_s_image_bit_for_bit() {
    assert!(
        check_every_scene("default", |_| {}) > 0,
        "no hit took the lanes"
    );
}

#[test]
fn lanes_give_the_scalar_path_s_aovs_bit_for_bit() {
    let lane_hits = check_every_scene("every AOV", |options| options.aovs = AovSelection::ALL);
    // First samples record their pixel's first texture lookup by the scalar path; the
    // second samples take the lanes.
    assert!(lane_hits > 0, "no hit took the lanes");
}

#[test]
fn lanes_give_the_scalar_path_s_image_under_ray_differentials() {
    // Each lane's differential is moved to its hit in the lanes (`lanes::differentials`).
    let lane_hits = check_every_scene("differentials", |options| {
        options.lod = LodStrategy::Differential
    });
    assert!(lane_hits > 0, "no hit took the lanes");
}

#[test]
fn lanes_give_the_scalar_path_s_image_without_footprints() {
    let lane_hits = check_every_scene("mip0", |options| options.lod = LodStrategy::Mip0);
    assert!(lane_hits > 0, "no hit took the lanes");
}

#[test]
fn lanes_weigh_light_and_bsdf_samples_as_the_scalar_path_under_every_strategy() {
    // Light sampling alone (never weighted) and BSDF sampling alone (delta lights only):
    // the lanes' stages 5 and 6 branch on the strategy as `next_event::sample_light` does.
    for strategy in [LightStrategy::LightSampling, LightStrategy::BsdfSampling] {
        let tracer = PathTracer {
            strategy,
            ..PathTracer::default()
        };
        let lane_hits = check_every_scene_with(&format!("{strategy:?}"), tracer, |_| {});
        assert!(lane_hits > 0, "no hit took the lanes");
    }
}

#[test]
fn lanes_keep_the_scalar_path_s_diffuse_bounce_limit() {
    // One non-delta bounce: the second diffuse vertex samples light unweighted and ends.
    let tracer = PathTracer {
        diffuse_bounces: 1,
        ..PathTracer::default()
    };
    let lane_hits =
        check_every_scene_with("diffuse_bounces 1", tracer, |options| options.max_depth = 3);
    assert!(lane_hits > 0, "no hit took the lanes");
}

#[test]
fn lanes_shade_the_hits_fog_lets_pass_as_the_scalar_path() {
    // Each ray's fog is sampled for the whole wave first; those it lets through reach their
    // hits in the lanes, the others scatter in the fog by the scalar path.
    for scene in ["assets/scenes/fog.toml", "assets/scenes/fog_mesh.toml"] {
        let (lanes, hits) = render_film_with(scene, PathTracer::default(), true, |_| {});
        let (scalar, scalar_hits) = render_film_with(scene, PathTracer::default(), false, |_| {});
        assert_eq!(scalar_hits, 0, "{scene}: the scalar render used the lanes");
        assert_same_bits(&format!("{scene} (fog)"), &lanes, &scalar);
        assert!(hits > 0, "{scene}: no hit behind the fog took the lanes");
    }
}
