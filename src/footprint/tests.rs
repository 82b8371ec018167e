//! Footprint behaviour end to end: camera initialisation, transfer to real hits, bounces
//! and texture gradients, across strategies.

use glam::{Vec2, Vec3};
use proptest::prelude::*;

use super::*;
use crate::camera::Camera;
use crate::hit::{Patch, SurfaceHit};
use crate::scene::{CameraDesc, Projection};

const W: u32 = 640;
const H: u32 = 480;
const VFOV: f32 = 50.0;

fn pinhole(target_distance: f32) -> Camera {
    let desc = CameraDesc {
        eye: Vec3::ZERO,
        target: Vec3::new(0.0, 0.0, -target_distance),
        up: Vec3::Y,
        projection: Projection::Pinhole { vfov_degrees: VFOV },
    };
    Camera::new(&desc, W, H)
}

/// A hit on the plane through `point` with unit normal `n`, as a large triangle whose st is
/// world position along the plane's axes times `st_scale`.
fn plane_hit(origin: Vec3, dir: Vec3, point: Vec3, n: Vec3, st_scale: f32) -> SurfaceHit {
    let t = (point - origin).dot(n) / dir.dot(n);
    let position = origin + dir * t;
    let (a, b) = n.any_orthonormal_pair();
    let p = [
        point - a * 50.0 - b * 50.0,
        point + a * 50.0 - b * 50.0,
        point + b * 50.0,
    ];
    let st_of = |q: Vec3| Vec2::new((q - point).dot(a), (q - point).dot(b)) * st_scale;
    let st = [st_of(p[0]), st_of(p[1]), st_of(p[2])];
    // Winding so that the geometric normal is n.
    let (p, st) = if (p[1] - p[0]).cross(p[2] - p[0]).dot(n) > 0.0 {
        (p, st)
    } else {
        ([p[0], p[2], p[1]], [st[0], st[2], st[1]])
    };
    SurfaceHit {
        t,
        position,
        geometric_normal: n,
        shading_normal: n,
        barycentric: Vec2::ZERO,
        st: st_of(position),
        dpds: a / st_scale,
        dpdt: b / st_scale,
        material: 0,
        patch: Patch::Triangle {
            p,
            n: None,
            st: Some(st),
        },
    }
}

fn sphere_hit(origin: Vec3, dir: Vec3, center: Vec3, radius: f32) -> Option<SurfaceHit> {
    let oc = origin - center;
    let b = oc.dot(dir);
    let disc = b * b - (oc.length_squared() - radius * radius);
    if disc < 0.0 {
        return None;
    }
    let t = [-b - disc.sqrt(), -b + disc.sqrt()]
        .into_iter()
        .find(|&t| t > 1e-4)?;
    let position = origin + dir * t;
    let n = (position - center) / radius;
    let (st, dpds, dpdt) = lat_long_frame(n, radius);
    Some(SurfaceHit {
        t,
        position,
        geometric_normal: n,
        shading_normal: n,
        barycentric: st,
        st,
        dpds,
        dpdt,
        material: 0,
        patch: Patch::Sphere { center, radius },
    })
}

fn first_hit(
    cam: &Camera,
    strategy: LodStrategy,
    px: f32,
    py: f32,
    hit_of: impl Fn(Vec3, Vec3) -> SurfaceHit,
) -> (Footprint, Vec3, SurfaceHit) {
    let (o, d) = cam.generate_ray(px, py, Vec2::splat(0.5));
    let hit = hit_of(o, d);
    let mut f = cam.initial_footprint(strategy, px, py, o, d);
    f.transfer(d, &hit);
    (f, d, hit)
}

#[test]
fn cone_width_on_a_facing_plane_is_the_projected_pixel() {
    let d = 7.0;
    let pixel_at_d = 2.0 * (VFOV.to_radians() * 0.5).tan() * d / H as f32;
    for target in [1.0, 7.0, 30.0] {
        let cam = pinhole(target);
        for strategy in [LodStrategy::Cone1, LodStrategy::Cone, LodStrategy::Distance] {
            let (f, _, _) = first_hit(&cam, strategy, 320.0, 240.0, |o, dir| {
                plane_hit(o, dir, Vec3::new(0.0, 0.0, -d), Vec3::Z, 1.0)
            });
            let rel = (f.width() - pixel_at_d).abs() / pixel_at_d;
            assert!(
                rel <= 1e-5,
                "{strategy} target {target}: {} vs {pixel_at_d}",
                f.width()
            );
        }
    }
}

