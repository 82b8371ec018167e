//! Curved patches traced exactly through Embree's user geometry: packets, streams and single
//! rays agree; hits lie on the patch; and the hard cases (silhouettes, grazing rays, the
//! teapot's collapsed lid and bottom, rays leaving the surface) give finite results and no
//! self-intersection.

mod common;

use std::path::Path;
use std::sync::Arc;

use common::Rng;
use conetrace::footprint::LodStrategy;
use conetrace::render::prepared::{GeometryRef, SurfaceDetail, SurfaceLookup};
use conetrace::render::stats::WorkCounters;
use conetrace::render::tracer::{TraceHit, TraceRay, Tracer};
use conetrace::render::RenderOptions;
use conetrace::scene::load::load_toml_str;
use conetrace::scene::patch::BezierPatch;
use conetrace::scene::RenderSettings;
use conetrace::scene::SceneDescription;
use glam::Vec3;

fn options() -> RenderOptions {
    RenderOptions {
        width: 16,
        height: 16,
        max_depth: 0,
        min_throughput: 0.0,
        lod: LodStrategy::Mip0,
        ..RenderOptions::from_settings(&RenderSettings::default())
    }
}

/// The teapot alone, y up, half size: its body's widest circle has radius 1 at y = 0.45,
/// the lid's apex is at y = 1.575 and the bottom's centre at the origin.
const TEAPOT: &str = "[[light]]\ntype = \"directional\"\ndirection = [0, -1, 0]\n\n\
    [[patch_file]]\nfile = \"../models/teapot.bpt\"\nrotate = [-90, 0, 0]\nscale = 0.5\n";

struct Traced {
    scene: Arc<SceneDescription>,
    tracer: Tracer,
    lookup: SurfaceLookup,
}

fn traced(text: &str) -> Traced {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let scene = Arc::new(load_toml_str(text, &assets, "test.toml").expect("the scene loads"));
    let (tracer, geometries) = Tracer::build(&scene, &[], &options()).expect("the scene builds");
    let lookup = SurfaceLookup::new(scene.clone(), geometries);
    Traced {
        scene,
        tracer,
        lookup,
    }
}

fn ray(origin: Vec3, direction: Vec3) -> TraceRay {
    TraceRay {
        origin,
        direction: direction.normalize(),
        tfar: f32::INFINITY,
        cone_width: 0.0,
        cone_spread: 0.0,
    }
}

impl Traced {
    fn trace(&self, rays: &[TraceRay], coherent: bool) -> Vec<TraceHit> {
        let mut hits = Vec::new();
        self.tracer
            .intersect(rays, &mut hits, coherent, &mut WorkCounters::default());
        assert!(self.tracer.take_failure().is_none(), "a trace failed");
        hits
    }

    fn patch(&self, hit: &TraceHit) -> Option<&BezierPatch> {
        (hit.is_hit() && self.lookup.geometries[hit.geometry as usize] == GeometryRef::Patches)
            .then(|| &self.scene.patches[hit.primitive as usize])
    }

    /// Checks a patch hit: finite, (u, v) in the unit square, the patch at (u, v) on the ray
    /// at t, a unit normal. Returns the distance between the two points.
    fn check_on_patch(&self, r: &TraceRay, hit: &TraceHit) -> f64 {
        let patch = self.patch(hit).expect("a patch hit");
        assert!(
            hit.t.is_finite() && hit.u.is_finite() && hit.v.is_finite(),
            "{hit:?}"
        );
        assert!(
            (0.0..=1.0).contains(&hit.u) && (0.0..=1.0).contains(&hit.v),
            "{hit:?}"
        );
        let on_patch = patch.evaluate(f64::from(hit.u), f64::from(hit.v)).position;
        let on_ray = r.origin.as_dvec3() + r.direction.as_dvec3() * f64::from(hit.t);
        let surface = self
            .lookup
            .surface_hit(r.origin, r.direction, hit, SurfaceDetail::Texturing);
        let n = surface.geometric_normal;
        assert!(
            n.is_finite() && (n.length() - 1.0).abs() < 1e-4,
            "normal {n} at {hit:?}"
        );
        assert!(surface.position.is_finite() && surface.dpds.is_finite());
        (on_patch - on_ray).length()
    }
}

/// Rays from a camera in front of the teapot, in 4x4 blocks as the renderer makes them.
fn camera_rays() -> Vec<TraceRay> {
    let eye = Vec3::new(0.3, 1.6, 5.0);
    let mut rays = Vec::new();
    for block in 0..64 {
        for k in 0..16 {
            let (x, y) = ((block % 8) * 4 + k % 4, (block / 8) * 4 + k / 4);
            let target = Vec3::new(
                -2.0 + 4.0 * x as f32 / 31.0,
                1.6 - 1.8 * y as f32 / 31.0,
                0.0,
            );
            rays.push(ray(eye, target - eye));
        }
    }
    rays
}

