//! Footprints off a curved mirror patch use its exact curvature: ray cones and ray
//! differentials after reflection and refraction agree with finite differences of
//! neighbouring rays traced to the same patch.
//!
//! The patch is the bicubic Lagrange rectangle through 16 points of a sphere of radius 2
//! (apex at the origin, outward normal +z), so its curvature near the apex is close to 1/2
//! but comes from the patch's own second derivatives, not from the sphere.

mod common;

use std::path::Path;
use std::sync::Arc;

use conetrace::footprint::{curvature_at, LodStrategy, RayCone, RayDifferential};
use conetrace::render::prepared::{SurfaceDetail, SurfaceLookup};
use conetrace::render::stats::WorkCounters;
use conetrace::render::tracer::{TraceRay, Tracer};
use conetrace::render::RenderOptions;
use conetrace::scene::load::load_toml_str;
use conetrace::scene::RenderSettings;
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

struct Mirror {
    tracer: Tracer,
    lookup: SurfaceLookup,
}

fn mirror() -> Mirror {
    let nodes = [-0.6f32, -0.2, 0.2, 0.6];
    let mut points = Vec::new();
    for y in nodes {
        for x in nodes {
            let z = (4.0 - x * x - y * y).sqrt() - 2.0;
            points.push(format!("[{x}, {y}, {z}]"));
        }
    }
    let text = format!(
        "[[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\n\n\
         [[patch]]\nkind = \"lagrange\"\ncontrol_points = [{}]\n",
        points.join(", ")
    );
    let scene = Arc::new(load_toml_str(&text, Path::new("."), "mirror.toml").expect("loads"));
    let (tracer, geometries) = Tracer::build(&scene, &[], &options()).expect("builds");
    Mirror {
        tracer,
        lookup: SurfaceLookup::new(scene, geometries),
    }
}

impl Mirror {
    /// The hit of the ray straight down at (x, y): its surface.
    fn surface(&self, x: f32, y: f32) -> conetrace::hit::SurfaceHit {
        let r = TraceRay {
            origin: Vec3::new(x, y, 5.0),
            direction: Vec3::NEG_Z,
            tfar: f32::INFINITY,
            cone_width: 0.0,
            cone_spread: 0.0,
        };
        let mut hits = Vec::new();
        self.tracer
            .intersect(&[r], &mut hits, false, &mut WorkCounters::default());
        assert!(hits[0].is_hit(), "the ray at ({x}, {y}) misses the mirror");
        self.lookup
            .surface_hit(r.origin, r.direction, &hits[0], SurfaceDetail::Texturing)
    }
}

fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell refraction of unit `d` through unit `n` (facing against `d`), eta = n1 / n2.
fn refract(d: Vec3, n: Vec3, eta: f32) -> Vec3 {
    let c = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - c * c);
    d * eta + n * (eta * c - k.sqrt())
}

/// Signed spread angle between the directions leaving the beam's two edges, `plus` at the
/// edge towards `axis` (positive: diverging), for small angles.
fn spread(plus: Vec3, minus: Vec3, axis: Vec3) -> f32 {
    (plus - minus).dot(axis)
}

#[test]
fn reflected_and_refracted_cones_match_neighbouring_rays() {
    let m = mirror();
    let d = Vec3::NEG_Z;
    let eta = 1.0 / 1.5;
    for (x0, y0) in [(0.0f32, 0.0f32), (0.05, -0.03)] {
        let centre = m.surface(x0, y0);
        let k = curvature_at(&centre, d);
        let h = 1e-3f32; // the beam is 2h wide
        for axis in [Vec3::X, Vec3::Y] {
            let p = m.surface(x0 + axis.x * h, y0 + axis.y * h);
            let q = m.surface(x0 - axis.x * h, y0 - axis.y * h);
            let (np, nq) = (p.geometric_normal, q.geometric_normal);
            let reflected = spread(reflect(d, np), reflect(d, nq), axis);
            let refracted = spread(refract(d, np, eta), refract(d, nq, eta), axis);
            let cone = RayCone::new(2.0 * h, 0.0);
            let cone_reflected = cone.reflect(k).angle;
            let cone_refracted = cone.refract(k, eta).angle;
            eprintln!(
                "at ({x0}, {y0}) along {axis}: k = {k}; reflected cone {cone_reflected:e} vs \
                 rays {reflected:e}; refracted cone {cone_refracted:e} vs rays {refracted:e}"
            );
            // The cone takes the smaller principal curvature, so it may be narrower than
            // the rays along the other principal direction, by their (small) difference.
            assert!(
                (cone_reflected - reflected).abs() < 0.01 * reflected.abs(),
                "reflection: cone {cone_reflected} vs rays {reflected}"
            );
            assert!(
                (cone_refracted - refracted).abs() < 0.01 * refracted.abs(),
                "refraction: cone {cone_refracted} vs rays {refracted}"
            );
        }
    }
}

#[test]
fn reflected_differentials_match_neighbouring_rays() {
    let m = mirror();
    let d = Vec3::NEG_Z;
    for (x0, y0) in [(0.0f32, 0.0f32), (0.3, -0.2), (-0.45, 0.4)] {
        let centre = m.surface(x0, y0);
        // A beam of parallel rays, one unit of x and y per unit of "pixel".
        let differential =
            RayDifferential::new(Vec3::X, Vec3::Y, Vec3::ZERO, Vec3::ZERO).transfer(d, &centre);
        let reflected = reflect(d, centre.shading_normal);
        let after = differential.reflect(d, &centre, reflected);
        let h = 1e-3f32;
        for (axis, dddaxis) in [(Vec3::X, after.dddx), (Vec3::Y, after.dddy)] {
            let p = m.surface(x0 + axis.x * h, y0 + axis.y * h);
            let q = m.surface(x0 - axis.x * h, y0 - axis.y * h);
            let finite =
                (reflect(d, p.geometric_normal) - reflect(d, q.geometric_normal)) / (2.0 * h);
            eprintln!("at ({x0}, {y0}) along {axis}: dD {dddaxis} vs rays {finite}");
            assert!(
                (dddaxis - finite).length() < 1e-2 * finite.length().max(1e-3),
                "dD {dddaxis} vs rays {finite}"
            );
        }
    }
}
