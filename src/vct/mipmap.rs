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
//! Children beyond the grid's edge count as empty in both. Once every level is reduced,
//! each value is turned into optical depth (`grid::to_optical_depth`), which is what
//! lookups interpolate.

use rayon::prelude::*;

use super::grid::{level_dims, to_optical_depth, GridFrame, VoxelKind, VoxelLevel, VoxelPyramid};

/// The pyramid over `level0` (which must have `frame.dims` and one `[a L, a]` value per
/// voxel), every coarser level reduced from the finer one as `kind` says, then stored as
/// optical depth. Parallel over slices.
pub fn build_pyramid(frame: GridFrame, level0: VoxelLevel, kind: VoxelKind) -> VoxelPyramid {
    let mut levels = reduce_levels(frame, level0, kind);
    for level in &mut levels {
        level
            .voxels
            .par_iter_mut()
            .for_each(|v| *v = to_optical_depth(*v));
    }
    VoxelPyramid {
        frame,
        kind,
        levels,
    }
}

/// Every level over `level0`, each reduced from the finer one as `kind` says, as opacity and
/// premultiplied radiance.
pub fn reduce_levels(frame: GridFrame, level0: VoxelLevel, kind: VoxelKind) -> Vec<VoxelLevel> {
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
    levels
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
/// six above it). Most blocks of a voxelised scene are empty: a face whose eight children
/// are all transparent stays zero without being composed.
pub fn reduce_directional(finer: &VoxelLevel, dims: [u32; 3]) -> VoxelLevel {
    const FACES: usize = 6;
    let mut out = VoxelLevel::empty_with_faces(dims, FACES);
    let slice = (dims[0] * dims[1]) as usize * FACES;
    out.voxels
        .par_chunks_mut(slice)
        .enumerate()
        .for_each(|(z, plane)| {
            let mut children = [[0.0f32; 4]; 8];
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let at = (x + dims[0] * y) as usize * FACES;
                    let corner = [2 * x, 2 * y, 2 * z as u32];
                    for face in 0..FACES {
                        // A one-value level shows the same children to every face.
                        if face == 0 || finer.faces > 1 {
                            read_children(finer, corner, face, &mut children);
                        }
                        if children.iter().all(|c| c[3] == 0.0) {
                            if finer.faces == 1 {
                                break;
                            }
                            continue;
                        }
                        plane[at + face] = composed_face(&children, face / 2, face % 2 == 1);
                    }
                }
            }
        });
    out
}

/// Face `face` of the eight children of the block whose lowest corner is `corner`, child
/// `i` at offset `(i & 1, (i >> 1) & 1, (i >> 2) & 1)`; children past the level's edge are
/// empty.
#[inline]
fn read_children(finer: &VoxelLevel, corner: [u32; 3], face: usize, out: &mut [[f32; 4]; 8]) {
    let [dx, dy, dz] = finer.dims;
    let [x, y, z] = corner;
    if x + 1 < dx && y + 1 < dy && z + 1 < dz {
        let (sx, sy) = (dx as usize, (dx * dy) as usize);
        let base = x as usize + sx * y as usize + sy * z as usize;
        let face = if finer.faces == 1 { 0 } else { face };
        for (i, child) in out.iter_mut().enumerate() {
            let index = base + (i & 1) + sx * ((i >> 1) & 1) + sy * (i >> 2);
            *child = finer.voxels[index * finer.faces + face];
        }
        return;
    }
    for (i, child) in out.iter_mut().enumerate() {
        *child = finer.get_face(
            i64::from(x) + (i & 1) as i64,
            i64::from(y) + ((i >> 1) & 1) as i64,
            i64::from(z) + (i >> 2) as i64,
            face,
        );
    }
}

