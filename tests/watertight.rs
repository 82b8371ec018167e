//! No ray passes between triangles that share an edge: rays aimed exactly at shared edges
//! and vertices of translated, rotated and scaled meshes hit the mesh, through the
//! renderer's tracer (camera rays as packets, secondary rays as streams, shadow rays as
//! occlusion streams, and single rays), and renders of a translated two-triangle quad and a
//! translated grid have no pixel that sees the environment through a shared edge.

mod common;

use std::sync::Arc;

use common::*;
use conetrace::footprint::LodStrategy;
use conetrace::render::stats::WorkCounters;
use conetrace::render::tracer::{TraceHit, TraceRay, Tracer};
use conetrace::render::RenderOptions;
use conetrace::scene::RenderSettings;
use conetrace::scene::{Material, SceneDescription, TriangleMesh};
use glam::{Affine3A, Quat, Vec3};

/// Cells per side of the test grid: (CELLS + 1)^2 vertices, 2 CELLS^2 triangles.
const CELLS: usize = 6;
/// Points per shared edge that rays are aimed at (end points included).
const POINTS_PER_EDGE: usize = 17;

/// A CELLS x CELLS grid of unit cells in the local z = 0 plane, each cell split along its
/// diagonal, mapped by `transform`. Returns the world-space vertices and the triangles.
fn grid_mesh(transform: Affine3A) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let n = CELLS + 1;
    let positions: Vec<Vec3> = (0..n * n)
        .map(|i| transform.transform_point3(Vec3::new((i % n) as f32, (i / n) as f32, 0.0)))
        .collect();
    let mut triangles = Vec::new();
    for y in 0..CELLS {
        for x in 0..CELLS {
            let i = (y * n + x) as u32;
            let (right, up, diagonal) = (i + 1, i + n as u32, i + n as u32 + 1);
            triangles.push([i, right, diagonal]);
            triangles.push([i, diagonal, up]);
        }
    }
    (positions, triangles)
}

/// The points rays are aimed at, in local grid coordinates: POINTS_PER_EDGE points along
/// every edge shared by two triangles (interior horizontal, vertical and diagonal edges),
/// which includes every interior vertex.
fn shared_edge_targets() -> Vec<Vec3> {
    let mut edges: Vec<(Vec3, Vec3)> = Vec::new();
    let c = CELLS as f32;
    for k in 0..CELLS {
        let k = k as f32;
        for j in 1..CELLS {
            let j = j as f32;
            // Interior horizontal and vertical edges.
            edges.push((Vec3::new(k, j, 0.0), Vec3::new(k + 1.0, j, 0.0)));
            edges.push((Vec3::new(j, k, 0.0), Vec3::new(j, k + 1.0, 0.0)));
        }
        for j in 0..CELLS {
            // Every cell's diagonal is shared by its two triangles.
            let j = j as f32;
            edges.push((Vec3::new(k, j, 0.0), Vec3::new(k + 1.0, j + 1.0, 0.0)));
        }
    }
    let mut targets = Vec::new();
    for (a, b) in edges {
        for p in 0..POINTS_PER_EDGE {
            let s = p as f32 / (POINTS_PER_EDGE - 1) as f32;
            let point = a + (b - a) * s;
            // Points on the grid's border are not shared by two triangles.
            let on_border = |v: f32| v <= 0.0 || v >= c;
            if !on_border(point.x) && !on_border(point.y) {
                targets.push(point);
            }
        }
    }
    targets
}

/// The placements of the grid the rays are tested against.
fn placements() -> Vec<(&'static str, Affine3A)> {
    vec![
        ("identity", Affine3A::IDENTITY),
        (
            "translated by (0.3, 0.7, 0)",
            Affine3A::from_translation(Vec3::new(0.3, 0.7, 0.0)),
        ),
        (
            "rotated",
            Affine3A::from_rotation_translation(
                Quat::from_axis_angle(Vec3::new(0.3, -0.5, 0.8).normalize(), 0.7),
                Vec3::new(-1.3, 2.1, 0.45),
            ),
        ),
        (
            "scaled and rotated",
            Affine3A::from_scale_rotation_translation(
                Vec3::new(0.173, 3.7, 1.0),
                Quat::from_rotation_z(-0.3),
                Vec3::new(10.1, -7.3, 2.2),
            ),
        ),
        (
            "far from the origin",
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.01),
                Quat::from_rotation_x(0.2),
                Vec3::new(123.4, -56.7, 89.1),
            ),
        ),
    ]
}

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

