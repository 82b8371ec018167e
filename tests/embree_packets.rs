//! Whole-layer checks of `conetrace::embree`: single rays, 16/8/4-wide packets, tiles and
//! streams agree hit for hit; tfar limits, occlusion, validity masks, spheres, alpha filters
//! (including a panicking one), Embree errors and the denormal bits.

mod common;

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use common::Rng;
use conetrace::embree::{
    enable_flush_denormals, flush_denormals_enabled, CommittedScene, Device, EmbreeError,
    FilterCandidate, Hit, Ray, RayHit, RayPacket, RayPayload, SceneBuilder, TraceOptions,
    INVALID_GEOMETRY_ID,
};
use glam::Vec3;

/// Random triangles in [-10, 10]^3 (geometry 0) and a few spheres (geometry 1).
fn random_scene(device: &Device, triangles: usize) -> CommittedScene {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let mut vertices = Vec::with_capacity(triangles * 3);
    let mut indices = Vec::with_capacity(triangles);
    for t in 0..triangles {
        let c = rng.vec(-10.0, 10.0);
        for _ in 0..3 {
            vertices.push(c + rng.vec(-1.0, 1.0));
        }
        let b = 3 * t as u32;
        indices.push([b, b + 1, b + 2]);
    }
    let spheres: Vec<(Vec3, f32)> = (0..20)
        .map(|_| (rng.vec(-8.0, 8.0), rng.range(0.3, 1.5)))
        .collect();
    let mut builder = SceneBuilder::new(device).expect("scene builder");
    assert_eq!(
        builder
            .add_triangle_mesh(&vertices, &indices)
            .expect("mesh"),
        0
    );
    assert_eq!(builder.add_spheres(&spheres).expect("spheres"), 1);
    builder.commit().expect("commit")
}

/// Rays from around the scene; every 7th points away from it (a guaranteed miss).
fn random_rays(count: usize) -> Vec<Ray> {
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    (0..count)
        .map(|i| {
            let origin = rng.vec(-14.0, 14.0);
            let direction = if i % 7 == 0 {
                // Away from the scene box [-11, 11]^3 from outside it.
                let o = Vec3::new(
                    20.0 + rng.range(0.0, 5.0),
                    rng.range(-5.0, 5.0),
                    rng.range(-5.0, 5.0),
                );
                return Ray::new(o, (Vec3::X + 0.1 * rng.direction()).normalize());
            } else {
                rng.direction()
            };
            Ray::new(origin, direction)
        })
        .collect()
}

fn assert_same_hit(reference: Option<Hit>, other: Option<Hit>, what: &str, index: usize) {
    match (reference, other) {
        (None, None) => {}
        (Some(a), Some(b)) => {
            assert_eq!(a.geom_id, b.geom_id, "{what}: ray {index} geom");
            assert_eq!(a.prim_id, b.prim_id, "{what}: ray {index} prim");
            assert!(
                (a.t - b.t).abs() <= 1e-5 * a.t.abs().max(1e-3),
                "{what}: ray {index} t {} vs {}",
                a.t,
                b.t
            );
            assert!(
                (a.u - b.u).abs() <= 1e-4 && (a.v - b.v).abs() <= 1e-4,
                "{what}: ray {index} uv"
            );
            let ng_scale = a.ng.length().max(1e-6);
            assert!(
                (a.ng - b.ng).length() <= 1e-4 * ng_scale,
                "{what}: ray {index} Ng"
            );
        }
        _ => panic!("{what}: ray {index}: {reference:?} vs {other:?}"),
    }
}

fn single_hits(scene: &CommittedScene, rays: &[Ray]) -> Vec<Option<Hit>> {
    rays.iter()
        .map(|r| {
            scene
                .intersect1(r, TraceOptions::incoherent())
                .expect("intersect1")
        })
        .collect()
}

fn packet_hits<const N: usize>(
    scene: &CommittedScene,
    rays: &[Ray],
    tile: bool,
) -> Vec<Option<Hit>> {
    let mut out = Vec::with_capacity(rays.len());
    for chunk in rays.chunks(N) {
        let mut packet = RayPacket::<N>::new();
        for (lane, ray) in chunk.iter().enumerate() {
            packet.set_ray(lane, ray);
        }
        if tile {
            // Only called with N == 16.
            let p16: &mut RayPacket<16> = (&mut packet as &mut dyn std::any::Any)
                .downcast_mut()
                .expect("tiles are 16 wide");
            scene
                .intersect_tile(p16, TraceOptions::coherent())
                .expect("tile");
        } else {
            scene
                .intersect_packet(&mut packet, TraceOptions::incoherent())
                .expect("packet");
        }
        for lane in 0..chunk.len() {
            out.push(packet.hit(lane));
        }
    }
    out
}