#[test]
fn tilted_plane_stretches_the_major_axis_up_to_the_anisotropy_clamp() {
    let cam = pinhole(5.0);
    let d = 5.0;
    let pixel_at_d = 2.0 * (VFOV.to_radians() * 0.5).tan() * d / H as f32;
    let max_aniso = 16.0;
    let scale = 3.0;
    for deg in [0.0f32, 30.0, 60.0, 75.0, 85.0, 88.0, 89.9] {
        let a = deg.to_radians();
        let n = Vec3::new(0.0, a.sin(), a.cos());
        let (f, dir, hit) = first_hit(&cam, LodStrategy::Cone, 320.0, 240.0, |o, dir| {
            plane_hit(o, dir, Vec3::new(0.0, 0.0, -d), n, scale)
        });
        let g = f.texture_gradients(dir, &hit, max_aniso);
        let major = g.ddx().length().max(g.ddy().length());
        let minor = g.ddx().length().min(g.ddy().length());
        let cos = dir.dot(n).abs();
        let expected = pixel_at_d * scale / cos.max(1.0 / max_aniso);
        assert!(
            (major - expected).abs() <= 1e-3 * expected,
            "{deg}: {major} vs {expected}"
        );
        assert!((minor - pixel_at_d * scale).abs() <= 1e-3 * pixel_at_d * scale);
    }
}

#[test]
fn cones_and_differentials_agree_on_first_hits() {
    let cam = pinhole(4.0);
    let pixels = [(320.0, 240.0), (100.5, 50.5), (600.5, 400.5), (320.5, 20.5)];
    let scenes: [&dyn Fn(Vec3, Vec3) -> SurfaceHit; 2] = [
        &|o, dir| plane_hit(o, dir, Vec3::new(0.0, 0.0, -6.0), Vec3::Z, 1.0),
        &|o, dir| {
            sphere_hit(o, dir, Vec3::new(0.0, 0.0, -30.0), 25.0).expect("sphere fills the view")
        },
    ];
    for scene in scenes {
        for &(px, py) in &pixels {
            let (cone, dir, hit) = first_hit(&cam, LodStrategy::Cone, px, py, scene);
            let (diff, _, _) = first_hit(&cam, LodStrategy::Differential, px, py, scene);
            // Compare on the surface: the cone's projected ellipse against the parallelogram.
            let (ex, ey) = project_cone_to_ellipse(cone.width(), dir, hit.geometric_normal, 1.0e6);
            let cone_area = ex.cross(ey).length().sqrt();
            let ratio = cone_area / diff.width();
            assert!(
                (ratio - 1.0).abs() < 0.1,
                "pixel ({px},{py}): cone {cone_area} vs differential {}",
                diff.width()
            );
            // And in texture space.
            let gc = cone.texture_gradients(dir, &hit, 1.0e6);
            let gd = diff.texture_gradients(dir, &hit, 1.0e6);
            let area = |g: TextureGradients| g.ddx().perp_dot(g.ddy()).abs().sqrt();
            assert!(
                (area(gc) / area(gd) - 1.0).abs() < 0.1,
                "st area at ({px},{py})"
            );
        }
    }
}

#[test]
fn differential_texture_gradients_on_a_sphere_match_neighbouring_pixels() {
    let cam = pinhole(4.0);
    let (center, radius) = (Vec3::new(0.3, -0.2, -6.0), 2.0);
    let st_at = |px: f32, py: f32| {
        let (o, d) = cam.generate_ray(px, py, Vec2::ZERO);
        sphere_hit(o, d, center, radius).unwrap().st
    };
    let (px, py) = (350.0, 260.0);
    let (f, dir, hit) = first_hit(&cam, LodStrategy::Differential, px, py, |o, d| {
        sphere_hit(o, d, center, radius).unwrap()
    });
    let g = f.texture_gradients(dir, &hit, 16.0);
    let fd_x = (st_at(px + 0.5, py) - st_at(px - 0.5, py)) / 1.0;
    let fd_y = (st_at(px, py + 0.5) - st_at(px, py - 0.5)) / 1.0;
    assert!(
        (g.ddx() - fd_x).length() <= 1e-2 * fd_x.length(),
        "{:?} vs {fd_x:?}",
        g.ddx()
    );
    assert!(
        (g.ddy() - fd_y).length() <= 1e-2 * fd_y.length(),
        "{:?} vs {fd_y:?}",
        g.ddy()
    );
}

