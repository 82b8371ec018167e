//! Extra bounces accumulated inside the voxels (seed 003: "the diffuse illumination from
//! additional bounces can be accumulated inside the voxels").
//!
//! Occupied voxels gather what their diffuse cones see from the current pyramid, about the
//! normal their surfaces were lit from (`inject`), and add their diffuse reflectance times
//! that to the direct light they send out; the pyramid is then rebuilt. One pass adds one
//! bounce (a Jacobi step: every voxel gathers from the previous pass).
//!
//! Indirect light varies slowly, so the gather is shared: the occupied voxels of one block
//! of `2^GATHER_LEVEL` voxels per axis whose normals face the same way (the same dominant
//! axis and sign) gather once, from their mean centre about their mean normal, and each
//! scales that by its own reflectance. At level 3 a flat surface gathers once per 64 voxels;
//! on the Cornell boxes the mean and RMSE match every voxel gathering on its own to 0.001,
//! at a 57th of the cones (`docs/vct.md` measures the choice).

use std::collections::HashMap;

use glam::Vec3;
use rayon::prelude::*;

use super::cone::{gather_diffuse, CONE_START, DIFFUSE_CONE_COUNT, STEP_FRACTION};
use super::grid::{face_index, GridFrame, VoxelLevel, VoxelPyramid};
use super::mipmap::build_pyramid;

/// The level whose blocks share one gather (0: every voxel gathers on its own).
pub const GATHER_LEVEL: u32 = 3;

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

/// Where the surfaces gather: one point and normal per group, and each surface's group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GatherGroups {
    /// Mean centre and unit mean normal of each group's voxels.
    pub points: Vec<(Vec3, Vec3)>,
    /// The group of each surface, in the order of the surfaces.
    pub group_of: Vec<u32>,
}

/// Group `surfaces` by their block at level `level` and the face their normal points to.
pub fn gather_groups(frame: &GridFrame, surfaces: &[SurfaceVoxel], level: u32) -> GatherGroups {
    let [dx, dy, _] = frame.dims;
    let block_dims = frame.dims.map(|d| d.div_ceil(1 << level));
    let mut groups: HashMap<u64, u32> = HashMap::new();
    let mut sums: Vec<(Vec3, Vec3, u32)> = Vec::new();
    let mut group_of = Vec::with_capacity(surfaces.len());
    for s in surfaces {
        let (x, y, z) = (s.index % dx, (s.index / dx) % dy, s.index / (dx * dy));
        let block = u64::from(x >> level)
            + u64::from(block_dims[0])
                * (u64::from(y >> level) + u64::from(block_dims[1]) * u64::from(z >> level));
        let key = block * 6 + dominant_face(s.normal) as u64;
        let next = sums.len() as u32;
        let group = *groups.entry(key).or_insert(next);
        if group == next {
            sums.push((Vec3::ZERO, Vec3::ZERO, 0));
        }
        let sum = &mut sums[group as usize];
        sum.0 += s.center;
        sum.1 += s.normal;
        sum.2 += 1;
        group_of.push(group);
    }
    let points = sums
        .iter()
        .map(|&(centers, normals, n)| (centers / n as f32, normals.normalize_or(Vec3::Y)))
        .collect();
    GatherGroups { points, group_of }
}

/// The face of a directional voxel a unit normal points to most: its largest component's
/// axis and sign.
fn dominant_face(n: Vec3) -> usize {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    face_index(axis, n[axis] < 0.0)
}