#[test]
fn single_packet_and_stream_traces_agree() {
    let device = Device::new().expect("device");
    let scene = random_scene(&device, 3000);
    let rays = random_rays(10_000);
    let reference = single_hits(&scene, &rays);
    let hits = reference.iter().filter(|h| h.is_some()).count();
    assert!(
        hits > 2000 && hits < 9000,
        "a mix of hits and misses, got {hits}"
    );
    for (i, r) in rays.iter().enumerate() {
        if i % 7 == 0 {
            assert!(
                reference[i].is_none(),
                "ray {i} points away from the scene: {r:?}"
            );
        }
    }

    let p16 = packet_hits::<16>(&scene, &rays, false);
    let p8 = packet_hits::<8>(&scene, &rays, false);
    let p4 = packet_hits::<4>(&scene, &rays, false);
    let tile = packet_hits::<16>(&scene, &rays, true);
    let mut stream: Vec<RayHit> = rays.iter().map(RayHit::new).collect();
    scene
        .intersect_stream(&mut stream, TraceOptions::incoherent())
        .expect("stream");
    for i in 0..rays.len() {
        assert_same_hit(reference[i], p16[i], "16-wide", i);
        assert_same_hit(reference[i], p8[i], "8-wide", i);
        assert_same_hit(reference[i], p4[i], "4-wide", i);
        assert_same_hit(reference[i], tile[i], "tile", i);
        assert_same_hit(reference[i], stream[i].hit(), "stream", i);
        if reference[i].is_none() {
            assert_eq!(stream[i].geom_id(), INVALID_GEOMETRY_ID);
        }
    }
}

#[test]
fn tiles_split_to_the_native_width_of_narrower_devices() {
    let rays = random_rays(2_000);
    for (config, width) in [("isa=sse4.2", 4), ("isa=avx2", 8)] {
        let device = Device::with_config(config).expect("device");
        assert_eq!(device.packet_width(), width, "{config}");
        let scene = random_scene(&device, 1000);
        assert_eq!(scene.packet_width(), width);
        let reference = single_hits(&scene, &rays);
        let tile = packet_hits::<16>(&scene, &rays, true);
        for i in 0..rays.len() {
            assert_same_hit(reference[i], tile[i], config, i);
        }
    }
}

#[test]
fn occlusion_agrees_with_intersect_and_tfar_is_respected() {
    let device = Device::new().expect("device");
    let scene = random_scene(&device, 3000);
    let rays = random_rays(2_000);
    let reference = single_hits(&scene, &rays);

    // Occlusion over the full segment agrees with intersect, in all paths.
    let mut stream: Vec<RayHit> = rays.iter().map(RayHit::new).collect();
    scene
        .occluded_stream(&mut stream, TraceOptions::incoherent())
        .expect("occluded stream");
    for (chunk_index, chunk) in rays.chunks(16).enumerate() {
        let mut packet = RayPacket::<16>::new();
        for (lane, ray) in chunk.iter().enumerate() {
            packet.set_ray(lane, ray);
        }
        scene
            .occluded16(&mut packet, TraceOptions::incoherent())
            .expect("occluded16");
        for lane in 0..chunk.len() {
            let i = chunk_index * 16 + lane;
            let blocked = reference[i].is_some();
            assert_eq!(packet.is_occluded(lane), blocked, "occluded16 ray {i}");
            assert_eq!(stream[i].is_occluded(), blocked, "occluded stream ray {i}");
            assert_eq!(
                scene
                    .occluded1(&rays[i], TraceOptions::incoherent())
                    .expect("occluded1"),
                blocked
            );
        }
    }

    // A hit just beyond tfar is not reported; just within, it is.
    let mut checked = 0;
    for (i, hit) in reference.iter().enumerate() {
        let Some(hit) = hit else { continue };
        let short = Ray {
            tfar: hit.t * 0.999,
            ..rays[i]
        };
        let long = Ray {
            tfar: hit.t * 1.001,
            ..rays[i]
        };
        assert!(scene
            .intersect1(&short, TraceOptions::incoherent())
            .expect("short")
            .is_none());
        assert!(!scene
            .occluded1(&short, TraceOptions::incoherent())
            .expect("short occluded"));
        assert!(scene
            .occluded1(&long, TraceOptions::incoherent())
            .expect("long occluded"));
        let mut packet = RayPacket::<8>::new();
        packet.set_ray(0, &short);
        packet.set_ray(1, &long);
        scene
            .intersect8(&mut packet, TraceOptions::incoherent())
            .expect("intersect8");
        assert!(packet.hit(0).is_none(), "ray {i}: hit beyond tfar reported");
        assert_eq!(packet.tfar(0), short.tfar, "a miss leaves tfar unchanged");
        assert_eq!(packet.hit(1).map(|h| h.prim_id), Some(hit.prim_id));
        let mut packet = RayPacket::<4>::new();
        packet.set_ray(2, &short);
        packet.set_ray(3, &long);
        scene
            .occluded4(&mut packet, TraceOptions::incoherent())
            .expect("occluded4");
        assert!(!packet.is_occluded(2) && packet.is_occluded(3));
        checked += 1;
    }
    assert!(checked > 500);
}