/// A pinhole camera inside a spherical mirror (concave side) or in front of a flat one.
fn mirror_bounce(strategy: LodStrategy, concave: bool, after: f32) -> (Footprint, Footprint) {
    let cam = pinhole(10.0);
    let (px, py) = (330.5, 250.5);
    let (o, d) = cam.generate_ray(px, py, Vec2::ZERO);
    let hit = if concave {
        // Radius 4 around (0,0,-1): the ray from the origin meets the far wall near z = -5.
        sphere_hit(o, d, Vec3::new(0.0, 0.0, -1.0), 4.0).unwrap()
    } else {
        plane_hit(o, d, Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 1.0)
    };
    let mut f = cam.initial_footprint(strategy, px, py, o, d);
    f.transfer(d, &hit);
    let n = if hit.is_front_face(d) {
        hit.shading_normal
    } else {
        -hit.shading_normal
    };
    let r = d - 2.0 * d.dot(n) * n;
    let mut reflected = f.reflect(d, &hit, r);
    let screen = plane_hit(hit.position, r, hit.position + r * after, -r, 1.0);
    let before = reflected;
    reflected.transfer(r, &screen);
    (before, reflected)
}

#[test]
fn concave_mirror_focuses_the_cone_and_the_envelope_keeps_it_open() {
    for strategy in [
        LodStrategy::Cone1,
        LodStrategy::Cone,
        LodStrategy::Differential,
    ] {
        let (_, concave) = mirror_bounce(strategy, true, 1.5);
        let (_, flat) = mirror_bounce(strategy, false, 1.5);
        assert!(
            concave.width() < 0.6 * flat.width(),
            "{strategy}: concave {} flat {}",
            concave.width(),
            flat.width()
        );
    }
    // The distance metric cannot see the curvature.
    let (_, concave) = mirror_bounce(LodStrategy::Distance, true, 1.5);
    let (_, flat) = mirror_bounce(LodStrategy::Distance, false, 1.5);
    assert!((concave.width() - flat.width()).abs() < 1e-3 * flat.width());

    // Find where the single cone collapses to its apex and check the envelope there.
    let (cone1, _) = mirror_bounce(LodStrategy::Cone1, true, 1.0);
    let Footprint::Cone1(c) = cone1 else {
        panic!("cone1 footprint expected")
    };
    assert!(c.angle < 0.0, "the concave mirror makes the cone converge");
    let apex = c.width / -c.angle;
    let (_, at_apex_single) = mirror_bounce(LodStrategy::Cone1, true, apex);
    let (_, at_apex_envelope) = mirror_bounce(LodStrategy::Cone, true, apex);
    assert!(at_apex_single.width() < 1e-3 * c.width);
    assert!(
        at_apex_envelope.width() > 0.05 * c.width,
        "envelope {}",
        at_apex_envelope.width()
    );
    for i in 0..200 {
        let (_, e) = mirror_bounce(LodStrategy::Cone, true, i as f32 * 0.05);
        assert!(e.width() > 0.0);
    }
}

#[test]
fn thin_lens_envelope_is_never_zero_at_the_focal_plane() {
    let desc = CameraDesc {
        eye: Vec3::ZERO,
        target: Vec3::new(0.0, 0.0, -5.0),
        up: Vec3::Y,
        projection: Projection::ThinLens {
            vfov_degrees: VFOV,
            aperture_radius: 0.05,
            focus_distance: 5.0,
        },
    };
    let cam = Camera::new(&desc, W, H);
    let (o, d) = cam.generate_ray(320.0, 240.0, Vec2::new(0.3, 0.8));
    let hit = plane_hit(o, d, Vec3::new(0.0, 0.0, -5.0), Vec3::Z, 1.0);
    let mut single = cam.initial_footprint(LodStrategy::Cone1, 320.0, 240.0, o, d);
    let mut envelope = cam.initial_footprint(LodStrategy::Cone, 320.0, 240.0, o, d);
    single.transfer(d, &hit);
    envelope.transfer(d, &hit);
    let pixel_at_focus = 2.0 * (VFOV.to_radians() * 0.5).tan() * 5.0 / H as f32;
    assert!(single.width() < 1e-2 * pixel_at_focus);
    assert!((envelope.width() - pixel_at_focus).abs() < 2e-2 * pixel_at_focus);
}

