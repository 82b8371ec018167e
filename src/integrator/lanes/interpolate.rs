//! Stage 2: what the hits' barycentrics give, over lane arrays: the point with its rounding
//! error bound, the triangle's edges and normals, the shading normal and the texture
//! coordinates, computed as `render::prepared::SurfaceLookup::surface_hit` does.

use glam::{Vec2, Vec3};

use super::{refill, WaveLanes};
use crate::shading::SpawnPoint;

/// Interpolate every lane (the loops are split so that each is free of per-lane branches
/// but selects).
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn interpolate(lanes: &mut WaveLanes) {
    spawn_points(lanes);
    normals(lanes);
    texture_coordinates(lanes);
}

/// The point and the bound on its error (`SpawnPoint::on_triangle`, in double precision).
fn spawn_points(lanes: &mut WaveLanes) {
    let len = lanes.len();
    refill(&mut lanes.position, len, Vec3::ZERO);
    refill(&mut lanes.error, len, Vec3::ZERO);
    for lane in 0..len {
        let p = [lanes.p[0][lane], lanes.p[1][lane], lanes.p[2][lane]];
        let spawn = SpawnPoint::on_triangle(p, lanes.u[lane], lanes.v[lane]);
        lanes.position[lane] = spawn.position;
        lanes.error[lane] = spawn.error;
    }
}

/// Edges, the unnormalised and unit geometric normal, and the interpolated shading normal on
/// the geometric normal's side (the geometric normal where the vertex normals give none).
fn normals(lanes: &mut WaveLanes) {
    let len = lanes.len();
    for array in [
        &mut lanes.edge1,
        &mut lanes.edge2,
        &mut lanes.area_normal,
        &mut lanes.geometric_normal,
        &mut lanes.shading_normal,
    ] {
        refill(array, len, Vec3::ZERO);
    }
    for lane in 0..len {
        let p0 = lanes.p[0][lane];
        let e1 = lanes.p[1][lane] - p0;
        let e2 = lanes.p[2][lane] - p0;
        let area_normal = e1.cross(e2);
        let geometric = area_normal.normalize_or(Vec3::Y);
        let (u, v) = (lanes.u[lane], lanes.v[lane]);
        let w = 1.0 - u - v;
        let interpolated = lanes.n[0][lane] * w + lanes.n[1][lane] * u + lanes.n[2][lane] * v;
        let shading = if interpolated.is_finite() {
            interpolated.normalize_or(geometric)
        } else {
            geometric
        };
        let facing = if shading.dot(geometric) < 0.0 {
            -shading
        } else {
            shading
        };
        lanes.edge1[lane] = e1;
        lanes.edge2[lane] = e2;
        lanes.area_normal[lane] = area_normal;
        lanes.geometric_normal[lane] = geometric;
        lanes.shading_normal[lane] = facing;
    }
}

/// Texture coordinates of the lanes that read them, zero elsewhere.
fn texture_coordinates(lanes: &mut WaveLanes) {
    let len = lanes.len();
    refill(&mut lanes.st, len, Vec2::ZERO);
    for lane in 0..len {
        let (u, v) = (lanes.u[lane], lanes.v[lane]);
        let w = 1.0 - u - v;
        let [t0, t1, t2] = [0, 1, 2].map(|i| lanes.st_vertices[i][lane]);
        let st = t0 * w + t1 * u + t2 * v;
        lanes.st[lane] = if lanes.has_st[lane] { st } else { Vec2::ZERO };
    }
}