#[test]
fn packets_streams_and_single_rays_agree_and_hit_the_patch() {
    let t = traced(TEAPOT);
    let rays = camera_rays();
    let packets = t.trace(&rays, true);
    let streams = t.trace(&rays, false);
    let mut single = Vec::new();
    t.tracer
        .intersect_one_by_one(&rays, &mut single, &mut WorkCounters::default());
    let mut hits = 0;
    let mut worst: f64 = 0.0;
    for (i, r) in rays.iter().enumerate() {
        for other in [&streams[i], &single[i]] {
            assert_eq!(packets[i].is_hit(), other.is_hit(), "ray {i}");
            if packets[i].is_hit() {
                assert_eq!(packets[i].primitive, other.primitive, "ray {i}");
                assert!(
                    (packets[i].t - other.t).abs() <= 1e-5 * packets[i].t,
                    "ray {i}"
                );
            }
        }
        if packets[i].is_hit() {
            hits += 1;
            worst = worst.max(t.check_on_patch(r, &packets[i]));
        }
    }
    eprintln!(
        "{hits} of {} camera rays hit the teapot; worst point distance {worst:e}",
        rays.len()
    );
    assert!(hits > 200, "only {hits} hits");
    assert!(worst < 1e-5, "a hit is {worst} off its patch");
}

#[test]
fn the_silhouette_is_exact() {
    // Rays along -x at the height of the body's widest circle (radius 1, centred on the y
    // axis), on the side away from spout and handle: they hit for z < 1 and miss for z > 1,
    // with no tessellation's facets in between. The tangent point is a corner shared by
    // four patches.
    let t = traced(TEAPOT);
    let xs: Vec<f32> = (0..2000)
        .map(|i| 0.998 + 0.004 * i as f32 / 1999.0)
        .collect();
    let rays: Vec<TraceRay> = xs
        .iter()
        .map(|&z| ray(Vec3::new(5.0, 0.45, z), Vec3::NEG_X))
        .collect();
    let hits = t.trace(&rays, false);
    let mut last_hit: f32 = 0.0;
    let mut first_miss = f32::INFINITY;
    for ((x, r), hit) in xs.iter().zip(&rays).zip(&hits) {
        if hit.is_hit() {
            last_hit = last_hit.max(*x);
            assert!(t.check_on_patch(r, hit) < 1e-5);
        } else {
            first_miss = first_miss.min(*x);
        }
    }
    eprintln!("silhouette: last hit at z = {last_hit}, first miss at z = {first_miss}");
    assert!((last_hit - 1.0).abs() < 1e-5, "last hit at {last_hit}");
    assert!(
        (first_miss - 1.0).abs() < 1e-5,
        "first miss at {first_miss}"
    );
    assert!(last_hit < first_miss);
}

#[test]
fn grazing_rays_meet_a_flat_patch_where_they_cross_it() {
    let text = "[[patch]]\ndegree = [1, 1]\ncontrol_points = [[-5, 0, -5], [5, 0, -5], [-5, 0, 5], [5, 0, 5]]\n";
    let t = traced(text);
    for slope in [1e-1f32, 1e-2, 1e-3, 1e-4] {
        let r = ray(
            Vec3::new(-4.0, 4.0 * slope, 0.3),
            Vec3::new(1.0, -slope, 0.0),
        );
        let hit = t.trace(&[r], false)[0];
        assert!(hit.is_hit(), "slope {slope}: missed");
        let expected = 4.0 * (1.0 + slope * slope).sqrt();
        assert!(
            (hit.t - expected).abs() < 1e-4,
            "slope {slope}: t {} vs {expected}",
            hit.t
        );
        assert!(t.check_on_patch(&r, &hit) < 1e-5);
    }
}

