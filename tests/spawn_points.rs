//! Spawn points against the real intersector: a ray leaving a triangle or a sphere from
//! `SpawnPoint::offset_origin` must not meet the surface it leaves, as Embree evaluates it.
//! The error bounds in `conetrace::shading::ray_offset` cover the rounding of the recomputed
//! point; `INTERSECTOR_SLACK` covers Embree's own rounding of the plane or the quadratic.
//! Triangles and spheres of sizes 1e-4 to 1e6, up to 1e4 of their sizes (at most 1e6) from
//! the origin, leaving directions from grazing (|d . n| = 1e-4) to normal.

mod common;

use common::Rng;
use conetrace::embree::{Device, Ray, SceneBuilder, TraceOptions};
use conetrace::shading::SpawnPoint;
use glam::Vec3;

/// A size 10^k for k uniform in [-4, 6].
fn random_scale(rng: &mut Rng) -> f32 {
    10f32.powf(rng.range(-4.0, 6.0))
}

/// A unit direction on the side of `n` with `d . n` close to `cosine` (> 0).
fn leaving(rng: &mut Rng, n: Vec3, cosine: f32) -> Vec3 {
    let tangent =
        (rng.direction() - n * rng.direction().dot(n)).normalize_or(n.any_orthonormal_vector());
    let tangent = (tangent - n * tangent.dot(n)).normalize();
    (n * cosine + tangent * (1.0 - cosine * cosine).max(0.0).sqrt()).normalize()
}

const COSINES: [f32; 6] = [1e-4, 1e-3, 0.01, 0.1, 0.5, 1.0];

#[test]
fn rays_leaving_a_triangle_do_not_meet_it() {
    let device = Device::new().expect("Embree device");
    let mut rng = Rng(0x005E_ED0F_5AA7_1E57);
    let mut failures = Vec::new();
    let mut tested = 0;
    for case in 0..1500 {
        let scale = random_scale(&mut rng);
        let away = (scale * 10f32.powf(rng.range(0.0, 4.0))).min(1e6);
        let center = rng.direction() * away;
        let p = [
            center + rng.vec(-1.0, 1.0) * scale,
            center + rng.vec(-1.0, 1.0) * scale,
            center + rng.vec(-1.0, 1.0) * scale,
        ];
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let longest = (p[1] - p[0])
            .length()
            .max((p[2] - p[0]).length())
            .max((p[2] - p[1]).length());
        let well_shaped = cross.length() > 0.05 * longest * longest;
        if !well_shaped {
            continue; // slivers have ill-conditioned normals in any precision
        }
        let n = cross.normalize();
        let mut builder = SceneBuilder::new(&device).expect("scene builder");
        builder
            .add_triangle_mesh(&p, &[[0, 1, 2]])
            .expect("triangle");
        let scene = builder.commit().expect("commit");
        let (mut u, mut v) = (rng.next_f32(), rng.next_f32());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let spawn = SpawnPoint::on_triangle(p, u, v);
        for cosine in COSINES {
            for side in [n, -n] {
                let direction = leaving(&mut rng, side, cosine);
                if direction.dot(side) <= 0.0 {
                    continue;
                }
                let origin = spawn.offset_origin(side);
                let ray = Ray::new(origin, direction);
                let hit = scene
                    .intersect1(&ray, TraceOptions::incoherent())
                    .expect("intersect1");
                tested += 1;
                if let Some(hit) = hit {
                    failures.push(format!(
                        "case {case}: triangle {p:?} at ({u}, {v}), cosine {cosine}: hit at t = {}",
                        hit.t
                    ));
                }
            }
        }
    }
    println!(
        "{tested} rays leaving triangles, {} met their triangle",
        failures.len()
    );
    assert!(tested > 10_000, "only {tested} rays tested");
    assert!(
        failures.is_empty(),
        "{} self-intersections, first: {:?}",
        failures.len(),
        &failures[..failures.len().min(5)]
    );
}

#[test]
fn rays_leaving_a_sphere_do_not_meet_it_where_they_start() {
    let device = Device::new().expect("Embree device");
    let mut rng = Rng(0x00DD_BA11_5EED_1234);
    let mut failures = Vec::new();
    let mut tested = 0;
    for case in 0..1500 {
        let radius = random_scale(&mut rng);
        let away = (radius * 10f32.powf(rng.range(0.0, 4.0))).min(1e6);
        let center = rng.direction() * away;
        let mut builder = SceneBuilder::new(&device).expect("scene builder");
        builder.add_spheres(&[(center, radius)]).expect("sphere");
        let scene = builder.commit().expect("commit");
        let (spawn, n) = SpawnPoint::on_sphere(center, radius, center + rng.direction() * radius);
        for cosine in COSINES {
            // Outward: nothing to meet on a convex surface.
            let direction = leaving(&mut rng, n, cosine);
            let ray = Ray::new(spawn.offset_origin(n), direction);
            let hit = scene
                .intersect1(&ray, TraceOptions::incoherent())
                .expect("intersect1");
            tested += 1;
            if let Some(hit) = hit {
                failures.push(format!(
                    "case {case}: sphere {center} r {radius}, outward cosine {cosine}: hit at t = {}",
                    hit.t
                ));
            }
            // Inward: the far side, at the chord's length 2 r cos, not near the start.
            // Only where the point's error is small against the chord.
            let error = spawn.error.length();
            let chord = 2.0 * radius * cosine;
            if error > 1e-3 * chord {
                continue;
            }
            let direction = leaving(&mut rng, -n, cosine);
            let ray = Ray::new(spawn.offset_origin(-n), direction);
            let hit = scene
                .intersect1(&ray, TraceOptions::incoherent())
                .expect("intersect1");
            tested += 1;
            match hit {
                Some(hit) if hit.t > 0.5 * chord => {}
                other => failures.push(format!(
                    "case {case}: sphere {center} r {radius}, inward cosine {cosine}: {other:?}, \
                     chord {chord}"
                )),
            }
        }
    }
    println!("{tested} rays leaving spheres, {} failed", failures.len());
    assert!(tested > 5_000, "only {tested} rays tested");
    assert!(
        failures.is_empty(),
        "{} failures, first: {:?}",
        failures.len(),
        &failures[..failures.len().min(5)]
    );
}
