//! The opacity-correct reductions that build the voxel mip pyramid.
//!
//! Voxels hold radiance premultiplied by opacity. The isotropic reduction is the plain
//! average of the eight children: the alpha-weighted average of their radiance with the
//! average of their opacities, so an empty child dilutes the opacity without darkening the
//! radiance of the surfaces that are there, and a surface one voxel thick has opacity
//! `2^-l` at level `l`.
//!
//! The directional reduction (Crassin et al. 2011, sec. 3.1) keeps, for each of the six
//! axis directions of travel, what a cone moving that way sees of the eight children: each
//! of the four columns of two children along the axis is composed front to back,
//! `c = c_front + (1 - a_front) c_back`, and the four columns are averaged. A surface
//! across the axis then stays opaque at every level; one along it is diluted as before.
//! Children beyond the grid's edge count as empty in both.

use rayon::prelude::*;

use super::grid::{face_index, level_dims, GridFrame, VoxelKind, VoxelLevel, VoxelPyramid};

/// The pyramid over `level0` (which must have `frame.dims` and one value per voxel), every
/// coarser level reduced from the finer one as `kind` says. Parallel over slices.
pub fn build_pyramid(frame: GridFrame, level0: VoxelLevel, kind: VoxelKind) -> VoxelPyramid {
    debug_assert_eq!(level0.dims, frame.dims);
    debug_assert_eq!(level0.faces, 1);
    let dims = level_dims(frame.dims);
    let mut levels = vec![level0];
    for d in dims.into_iter().skip(1) {
        let finer = levels.last().expect("level 0 is there");
        levels.push(match kind {
            VoxelKind::Isotropic => reduce(finer, d),
            VoxelKind::Directional => reduce_directional(finer, d),
        });
    }
    VoxelPyramid {
        frame,
        kind,
        levels,
    }
}

/// The isotropic level of dimensions `dims` above the one-value level `finer`.
pub fn reduce(finer: &VoxelLevel, dims: [u32; 3]) -> VoxelLevel {
    let mut out = VoxelLevel::empty(dims);
    let slice = (dims[0] * dims[1]) as usize;
    out.voxels
        .par_chunks_mut(slice)
        .enumerate()
        .for_each(|(z, plane)| {
            let z = z as i64;
            for y in 0..dims[1] as i64 {
                for x in 0..dims[0] as i64 {
                    let mut sum = [0.0f32; 4];
                    for child in 0..8 {
                        let t = finer.get(
                            2 * x + (child & 1),
                            2 * y + ((child >> 1) & 1),
                            2 * z + ((child >> 2) & 1),
                        );
                        for (s, c) in sum.iter_mut().zip(t) {
                            *s += c;
                        }
                    }
                    plane[(x + dims[0] as i64 * y) as usize] = sum.map(|s| s * 0.125);
                }
            }
        });
    out
}

/// The six-face level of dimensions `dims` above `finer` (one value per voxel at level 0,
/// six above it).
pub fn reduce_directional(finer: &VoxelLevel, dims: [u32; 3]) -> VoxelLevel {
    const FACES: usize = 6;
    let mut out = VoxelLevel::empty_with_faces(dims, FACES);
    let slice = (dims[0] * dims[1]) as usize * FACES;
    out.voxels
        .par_chunks_mut(slice)
        .enumerate()
        .for_each(|(z, plane)| {
            let z = z as i64;
            for y in 0..dims[1] as i64 {
                for x in 0..dims[0] as i64 {
                    let at = (x + dims[0] as i64 * y) as usize * FACES;
                    let corner = [2 * x, 2 * y, 2 * z];
                    for axis in 0..3 {
                        for negative in [false, true] {
                            let face = face_index(axis, negative);
                            plane[at + face] = composed_face(finer, corner, axis, negative, face);
                        }
                    }
                }
            }
        });
    out
}

/// Face `face` (travel along `axis`, towards its negative end when `negative`) of the
/// block of eight children whose lowest corner is `corner`: the mean over the four columns
/// along `axis` of front-to-back composition.
#[inline]
fn composed_face(
    finer: &VoxelLevel,
    corner: [i64; 3],
    axis: usize,
    negative: bool,
    face: usize,
) -> [f32; 4] {
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut sum = [0.0f32; 4];
    for column in 0..4 {
        let child = |along: i64| {
            let mut c = corner;
            c[axis] += along;
            c[u] += column & 1;
            c[v] += column >> 1;
            finer.get_face(c[0], c[1], c[2], face)
        };
        let (front, back) = if negative {
            (child(1), child(0))
        } else {
            (child(0), child(1))
        };
        let through = 1.0 - front[3];
        for (s, (f, b)) in sum.iter_mut().zip(front.into_iter().zip(back)) {
            *s += f + through * b;
        }
    }
    sum.map(|s| s * 0.25)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A grid of `n^3` voxels with one opaque layer across `axis` at index `at`, radiance 2.
    fn plane(n: u32, axis: usize, at: u32) -> VoxelPyramid {
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [n; 3],
        };
        let mut level = VoxelLevel::empty(frame.dims);
        for a in 0..n {
            for b in 0..n {
                let mut c = [0; 3];
                c[axis] = at;
                c[(axis + 1) % 3] = a;
                c[(axis + 2) % 3] = b;
                level.voxels[frame.index(c[0], c[1], c[2])] = [2.0, 2.0, 2.0, 1.0];
            }
        }
        build_pyramid(frame, level, VoxelKind::Directional)
    }

    #[test]
    fn a_one_voxel_plane_stays_opaque_along_its_normal_at_every_level() {
        for (axis, at) in [(0, 5), (1, 0), (2, 12)] {
            let p = plane(16, axis, at);
            for (l, level) in p.levels.iter().enumerate() {
                let mut c = [0i64; 3];
                c[axis] = i64::from(at >> l);
                for negative in [false, true] {
                    let seen = level.get_face(c[0], c[1], c[2], face_index(axis, negative));
                    assert_eq!(seen, [2.0, 2.0, 2.0, 1.0], "axis {axis} level {l}");
                }
                // Seen edge-on, the plane fills only part of a coarse voxel's view.
                let across = face_index((axis + 1) % 3, false);
                let edge_on = level.get_face(c[0], c[1], c[2], across)[3];
                assert!(l == 0 || edge_on <= 0.5, "level {l}: {edge_on}");
            }
        }
    }

    #[test]
    fn composition_puts_the_nearer_child_in_front() {
        // Two layers along x: an opaque red one at x = 0, an opaque green one at x = 1.
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [2, 2, 2],
        };
        let mut level = VoxelLevel::empty(frame.dims);
        for y in 0..2 {
            for z in 0..2 {
                level.voxels[frame.index(0, y, z)] = [1.0, 0.0, 0.0, 1.0];
                level.voxels[frame.index(1, y, z)] = [0.0, 1.0, 0.0, 1.0];
            }
        }
        let p = build_pyramid(frame, level, VoxelKind::Directional);
        let top = &p.levels[1];
        assert_eq!(
            top.get_face(0, 0, 0, face_index(0, false)),
            [1.0, 0.0, 0.0, 1.0]
        );
        assert_eq!(
            top.get_face(0, 0, 0, face_index(0, true)),
            [0.0, 1.0, 0.0, 1.0]
        );
        // Along y both layers share the view half and half.
        assert_eq!(
            top.get_face(0, 0, 0, face_index(1, false)),
            [0.5, 0.5, 0.0, 1.0]
        );
    }
}
