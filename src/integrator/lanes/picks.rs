//! The hits of a wave an integrator hands to the lanes: picked in the wave's order, then
//! each placed straight at its lane, the lanes ordered by material (a counting sort,
//! stable: the lanes of one material keep the wave's order). Placing each hit once costs
//! nothing, where pushing the lanes and then permuting them copies every array again.

use glam::Vec3;

use super::{LaneMaterial, WaveLanes};
use crate::render::tracer::TraceHit;

/// What a lane needs of its ray and hit, besides the pick's material and mesh.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneHit {
    pub triangle: u32,
    /// Barycentrics as the intersector reported them.
    pub uv: (f32, f32),
    /// Hit distance along the ray.
    pub t: f32,
    /// Unit ray direction.
    pub direction: Vec3,
    pub throughput: Vec3,
    /// Whether the lane needs texture coordinates.
    pub wants_st: bool,
}

impl LaneHit {
    /// The lane of a ray in direction `direction` carrying `throughput`, which hit `hit`.
    #[inline(always)]
    pub(crate) fn new(hit: &TraceHit, direction: Vec3, throughput: Vec3, wants_st: bool) -> Self {
        LaneHit {
            triangle: hit.primitive,
            uv: (hit.u, hit.v),
            t: hit.t,
            direction,
            throughput,
            wants_st,
        }
    }
}

/// The picked hits, in the wave's order, reused from wave to wave.
#[derive(Default)]
pub(crate) struct LanePicks {
    ray: Vec<u32>,
    material: Vec<u32>,
    mesh: Vec<u32>,
    /// The footprint's width at the hit, for a textured material under a cone-like
    /// footprint (`None`: a point sample).
    cone_width: Vec<Option<f32>>,
}

impl LanePicks {
    pub(crate) fn clear(&mut self) {
        self.ray.clear();
        self.material.clear();
        self.mesh.clear();
        self.cone_width.clear();
    }

    pub(crate) fn len(&self) -> usize {
        self.ray.len()
    }

    /// Pick the wave's ray `ray`, whose hit lies on mesh `mesh` of material `material`.
    #[inline]
    pub(crate) fn push(
        &mut self,
        ray: usize,
        material: usize,
        mesh: usize,
        cone_width: Option<f32>,
    ) {
        self.ray.push(ray as u32);
        self.material.push(material as u32);
        self.mesh.push(mesh as u32);
        self.cone_width.push(cone_width);
    }

    /// Lay the picks out in `lanes`, ordered by material with the runs recorded in
    /// `lanes.material_runs`; each lane filled from `hit(ray, material)` for its ray and
    /// the ray's material, and `lane_of_ray[ray]` set to its lane.
    pub(crate) fn place(
        &self,
        lanes: &mut WaveLanes,
        lane_of_ray: &mut [u32],
        mut hit: impl FnMut(usize, LaneMaterial) -> LaneHit,
    ) {
        lanes.lay_out_by_material(&self.material);
        for (k, &ray) in self.ray.iter().enumerate() {
            let lane = lanes.lane_of_pick[k] as usize;
            lane_of_ray[ray as usize] = lane as u32;
            let LaneHit {
                triangle,
                uv: (u, v),
                t,
                direction,
                throughput,
                wants_st,
            } = hit(ray as usize, lanes.materials[self.material[k] as usize]);
            lanes.wave_index[lane] = ray;
            lanes.material[lane] = self.material[k];
            lanes.mesh[lane] = self.mesh[k];
            lanes.triangle[lane] = triangle;
            lanes.u[lane] = u;
            lanes.v[lane] = v;
            lanes.t[lane] = t;
            lanes.direction.set(lane, direction);
            lanes.throughput.set(lane, throughput);
            lanes.wants_st[lane] = wants_st;
            lanes.cone_width[lane] = self.cone_width[k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placing_orders_lanes_by_material_stably_and_maps_rays_to_lanes() {
        let mut lanes = WaveLanes {
            materials: vec![LaneMaterial::default(); 4],
            ..WaveLanes::default()
        };
        let mut picks = LanePicks::default();
        // Rays 0..7 of which 2 is not picked.
        for (ray, material) in [(0, 3), (1, 1), (3, 3), (4, 0), (5, 1), (6, 3)] {
            picks.push(ray, material, 9, Some(ray as f32));
        }
        let mut lane_of_ray = vec![u32::MAX; 7];
        picks.place(&mut lanes, &mut lane_of_ray, |ray, _| LaneHit {
            triangle: 100 + ray as u32,
            uv: (ray as f32, 0.5),
            t: 1.0,
            direction: Vec3::Z,
            throughput: Vec3::splat(ray as f32),
            wants_st: ray % 2 == 0,
        });
        assert_eq!(lanes.wave_index, [4, 1, 5, 0, 3, 6]);
        assert_eq!(lanes.material, [0, 1, 1, 3, 3, 3]);
        assert_eq!(lanes.triangle, [104, 101, 105, 100, 103, 106]);
        assert_eq!(lanes.u, [4.0, 1.0, 5.0, 0.0, 3.0, 6.0]);
        assert_eq!(lanes.throughput.x, [4.0, 1.0, 5.0, 0.0, 3.0, 6.0]);
        assert_eq!(lanes.wants_st, [true, false, false, true, false, true]);
        assert_eq!(lanes.cone_width, [4.0, 1.0, 5.0, 0.0, 3.0, 6.0].map(Some));
        assert_eq!(lane_of_ray, [3, 1, u32::MAX, 4, 0, 2, 5]);
        let runs: Vec<_> = (0..lanes.material_runs.len())
            .map(|run| lanes.material_run(run))
            .collect();
        assert_eq!(runs, [(0, 0..1), (1, 1..3), (3, 3..6)]);
    }
}