#[test]
fn invalid_lanes_are_left_untouched() {
    let device = Device::new().expect("device");
    let scene = random_scene(&device, 3000);
    let rays = random_rays(16 * 50);
    let reference = single_hits(&scene, &rays);
    for (chunk_index, chunk) in rays.chunks(16).enumerate() {
        for occlusion in [false, true] {
            let mut packet = RayPacket::<16>::new();
            for (lane, ray) in chunk.iter().enumerate() {
                packet.set_ray(lane, ray);
                // A pattern that changes per chunk; invalid lanes keep their ray and "no hit".
                if (lane + chunk_index) % 3 == 0 {
                    packet.set_valid(lane, false);
                }
            }
            let before = packet.clone();
            if occlusion {
                scene
                    .occluded_tile(&mut packet, TraceOptions::coherent())
                    .expect("occluded tile");
            } else {
                scene
                    .intersect_tile(&mut packet, TraceOptions::coherent())
                    .expect("tile");
            }
            for lane in 0..16 {
                let i = chunk_index * 16 + lane;
                if packet.is_valid(lane) {
                    if occlusion {
                        assert_eq!(packet.is_occluded(lane), reference[i].is_some());
                    } else {
                        assert_same_hit(reference[i], packet.hit(lane), "partial packet", i);
                    }
                } else {
                    assert_eq!(
                        packet.ray(lane),
                        before.ray(lane),
                        "invalid lane {lane} ray changed"
                    );
                    assert_eq!(packet.geom_id(lane), INVALID_GEOMETRY_ID);
                    assert!(packet.hit(lane).is_none());
                }
            }
        }
    }
}

#[test]
fn sphere_hit_distance_is_distance_minus_radius() {
    let device = Device::new().expect("device");
    let mut builder = SceneBuilder::new(&device).expect("builder");
    let center = Vec3::new(1.0, 2.0, -3.0);
    let radius = 1.25;
    let id = builder.add_spheres(&[(center, radius)]).expect("sphere");
    let scene = builder.commit().expect("commit");
    let bounds = scene.bounds();
    assert!(
        (bounds.lower - (center - Vec3::splat(radius)))
            .abs()
            .max_element()
            < 1e-4
    );
    assert!(
        (bounds.upper - (center + Vec3::splat(radius)))
            .abs()
            .max_element()
            < 1e-4
    );
    let mut packet = RayPacket::<16>::new();
    let mut rng = Rng(42);
    let mut expected = Vec::new();
    for lane in 0..16 {
        let distance = rng.range(3.0, 40.0);
        let origin = center - rng.direction() * distance;
        let ray = Ray::new(origin, (center - origin).normalize());
        packet.set_ray(lane, &ray);
        let hit = scene
            .intersect1(&ray, TraceOptions::incoherent())
            .expect("intersect1")
            .expect("a hit");
        assert_eq!(hit.geom_id, id);
        assert_eq!(hit.prim_id, 0);
        assert!(
            (hit.t - (distance - radius)).abs() < 1e-4 * distance,
            "t {} vs {}",
            hit.t,
            distance - radius
        );
        // Embree's sphere normal points outward, towards the ray origin here.
        assert!(hit.ng.normalize().dot(-ray.direction) > 0.999);
        expected.push(distance - radius);
    }
    scene
        .intersect16(&mut packet, TraceOptions::coherent())
        .expect("intersect16");
    for (lane, want) in expected.iter().enumerate() {
        let hit = packet.hit(lane).expect("packet hit");
        assert!((hit.t - want).abs() < 1e-4 * want.max(1.0));
    }
}

