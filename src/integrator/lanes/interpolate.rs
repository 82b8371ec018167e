//! Stage 2: what the hits give, over lane arrays, computed as
//! `render::prepared::SurfaceLookup::surface_hit` does: on triangles, from the
//! barycentrics, the point with its rounding error bound, the triangle's edges and normals,
//! the shading normal and the texture coordinates; on spheres, the ray's point projected
//! onto the sphere, its normal, and the lat-long coordinates with dP/ds, dP/dt; and on
//! triangles of normal-mapped materials, dP/ds and dP/dt (their tangent frame).
//!
//! Each triangle loop reads and writes one array per coordinate and has no branch but
//! selects, so it runs 8 or 16 lanes per instruction at the level `simd::dispatch` picks;
//! the operations and their order are the scalar path's, so every level gives its bits.

use std::ops::Range;

use glam::{Vec2, Vec3};

use super::soa::{corner_lanes, corner_lanes_2, normalize_or, select};
use super::{LaneSections, WaveLanes};
use crate::footprint::lat_long_frame;
use crate::render::prepared::triangle_position_derivatives;
use crate::shading::SpawnPoint;
use crate::simd;

/// Interpolate every lane.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn interpolate(lanes: &mut WaveLanes) {
    let len = lanes.len();
    let LaneSections {
        triangles, spheres, ..
    } = lanes.sections();
    for array in [
        &mut lanes.position,
        &mut lanes.error,
        &mut lanes.edge1,
        &mut lanes.edge2,
        &mut lanes.area_normal,
        &mut lanes.geometric_normal,
        &mut lanes.shading_normal,
    ] {
        array.resize(len);
    }
    lanes.st.resize(len);
    simd::run_at(
        lanes.level(),
        #[inline(always)]
        || {
            let triangles = triangles.end;
            spawn_points(lanes, triangles);
            normals(lanes, triangles);
            texture_coordinates(lanes, triangles);
        },
    );
    for array in [&mut lanes.sphere_point, &mut lanes.dpds, &mut lanes.dpdt] {
        array.resize(len);
    }
    triangle_frames(lanes);
    if !spheres.is_empty() {
        simd::run_at(
            lanes.level(),
            #[inline(always)]
            || sphere_points(lanes, spheres.clone()),
        );
        sphere_frames(lanes, spheres);
    }
}

/// The point and the bound on its error (`SpawnPoint::on_triangle`, in double precision).
#[inline(always)]
fn spawn_points(lanes: &mut WaveLanes, len: usize) {
    let p = corner_lanes(&lanes.p, len);
    let (u, v) = (&lanes.u[..len], &lanes.v[..len]);
    let mut position = lanes.position.lanes_mut(len);
    let mut error = lanes.error.lanes_mut(len);
    for lane in 0..len {
        let corners = [p[0].get(lane), p[1].get(lane), p[2].get(lane)];
        let spawn = SpawnPoint::on_triangle(corners, u[lane], v[lane]);
        position.set(lane, spawn.position);
        error.set(lane, spawn.error);
    }
}

/// Edges, the unnormalised and unit geometric normal, then the shading normal (two loops,
/// each with few enough arrays that the compiler vectorises it).
#[inline(always)]
fn normals(lanes: &mut WaveLanes, len: usize) {
    geometric_normals(lanes, len);
    shading_normals(lanes, len);
}

/// Edges, `e1 x e2` and the unit geometric normal (+Y for a degenerate triangle).
#[inline(always)]
fn geometric_normals(lanes: &mut WaveLanes, len: usize) {
    let p = corner_lanes(&lanes.p, len);
    let mut edge1 = lanes.edge1.lanes_mut(len);
    let mut edge2 = lanes.edge2.lanes_mut(len);
    let mut area_normal = lanes.area_normal.lanes_mut(len);
    let mut geometric_normal = lanes.geometric_normal.lanes_mut(len);
    for lane in 0..len {
        let p0 = p[0].get(lane);
        let e1 = p[1].get(lane) - p0;
        let e2 = p[2].get(lane) - p0;
        let area = e1.cross(e2);
        edge1.set(lane, e1);
        edge2.set(lane, e2);
        area_normal.set(lane, area);
        geometric_normal.set(lane, normalize_or(area, Vec3::Y));
    }
}

/// The interpolated shading normal on the geometric normal's side (the geometric normal
/// where the vertex normals give none).
#[inline(always)]
fn shading_normals(lanes: &mut WaveLanes, len: usize) {
    let n = corner_lanes(&lanes.n, len);
    let (u, v) = (&lanes.u[..len], &lanes.v[..len]);
    let geometric_normal = lanes.geometric_normal.lanes(len);
    let mut shading_normal = lanes.shading_normal.lanes_mut(len);
    for lane in 0..len {
        let geometric = geometric_normal.get(lane);
        let (u, v) = (u[lane], v[lane]);
        let w = 1.0 - u - v;
        let interpolated = n[0].get(lane) * w + n[1].get(lane) * u + n[2].get(lane) * v;
        // A non-finite sum has an infinite or NaN length, so `normalize_or` falls back to
        // the geometric normal as the scalar path's explicit finiteness test does.
        let shading = normalize_or(interpolated, geometric);
        let facing = select(shading.dot(geometric) < 0.0, -shading, shading);
        shading_normal.set(lane, facing);
    }
}