/// The renderer's tracer over one grid mesh.
fn tracer_for(transform: Affine3A) -> Tracer {
    let (positions, triangles) = grid_mesh(transform);
    let scene = Arc::new(SceneDescription {
        source: "watertight grid".to_string(),
        materials: vec![Material::default()],
        meshes: vec![TriangleMesh {
            name: "grid".to_string(),
            positions,
            triangles,
            ..TriangleMesh::default()
        }],
        ..SceneDescription::default()
    });
    let (tracer, _) = Tracer::build(&scene, &[], &options()).expect("the grid builds");
    tracer
}

/// Rays towards every shared-edge target from `distance` along `direction_to_origin`
/// (world space, before normalisation), ending `overshoot` past the target.
fn rays_at_targets(transform: Affine3A, direction_to_origin: Vec3, distance: f32) -> Vec<TraceRay> {
    let away = transform.transform_vector3(direction_to_origin).normalize();
    shared_edge_targets()
        .into_iter()
        .map(|local| {
            let target = transform.transform_point3(local);
            TraceRay {
                origin: target + away * distance,
                direction: -away,
                tfar: f32::INFINITY,
                cone_width: 0.0,
                cone_spread: 0.0,
            }
        })
        .collect()
}

/// Misses of each path for one set of rays: (path, misses, rays).
fn misses(tracer: &Tracer, rays: &[TraceRay]) -> Vec<(&'static str, usize)> {
    let mut counters = WorkCounters::default();
    let mut hits: Vec<TraceHit> = Vec::new();
    let mut out = Vec::new();
    tracer.intersect(rays, &mut hits, true, &mut counters);
    out.push((
        "packets (camera rays)",
        hits.iter().filter(|h| !h.is_hit()).count(),
    ));
    tracer.intersect(rays, &mut hits, false, &mut counters);
    out.push((
        "streams (secondary rays)",
        hits.iter().filter(|h| !h.is_hit()).count(),
    ));
    tracer.intersect_one_by_one(rays, &mut hits, &mut counters);
    out.push(("single rays", hits.iter().filter(|h| !h.is_hit()).count()));
    // Shadow rays that end well behind the surface must all be blocked.
    let shadow: Vec<TraceRay> = rays
        .iter()
        .map(|r| {
            let mut ray = *r;
            ray.tfar = 1e6;
            ray
        })
        .collect();
    let mut blocked = Vec::new();
    tracer.occluded(&shadow, &mut blocked, &mut counters);
    out.push((
        "occlusion streams (shadow rays)",
        blocked.iter().filter(|&&b| !b).count(),
    ));
    out
}

#[test]
fn rays_at_shared_edges_and_vertices_never_miss() {
    // Head-on, slightly oblique and grazing-ish views, from both sides of the surface.
    let views = [
        ("head-on", Vec3::Z, 3.0),
        ("head-on from behind", -Vec3::Z, 3.0),
        ("oblique", Vec3::new(0.4, -0.25, 1.0), 5.0),
        ("steep", Vec3::new(-2.0, 1.5, 0.5), 7.0),
        ("from far away", Vec3::new(0.05, 0.1, 1.0), 400.0),
    ];
    let mut failures = Vec::new();
    let mut traced = 0;
    for (placement, transform) in placements() {
        let tracer = tracer_for(transform);
        for (view, direction, distance) in views {
            let rays = rays_at_targets(transform, direction, distance);
            traced += rays.len();
            for (path, missed) in misses(&tracer, &rays) {
                if missed > 0 {
                    failures.push(format!(
                        "{placement}, {view}, {path}: {missed} of {} rays missed",
                        rays.len()
                    ));
                }
            }
        }
    }
    assert!(traced > 10_000, "only {traced} rays per path");
    assert!(
        failures.is_empty(),
        "rays slipped between triangles:\n{}",
        failures.join("\n")
    );
}

