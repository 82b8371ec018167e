//! The opacity-correct reduction that builds the voxel mip pyramid.
//!
//! Voxels hold radiance premultiplied by opacity, so the plain average of the eight
//! children is the alpha-weighted average of their radiance with the average of their
//! opacities: an empty child dilutes the opacity (a half-empty parent lets half the light
//! through) without darkening the radiance of the surfaces that are there. Children beyond
//! the grid's edge count as empty. This is the isotropic form of the pre-integration of
//! Crassin et al. 2011 (sec. 3.1); `docs/vct.md` says why not the six-direction one.

use rayon::prelude::*;

use super::grid::{level_dims, GridFrame, VoxelLevel, VoxelPyramid};

/// The pyramid over `level0` (which must have `frame.dims`), every coarser level the
/// average of eight voxels of the finer one. Parallel over the slices of each level.
pub fn build_pyramid(frame: GridFrame, level0: VoxelLevel) -> VoxelPyramid {
    debug_assert_eq!(level0.dims, frame.dims);
    let dims = level_dims(frame.dims);
    let mut levels = vec![level0];
    for d in dims.into_iter().skip(1) {
        let finer = levels.last().expect("level 0 is there");
        levels.push(reduce(finer, d));
    }
    VoxelPyramid { frame, levels }
}

/// The level of dimensions `dims` above `finer`.
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