#[test]
fn triangle_normal_and_barycentrics_follow_embree() {
    let device = Device::new().expect("device");
    let mut builder = SceneBuilder::new(&device).expect("builder");
    let p = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    builder.add_triangle_mesh(&p, &[[0, 1, 2]]).expect("mesh");
    assert!(matches!(
        builder.add_triangle_mesh(&p, &[[0, 1, 3]]),
        Err(EmbreeError::IndexOutOfRange { index: 3, .. })
    ));
    assert!(matches!(
        builder.add_triangle_mesh(&p, &[]),
        Err(EmbreeError::BadPrimitiveCount { .. })
    ));
    let scene = builder.commit().expect("commit");
    assert_eq!(scene.geometry_count(), 1);
    let hit = scene
        .intersect1(
            &Ray::new(Vec3::new(0.25, 0.5, 2.0), -Vec3::Z),
            TraceOptions::coherent(),
        )
        .expect("trace")
        .expect("hit");
    assert!((hit.t - 2.0).abs() < 1e-6);
    assert!((hit.u - 0.25).abs() < 1e-6 && (hit.v - 0.5).abs() < 1e-6);
    let ng = (p[1] - p[0]).cross(p[2] - p[0]);
    assert!((hit.ng - ng).length() < 1e-6, "Ng {:?} vs {:?}", hit.ng, ng);
}

/// Two parallel unit quads: a front one at z = 0 (prims 0 and 1, geometry 0) and a back one
/// at z = -1 (geometry 1). Rays go down -z from z = 1.
fn two_quads(filter: Option<conetrace::embree::AlphaFilter>) -> CommittedScene {
    two_quads_on(&Device::new().expect("device"), filter)
}

/// [`two_quads`] on `device`.
fn two_quads_on(device: &Device, filter: Option<conetrace::embree::AlphaFilter>) -> CommittedScene {
    let mut builder = SceneBuilder::new(device).expect("builder");
    let quad = |z: f32| {
        vec![
            Vec3::new(0.0, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(0.0, 1.0, z),
        ]
    };
    // prim 0 covers x > y, prim 1 covers x < y.
    let front = builder
        .add_triangle_mesh(&quad(0.0), &[[0, 1, 2], [0, 2, 3]])
        .expect("front");
    builder
        .add_triangle_mesh(&quad(-1.0), &[[0, 1, 2], [0, 2, 3]])
        .expect("back");
    if let Some(filter) = filter {
        builder.set_alpha_filter(front, filter).expect("filter");
    }
    assert!(matches!(
        builder.set_alpha_filter(7, Arc::new(|_: &FilterCandidate| true)),
        Err(EmbreeError::UnknownGeometry { geom_id: 7 })
    ));
    builder.commit().expect("commit")
}

/// Lane i's ray: over prim 0 for even i, prim 1 for odd i.
fn quad_ray(i: usize) -> Ray {
    let s = 0.05 + 0.9 * (i as f32 + 0.5) / 64.0;
    let (x, y) = if i.is_multiple_of(2) {
        (0.9, s.min(0.85))
    } else {
        (s.min(0.85), 0.9)
    };
    Ray::new(Vec3::new(x, y, 1.0), -Vec3::Z)
}

/// Traces lanes 0..16 through every path; returns, per path, the (geom_id, prim_id) per lane.
fn filtered_hits(scene: &CommittedScene, payload: &[RayPayload]) -> Vec<(String, Vec<(u32, u32)>)> {
    let rays: Vec<Ray> = (0..16).map(quad_ray).collect();
    let id = |h: Option<Hit>| h.map_or((INVALID_GEOMETRY_ID, 0), |h| (h.geom_id, h.prim_id));
    let mut out = Vec::new();

    let single: Vec<_> = rays
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let opts = TraceOptions::incoherent().with_payload(&payload[i..i + 1]);
            id(scene.intersect1(r, opts).expect("single"))
        })
        .collect();
    out.push(("single".to_string(), single));

    let mut p16 = RayPacket::<16>::new();
    rays.iter().enumerate().for_each(|(l, r)| p16.set_ray(l, r));
    scene
        .intersect16(&mut p16, TraceOptions::coherent().with_payload(payload))
        .expect("16");
    out.push(("16".to_string(), (0..16).map(|l| id(p16.hit(l))).collect()));

    let mut tile = RayPacket::<16>::new();
    rays.iter()
        .enumerate()
        .for_each(|(l, r)| tile.set_ray(l, r));
    scene
        .intersect_tile(&mut tile, TraceOptions::coherent().with_payload(payload))
        .expect("tile");
    out.push((
        "tile".to_string(),
        (0..16).map(|l| id(tile.hit(l))).collect(),
    ));

    let mut v8 = Vec::new();
    for half in 0..2 {
        let mut p8 = RayPacket::<8>::new();
        (0..8).for_each(|l| p8.set_ray(l, &rays[half * 8 + l]));
        let opts = TraceOptions::coherent().with_payload(&payload[half * 8..half * 8 + 8]);
        scene.intersect8(&mut p8, opts).expect("8");
        v8.extend((0..8).map(|l| id(p8.hit(l))));
    }
    out.push(("8".to_string(), v8));

    let mut v4 = Vec::new();
    for quarter in 0..4 {
        let mut p4 = RayPacket::<4>::new();
        (0..4).for_each(|l| p4.set_ray(l, &rays[quarter * 4 + l]));
        let opts = TraceOptions::coherent().with_payload(&payload[quarter * 4..quarter * 4 + 4]);
        scene.intersect4(&mut p4, opts).expect("4");
        v4.extend((0..4).map(|l| id(p4.hit(l))));
    }
    out.push(("4".to_string(), v4));

    let mut stream: Vec<RayHit> = rays.iter().map(RayHit::new).collect();
    scene
        .intersect_stream(
            &mut stream,
            TraceOptions::incoherent().with_payload(payload),
        )
        .expect("stream");
    out.push((
        "stream".to_string(),
        stream.iter().map(|r| id(r.hit())).collect(),
    ));
    out
}

