//! Hits on curved and height patches shaded in lanes, by both integrators: the shipped
//! patch scenes give the scalar path's image and AOVs bit for bit under cones, ray
//! differentials and every AOV, and every ray of a render takes the lanes, its hit or its
//! miss, where nothing else sends it to the scalar path.

mod common;

use common::{assert_same_bits, render_small};
use conetrace::film::AovSelection;
use conetrace::footprint::LodStrategy;
use conetrace::integrator::path::PathTracer;
use conetrace::integrator::Whitted;
use conetrace::render::stats::WorkCounters;
use conetrace::render::RenderOptions;

/// The teapot's 32 Bezier patches over a mesh floor (textured, and a partly mirror glaze,
/// whose reflections the path tracer follows), and a textured height patch alone.
const SCENES: [&str; 3] = [
    "assets/scenes/teapot_textured.toml",
    "assets/scenes/teapot_mirror.toml",
    "assets/scenes/height_patch.toml",
];

/// A change to a scene's render options.
type Variant = Box<dyn Fn(&mut RenderOptions)>;

/// The footprints and AOVs the scenes are compared under.
fn variants() -> [(&'static str, Variant); 4] {
    [
        ("default", Box::new(|_| {})),
        (
            "differentials",
            Box::new(|o| o.lod = LodStrategy::Differential),
        ),
        ("mip0", Box::new(|o| o.lod = LodStrategy::Mip0)),
        ("every AOV", Box::new(|o| o.aovs = AovSelection::ALL)),
    ]
}

/// Whether some ray of the render took the scalar path: every ray the path tracer traces
/// (camera rays and bounces) ends at a hit or a miss, which the lanes counted.
fn path_rays_outside_lanes(counters: &WorkCounters) -> u64 {
    counters.camera_rays + counters.path_bounces - counters.lane_hits - counters.lane_misses
}

#[test]
fn path_lanes_shade_patch_hits_as_the_scalar_path() {
    for scene in SCENES {
        for (variant, options) in variants() {
            let what = format!("{scene} ({variant})");
            let lanes = PathTracer::default();
            let scalar = PathTracer {
                shade_in_lanes: false,
                ..PathTracer::default()
            };
            let (film, counters) = render_small(scene, &lanes, &options);
            let (scalar_film, scalar_counters) = render_small(scene, &scalar, &options);
            assert_eq!(scalar_counters.lane_hits, 0, "{what}");
            assert_same_bits(&what, &film, &scalar_film);
            assert_eq!(path_rays_outside_lanes(&counters), 0, "{what}");
            assert!(counters.lane_hits > 0, "{what}");
        }
    }
}

#[test]
fn whitted_lanes_shade_patch_hits_as_the_scalar_path() {
    for scene in SCENES {
        for (variant, options) in variants() {
            let what = format!("{scene} ({variant})");
            let (film, counters) = render_small(scene, &Whitted::default(), &options);
            let scalar = Whitted {
                shade_in_lanes: false,
            };
            let (scalar_film, scalar_counters) = render_small(scene, &scalar, &options);
            assert_eq!(scalar_counters.lane_hits, 0, "{what}");
            assert_same_bits(&what, &film, &scalar_film);
            assert!(counters.lane_hits > 0, "{what}");
        }
    }
}

#[test]
fn every_whitted_ray_on_a_height_patch_takes_the_lanes() {
    // A textured, opaque height patch under a directional light and the environment: no
    // ray is spawned beyond the shadow rays, and no hit is left to the scalar path.
    let scene = "assets/scenes/height_patch.toml";
    for (variant, options) in variants() {
        let (_, counters) = render_small(scene, &Whitted::default(), &options);
        assert_eq!(
            counters.lane_hits + counters.lane_misses,
            counters.camera_rays,
            "{scene} ({variant})"
        );
        // A third of the frame is the patch.
        assert!(
            4 * counters.lane_hits > counters.camera_rays,
            "{scene} ({variant})"
        );
    }
}
