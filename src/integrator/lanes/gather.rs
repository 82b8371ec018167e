//! Stage 1: the vertex data of each lane's triangle, and the centre and radius of each
//! lane's sphere, gathered into lane arrays (one array per coordinate). Indexed loads from
//! the scene: the one stage that cannot be a straight vector loop.

use super::{refill, LaneArray, WaveLanes};
use crate::scene::{Sphere, TriangleMesh};

/// Gather every triangle lane's triangle: positions always, vertex normals (zero where the
/// mesh has none), and texture coordinates for lanes that want them and whose mesh has
/// them.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn gather_triangles(lanes: &mut WaveLanes, meshes: &[TriangleMesh]) {
    let len = lanes.len();
    for array in lanes.p.iter_mut().chain(lanes.n.iter_mut()) {
        array.refill(len);
    }
    refill(&mut lanes.has_st, len, false);
    for lane in lanes.sections().triangles {
        let mesh = &meshes[lanes.mesh[lane] as usize];
        let corners = mesh.triangles[lanes.primitive[lane] as usize].map(|i| i as usize);
        for (corner, &i) in corners.iter().enumerate() {
            lanes.p[corner].set(lane, mesh.positions[i]);
        }
        if !mesh.normals.is_empty() {
            for (corner, &i) in corners.iter().enumerate() {
                lanes.n[corner].set(lane, mesh.normals[i]);
            }
        }
        lanes.has_st[lane] = lanes.wants_st[lane] && !mesh.st.is_empty();
    }
    gather_texture_coordinates(lanes, meshes);
}

/// The texture coordinates of the lanes that read them (zero elsewhere).
fn gather_texture_coordinates(lanes: &mut WaveLanes, meshes: &[TriangleMesh]) {
    let len = lanes.len();
    for array in &mut lanes.st_vertices {
        array.refill(len);
    }
    for lane in lanes.sections().triangles {
        if !lanes.has_st[lane] {
            continue;
        }
        let mesh = &meshes[lanes.mesh[lane] as usize];
        let corners = mesh.triangles[lanes.primitive[lane] as usize].map(|i| i as usize);
        for (corner, &i) in corners.iter().enumerate() {
            lanes.st_vertices[corner].set(lane, mesh.st[i]);
        }
    }
}

/// Gather every sphere lane's sphere: its centre and radius. Every sphere has texture
/// coordinates (its lat-long parameterisation), so a lane has them when it wants them.
/// Runs after [`gather_triangles`], which clears `has_st`.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn gather_spheres(lanes: &mut WaveLanes, spheres: &[Sphere]) {
    let len = lanes.len();
    lanes.center.resize(len);
    lanes.radius.resize_lanes(len, 0.0);
    lanes.has_st.resize_lanes(len, false);
    for lane in lanes.sections().spheres {
        let sphere = &spheres[lanes.primitive[lane] as usize];
        lanes.center.set(lane, sphere.center);
        lanes.radius[lane] = sphere.radius;
        lanes.has_st[lane] = lanes.wants_st[lane];
    }
}