#[test]
fn alpha_filter_rejecting_prim_zero_lets_rays_through_in_every_path() {
    let calls = Arc::new(AtomicUsize::new(0));
    let seen = calls.clone();
    let scene = two_quads(Some(Arc::new(move |c: &FilterCandidate| {
        seen.fetch_add(1, Ordering::Relaxed);
        assert!(
            c.t > 0.99 && c.t < 1.01,
            "the candidate on the front quad is at t = 1"
        );
        assert_eq!(c.geom_id, 0);
        c.prim_id != 0
    })));
    assert!(scene.has_alpha_filter(0) && !scene.has_alpha_filter(1));
    let payload = vec![RayPayload::default(); 16];
    for (path, hits) in filtered_hits(&scene, &payload) {
        for (lane, &(geom, prim)) in hits.iter().enumerate() {
            if lane % 2 == 0 {
                assert_eq!(
                    (geom, prim),
                    (1, 0),
                    "{path}: lane {lane} passes prim 0 to the back quad"
                );
            } else {
                assert_eq!(
                    (geom, prim),
                    (0, 1),
                    "{path}: lane {lane} stops on front prim 1"
                );
            }
        }
    }
    assert!(calls.load(Ordering::Relaxed) >= 6 * 16);

    // Shadow rays: through prim 0 only the back quad blocks; with tfar before it, nothing does.
    for i in 0..16 {
        let short = Ray {
            tfar: 1.5,
            ..quad_ray(i)
        };
        let blocked = scene
            .occluded1(&short, TraceOptions::incoherent())
            .expect("occluded1");
        assert_eq!(blocked, i % 2 == 1, "lane {i}");
    }
    let mut p16 = RayPacket::<16>::new();
    (0..16).for_each(|l| {
        p16.set_ray(
            l,
            &Ray {
                tfar: 1.5,
                ..quad_ray(l)
            },
        )
    });
    scene
        .occluded16(&mut p16, TraceOptions::incoherent())
        .expect("occluded16");
    (0..16).for_each(|l| assert_eq!(p16.is_occluded(l), l % 2 == 1, "occluded16 lane {l}"));
}

#[test]
fn filters_see_each_lanes_payload() {
    // Cut out wherever the ray's cone is wide: lanes with cone_width = lane index (>= 8
    // passes through), for every path.
    let scene = two_quads(Some(Arc::new(|c: &FilterCandidate| {
        assert_eq!(
            c.payload.cone_spread,
            0.5 * c.payload.cone_width,
            "payload of lane {}",
            c.lane
        );
        c.payload.cone_width < 8.0
    })));
    let payload: Vec<RayPayload> = (0..16)
        .map(|i| RayPayload {
            cone_width: i as f32,
            cone_spread: 0.5 * i as f32,
        })
        .collect();
    for (path, hits) in filtered_hits(&scene, &payload) {
        for (lane, &(geom, _)) in hits.iter().enumerate() {
            let expected = if lane < 8 { 0 } else { 1 };
            assert_eq!(geom, expected, "{path}: lane {lane}");
        }
    }
}

