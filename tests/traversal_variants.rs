//! The traversal choices of `TracerSettings`: spheres through Embree's point geometry or as
//! a user geometry with our own test, incoherent waves as streams or as 16-wide packets,
//! medium or high BVH build quality.
//!
//! Checks:
//! - the user-geometry spheres give the analytic hit (`sphere_geometry::ray_sphere_roots`)
//!   through every call the renderer makes: coherent packets, incoherent streams,
//!   incoherent packets and single rays, the same bits in each, for tiny spheres far away,
//!   a huge sphere close by, rays from inside and grazing rays; and Embree's point geometry
//!   finds the same spheres at nearly the same distances;
//! - shipped scenes with spheres render within a stated tolerance whichever way spheres
//!   are traced, waves are laid out or the BVH is built, for Whitted and for the path
//!   tracer at a fixed seed.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use conetrace::integrator::selection::{self, IntegratorKind};
use conetrace::render::sphere_geometry::ray_sphere_roots;
use conetrace::render::stats::WorkCounters;
use conetrace::render::tracer::{
    AlphaTests, IncoherentLayout, SphereTraversal, TraceHit, TraceRay, Tracer, TracerSettings,
};
use conetrace::render::{self, RenderControl, RenderOptions};
use conetrace::scene::{Material, SceneDescription, Sphere};
use glam::Vec3;

/// (centre, radius) of the test spheres: ordinary, tiny and far, huge and close under the
/// origin region, and one around the origin (rays from inside).
const SPHERES: [([f32; 3], f32); 4] = [
    ([0.0, 0.0, -5.0], 1.0),
    ([3.0, 1.0, -2.0e4], 0.01),
    ([0.0, -1.0e3 - 2.0, 0.0], 1.0e3),
    ([-60.0, 0.0, 0.0], 45.0),
];

fn sphere_scene() -> Arc<SceneDescription> {
    Arc::new(SceneDescription {
        source: "test spheres".to_string(),
        materials: vec![Material::default()],
        spheres: SPHERES
            .iter()
            .map(|&(c, r)| Sphere {
                center: Vec3::from(c),
                radius: r,
                material: 0,
            })
            .collect(),
        ..SceneDescription::default()
    })
}

fn tracer(spheres: SphereTraversal, incoherent: IncoherentLayout) -> Tracer {
    let scene = sphere_scene();
    let options = RenderOptions::from_settings(&scene.settings);
    let settings = TracerSettings {
        spheres,
        incoherent,
        ..TracerSettings::new(AlphaTests::Off)
    };
    Tracer::build_with(&scene, &[], &options, settings)
        .expect("the spheres build")
        .0
}

fn ray(origin: Vec3, towards: Vec3) -> TraceRay {
    TraceRay {
        origin,
        direction: (towards - origin).normalize(),
        tfar: f32::INFINITY,
        cone_width: 0.0,
        cone_spread: 0.0,
    }
}

/// Rays at every test sphere: at its centre, across its disc, just inside its silhouette,
/// from inside it, and a few that pass it.
fn test_rays() -> Vec<TraceRay> {
    let mut rays = Vec::new();
    let eye = Vec3::new(0.0, 0.5, 3.0);
    for &(c, r) in &SPHERES {
        let c = Vec3::from(c);
        let view = (c - eye).normalize();
        let side = view.cross(Vec3::Y).normalize();
        let up = side.cross(view);
        for k in 0..24 {
            let angle = k as f32 * 0.2618;
            let spread = [0.0, 0.3, 0.7, 0.999, 1.01][k % 5];
            let offset = (side * angle.cos() + up * angle.sin()) * r * spread;
            rays.push(ray(eye, c + offset));
        }
        rays.push(ray(
            c + Vec3::new(0.1, 0.2, 0.05) * r,
            c + Vec3::X * 3.0 * r,
        ));
    }
    rays
}