/// Texture coordinates of the lanes that read them, zero elsewhere.
#[inline(always)]
fn texture_coordinates(lanes: &mut WaveLanes, len: usize) {
    let [[s0, t0], [s1, t1], [s2, t2]] = corner_lanes_2(&lanes.st_vertices, len);
    let (u, v) = (&lanes.u[..len], &lanes.v[..len]);
    let has_st = &lanes.has_st[..len];
    let [s, t] = &mut lanes.st.x_y_mut(len);
    for lane in 0..len {
        let (u, v) = (u[lane], v[lane]);
        let w = 1.0 - u - v;
        let st0 = Vec2::new(s0[lane], t0[lane]);
        let st1 = Vec2::new(s1[lane], t1[lane]);
        let st2 = Vec2::new(s2[lane], t2[lane]);
        let st = st0 * w + st1 * u + st2 * v;
        let st = if has_st[lane] { st } else { Vec2::ZERO };
        s[lane] = st.x;
        t[lane] = st.y;
    }
}

/// dP/ds and dP/dt of the triangle lanes whose material is normal-mapped, as
/// `SurfaceLookup::surface_hit` computes them for its tangent frame: zero where the mesh has
/// no texture coordinates or their mapping is degenerate. Lane by lane: the degenerate
/// cases return early, and only normal-mapped materials' runs pay for it.
fn triangle_frames(lanes: &mut WaveLanes) {
    for run in 0..lanes.material_runs.len() {
        let (material, range) = lanes.material_run(run);
        if range.start >= lanes.spheres_start || !lanes.materials[material as usize].normal_mapped {
            continue;
        }
        for lane in range {
            let (dpds, dpdt) = if lanes.has_st[lane] {
                let p = [0, 1, 2].map(|corner| lanes.p[corner].get(lane));
                let st = [0, 1, 2].map(|corner| lanes.st_vertices[corner].get(lane));
                triangle_position_derivatives(p, st)
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            lanes.dpds.set(lane, dpds);
            lanes.dpdt.set(lane, dpdt);
        }
    }
}

/// The ray's point projected onto the sphere, and its normal (`SpawnPoint::on_sphere`);
/// the spawn point projected from that point once more, as `SurfaceHit::spawn_point`
/// projects it. A sphere's shading normal is its geometric one.
#[inline(always)]
fn sphere_points(lanes: &mut WaveLanes, spheres: Range<usize>) {
    let origin = lanes.origin.range(spheres.clone());
    let direction = lanes.direction.range(spheres.clone());
    let t = &lanes.t[spheres.clone()];
    let center = lanes.center.range(spheres.clone());
    let radius = &lanes.radius[spheres.clone()];
    let mut point = lanes.sphere_point.range_mut(spheres.clone());
    let mut position = lanes.position.range_mut(spheres.clone());
    let mut error = lanes.error.range_mut(spheres.clone());
    let mut geometric_normal = lanes.geometric_normal.range_mut(spheres.clone());
    let mut shading_normal = lanes.shading_normal.range_mut(spheres.clone());
    for k in 0..t.len() {
        let (c, r) = (center.get(k), radius[k]);
        let near = origin.get(k) + direction.get(k) * t[k];
        let (surface, normal) = SpawnPoint::on_sphere(c, r, near);
        let spawn = SpawnPoint::on_sphere(c, r, surface.position).0;
        point.set(k, surface.position);
        position.set(k, spawn.position);
        error.set(k, spawn.error);
        geometric_normal.set(k, normal);
        shading_normal.set(k, normal);
    }
}

/// Lat-long texture coordinates and dP/ds, dP/dt of the sphere lanes that want texture
/// coordinates (`footprint::lat_long_frame`), zero elsewhere. Lane by lane: the frame's
/// inverse trigonometric functions are calls, which no vector loop would run.
fn sphere_frames(lanes: &mut WaveLanes, spheres: Range<usize>) {
    for lane in spheres {
        let (st, dpds, dpdt) = if lanes.has_st[lane] {
            lat_long_frame(lanes.geometric_normal.get(lane), lanes.radius[lane])
        } else {
            (Vec2::ZERO, Vec3::ZERO, Vec3::ZERO)
        };
        lanes.st.set(lane, st);
        lanes.dpds.set(lane, dpds);
        lanes.dpdt.set(lane, dpdt);
    }
}