/// On the machine's own device, and on devices whose native packets are 8 and 4 lanes wide
/// (a 16-lane packet traced in parts, whose panics add up to the whole packet's count).
#[test]
fn a_panicking_filter_is_reported_and_rejects_the_hit() {
    let native = Device::new().expect("device");
    for (config, device) in [
        ("native", native),
        ("isa=avx2", Device::with_config("isa=avx2").expect("device")),
        (
            "isa=sse4.2",
            Device::with_config("isa=sse4.2").expect("device"),
        ),
    ] {
        eprintln!("{config}: {} lanes", device.packet_width());
        panicking_filter_on(&device);
    }
}

fn panicking_filter_on(device: &Device) {
    let scene = two_quads_on(
        device,
        Some(Arc::new(|c: &FilterCandidate| {
            if c.prim_id == 0 {
                panic!("alpha texture lookup failed");
            }
            true
        })),
    );
    let rays: Vec<Ray> = (0..16).map(quad_ray).collect();

    let err = scene
        .intersect1(&rays[0], TraceOptions::incoherent())
        .unwrap_err();
    assert!(
        matches!(&err, EmbreeError::FilterPanicked { geom_id: 0, message, .. } if message.contains("alpha texture")),
        "{err}"
    );
    assert!(scene
        .intersect1(&rays[1], TraceOptions::incoherent())
        .is_ok());

    let mut p16 = RayPacket::<16>::new();
    rays.iter().enumerate().for_each(|(l, r)| p16.set_ray(l, r));
    let err = scene
        .intersect16(&mut p16, TraceOptions::coherent())
        .unwrap_err();
    match err {
        EmbreeError::FilterPanicked { geom_id, count, .. } => {
            assert_eq!(geom_id, 0);
            assert!(
                count >= 8,
                "one panic per prim-0 lane at least, got {count}"
            );
        }
        other => panic!("unexpected {other}"),
    }
    // Rejected deterministically: the results are complete, prim-0 lanes pass through.
    for lane in 0..16 {
        let hit = p16.hit(lane).expect("every lane hits a quad");
        assert_eq!(hit.geom_id, if lane % 2 == 0 { 1 } else { 0 });
    }

    let mut stream: Vec<RayHit> = rays.iter().map(RayHit::new).collect();
    assert!(scene
        .occluded_stream(&mut stream, TraceOptions::incoherent())
        .is_err());
    assert!(
        stream.iter().all(|r| r.is_occluded()),
        "the back quad still blocks"
    );

    // The scene stays usable afterwards.
    assert!(scene
        .intersect1(&rays[3], TraceOptions::incoherent())
        .expect("ok")
        .is_some());
}

#[test]
fn a_bad_device_config_is_an_embree_error() {
    let err = Device::with_config("threads=not-a-number").unwrap_err();
    assert!(matches!(err, EmbreeError::DeviceCreation { .. }));
    let text = err.to_string();
    assert!(
        text.contains("threads=not-a-number") && text.contains("RTC_ERROR_"),
        "{text}"
    );
}

#[test]
fn committed_scenes_are_shared_across_threads() {
    let device = Device::new().expect("device");
    let scene = Arc::new(random_scene(&device, 2000));
    let rays = Arc::new(random_rays(4000));
    let reference = single_hits(&scene, &rays);
    let handles: Vec<_> = (0..2)
        .map(|t| {
            let scene = Arc::clone(&scene);
            let rays = Arc::clone(&rays);
            std::thread::spawn(move || {
                enable_flush_denormals();
                assert!(flush_denormals_enabled());
                let part = &rays[t * 2000..(t + 1) * 2000];
                packet_hits::<16>(&scene, part, true)
            })
        })
        .collect();
    for (t, h) in handles.into_iter().enumerate() {
        let hits = h.join().expect("thread");
        for (k, hit) in hits.into_iter().enumerate() {
            assert_same_hit(reference[t * 2000 + k], hit, "threaded tile", t * 2000 + k);
        }
    }
    assert!(device.memory_usage() > 0, "Embree reported its allocations");
}

#[test]
fn denormal_bits_are_set_after_enabling() {
    std::thread::spawn(|| {
        enable_flush_denormals();
        assert!(flush_denormals_enabled());
    })
    .join()
    .expect("thread");
}