/// The analytic closest hit of `ray` over the test spheres: (distance, sphere index).
fn analytic_hit(ray: &TraceRay) -> Option<(f64, u32)> {
    SPHERES
        .iter()
        .enumerate()
        .filter_map(|(i, &(c, r))| {
            let (t0, t1) = ray_sphere_roots(ray.origin, ray.direction, Vec3::from(c), r)?;
            [t0, t1]
                .into_iter()
                .find(|&t| t > 0.0 && (t as f32) < ray.tfar)
                .map(|t| (t, i as u32))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// The closest hits of `rays` by every call the integrators make.
fn hits_by_every_call(tracer: &Tracer, rays: &[TraceRay]) -> Vec<(&'static str, Vec<TraceHit>)> {
    let mut counters = WorkCounters::default();
    let mut coherent = Vec::new();
    tracer.intersect(rays, &mut coherent, true, &mut counters);
    let mut incoherent = Vec::new();
    tracer.intersect(rays, &mut incoherent, false, &mut counters);
    let mut from_iterator = Vec::new();
    tracer.intersect_stream(rays.iter().copied(), &mut from_iterator, &mut counters);
    let mut single = Vec::new();
    tracer.intersect_one_by_one(rays, &mut single, &mut counters);
    assert!(tracer.take_failure().is_none(), "a trace failed");
    vec![
        ("coherent packets", coherent),
        ("incoherent slice", incoherent),
        ("incoherent iterator", from_iterator),
        ("single rays", single),
    ]
}

#[test]
fn user_sphere_hits_are_analytic_through_every_call() {
    let rays = test_rays();
    for layout in [IncoherentLayout::Streams, IncoherentLayout::Packets] {
        let tracer = tracer(SphereTraversal::UserGeometry, layout);
        let all = hits_by_every_call(&tracer, &rays);
        for (call, hits) in &all {
            for (i, (ray, hit)) in rays.iter().zip(hits).enumerate() {
                let expected = analytic_hit(ray);
                match expected {
                    None => assert!(!hit.is_hit(), "{call} {layout:?}, ray {i}: {hit:?}"),
                    Some((t, sphere)) => {
                        assert_eq!(hit.primitive, sphere, "{call} {layout:?}, ray {i}");
                        assert_eq!(hit.t, t as f32, "{call} {layout:?}, ray {i}");
                    }
                }
            }
        }
        let hit_count = all[0].1.iter().filter(|h| h.is_hit()).count();
        assert!(hit_count > rays.len() / 2, "only {hit_count} hits");
        assert!(hit_count < rays.len(), "the rays past the silhouettes miss");
    }
}

#[test]
fn embree_point_spheres_agree_with_the_user_geometry() {
    let rays = test_rays();
    let ours = tracer(SphereTraversal::UserGeometry, IncoherentLayout::Streams);
    let embree = tracer(SphereTraversal::EmbreePoints, IncoherentLayout::Streams);
    let mut counters = WorkCounters::default();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    ours.intersect(&rays, &mut a, false, &mut counters);
    embree.intersect(&rays, &mut b, false, &mut counters);
    for (i, (a, b)) in a.iter().zip(&b).enumerate() {
        assert_eq!(a.is_hit(), b.is_hit(), "ray {i}: {a:?} against {b:?}");
        if a.is_hit() {
            assert_eq!(a.primitive, b.primitive, "ray {i}");
            // Embree's f32 test against ours in f64: close, not equal, far from the origin.
            assert!(
                (a.t - b.t).abs() <= 1.0e-4 * a.t.max(1.0),
                "ray {i}: {} against {}",
                a.t,
                b.t
            );
        }
    }
}

#[test]
fn occlusion_by_user_spheres_matches_their_closest_hits() {
    let rays = test_rays();
    for layout in [IncoherentLayout::Streams, IncoherentLayout::Packets] {
        let tracer = tracer(SphereTraversal::UserGeometry, layout);
        // Segments ending just short of, and just past, the analytic hit.
        for (scale, blocked_if_hit) in [(0.999, false), (1.001, true)] {
            let segments: Vec<TraceRay> = rays
                .iter()
                .map(|r| TraceRay {
                    tfar: analytic_hit(r).map_or(f32::INFINITY, |(t, _)| (t * scale) as f32),
                    ..*r
                })
                .collect();
            let mut counters = WorkCounters::default();
            let mut blocked = Vec::new();
            tracer.occluded(&segments, &mut blocked, &mut counters);
            let mut coherent = Vec::new();
            tracer.occluded_coherent(&segments, &mut coherent, &mut counters);
            for (i, r) in rays.iter().enumerate() {
                let expected = analytic_hit(r).is_some() && blocked_if_hit;
                assert_eq!(blocked[i], expected, "{layout:?} x{scale}, ray {i}");
                assert_eq!(coherent[i], expected, "coherent x{scale}, ray {i}");
            }
        }
    }
}

fn shipped_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/scenes")
        .join(name)
}

/// RGB of `scene` rendered at 48 x 36 by `kind` with the default traversal changed by
/// `change`.
fn render_rgb(
    scene: &Path,
    kind: IntegratorKind,
    change: &dyn Fn(TracerSettings) -> TracerSettings,
) -> Vec<f32> {
    let description = conetrace::scene::load::load_scene(scene)
        .unwrap_or_else(|e| panic!("{}: {e}", scene.display()));
    assert!(
        !description.spheres.is_empty(),
        "{} has no sphere",
        scene.display()
    );
    let options = RenderOptions {
        width: 48,
        height: 36,
        spp: if kind == IntegratorKind::Path { 4 } else { 1 },
        ..RenderOptions::from_settings(&description.settings)
    };
    let mut context = render::prepare(Arc::new(description), options).expect("prepares");
    let settings = change(context.tracer.settings());
    context.set_tracer_settings(settings).expect("rebuilds");
    let integrator = selection::select(kind, &context).expect("integrator");
    let result = render::render(&context, &integrator, &RenderControl::default()).expect("renders");
    ["R", "G", "B"]
        .iter()
        .flat_map(|c| result.film.channel(c).expect("channel").to_vec())
        .collect()
}

/// The largest absolute difference between two images.
fn largest_difference(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0f32, f32::max)
}

/// Shipped scenes with spheres, each with the integrator it is rendered with (the path
/// tracer at the scene's fixed seed).
const SCENES: [(&str, IntegratorKind); 4] = [
    ("default.toml", IntegratorKind::Whitted),
    ("cornell.toml", IntegratorKind::Path),
    ("path_textured.toml", IntegratorKind::Path),
    ("fp_convex.toml", IntegratorKind::Whitted),
];

/// Renders every scene of [`SCENES`] with settings `a` and `b`; their images may differ by
/// at most `tolerance` in any value.
fn assert_renders_alike(
    label: &str,
    a: &dyn Fn(TracerSettings) -> TracerSettings,
    b: &dyn Fn(TracerSettings) -> TracerSettings,
    tolerance: f32,
) {
    for (name, kind) in SCENES {
        let scene = shipped_scene(name);
        let largest =
            largest_difference(&render_rgb(&scene, kind, a), &render_rgb(&scene, kind, b));
        assert!(
            largest <= tolerance,
            "{label}, {name} ({kind:?}): largest difference {largest}, above {tolerance}"
        );
    }
}

/// The tracer's sphere test changes the hit distance in its last bits; the surface lookup
/// projects the hit onto the sphere, so only footprints and secondary rays see it (measured
/// largest difference 1.6e-4, on default.toml's reflections).
#[test]
fn shipped_sphere_scenes_render_alike_with_either_sphere_test() {
    assert_renders_alike(
        "Embree point spheres against user-geometry spheres",
        &|s| TracerSettings {
            spheres: SphereTraversal::EmbreePoints,
            ..s
        },
        &|s| TracerSettings {
            spheres: SphereTraversal::UserGeometry,
            ..s
        },
        1.0e-3,
    );
}

/// Packets and streams find the same closest hits (a tie of two triangles at one distance
/// could go either way, and does not occur in these scenes): the images are identical.
#[test]
fn shipped_sphere_scenes_render_identically_as_incoherent_packets_or_streams() {
    assert_renders_alike(
        "incoherent streams against packets",
        &|s| TracerSettings {
            incoherent: IncoherentLayout::Streams,
            ..s
        },
        &|s| TracerSettings {
            incoherent: IncoherentLayout::Packets,
            ..s
        },
        0.0,
    );
}

/// As for the wave layout: another BVH finds the same closest hits.
#[test]
fn shipped_sphere_scenes_render_identically_with_either_build_quality() {
    assert_renders_alike(
        "medium against high build quality",
        &|s| TracerSettings {
            high_quality_min_triangles: usize::MAX,
            ..s
        },
        &|s| TracerSettings {
            high_quality_min_triangles: 0,
            ..s
        },
        0.0,
    );
}

/// A sphere the renderer cannot trace is refused at build time whichever test traces it,
/// not left out of the BVH in silence.
#[test]
fn an_invalid_sphere_is_refused_by_either_sphere_test() {
    for spheres in [SphereTraversal::UserGeometry, SphereTraversal::EmbreePoints] {
        for (center, radius) in [
            (Vec3::ZERO, f32::NAN),
            (Vec3::new(f32::INFINITY, 0.0, 0.0), 1.0),
        ] {
            let scene = Arc::new(SceneDescription {
                source: "bad sphere".to_string(),
                materials: vec![Material::default()],
                spheres: vec![
                    Sphere {
                        center: Vec3::ZERO,
                        radius: 1.0,
                        material: 0,
                    },
                    Sphere {
                        center,
                        radius,
                        material: 0,
                    },
                ],
                ..SceneDescription::default()
            });
            let options = RenderOptions::from_settings(&scene.settings);
            let settings = TracerSettings {
                spheres,
                ..TracerSettings::new(AlphaTests::Off)
            };
            let error = match Tracer::build_with(&scene, &[], &options, settings) {
                Ok(_) => panic!("{spheres:?}: sphere ({center}, {radius}) was accepted"),
                Err(error) => error.to_string(),
            };
            assert!(error.contains("sphere 1"), "{spheres:?}: {error}");
        }
    }
}
