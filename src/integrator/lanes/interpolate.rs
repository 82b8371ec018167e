//! Stage 2: what the hits' barycentrics give, over lane arrays: the point with its rounding
//! error bound, the triangle's edges and normals, the shading normal and the texture
//! coordinates, computed as `render::prepared::SurfaceLookup::surface_hit` does.
//!
//! Each loop reads and writes one array per coordinate and has no branch but selects, so
//! it runs 8 or 16 lanes per instruction at the level `simd::dispatch` picks; the
//! operations and their order are the scalar path's, so every level gives its bits.

use glam::{Vec2, Vec3};

use super::soa::{corner_lanes, corner_lanes_2, normalize_or, select};
use super::WaveLanes;
use crate::shading::SpawnPoint;
use crate::simd;

/// Interpolate every lane.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn interpolate(lanes: &mut WaveLanes) {
    let len = lanes.len();
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
            spawn_points(lanes, len);
            normals(lanes, len);
            texture_coordinates(lanes, len);
        },
    );
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
