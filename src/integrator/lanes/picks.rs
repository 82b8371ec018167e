//! The hits of a wave an integrator hands to the lanes: picked in the wave's order, then
//! each placed straight at its lane, in one section per kind of surface (triangles, spheres,
//! then curved and height patches) and each section ordered by material (a counting sort, stable: the lanes of one material keep the
//! wave's order). Placing each hit once costs nothing, where pushing the lanes and then
//! permuting them copies every array again.

use glam::Vec3;

use super::differentials::LaneDifferential;
use super::footprints::LaneFootprint;
use super::{LaneArray, LaneMaterial, WaveLanes};
use crate::render::prepared::{GeometryRef, SurfaceLookup};
use crate::render::tracer::TraceHit;

/// The kind of surface a lane's hit lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LaneSurface {
    /// A triangle of this mesh (index into `SceneDescription::meshes`).
    Mesh(usize),
    /// One of the scene's analytic spheres.
    Sphere,
    /// One of the scene's curved (Bezier) patches.
    CurvedPatch,
    /// One of the scene's height patches (traced by marching, shaded as the same surface
    /// made a Bezier patch).
    HeightPatch,
}

impl LaneSurface {
    /// The surface `hit` lies on and its material.
    #[inline]
    pub(crate) fn at(surfaces: &SurfaceLookup, hit: &TraceHit) -> (LaneSurface, usize) {
        let scene = &surfaces.scene;
        let primitive = hit.primitive as usize;
        match surfaces.geometries[hit.geometry as usize] {
            GeometryRef::Mesh(index) => (LaneSurface::Mesh(index), scene.meshes[index].material),
            GeometryRef::Spheres => (LaneSurface::Sphere, scene.spheres[primitive].material),
            GeometryRef::Patches => (LaneSurface::CurvedPatch, scene.patches[primitive].material),
            GeometryRef::HeightPatches => (
                LaneSurface::HeightPatch,
                scene.height_patches[primitive].material,
            ),
        }
    }

    /// The section of the lanes this kind of surface is placed in
    /// ([`super::LaneSections`]).
    #[inline]
    fn section(self) -> u32 {
        match self {
            LaneSurface::Mesh(_) => 0,
            LaneSurface::Sphere => 1,
            LaneSurface::CurvedPatch | LaneSurface::HeightPatch => 2,
        }
    }
}

/// What a lane needs of its ray and hit, besides the pick's material and surface.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneHit {
    /// The triangle of the mesh, or the sphere.
    pub primitive: u32,
    /// Barycentrics as the intersector reported them.
    pub uv: (f32, f32),
    /// Hit distance along the ray.
    pub t: f32,
    /// The ray's origin.
    pub origin: Vec3,
    /// Unit ray direction.
    pub direction: Vec3,
    pub throughput: Vec3,
    /// Whether the lane needs texture coordinates.
    pub wants_st: bool,
}