#[test]
fn environment_gradients_follow_the_spread() {
    let cam = pinhole(3.0);
    let (o, d) = cam.generate_ray(320.0, 240.0, Vec2::ZERO);
    let cone = cam.initial_footprint(LodStrategy::Cone, 320.0, 240.0, o, d);
    let diff = cam.initial_footprint(LodStrategy::Differential, 320.0, 240.0, o, d);
    let gc = cone.environment_gradients(d);
    let gd = diff.environment_gradients(d);
    // Looking along the equator both see the same angular size per pixel.
    let angle = 2.0 * (VFOV.to_radians() * 0.5).tan() / H as f32;
    assert!((gc.dsdx - angle / std::f32::consts::TAU).abs() < 1e-3 * gc.dsdx);
    assert!(
        (gd.ddx().length() - gc.dsdx).abs() < 1e-2 * gc.dsdx,
        "{gd:?} vs {gc:?}"
    );
    assert!((gd.ddy().length() - gc.dtdy).abs() < 1e-2 * gc.dtdy);
    assert_eq!(
        Footprint::Mip0.environment_gradients(d),
        TextureGradients::ZERO
    );
}

/// Lat-long st change per radian of direction change along `axis` (a unit tangent at `d`),
/// by central differences of the mapping itself.
fn lat_long_rate(d: Vec3, axis: Vec3) -> Vec2 {
    let h = 1.0e-3;
    let ahead = direction_to_lat_long((d + axis * h).normalize());
    let behind = direction_to_lat_long((d - axis * h).normalize());
    (ahead - behind) / (2.0 * h)
}

#[test]
fn environment_cone_gradients_match_the_mapping_towards_the_poles() {
    // A cone of spread alpha around d covers alpha radians across and along the meridian;
    // its extent in the map is alpha times the mapping's rate along those two tangents.
    // Near a pole a circle of latitude is short, so the same angle spans more of s.
    use std::f32::consts::PI;
    let alpha = 2.0e-3;
    let phi = 1.0f32;
    for theta in [0.03f32, 0.1, 0.5, PI / 2.0, PI - 0.2, PI - 0.05] {
        let d = lat_long_to_direction(Vec2::new(phi / std::f32::consts::TAU, theta / PI));
        let east = Vec3::new(-phi.sin(), 0.0, phi.cos());
        let south = Vec3::new(
            theta.cos() * phi.cos(),
            -theta.sin(),
            theta.cos() * phi.sin(),
        );
        let ds = alpha * lat_long_rate(d, east).x;
        let dt = alpha * lat_long_rate(d, south).y;
        for footprint in [
            Footprint::Cone1(RayCone::new(0.0, alpha)),
            Footprint::Distance(DistanceFootprint::new(0.0, alpha)),
        ] {
            let g = footprint.environment_gradients(d);
            eprintln!(
                "theta {theta:.3}: dsdx {:.6} (mapping {ds:.6}), dtdy {:.6} (mapping {dt:.6})",
                g.dsdx, g.dtdy
            );
            assert!(
                (g.dsdx - ds).abs() < 1e-2 * ds,
                "theta {theta}: ds {} vs the mapping's {ds}",
                g.dsdx
            );
            assert!(
                (g.dtdy - dt).abs() < 1e-2 * dt,
                "theta {theta}: dt {} vs {dt}",
                g.dtdy
            );
            assert_eq!((g.dtdx, g.dsdy), (0.0, 0.0));
        }
    }
    // Straight at a pole every azimuth is inside the cone: the whole row, never infinity.
    let at_pole = Footprint::Cone1(RayCone::new(0.0, alpha)).environment_gradients(Vec3::Y);
    assert!(at_pole.is_finite() && at_pole.dsdx == 1.0, "{at_pole:?}");
}