/// Devices without wide packets or without streams: tiles, packets and streams fall back to
/// narrower packets or single rays and still agree with single-ray traces hit for hit.
#[test]
fn narrower_devices_fall_back_to_packets_they_support_or_single_rays() {
    let native = Device::new().expect("device");
    let rays = random_rays(512);
    for (max_width, streams) in [(1, false), (4, false), (8, true), (1, true)] {
        let device = native.with_traversal_limits(max_width, streams);
        let what = format!("packets <= {max_width}, streams {streams}");
        assert!(device.packet_width() <= max_width.max(1), "{what}");
        let scene = random_scene(&device, 3000);
        assert_eq!(
            scene.stream_supported(),
            streams && native.stream_supported()
        );
        let reference = single_hits(&scene, &rays);
        let tiles = packet_hits::<16>(&scene, &rays, true);
        let sixteen = packet_hits::<16>(&scene, &rays, false);
        let eight = packet_hits::<8>(&scene, &rays, false);
        let mut stream: Vec<RayHit> = rays.iter().map(RayHit::new).collect();
        scene
            .intersect_stream(&mut stream, TraceOptions::incoherent())
            .expect("stream");
        for i in 0..rays.len() {
            assert_same_hit(reference[i], tiles[i], &format!("{what}: tile"), i);
            assert_same_hit(reference[i], sixteen[i], &format!("{what}: 16"), i);
            assert_same_hit(reference[i], eight[i], &format!("{what}: 8"), i);
            assert_same_hit(reference[i], stream[i].hit(), &format!("{what}: stream"), i);
        }
        // Occlusion through every path agrees with intersect.
        let mut shadow: Vec<RayHit> = rays.iter().map(RayHit::new).collect();
        scene
            .occluded_stream(&mut shadow, TraceOptions::incoherent())
            .expect("occluded stream");
        let mut tile = RayPacket::<16>::new();
        for (chunk_index, chunk) in rays.chunks(16).enumerate() {
            chunk
                .iter()
                .enumerate()
                .for_each(|(l, r)| tile.set_ray(l, r));
            scene
                .occluded_tile(&mut tile, TraceOptions::coherent())
                .expect("occluded tile");
            for lane in 0..chunk.len() {
                let i = chunk_index * 16 + lane;
                assert_eq!(
                    tile.is_occluded(lane),
                    reference[i].is_some(),
                    "{what}: tile {i}"
                );
                assert_eq!(
                    shadow[i].is_occluded(),
                    reference[i].is_some(),
                    "{what}: stream {i}"
                );
            }
        }
    }
}

/// Filters see the lane index as ray id on the single-ray fallback too.
#[test]
fn single_ray_fallback_keeps_lane_payloads() {
    let device = Device::new()
        .expect("device")
        .with_traversal_limits(1, false);
    let mut builder = SceneBuilder::new(&device).expect("builder");
    let quad = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let front = builder
        .add_triangle_mesh(&quad, &[[0, 1, 2], [0, 2, 3]])
        .expect("front");
    builder
        .set_alpha_filter(
            front,
            Arc::new(|c: &FilterCandidate| c.payload.cone_width < 8.0),
        )
        .expect("filter");
    let scene = builder.commit().expect("commit");
    let payload: Vec<RayPayload> = (0..16)
        .map(|i| RayPayload {
            cone_width: i as f32,
            cone_spread: 0.0,
        })
        .collect();
    let mut tile = RayPacket::<16>::new();
    (0..16).for_each(|l| tile.set_ray(l, &quad_ray(l)));
    scene
        .intersect_tile(&mut tile, TraceOptions::coherent().with_payload(&payload))
        .expect("tile");
    let mut stream: Vec<RayHit> = (0..16).map(|l| RayHit::new(&quad_ray(l))).collect();
    scene
        .intersect_stream(
            &mut stream,
            TraceOptions::incoherent().with_payload(&payload),
        )
        .expect("stream");
    for (lane, ray_hit) in stream.iter().enumerate() {
        assert_eq!(tile.hit(lane).is_some(), lane < 8, "tile lane {lane}");
        assert_eq!(ray_hit.hit().is_some(), lane < 8, "stream ray {lane}");
    }
}

