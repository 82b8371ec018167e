//! Whitted's hits shaded in lanes (`Whitted::shade_in_lanes`) against its scalar path:
//! shipped scenes give the same image and AOVs, bit for bit, and the lanes take the hits
//! they cover, fog on the way included.

mod common;

use common::{assert_same_bits, render_small};
use conetrace::film::{AovSelection, Film};
use conetrace::footprint::LodStrategy;
use conetrace::integrator::Whitted;
use conetrace::render::RenderOptions;

/// Textured and untextured opaque materials on meshes and spheres, mirrors and glass (which
/// the scalar path shades), point and environment light, and fog over a ground, in front of
/// spheres, and bounded by a mesh.
const SCENES: [&str; 8] = [
    "assets/scenes/default.toml",
    "assets/scenes/teapot_textured.toml",
    "assets/scenes/teapot_mirror.toml",
    "assets/scenes/fp_magnifier.toml",
    "assets/scenes/bench/env_lit_textured.toml",
    "assets/scenes/bench/matte_lit.toml",
    "assets/scenes/fog.toml",
    "assets/scenes/fog_mesh.toml",
];

/// The film of `scene` rendered small by Whitted, in lanes or not, and how many hits the
/// lanes shaded.
fn render_film(scene: &str, in_lanes: bool, options: impl Fn(&mut RenderOptions)) -> (Film, u64) {
    let whitted = Whitted {
        shade_in_lanes: in_lanes,
    };
    let (film, counters) = render_small(scene, &whitted, options);
    (film, counters.lane_hits)
}

/// Renders `scene` both ways, compares them and returns how many hits the lanes shaded.
fn check(scene: &str, variant: &str, options: impl Fn(&mut RenderOptions)) -> u64 {
    let (lanes, hits) = render_film(scene, true, &options);
    let (scalar, scalar_hits) = render_film(scene, false, &options);
    assert_eq!(scalar_hits, 0, "{scene}: the scalar render used the lanes");
    assert_same_bits(&format!("{scene} ({variant})"), &lanes, &scalar);
    hits
}

#[test]
fn lanes_give_the_scalar_path_s_image_bit_for_bit() {
    for scene in SCENES {
        let hits = check(scene, "default", |_| {});
        assert!(hits > 0, "{scene}: no hit took the lanes");
    }
}

#[test]
fn lanes_give_the_scalar_path_s_aovs_bit_for_bit() {
    for scene in SCENES {
        check(scene, "every AOV", |options| {
            options.aovs = AovSelection::ALL
        });
    }
}

#[test]
fn lanes_give_the_scalar_path_s_image_without_footprints() {
    for scene in SCENES {
        check(scene, "mip0", |options| options.lod = LodStrategy::Mip0);
    }
}