#[test]
fn mip0_is_always_a_point_sample() {
    let cam = pinhole(3.0);
    let (f, dir, hit) = first_hit(&cam, LodStrategy::Mip0, 10.5, 10.5, |o, d| {
        plane_hit(o, d, Vec3::new(0.0, 0.0, -2.0), Vec3::Z, 1.0)
    });
    assert_eq!(f.texture_gradients(dir, &hit, 16.0), TextureGradients::ZERO);
    assert_eq!(f.width(), 0.0);
    assert_eq!(f.cone_at_origin(), (0.0, 0.0));
}

// --- Robustness -------------------------------------------------------------------------

fn finite_vec() -> impl Strategy<Value = Vec3> {
    (-1.0e3f32..1.0e3, -1.0e3f32..1.0e3, -1.0e3f32..1.0e3).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn maybe_degenerate_vec() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        4 => finite_vec(),
        1 => Just(Vec3::ZERO),
        1 => Just(Vec3::splat(f32::NAN)),
        1 => Just(Vec3::new(1.0e-20, 0.0, 0.0)),
    ]
}

fn random_hit() -> impl Strategy<Value = SurfaceHit> {
    let triangle = (
        [finite_vec(), finite_vec(), finite_vec()],
        proptest::option::of([
            maybe_degenerate_vec(),
            maybe_degenerate_vec(),
            maybe_degenerate_vec(),
        ]),
        proptest::option::of(proptest::array::uniform3(
            (-1.0e6f32..1.0e6, -1.0e6f32..1.0e6).prop_map(|(s, t)| Vec2::new(s, t)),
        )),
        prop_oneof![Just(false), Just(true)],
    )
        .prop_map(|(p, n, st, collapse)| {
            // Sometimes make the triangle collinear.
            let p = if collapse {
                [p[0], p[1], p[0] * 2.0 - p[1]]
            } else {
                p
            };
            Patch::Triangle { p, n, st }
        });
    let sphere = (finite_vec(), prop_oneof![0.0f32..1.0e3, Just(0.0)])
        .prop_map(|(center, radius)| Patch::Sphere { center, radius });
    (
        prop_oneof![triangle, sphere],
        0.0f32..1.0e6,
        maybe_degenerate_vec(),
        maybe_degenerate_vec(),
        (0.0f32..1.0, 0.0f32..1.0),
        finite_vec(),
    )
        .prop_map(|(patch, t, ng, ns, (u, v), position)| SurfaceHit {
            t,
            position,
            geometric_normal: ng.normalize_or_zero(),
            shading_normal: ns.normalize_or_zero(),
            barycentric: Vec2::new(u, v),
            st: Vec2::ZERO,
            dpds: Vec3::ZERO,
            dpdt: Vec3::ZERO,
            material: 0,
            patch,
        })
}

fn random_camera() -> impl Strategy<Value = (Camera, f32, f32, Vec2)> {
    let projection = prop_oneof![
        (0.0f32..200.0).prop_map(|v| Projection::Pinhole { vfov_degrees: v }),
        (0.0f32..200.0, -1.0f32..1.0, -10.0f32..100.0).prop_map(|(v, a, f)| Projection::ThinLens {
            vfov_degrees: v,
            aperture_radius: a,
            focus_distance: f
        }),
        (-1.0f32..100.0).prop_map(|h| Projection::Orthographic { height: h }),
    ];
    (
        finite_vec(),
        finite_vec(),
        maybe_degenerate_vec(),
        projection,
        0u32..2000,
        0u32..2000,
        0.0f32..1.0,
        0.0f32..1.0,
        (0.0f32..1.0, 0.0f32..1.0),
    )
        .prop_map(|(eye, target, up, projection, w, h, fx, fy, (lx, ly))| {
            let cam = Camera::new(
                &CameraDesc {
                    eye,
                    target,
                    up,
                    projection,
                },
                w,
                h,
            );
            let (w, h) = cam.resolution();
            (cam, fx * w as f32, fy * h as f32, Vec2::new(lx, ly))
        })
}