/// The two-triangle quad [-1, 1]^2 in an OBJ file; the scene translates it by (0.3, 0.7, 0).
const QUAD_OBJ: &str = "\
v -1 -1 0
v 1 -1 0
v 1 1 0
v -1 1 0
vn 0 0 1
f 1//1 2//1 3//1
f 1//1 3//1 4//1
";

/// A 6x6 grid of cells 1/3 wide over [-1, 1]^2 (each cell split along its diagonal), in an
/// OBJ file.
fn grid_obj() -> String {
    let mut obj = String::new();
    for j in 0..7 {
        for i in 0..7 {
            obj += &format!("v {} {} 0\n", i as f32 / 3.0 - 1.0, j as f32 / 3.0 - 1.0);
        }
    }
    for j in 0..6 {
        for i in 0..6 {
            let a = j * 7 + i + 1;
            obj += &format!("f {a} {} {}\nf {a} {} {}\n", a + 1, a + 8, a + 8, a + 7);
        }
    }
    obj
}

/// A `size` x `size` scene of `quad.obj` translated by (0.3, 0.7, 0) with `camera`.
fn translated_scene(camera: &str, size: u32) -> String {
    format!(
        "[render]\nwidth = {size}\nheight = {size}\n\n{camera}\n\n[environment]\ncolor = [0.2, 0.3, 0.4]\n\n\
         [[material]]\nname = \"grey\"\nbase_color = [0.5, 0.5, 0.5]\n\n\
         [[mesh]]\nfile = \"quad.obj\"\nmaterial = \"grey\"\ntranslate = [0.3, 0.7, 0.0]\n"
    )
}

/// Pixels whose camera ray missed (depth `Z` is `f32::MAX` there) in a `conetrace render` of
/// `scene` with `obj` as `quad.obj`.
fn missed_pixels(obj: &str, scene: &str, size: u32) -> usize {
    let dir = temp_dir();
    write(dir.path(), "quad.obj", obj);
    write(dir.path(), "quad.toml", scene);
    let out = run_in(
        dir.path(),
        &[
            "render",
            "quad.toml",
            "-o",
            "quad.exr",
            "--no-png",
            "--quiet",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = read_exr(&dir.path().join("quad.exr"));
    assert_eq!((image.width, image.height), (size as usize, size as usize));
    image
        .channel("Z")
        .iter()
        .filter(|&&z| z == f32::MAX)
        .count()
}

/// Every view lies inside the mesh, so every camera ray must hit it. The far, narrow view of
/// the translated grid is one where Embree's default (non-watertight) traversal let 3 of the
/// 129x129 camera rays through shared edges.
#[test]
fn renders_of_translated_meshes_show_no_crack() {
    let head_on_pinhole =
        "[camera]\ntype = \"pinhole\"\neye = [0.3, 0.7, 2.0]\ntarget = [0.3, 0.7, 0.0]\nfov = 40";
    let head_on_orthographic = "[camera]\ntype = \"orthographic\"\neye = [0.3, 0.7, 2.0]\n\
                                target = [0.3, 0.7, 0.0]\nheight = 1.5";
    let far_oblique =
        "[camera]\ntype = \"pinhole\"\neye = [20.3, 40.7, 400.0]\ntarget = [0.3, 0.7, 0.0]\nfov = 0.25";
    let grid = grid_obj();
    let cases = [
        (
            "two-triangle quad, head-on pinhole",
            QUAD_OBJ,
            head_on_pinhole,
            64,
        ),
        (
            "two-triangle quad, head-on orthographic",
            QUAD_OBJ,
            head_on_orthographic,
            64,
        ),
        (
            "6x6 grid, head-on orthographic",
            grid.as_str(),
            head_on_orthographic,
            65,
        ),
        (
            "6x6 grid, far oblique pinhole",
            grid.as_str(),
            far_oblique,
            129,
        ),
    ];
    let mut cracks = Vec::new();
    for (what, obj, camera, size) in cases {
        let missed = missed_pixels(obj, &translated_scene(camera, size), size);
        if missed > 0 {
            cracks.push(format!("{what}: {missed} pixels see the environment"));
        }
    }
    assert!(cracks.is_empty(), "{}", cracks.join("\n"));
}