/// One more bounce: the pyramid whose voxels send out their direct light plus the diffuse
/// reflection of what `current` shows their group's gather point.
pub fn add_bounce(
    current: &VoxelPyramid,
    surfaces: &[SurfaceVoxel],
    groups: &GatherGroups,
) -> (VoxelPyramid, BounceWork) {
    let gathered: Vec<(Vec3, u64)> = groups
        .points
        .par_iter()
        .map(|&(center, normal)| {
            let g = gather_diffuse(current, center, normal, CONE_START, STEP_FRACTION);
            (g.radiance, g.steps)
        })
        .collect();
    let mut level0 = VoxelLevel::empty(current.frame.dims);
    for (s, &group) in surfaces.iter().zip(&groups.group_of) {
        let radiance = s.direct + s.reflectance * gathered[group as usize].0;
        let a = s.opacity;
        level0.voxels[s.index as usize] = [a * radiance.x, a * radiance.y, a * radiance.z, a];
    }
    let work = BounceWork {
        cones: (gathered.len() * DIFFUSE_CONE_COUNT) as u64,
        steps: gathered.iter().map(|g| g.1).sum(),
    };
    (build_pyramid(current.frame, level0, current.kind), work)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vct::grid::VoxelKind;

    /// Unit voxels, `n` per axis.
    fn frame(n: u32) -> GridFrame {
        GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [n; 3],
        }
    }

    fn surface(frame: &GridFrame, (x, y, z): (u32, u32, u32), normal: Vec3) -> SurfaceVoxel {
        SurfaceVoxel {
            index: frame.index(x, y, z) as u32,
            center: frame.voxel_center(x, y, z),
            normal,
            reflectance: Vec3::splat(0.5),
            direct: Vec3::ZERO,
            opacity: 1.0,
        }
    }

    #[test]
    fn surfaces_share_a_gather_per_block_and_facing() {
        // A 16x16 floor and a wall on x = 0 above it: at level 3 each is cut into 2x2
        // blocks, and the wall's voxels on the floor's blocks stay apart (another facing).
        let f = frame(16);
        let mut surfaces = Vec::new();
        for a in 0..16 {
            for b in 0..16 {
                surfaces.push(surface(&f, (a, 0, b), Vec3::Y));
                if a > 0 {
                    surfaces.push(surface(&f, (0, a, b), Vec3::X));
                }
            }
        }
        let groups = gather_groups(&f, &surfaces, 3);
        assert_eq!(groups.points.len(), 8);
        assert_eq!(groups.group_of.len(), surfaces.len());
        for (s, &g) in surfaces.iter().zip(&groups.group_of) {
            let (center, normal) = groups.points[g as usize];
            assert_eq!(normal, s.normal);
            // Same block: the centre is within the block's 8 voxels of every member.
            assert!((center - s.center).abs().max_element() < 8.0);
            assert_eq!(center.dot(s.normal), s.center.dot(s.normal));
        }
        // Level 0: every voxel on its own, at its own centre.
        let single = gather_groups(&f, &surfaces, 0);
        assert_eq!(single.points.len(), surfaces.len());
        assert!(surfaces
            .iter()
            .zip(&single.group_of)
            .all(|(s, &g)| single.points[g as usize] == (s.center, s.normal)));
    }

    #[test]
    fn a_shared_gather_bounces_what_gathering_per_voxel_does() {
        // A closed 32-voxel box: an emissive ceiling over a grey floor and walls. The light
        // the floor and walls reflect after one bounce, gathered per level-3 block, is within
        // 3 % of every voxel gathering on its own, and is far from nothing.
        let n = 32;
        let f = frame(n);
        let mut surfaces = Vec::new();
        for a in 0..n {
            for b in 0..n {
                let mut ceiling = surface(&f, (a, n - 1, b), -Vec3::Y);
                (ceiling.direct, ceiling.reflectance) = (Vec3::splat(2.0), Vec3::ZERO);
                surfaces.push(ceiling);
                surfaces.push(surface(&f, (a, 0, b), Vec3::Y));
                if (1..n - 1).contains(&a) {
                    surfaces.push(surface(&f, (0, a, b), Vec3::X));
                    surfaces.push(surface(&f, (n - 1, a, b), -Vec3::X));
                }
            }
        }
        let mut level0 = VoxelLevel::empty(f.dims);
        for s in &surfaces {
            let l = s.direct;
            level0.voxels[s.index as usize] = [l.x, l.y, l.z, s.opacity];
        }
        let direct = build_pyramid(f, level0, VoxelKind::Directional);
        let reflected = |level: u32| -> (f64, u64) {
            let (bounced, work) =
                add_bounce(&direct, &surfaces, &gather_groups(&f, &surfaces, level));
            let sum = surfaces
                .iter()
                .filter(|s| s.direct == Vec3::ZERO)
                .map(|s| {
                    // Level 0 holds [tau L, tau] per voxel.
                    let [r, _, _, tau] = bounced.levels[0].voxels[s.index as usize];
                    f64::from(r / tau)
                })
                .sum::<f64>();
            (sum, work.cones)
        };
        let (per_voxel, cones_each) = reflected(0);
        let (shared, cones_shared) = reflected(GATHER_LEVEL);
        assert!(per_voxel > 0.1 * surfaces.len() as f64 * 0.5, "{per_voxel}");
        assert!(
            (shared - per_voxel).abs() < 0.03 * per_voxel,
            "shared {shared} vs per voxel {per_voxel}"
        );
        assert!(
            cones_shared * 16 <= cones_each,
            "{cones_shared} vs {cones_each}"
        );
    }
}
