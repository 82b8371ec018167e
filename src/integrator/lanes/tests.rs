//! The lane stages against the scalar path they replace: stages 1-3 must give the very bits
//! of `SurfaceLookup::surface_hit` and `Footprint::texture_gradients`.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::footprints::{lane_footprint, texture_gradients, LaneFootprint};
use super::gather::gather_triangles;
use super::interpolate::interpolate;
use super::{LaneMaterial, WaveLanes};
use crate::footprint::{ConeEnvelope, Footprint, RayCone};
use crate::render::prepared::{GeometryRef, SurfaceDetail, SurfaceLookup};
use crate::render::tracer::TraceHit;
use crate::scene::{Material, SceneDescription, TriangleMesh};

/// A small deterministic generator (xorshift), values in [0, 1).
struct Numbers(u32);

impl Numbers {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 17;
        self.0 ^= self.0 << 5;
        (self.0 >> 8) as f32 / (1u32 << 24) as f32
    }

    fn vec3(&mut self, scale: f32) -> Vec3 {
        Vec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * scale
    }
}

/// Two meshes of 64 triangles each: one with normals (some pointing away from the face) and
/// texture coordinates, one with neither; the first mesh's triangle 0 is degenerate
/// (collinear), the second's texture coordinates are missing.
fn scene(numbers: &mut Numbers) -> SceneDescription {
    let mut textured = TriangleMesh {
        name: "textured".into(),
        positions: (0..192).map(|_| numbers.vec3(10.0)).collect(),
        normals: (0..192).map(|_| numbers.vec3(2.0)).collect(),
        st: (0..192)
            .map(|_| Vec2::new(numbers.next() * 3.0, numbers.next()))
            .collect(),
        triangles: (0..64).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect(),
        material: 0,
    };
    textured.positions[1] = textured.positions[0] * 2.0;
    textured.positions[2] = textured.positions[0] * 3.0;
    let flat = TriangleMesh {
        name: "flat".into(),
        normals: Vec::new(),
        st: Vec::new(),
        material: 1,
        ..textured.clone()
    };
    let texture = Some(crate::scene::TextureBinding {
        texture: 0,
        transform: glam::Affine2::IDENTITY,
    });
    SceneDescription {
        materials: vec![
            Material {
                base_color_texture: texture.clone(),
                ..Material::default()
            },
            Material {
                base_color_texture: texture,
                ..Material::default()
            },
        ],
        meshes: vec![textured, flat],
        ..SceneDescription::default()
    }
}

#[test]
fn interpolation_and_gradients_match_the_scalar_path_bit_for_bit() {
    let mut numbers = Numbers(0x9e37_79b9);
    let scene = Arc::new(scene(&mut numbers));
    let lookup = SurfaceLookup::new(
        scene.clone(),
        vec![GeometryRef::Mesh(0), GeometryRef::Mesh(1)],
    );
    let mut lanes = WaveLanes {
        materials: vec![
            LaneMaterial {
                covers: true,
                textured: true,
                opaque_weight: 1.0,
            };
            2
        ],
        ..WaveLanes::default()
    };
    let mut rays = Vec::new();
    for index in 0..512u32 {
        let (u, v) = (numbers.next(), numbers.next());
        let (u, v) = if u + v > 1.0 {
            (1.0 - u, 1.0 - v)
        } else {
            (u, v)
        };
        let hit = TraceHit {
            u,
            v,
            t: 0.5 + 20.0 * numbers.next(),
            geometry: index % 2,
            primitive: (index / 2) % 64,
        };
        let direction = numbers.vec3(1.0).normalize();
        let footprint = match index % 3 {
            0 => Footprint::Cone1(RayCone::new(0.0, 0.002 + 0.01 * numbers.next())),
            1 => Footprint::Cone(ConeEnvelope::new(
                RayCone::new(0.01, 0.003),
                RayCone::new(0.0, -0.001),
                false,
            )),
            _ => Footprint::Mip0,
        };
        lanes.push(
            index,
            hit.geometry,
            hit.geometry,
            hit.primitive,
            (hit.u, hit.v),
            hit.t,
            direction,
            Vec3::ONE,
            true,
        );
        rays.push((hit, direction, footprint));
    }
    let cone_width: Vec<Option<f32>> = rays
        .iter()
        .map(
            |(hit, _, footprint)| match lane_footprint(footprint, hit.t) {
                Some(LaneFootprint::Cone(width)) => Some(width),
                _ => None,
            },
        )
        .collect();
    gather_triangles(&mut lanes, &scene.meshes);
    interpolate(&mut lanes);
    texture_gradients(&mut lanes, &cone_width, 16.0);
    for (lane, (hit, direction, footprint)) in rays.iter().enumerate() {
        let origin = Vec3::ZERO;
        let surface = lookup.surface_hit(origin, *direction, hit, SurfaceDetail::Texturing);
        let spawn = surface.spawn_point();
        let same =
            |a: Vec3, b: Vec3| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits);
        assert!(same(lanes.position[lane], surface.position), "lane {lane}");
        assert!(same(lanes.error[lane], spawn.error), "lane {lane}");
        assert!(same(lanes.geometric_normal[lane], surface.geometric_normal));
        assert!(
            same(lanes.shading_normal[lane], surface.shading_normal),
            "lane {lane}"
        );
        assert_eq!(
            lanes.st[lane].to_array().map(f32::to_bits),
            surface.st.to_array().map(f32::to_bits)
        );
        let mut moved = *footprint;
        moved.transfer(*direction, &surface);
        let g = moved.texture_gradients(*direction, &surface, 16.0);
        let expected = [g.dsdx, g.dtdx, g.dsdy, g.dtdy].map(f32::to_bits);
        assert_eq!(
            lanes.gradients[lane].map(f32::to_bits),
            expected,
            "lane {lane}"
        );
    }
    // The cases the comparison is meant to cover did occur.
    let filtered = (0..rays.len()).filter(|&lane| lanes.gradients[lane] != [0.0; 4]);
    assert!(filtered.count() > 100);
    assert!(lanes.has_st.iter().filter(|&&s| !s).count() == 256);
}

#[test]
fn grouping_by_material_is_stable() {
    let mut lanes = WaveLanes {
        materials: vec![LaneMaterial::default(); 4],
        ..WaveLanes::default()
    };
    for (index, material) in [3u32, 1, 3, 0, 1, 3].into_iter().enumerate() {
        lanes.push(
            index as u32,
            material,
            0,
            0,
            (0.0, 0.0),
            1.0,
            Vec3::Z,
            Vec3::ONE,
            false,
        );
    }
    lanes.group_by_material();
    assert_eq!(lanes.by_material, [3, 1, 4, 0, 2, 5]);
    let runs: Vec<_> = (0..lanes.material_runs.len())
        .map(|run| lanes.material_run(run))
        .collect();
    assert_eq!(runs, [(0, 0..1), (1, 1..3), (3, 3..6)]);
}
