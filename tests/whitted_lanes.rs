//! Whitted's hits shaded in lanes (`Whitted::shade_in_lanes`) against its scalar path:
//! shipped scenes give the same image and AOVs, bit for bit, and the lanes take the hits
//! they cover, fog on the way included.

use std::path::Path;
use std::sync::Arc;

use conetrace::film::{AovSelection, Film};
use conetrace::footprint::LodStrategy;
use conetrace::integrator::Whitted;
use conetrace::render::{self, RenderControl, RenderOptions};
use conetrace::scene::load::load_scene;

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
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut render_options = RenderOptions::from_settings(&scene.settings);
    render_options.width = 40;
    render_options.height = 30;
    render_options.spp = 2;
    options(&mut render_options);
    let context = render::prepare(Arc::new(scene), render_options).expect("prepare");
    let whitted = Whitted {
        shade_in_lanes: in_lanes,
    };
    let result = render::render(&context, &whitted, &RenderControl::default()).expect("render");
    (result.film, result.stats.counters.lane_hits)
}

/// Every channel of the two films, compared bit for bit; panics naming the first that
/// differs.
fn assert_same_bits(scene: &str, variant: &str, lanes: &Film, scalar: &Film) {
    let names = scalar.channel_names();
    assert_eq!(lanes.channel_names(), names, "{scene} ({variant})");
    for name in &names {
        let a = lanes.channel(name).expect("channel");
        let b = scalar.channel(name).expect("channel");
        let differing = a
            .iter()
            .zip(b)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        assert_eq!(
            differing, 0,
            "{scene} ({variant}): {differing} values of {name} differ"
        );
    }
}

/// Renders `scene` both ways, compares them and returns how many hits the lanes shaded.
fn check(scene: &str, variant: &str, options: impl Fn(&mut RenderOptions)) -> u64 {
    let (lanes, hits) = render_film(scene, true, &options);
    let (scalar, scalar_hits) = render_film(scene, false, &options);
    assert_eq!(scalar_hits, 0, "{scene}: the scalar render used the lanes");
    assert_same_bits(scene, variant, &lanes, &scalar);
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