fn assert_finite(
    f: &Footprint,
    dir: Vec3,
    hit: &SurfaceHit,
    aniso: f32,
) -> Result<(), TestCaseError> {
    let g = f.texture_gradients(dir, hit, aniso);
    prop_assert!(g.is_finite(), "gradients {g:?} of {f:?}");
    prop_assert!(f.environment_gradients(dir).is_finite());
    prop_assert!(
        f.width().is_finite() && f.width() >= 0.0,
        "width {}",
        f.width()
    );
    let (w, a) = f.cone_at_origin();
    prop_assert!(w.is_finite() && a.is_finite() && w >= 0.0);
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn lod_inputs_stay_finite_for_random_paths(
        (cam, px, py, lens) in random_camera(),
        hits in proptest::collection::vec(random_hit(), 1..5),
        bounces in proptest::collection::vec((any::<bool>(), 0.2f32..3.0), 4),
        aniso in prop_oneof![Just(16.0f32), Just(1.0), Just(0.0), Just(f32::INFINITY), 1.0f32..64.0],
    ) {
        for strategy in LodStrategy::ALL {
            let (o, mut dir) = cam.generate_ray(px, py, lens);
            prop_assert!(o.is_finite() && dir.is_finite());
            let mut f = cam.initial_footprint(strategy, px, py, o, dir);
            for (hit, &(mirror, eta)) in hits.iter().zip(bounces.iter().cycle()) {
                f.transfer(dir, hit);
                assert_finite(&f, dir, hit, aniso)?;
                let n = hit.shading_normal;
                let next = if mirror {
                    (dir - 2.0 * dir.dot(n) * n).normalize_or(Vec3::Z)
                } else {
                    dir
                };
                f = if mirror {
                    f.reflect(dir, hit, next)
                } else {
                    f.refract(dir, hit, eta, next)
                };
                dir = next;
                assert_finite(&f, dir, hit, aniso)?;
            }
        }
    }

    #[test]
    fn envelope_widths_are_never_negative(
        w1 in -1.0f32..1.0, a1 in -1.0f32..1.0, w2 in -1.0f32..1.0, a2 in -1.0f32..1.0,
        steps in proptest::collection::vec((0.0f32..100.0, -10.0f32..10.0, 0.1f32..3.0, any::<bool>()), 1..8),
    ) {
        let mut e = ConeEnvelope::new(RayCone::new(w1, a1), RayCone::new(w2, a2), false);
        for &(d, k, eta, mirror) in &steps {
            e = e.propagate(d);
            prop_assert!(e.width() >= 0.0 && e.primary.width >= 0.0 || e.primary.angle >= 0.0);
            prop_assert!(e.width() >= 0.0);
            e = if mirror { e.reflect(k) } else { e.refract(k, eta) };
            prop_assert!(e.width() >= 0.0 && e.width().is_finite());
        }
    }

    #[test]
    fn grazing_hits_stay_finite(cos in 1.0e-7f32..1.0e-3, w in 0.0f32..10.0) {
        let dir = Vec3::new((1.0 - cos * cos).sqrt(), -cos, 0.0);
        for aniso in [1.0, 16.0, 1.0e6] {
            let (x, y) = project_cone_to_ellipse(w, dir, Vec3::Y, aniso);
            prop_assert!(x.is_finite() && y.is_finite());
            prop_assert!(x.length() <= w * aniso * 1.001 + 1e-6);
        }
        let diff = RayDifferential::from_point(Vec3::NEG_Z, Vec3::X * 1e-3, Vec3::Y * 1e-3).transfer_to(dir, 100.0, Vec3::Y);
        prop_assert!(diff.dpdx.is_finite() && diff.dpdy.is_finite());
    }
}

#[test]
fn propagating_by_distance_is_the_transfer_of_every_footprint_but_differentials() {
    let dir = Vec3::new(0.3, -0.8, -0.52).normalize();
    let hit = plane_hit(Vec3::ZERO, dir, Vec3::new(0.0, -4.0, 0.0), Vec3::Y, 2.0);
    let cone = RayCone::new(0.002, 0.01);
    let footprints = [
        Footprint::Mip0,
        Footprint::Distance(DistanceFootprint::new(0.002, 0.01)),
        Footprint::Cone1(cone),
        Footprint::Cone(ConeEnvelope::new(cone, RayCone::new(0.001, 0.02), false)),
    ];
    for footprint in footprints {
        let mut transferred = footprint;
        transferred.transfer(dir, &hit);
        assert_eq!(
            footprint.propagated(hit.t),
            Some(transferred),
            "{footprint:?}"
        );
    }
    let differential =
        Footprint::Differential(RayDifferential::parallel(Vec3::X * 1e-3, Vec3::Z * 1e-3));
    assert_eq!(differential.propagated(hit.t), None);
}