/// What a cone travelling along `axis` (towards its negative end when `negative`) sees of
/// eight children: the mean over the four columns along `axis` of front-to-back
/// composition.
#[inline]
fn composed_face(children: &[[f32; 4]; 8], axis: usize, negative: bool) -> [f32; 4] {
    let bit = 1 << axis;
    let mut sum = [0.0f32; 4];
    for low in (0..8).filter(|i| i & bit == 0) {
        let (front, back) = if negative {
            (children[low | bit], children[low])
        } else {
            (children[low], children[low | bit])
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
    use crate::test_rng::{unit_f32, xorshift32};
    use crate::vct::grid::{face_index, OPAQUE_DEPTH};
    use glam::Vec3;

    /// The levels (opacity and premultiplied radiance) over a grid of `n^3` voxels with one
    /// opaque layer across `axis` at index `at`, radiance 2.
    fn plane(n: u32, axis: usize, at: u32) -> Vec<VoxelLevel> {
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
        reduce_levels(frame, level, VoxelKind::Directional)
    }

    #[test]
    fn a_one_voxel_plane_stays_opaque_along_its_normal_at_every_level() {
        for (axis, at) in [(0, 5), (1, 0), (2, 12)] {
            let p = plane(16, axis, at);
            for (l, level) in p.iter().enumerate() {
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
    fn the_built_pyramid_holds_optical_depth() {
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [2, 1, 1],
        };
        let mut level = VoxelLevel::empty(frame.dims);
        level.voxels[0] = [0.5, 0.25, 0.0, 0.5];
        level.voxels[1] = [3.0, 3.0, 3.0, 1.0];
        let p = build_pyramid(frame, level, VoxelKind::Isotropic);
        let ln2 = std::f32::consts::LN_2;
        let half = p.levels[0].get(0, 0, 0);
        let expect = [ln2, 0.5 * ln2, 0.0, ln2];
        assert!(half.iter().zip(expect).all(|(a, b)| (a - b).abs() < 1e-6));
        // An opaque voxel gets the largest depth, its radiance kept as the ratio.
        let opaque = p.levels[0].get(1, 0, 0);
        assert!((opaque[3] - OPAQUE_DEPTH).abs() < 1e-3);
        assert!((opaque[0] / opaque[3] - 3.0).abs() < 1e-5);
    }

    #[test]
    fn every_face_is_the_mean_of_its_four_composed_columns() {
        // Odd dimensions put blocks across the grid's far edges; a third of the voxels are
        // filled at random. The reference composes each column from scratch.
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [11, 6, 9],
        };
        let mut level = VoxelLevel::empty(frame.dims);
        let mut state = 0x2545_F491u32;
        let mut next = || unit_f32(xorshift32(&mut state));
        for v in &mut level.voxels {
            if next() < 0.33 {
                let a = next();
                *v = [a * next(), a * next(), a * next(), a];
            }
        }
        let levels = reduce_levels(frame, level, VoxelKind::Directional);
        for l in 1..levels.len() {
            let (finer, level) = (&levels[l - 1], &levels[l]);
            let [dx, dy, dz] = level.dims.map(i64::from);
            for (x, y, z) in
                (0..dz).flat_map(|z| (0..dy).flat_map(move |y| (0..dx).map(move |x| (x, y, z))))
            {
                for axis in 0..3 {
                    for negative in [false, true] {
                        let face = face_index(axis, negative);
                        let mut expect = [0.0f32; 4];
                        for column in 0..4 {
                            let child = |along: i64| {
                                let mut c = [2 * x, 2 * y, 2 * z];
                                c[axis] += along;
                                c[(axis + 1) % 3] += column & 1;
                                c[(axis + 2) % 3] += column >> 1;
                                finer.get_face(c[0], c[1], c[2], face)
                            };
                            let (front, back) = if negative {
                                (child(1), child(0))
                            } else {
                                (child(0), child(1))
                            };
                            for k in 0..4 {
                                expect[k] += 0.25 * (front[k] + (1.0 - front[3]) * back[k]);
                            }
                        }
                        let got = level.get_face(x, y, z, face);
                        assert!(
                            got.iter().zip(expect).all(|(a, b)| (a - b).abs() < 1e-5),
                            "level {l} ({x},{y},{z}) face {face}: {got:?} vs {expect:?}"
                        );
                    }
                }
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
        let levels = reduce_levels(frame, level, VoxelKind::Directional);
        let top = &levels[1];
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
