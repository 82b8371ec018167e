//! Extra bounces accumulated inside the voxels (seed 003: "the diffuse illumination from
//! additional bounces can be accumulated inside the voxels").
//!
//! Each occupied voxel gathers what its diffuse cones see from the current pyramid,
//! about the normal its surfaces were lit from (`inject`), and adds its diffuse reflectance
//! times that to the direct light it sends out; the pyramid is then rebuilt. One pass adds
//! one bounce (a Jacobi step: every voxel gathers from the previous pass).

use glam::Vec3;
use rayon::prelude::*;

use super::cone::{gather_diffuse, CONE_START, DIFFUSE_CONE_COUNT, STEP_FRACTION};
use super::grid::{VoxelLevel, VoxelPyramid};
use super::mipmap::build_pyramid;

/// An occupied level-0 voxel, as the extra bounce needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceVoxel {
    pub index: u32,
    pub center: Vec3,
    /// Unit normal on the side the light came from.
    pub normal: Vec3,
    /// Diffuse reflectance of its surfaces (mean).
    pub reflectance: Vec3,
    /// Emission plus direct light (mean), not premultiplied.
    pub direct: Vec3,
    pub opacity: f32,
}

/// Cones traced and steps taken by one pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BounceWork {
    pub cones: u64,
    pub steps: u64,
}

/// One more bounce: the pyramid whose voxels send out their direct light plus the diffuse
/// reflection of what `current` shows them.
pub fn add_bounce(current: &VoxelPyramid, surfaces: &[SurfaceVoxel]) -> (VoxelPyramid, BounceWork) {
    let gathered: Vec<(Vec3, u64)> = surfaces
        .par_iter()
        .map(|s| {
            let g = gather_diffuse(current, s.center, s.normal, CONE_START, STEP_FRACTION);
            (g.radiance, g.steps)
        })
        .collect();
    let mut level0 = VoxelLevel::empty(current.frame.dims);
    let mut work = BounceWork::default();
    for (s, (gather, steps)) in surfaces.iter().zip(gathered) {
        let radiance = s.direct + s.reflectance * gather;
        let a = s.opacity;
        level0.voxels[s.index as usize] = [a * radiance.x, a * radiance.y, a * radiance.z, a];
        work.cones += DIFFUSE_CONE_COUNT as u64;
        work.steps += steps;
    }
    (build_pyramid(current.frame, level0, current.kind), work)
}
