//! Vertex normals that cannot be used as written.
//!
//! Exporters write zero-length normals (`vn 0 0 0` in OBJ, zero vectors in a glTF NORMAL
//! accessor, as Khronos' BoxBadNormals does) where they had none to give. Every mesh loader
//! repairs them the same way, with a note; non-finite normals stay errors (`validate`), as
//! non-finite positions are.

use glam::Vec3;

/// Replaces zero-length vertex normals by the area-weighted normal of the triangles around
/// the vertex; drops all normals (flat shading) when that is zero too. `triangles` must index
/// `positions`. Returns the note to record (what was done, without the mesh's name), or
/// `None` when every normal was usable.
pub(crate) fn repair_zero_normals(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    normals: &mut Vec<Vec3>,
) -> Option<String> {
    let is_zero = |n: &Vec3| n.length_squared() == 0.0;
    let count = normals.iter().filter(|n| is_zero(n)).count();
    if count == 0 {
        return None;
    }
    let mut face_sum = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let area_normal = (b - a).cross(c - a);
        for &i in t {
            face_sum[i as usize] += area_normal;
        }
    }
    for (n, sum) in normals.iter_mut().zip(&face_sum) {
        if is_zero(n) {
            *n = sum.normalize_or_zero();
        }
    }
    if normals.iter().any(is_zero) {
        normals.clear();
        return Some(format!(
            "{count} zero-length normals, some at vertices of degenerate faces only: \
             all normals dropped (flat shading)"
        ));
    }
    Some(format!(
        "{count} zero-length normals replaced by the surrounding faces' normal"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_normals_are_repaired_from_faces() {
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let mut normals = vec![Vec3::ZERO, Vec3::Z, Vec3::Z];
        let note = repair_zero_normals(&positions, &[[0, 1, 2]], &mut normals).unwrap();
        assert!(note.starts_with("1 zero-length normals replaced"), "{note}");
        assert_eq!(normals[0], Vec3::Z);
        let mut intact = vec![Vec3::Z; 3];
        assert_eq!(
            repair_zero_normals(&positions, &[[0, 1, 2]], &mut intact),
            None
        );
        // A degenerate triangle cannot supply a normal: fall back to flat shading.
        let mut normals = vec![Vec3::ZERO; 3];
        let note = repair_zero_normals(&[Vec3::ZERO; 3], &[[0, 1, 2]], &mut normals).unwrap();
        assert!(normals.is_empty());
        assert!(note.contains("flat shading"), "{note}");
    }
}