impl LaneHit {
    /// The lane of a ray from `origin` in direction `direction` carrying `throughput`,
    /// which hit `hit`.
    #[inline(always)]
    pub(crate) fn new(
        hit: &TraceHit,
        (origin, direction): (Vec3, Vec3),
        throughput: Vec3,
        wants_st: bool,
    ) -> Self {
        LaneHit {
            primitive: hit.primitive,
            uv: (hit.u, hit.v),
            t: hit.t,
            origin,
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
    /// The mesh of a triangle hit (zero on other surfaces).
    mesh: Vec<u32>,
    /// The lanes' section of the hit's surface (`LaneSurface::section`).
    section: Vec<u32>,
    /// Whether the hit lies on a height patch.
    height_patch: Vec<bool>,
    /// The footprint's width at the hit, for a textured material under a cone-like
    /// footprint (`None`: a point sample).
    cone_width: Vec<Option<f32>>,
    /// The picks that carry a ray differential (index among the picks) and how it reaches
    /// the hit: few waves have any, and the others copy nothing for them.
    differentials: Vec<(u32, LaneDifferential)>,
}

impl LanePicks {
    pub(crate) fn clear(&mut self) {
        self.ray.clear();
        self.material.clear();
        self.mesh.clear();
        self.section.clear();
        self.height_patch.clear();
        self.cone_width.clear();
        self.differentials.clear();
    }

    pub(crate) fn len(&self) -> usize {
        self.ray.len()
    }

    /// Pick the wave's ray `ray`, whose hit lies on `surface` of material `material`, with
    /// its footprint at the hit (`Point` for a lane that reads no texture through it).
    #[inline]
    pub(crate) fn push(
        &mut self,
        ray: usize,
        material: usize,
        surface: LaneSurface,
        footprint: LaneFootprint,
    ) {
        let (cone_width, differential) = match footprint {
            LaneFootprint::Point => (None, None),
            LaneFootprint::Cone(width) => (Some(width), None),
            LaneFootprint::Differential(differential) => (None, Some(differential)),
        };
        if let Some(differential) = differential {
            self.differentials
                .push((self.ray.len() as u32, differential));
        }
        self.ray.push(ray as u32);
        self.material.push(material as u32);
        let mesh = match surface {
            LaneSurface::Mesh(mesh) => mesh as u32,
            _ => 0,
        };
        self.mesh.push(mesh);
        self.section.push(surface.section());
        self.height_patch.push(surface == LaneSurface::HeightPatch);
        self.cone_width.push(cone_width);
    }

    /// Lay the picks out in `lanes`, triangles, spheres then patches, each ordered by
    /// material with the runs recorded in `lanes.material_runs`; each lane filled from `hit(ray, material)` for its ray and
    /// the ray's material, and `lane_of_ray[ray]` set to its lane.
    pub(crate) fn place(
        &self,
        lanes: &mut WaveLanes,
        lane_of_ray: &mut [u32],
        mut hit: impl FnMut(usize, LaneMaterial) -> LaneHit,
    ) {
        lanes.lay_out_by_material(&self.material, &self.section);
        for (k, &ray) in self.ray.iter().enumerate() {
            let lane = lanes.lane_of_pick[k] as usize;
            lane_of_ray[ray as usize] = lane as u32;
            let LaneHit {
                primitive,
                uv: (u, v),
                t,
                origin,
                direction,
                throughput,
                wants_st,
            } = hit(ray as usize, lanes.materials[self.material[k] as usize]);
            lanes.wave_index[lane] = ray;
            lanes.material[lane] = self.material[k];
            lanes.mesh[lane] = self.mesh[k];
            lanes.height_patch[lane] = self.height_patch[k];
            lanes.primitive[lane] = primitive;
            lanes.u[lane] = u;
            lanes.v[lane] = v;
            lanes.t[lane] = t;
            lanes.origin.set(lane, origin);
            lanes.direction.set(lane, direction);
            lanes.throughput.set(lane, throughput);
            lanes.wants_st[lane] = wants_st;
            lanes.cone_width[lane] = self.cone_width[k];
        }
        lanes.differential.clear();
        if !self.differentials.is_empty() {
            lanes.differential.resize_lanes(self.ray.len(), None);
            for &(k, differential) in &self.differentials {
                lanes.differential[lanes.lane_of_pick[k as usize] as usize] = Some(differential);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placing_puts_triangles_spheres_and_patches_in_turn_orders_each_by_material_stably_and_maps_rays(
    ) {
        let mut lanes = WaveLanes {
            materials: vec![LaneMaterial::default(); 4],
            ..WaveLanes::default()
        };
        let mut picks = LanePicks::default();
        // Rays 0..10 of which 2 is not picked; 3 and 5 hit spheres, 7 and 9 height patches,
        // 8 a curved patch.
        for (ray, material) in [
            (9, 2),
            (0, 3),
            (1, 1),
            (3, 3),
            (4, 0),
            (5, 1),
            (6, 3),
            (7, 2),
            (8, 0),
        ] {
            let surface = match ray {
                3 | 5 => LaneSurface::Sphere,
                7 | 9 => LaneSurface::HeightPatch,
                8 => LaneSurface::CurvedPatch,
                _ => LaneSurface::Mesh(9),
            };
            picks.push(ray, material, surface, LaneFootprint::Cone(ray as f32));
        }
        let mut lane_of_ray = vec![u32::MAX; 10];
        picks.place(&mut lanes, &mut lane_of_ray, |ray, _| LaneHit {
            primitive: 100 + ray as u32,
            uv: (ray as f32, 0.5),
            t: 1.0,
            origin: Vec3::splat(-(ray as f32)),
            direction: Vec3::Z,
            throughput: Vec3::splat(ray as f32),
            wants_st: ray % 2 == 0,
        });
        assert_eq!(lanes.wave_index, [4, 1, 0, 6, 5, 3, 8, 9, 7]);
        assert_eq!(lanes.material, [0, 1, 3, 3, 1, 3, 0, 2, 2]);
        assert_eq!(lanes.mesh, [9, 9, 9, 9, 0, 0, 0, 0, 0]);
        let height = [false, false, false, false, false, false, false, true, true];
        assert_eq!(lanes.height_patch, height);
        assert_eq!(
            lanes.sections(),
            super::super::LaneSections {
                triangles: 0..4,
                spheres: 4..6,
                patches: 6..9,
            }
        );
        assert_eq!(
            lanes.primitive,
            [104, 101, 100, 106, 105, 103, 108, 109, 107]
        );
        assert_eq!(lanes.u, [4.0, 1.0, 0.0, 6.0, 5.0, 3.0, 8.0, 9.0, 7.0]);
        assert_eq!(
            lanes.origin.y,
            [-4.0, -1.0, -0.0, -6.0, -5.0, -3.0, -8.0, -9.0, -7.0]
        );
        assert_eq!(
            lanes.throughput.x,
            [4.0, 1.0, 0.0, 6.0, 5.0, 3.0, 8.0, 9.0, 7.0]
        );
        assert_eq!(
            lanes.wants_st,
            [true, false, true, true, false, false, true, false, false]
        );
        assert_eq!(
            lanes.cone_width,
            [4.0, 1.0, 0.0, 6.0, 5.0, 3.0, 8.0, 9.0, 7.0].map(Some)
        );
        assert_eq!(lane_of_ray, [2, 1, u32::MAX, 5, 0, 4, 3, 8, 6, 7]);
        let runs: Vec<_> = (0..lanes.material_runs.len())
            .map(|run| lanes.material_run(run))
            .collect();
        assert_eq!(
            runs,
            [
                (0, 0..1),
                (1, 1..2),
                (3, 2..4),
                (1, 4..5),
                (3, 5..6),
                (0, 6..7),
                (2, 7..9)
            ]
        );
    }
}
