//! Stage 1: the vertex data of each lane's triangle, gathered into lane arrays.

use glam::{Vec2, Vec3};

use super::{refill, WaveLanes};
use crate::scene::TriangleMesh;

/// Gather every lane's triangle: positions always, vertex normals (zero where the mesh has
/// none), and texture coordinates for lanes that want them and whose mesh has them.
// Not inlined: one call per wave, and `perf` attributes each stage's time to it.
#[inline(never)]
pub(crate) fn gather_triangles(lanes: &mut WaveLanes, meshes: &[TriangleMesh]) {
    let len = lanes.len();
    for array in lanes.p.iter_mut().chain(lanes.n.iter_mut()) {
        refill(array, len, Vec3::ZERO);
    }
    refill(&mut lanes.has_st, len, false);
    for lane in 0..len {
        let mesh = &meshes[lanes.mesh[lane] as usize];
        let [i0, i1, i2] = mesh.triangles[lanes.triangle[lane] as usize].map(|i| i as usize);
        lanes.p[0][lane] = mesh.positions[i0];
        lanes.p[1][lane] = mesh.positions[i1];
        lanes.p[2][lane] = mesh.positions[i2];
        if !mesh.normals.is_empty() {
            lanes.n[0][lane] = mesh.normals[i0];
            lanes.n[1][lane] = mesh.normals[i1];
            lanes.n[2][lane] = mesh.normals[i2];
        }
        lanes.has_st[lane] = lanes.wants_st[lane] && !mesh.st.is_empty();
    }
    gather_texture_coordinates(lanes, meshes);
}

/// The texture coordinates of the lanes that read them (zero elsewhere).
fn gather_texture_coordinates(lanes: &mut WaveLanes, meshes: &[TriangleMesh]) {
    let len = lanes.len();
    for array in &mut lanes.st_vertices {
        refill(array, len, Vec2::ZERO);
    }
    for lane in 0..len {
        if !lanes.has_st[lane] {
            continue;
        }
        let mesh = &meshes[lanes.mesh[lane] as usize];
        let [i0, i1, i2] = mesh.triangles[lanes.triangle[lane] as usize].map(|i| i as usize);
        lanes.st_vertices[0][lane] = mesh.st[i0];
        lanes.st_vertices[1][lane] = mesh.st[i1];
        lanes.st_vertices[2][lane] = mesh.st[i2];
    }
}