#[test]
fn collapsed_edges_at_the_lid_and_bottom_give_finite_hits() {
    let t = traced(TEAPOT);
    let mut rays = Vec::new();
    for offset in [0.0f32, 1e-7, 1e-5, 1e-3, 1e-2] {
        for (dx, dz) in [(1.0, 0.0), (0.0, 1.0), (-0.7, 0.7)] {
            let (x, z) = (dx * offset, dz * offset);
            rays.push(ray(Vec3::new(x, 3.0, z), Vec3::NEG_Y)); // onto the lid's apex
            rays.push(ray(Vec3::new(x, -1.0, z), Vec3::Y)); // onto the bottom's centre
        }
    }
    let hits = t.trace(&rays, false);
    for (r, hit) in rays.iter().zip(&hits) {
        assert!(hit.is_hit(), "{r:?} missed");
        let distance = t.check_on_patch(r, hit);
        assert!(distance < 1e-5, "{r:?}: {distance}");
        let y = r.origin.y + r.direction.y * hit.t;
        let expected = if r.direction.y < 0.0 { 1.575 } else { 0.0 };
        assert!((y - expected).abs() < 1e-4, "{r:?} hit at y = {y}");
        let surface = t
            .lookup
            .surface_hit(r.origin, r.direction, hit, SurfaceDetail::Geometry);
        assert!(
            surface.geometric_normal.y.abs() > 0.999,
            "{}",
            surface.geometric_normal
        );
    }
}

/// The largest principal curvature's magnitude of `patch` at (u, v) (first and second
/// fundamental forms, in f64).
fn largest_curvature(patch: &BezierPatch, u: f32, v: f32) -> f64 {
    let p = patch.evaluate(f64::from(u), f64::from(v));
    let n = p.dpdu.cross(p.dpdv).normalize();
    let (e, f, g) = (p.dpdu.dot(p.dpdu), p.dpdu.dot(p.dpdv), p.dpdv.dot(p.dpdv));
    let (l, m, nn) = (p.d2pdu2.dot(n), p.d2pdudv.dot(n), p.d2pdv2.dot(n));
    let det = e * g - f * f;
    let gauss = (l * nn - m * m) / det;
    let mean = (e * nn - 2.0 * f * m + g * l) / (2.0 * det);
    mean.abs() + (mean * mean - gauss).max(0.0).sqrt()
}

/// Rays leave hits on the teapot to both sides at angles from 1e-4 to 90 degrees. A ray
/// leaving a surface that bends towards it at angle theta meets it again after a chord of at
/// least `2 sin(theta) / k_max` (k_max the largest principal curvature) near where it left;
/// a hit near the start (within 1e-4, a thousand times the spawn offset) and closer than
/// half that chord is the ray meeting the point it left. Hits farther away are other parts
/// of the teapot (the knob's overhang, the body seen from inside).
#[test]
fn rays_leaving_the_surface_do_not_meet_it_again_there() {
    let t = traced(TEAPOT);
    let rays = camera_rays();
    let hits = t.trace(&rays, false);
    let mut rng = Rng(0x7EA_9075);
    let mut leaving = Vec::new();
    for (r, hit) in rays.iter().zip(&hits).filter(|(_, h)| h.is_hit()) {
        let surface = t
            .lookup
            .surface_hit(r.origin, r.direction, hit, SurfaceDetail::Geometry);
        let spawn = surface.spawn_point();
        let n = surface.geometric_normal;
        for side in [n, -n] {
            for cosine in [1e-4f32, 1e-3, 1e-2, 0.1, 0.5, 1.0] {
                let tangent =
                    (rng.direction().cross(side)).normalize_or(side.any_orthonormal_vector());
                let direction =
                    (side * cosine + tangent * (1.0 - cosine * cosine).sqrt()).normalize();
                if direction.dot(side) <= 0.0 {
                    continue;
                }
                let patch = t.patch(hit).expect("a patch hit");
                let k_max = largest_curvature(patch, hit.u, hit.v);
                let shortest_chord = 2.0 * f64::from(cosine) / k_max;
                leaving.push((
                    ray(spawn.offset_origin(side), direction),
                    surface.position,
                    shortest_chord,
                ));
            }
        }
    }
    let rays: Vec<TraceRay> = leaving.iter().map(|(r, _, _)| *r).collect();
    let hits = t.trace(&rays, false);
    let mut self_hits = Vec::new();
    let mut closest_ratio = f64::INFINITY;
    for ((r, start, shortest_chord), hit) in leaving.iter().zip(&hits) {
        if !hit.is_hit() {
            continue;
        }
        assert!(hit.t.is_finite() && hit.u.is_finite() && hit.v.is_finite());
        let point = r.origin + r.direction * hit.t;
        let distance = f64::from((point - *start).length());
        if distance >= 1e-4 {
            continue;
        }
        closest_ratio = closest_ratio.min(distance / shortest_chord);
        if distance < 0.5 * shortest_chord {
            self_hits.push(format!(
                "{r:?} hit t = {} at distance {distance} (shortest chord {shortest_chord})",
                hit.t
            ));
        }
    }
    eprintln!(
        "{} rays left the teapot; {} met it again within 1e-4 and half the shortest chord; \
         closest re-hit within 1e-4 at {closest_ratio} of the shortest chord",
        rays.len(),
        self_hits.len()
    );
    assert!(rays.len() > 2000);
    assert!(
        self_hits.is_empty(),
        "{} self-intersections, e.g. {}",
        self_hits.len(),
        self_hits[0]
    );
}