/// The render's Embree device is limited to the worker pool's thread count (`threads=N`),
/// so BVH builds respect `--threads`; a configuration Embree rejects is an error naming it.
#[test]
fn the_embree_device_gets_the_worker_pool_thread_count() {
    use conetrace::render;
    for threads in [1usize, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let context = pool
            .install(|| render::prepare(Arc::new(quad_scene(None)), render_options()))
            .expect("prepare");
        assert_eq!(
            context.tracer.device().config(),
            format!("threads={threads}")
        );
        assert_eq!(context.tracer.settings().threads, threads);
    }
    assert_eq!(conetrace::embree::thread_config(8), "threads=8");
    let err = Device::with_config("threads=eight").unwrap_err();
    assert!(err.to_string().contains("threads=eight"), "{err}");
}

/// A one-quad scene seen head-on; with `cutout_st`, the quad's material is an alpha cut-out
/// and its texture coordinates are `cutout_st` (a description built in code, unvalidated).
fn quad_scene(cutout_st: Option<Vec<glam::Vec2>>) -> conetrace::scene::SceneDescription {
    use conetrace::scene::*;
    let mut material = Material::default();
    let mut textures = Vec::new();
    let mut st = Vec::new();
    if let Some(cutout_st) = cutout_st {
        material.alpha_cutoff = Some(0.5);
        material.alpha_texture = Some(TextureBinding {
            texture: 0,
            transform: glam::Affine2::IDENTITY,
        });
        textures.push(TextureDesc {
            name: "mask".to_string(),
            source: TextureSource::Encoded {
                label: "mask".to_string(),
                bytes: Arc::new(Vec::new()),
            },
            color_space: Some(ColorSpace::Linear),
            wrap_s: WrapMode::Clamp,
            wrap_t: WrapMode::Clamp,
        });
        st = cutout_st;
    }
    SceneDescription {
        source: "quad in code".to_string(),
        camera: Some(CameraDesc {
            eye: Vec3::new(0.0, 0.0, 3.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection: Projection::Pinhole { vfov_degrees: 30.0 },
        }),
        materials: vec![material],
        textures,
        meshes: vec![TriangleMesh {
            name: "quad".to_string(),
            positions: vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            st,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..TriangleMesh::default()
        }],
        ..SceneDescription::default()
    }
}

fn render_options() -> conetrace::render::RenderOptions {
    conetrace::render::RenderOptions {
        width: 16,
        height: 16,
        spp: 1,
        max_depth: 1,
        min_throughput: 0.0,
        lod: conetrace::footprint::LodStrategy::Cone,
        filter: conetrace::texture::FilterOptions::default(),
        fresnel: conetrace::scene::FresnelMode::Exact,
        aovs: conetrace::film::AovSelection {
            surface: true,
            ..Default::default()
        },
        count_texture_tiles: false,
        all_effects: false,
        seed: 0,
        sample_clamp: None,
    }
}

/// A render whose alpha filter panics (here: a cut-out mesh described in code with one
/// texture coordinate for four vertices, which the filter indexes out of bounds) ends with
/// an error carrying the panic's message, not with an image of misses.
#[test]
fn a_render_whose_alpha_filter_panics_fails_with_the_message() {
    use conetrace::render::{self, RenderControl, RenderError};
    let scene = Arc::new(quad_scene(Some(vec![glam::Vec2::ZERO])));
    let mask = Arc::new(
        conetrace::texture::Texture::from_rgba_f32(2, 2, vec![[1.0; 4]; 4]).expect("mask"),
    );
    let context =
        render::prepare_with_textures(scene, render_options(), vec![mask]).expect("prepare");
    let result = render::render(
        &context,
        &conetrace::integrator::Whitted::default(),
        &RenderControl::default(),
    );
    match result {
        Err(RenderError::Traversal { scene, source }) => {
            assert_eq!(scene, "quad in code");
            assert!(
                matches!(&source, EmbreeError::FilterPanicked { geom_id: 0, message, .. } if message.contains("out of bounds")),
                "{source}"
            );
        }
        Ok(result) => {
            let depth = result
                .film
                .channel("Z")
                .map(|z| z.to_vec())
                .unwrap_or_default();
            let missed = depth.iter().filter(|&&z| z == f32::MAX).count();
            panic!(
                "the render succeeded (complete: {}) with {missed} of {} pixels missed",
                result.stats.complete,
                depth.len()
            );
        }
        Err(other) => panic!("expected a traversal failure, got {other}"),
    }
    // The context renders again (the failure is the render's, not the context's) and fails
    // the same way.
    assert!(render::render(
        &context,
        &conetrace::integrator::Whitted::default(),
        &RenderControl::default()
    )
    .is_err());
}