#[test]
fn scenes_without_patches_have_no_user_geometry() {
    let t = traced("[[sphere]]\ncenter = [0, 0, 0]\nradius = 1\n");
    assert!(!t.lookup.geometries.contains(&GeometryRef::Patches));
    let with = traced(TEAPOT);
    assert_eq!(with.lookup.geometries, vec![GeometryRef::Patches]);
}

/// A user geometry of one plane square `z = 0, |x|, |y| <= 1` (u, v = x, y), or one that
/// panics in `intersect`.
struct Square {
    panics: bool,
}

impl conetrace::embree::UserGeometry for Square {
    fn primitive_count(&self) -> u32 {
        1
    }
    fn bounds(&self, _: u32) -> conetrace::embree::Bounds {
        conetrace::embree::Bounds {
            lower: Vec3::new(-1.0, -1.0, 0.0),
            upper: Vec3::new(1.0, 1.0, 0.0),
        }
    }
    fn intersect(
        &self,
        _: u32,
        ray: &conetrace::embree::UserRay,
        _: bool,
    ) -> Option<conetrace::embree::UserHit> {
        assert!(!self.panics, "a user geometry that panics");
        let t = -ray.origin.z / ray.direction.z;
        let p = ray.origin + ray.direction * t;
        (t > ray.tnear && t < ray.tfar && p.x.abs() <= 1.0 && p.y.abs() <= 1.0).then_some(
            conetrace::embree::UserHit {
                t,
                u: p.x,
                v: p.y,
                normal: Vec3::Z,
            },
        )
    }
}

/// Every lane of a 16-wide packet gets its own answer from the Rust callback (invalid lanes
/// none), the same as single rays and as occlusion; a panic in the callback is caught and
/// returned as an error, never unwinding into Embree.
#[test]
fn user_geometry_lanes_and_panics() {
    use conetrace::embree::{Device, EmbreeError, Ray, RayPacket, SceneBuilder, TraceOptions};
    let device = Device::new().expect("device");
    let build = |panics: bool| {
        let mut builder = SceneBuilder::new(&device).expect("builder");
        builder
            .add_user_geometry(Arc::new(Square { panics }))
            .expect("user geometry");
        builder.commit().expect("commit")
    };
    let scene = build(false);
    let mut packet = RayPacket::<16>::new();
    let mut shadow = RayPacket::<16>::new();
    let lane_ray = |lane: usize| {
        let x = -1.5 + 3.0 * lane as f32 / 15.0; // lanes beyond |x| = 1 miss
        Ray::new(Vec3::new(x, 0.25, 2.0), Vec3::NEG_Z)
    };
    for lane in 0..16 {
        if lane % 5 == 4 {
            continue; // left invalid
        }
        packet.set_ray(lane, &lane_ray(lane));
        shadow.set_ray(lane, &lane_ray(lane));
    }
    scene
        .intersect_tile(&mut packet, TraceOptions::coherent())
        .expect("packet trace");
    scene
        .occluded_tile(&mut shadow, TraceOptions::coherent())
        .expect("occlusion trace");
    for lane in 0..16 {
        let single = scene
            .intersect1(&lane_ray(lane), TraceOptions::incoherent())
            .expect("single trace");
        if lane % 5 == 4 {
            assert!(packet.hit(lane).is_none(), "invalid lane {lane} was traced");
            continue;
        }
        assert_eq!(packet.hit(lane).is_some(), single.is_some(), "lane {lane}");
        assert_eq!(shadow.is_occluded(lane), single.is_some(), "lane {lane}");
        if let (Some(a), Some(b)) = (packet.hit(lane), single) {
            assert!(
                (a.t - 2.0).abs() < 1e-6 && a.t == b.t && a.u == b.u,
                "lane {lane}"
            );
            assert!((a.v - 0.25).abs() < 1e-6);
        }
    }
    let panicking = build(true);
    let mut packet = RayPacket::<16>::new();
    packet.set_ray(3, &lane_ray(7));
    match panicking.intersect_tile(&mut packet, TraceOptions::coherent()) {
        Err(EmbreeError::FilterPanicked { message, .. }) => {
            assert!(message.contains("panics"), "{message}")
        }
        other => panic!("a panicking callback gave {other:?}"),
    }
    assert!(packet.hit(3).is_none());
    assert!(panicking
        .intersect1(&lane_ray(7), TraceOptions::incoherent())
        .is_err());
}
