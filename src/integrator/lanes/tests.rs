//! The lane stages against the scalar path they replace: stages 1-3 must give the very bits
//! of `SurfaceLookup::surface_hit`, `Footprint::transfer` and `Footprint::texture_gradients`
//! (under cones and ray differentials), stage 4 those of `shading::surface_inputs` (normal
//! maps and emission textures included), and stages 5-6 those of the lights' samples and the
//! lobes, on triangles, spheres and curved and height patches.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use super::bsdf::{eval_lights, incident_normals};
use super::differentials::differentials_at_hits;
use super::footprints::{lane_footprint, texture_gradients, LaneFootprint};
use super::gather::{gather_spheres, gather_triangles};
use super::interpolate::interpolate;
use super::lights::{sample_lights, shadow_rays};
use super::patches::evaluate_patches;
use super::picks::{LaneHit, LanePicks, LaneSurface};
use super::textures::{lane_emission, shading_inputs};
use super::{LaneMaterial, WaveLanes};
use crate::footprint::{ConeEnvelope, Footprint, RayCone, RayDifferential};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::prepared::{GeometryRef, SurfaceDetail, SurfaceLookup};
use crate::render::surface_textures::shading_inputs as shading_inputs_at;
use crate::render::tracer::TraceHit;
use crate::scene::patch::height::HeightPatch;
use crate::scene::patch::BezierPatch;
use crate::scene::{Light, Material, SceneDescription, Sphere, TriangleMesh};
use crate::shading::surface_inputs::SurfaceInputs;
use crate::texture::Texture;

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
/// (collinear), the second's texture coordinates are missing. And 16 spheres of both
/// materials, of radii from 0.01 to 100, some far from the origin; 8 curved patches, bumpy
/// over a square, half with corner texture coordinates, two with an edge collapsed to a
/// point (as the teapot's lid); 4 height patches.
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
        spheres: (0..16)
            .map(|i| Sphere {
                center: numbers.vec3(if i % 4 == 0 { 2000.0 } else { 10.0 }),
                radius: 10f32.powf(4.0 * numbers.next() - 2.0),
                material: i % 2,
            })
            .collect(),
        patches: (0..8).map(|i| bumpy_patch(numbers, i)).collect(),
        height_patches: (0..4)
            .map(|i| HeightPatch {
                min: Vec2::new(-3.0, -2.0) + Vec2::splat(i as f32),
                max: Vec2::new(3.0, 5.0) + Vec2::splat(i as f32),
                heights: std::array::from_fn(|_| 2.0 * numbers.next() - 1.0),
                material: i % 2,
                march_step: 0.01,
            })
            .collect(),
        ..SceneDescription::default()
    }
}

/// Curved patch `i` of [`scene`]: control points on a square of side 4, moved up and down
/// at random; corner texture coordinates on odd patches; the first row collapsed to one
/// point on patches 2 and 5.
fn bumpy_patch(numbers: &mut Numbers, i: usize) -> BezierPatch {
    let offset = Vec3::new(5.0 * i as f32, 0.0, -3.0);
    let mut control: [Vec3; 16] = std::array::from_fn(|k| {
        let (a, b) = ((k % 4) as f32, (k / 4) as f32);
        offset + Vec3::new(a * 1.3, 2.0 * numbers.next() - 1.0, b * 1.3)
    });
    if i == 2 || i == 5 {
        for k in 1..4 {
            control[k] = control[0];
        }
    }
    BezierPatch {
        control,
        corner_st: (i % 2 == 1).then(|| {
            [
                Vec2::new(0.1, 0.2),
                Vec2::new(2.0, 0.1),
                Vec2::new(0.3, 1.5),
                Vec2::new(1.8, 3.0 * numbers.next()),
            ]
        }),
        material: i % 2,
    }
}

/// The geometries of [`scene`]: its two meshes, then its spheres, curved patches and
/// height patches.
const GEOMETRIES: [GeometryRef; 5] = [
    GeometryRef::Mesh(0),
    GeometryRef::Mesh(1),
    GeometryRef::Spheres,
    GeometryRef::Patches,
    GeometryRef::HeightPatches,
];

/// A wave of hits on [`scene`]: per ray, its hit, origin, direction, footprint and whether
/// it wants texture coordinates. Triangles, spheres and patches take turns, with the two
/// materials, and a seventh of the hits on spheres and patches want no texture coordinates.
fn wave(numbers: &mut Numbers) -> Vec<(TraceHit, Vec3, Vec3, Footprint, bool)> {
    (0..1280u32)
        .map(|index| {
            let (u, v) = (numbers.next(), numbers.next());
            let geometry = index % 5;
            let (u, v) = if u + v > 1.0 && geometry < 3 {
                (1.0 - u, 1.0 - v)
            } else {
                (u, v)
            };
            let primitive = match geometry {
                0 | 1 => (index / 5) % 64,
                2 => (index / 5) % 16,
                3 => (index / 5) % 8,
                _ => (index / 5) % 4,
            };
            let hit = TraceHit {
                u,
                v,
                t: 0.5 + 20.0 * numbers.next(),
                geometry,
                primitive,
            };
            let origin = numbers.vec3(40.0);
            let direction = numbers.vec3(1.0).normalize();
            let footprint = match index % 4 {
                0 | 3 => Footprint::Cone1(RayCone::new(0.0, 0.002 + 0.01 * numbers.next())),
                1 => Footprint::Cone(ConeEnvelope::new(
                    RayCone::new(0.01, 0.003),
                    RayCone::new(0.0, -0.001),
                    false,
                )),
                _ => Footprint::Mip0,
            };
            let wants_st = geometry < 2 || index % 7 != 0;
            (hit, origin, direction, footprint, wants_st)
        })
        .collect()
}

#[test]
fn interpolation_and_gradients_match_the_scalar_path_bit_for_bit_at_every_level() {
    let mut numbers = Numbers(0x9e37_79b9);
    let scene = Arc::new(scene(&mut numbers));
    let rays = wave(&mut numbers);
    check_stages_1_to_3(
        &scene,
        &rays,
        |footprint, t, wants_st| match lane_footprint(footprint, t) {
            LaneFootprint::Cone(width) if wants_st => LaneFootprint::Cone(width),
            _ => LaneFootprint::Point,
        },
    );
}

#[test]
fn ray_differentials_move_to_their_hits_and_give_the_scalar_path_s_gradients_at_every_level() {
    let mut numbers = Numbers(0x2545_f491);
    let scene = Arc::new(scene(&mut numbers));
    // The wave's footprints as differentials: from a point (camera rays), parallel, and
    // spreading after a bounce; a few zero.
    let rays: Vec<_> = wave(&mut numbers)
        .into_iter()
        .enumerate()
        .map(|(index, (hit, origin, direction, _, wants_st))| {
            let scale = [0.0, 1.0e-3, 0.05, 2.0][index % 4];
            let differential = RayDifferential::new(
                numbers.vec3(scale),
                numbers.vec3(scale),
                numbers.vec3(scale * 0.1),
                numbers.vec3(scale * 0.1),
            );
            let footprint = Footprint::Differential(differential);
            (hit, origin, direction, footprint, wants_st)
        })
        .collect();
    // Every lane carries its differential, textured or not, as the path tracer's do.
    check_stages_1_to_3(&scene, &rays, |footprint, t, _| {
        lane_footprint(footprint, t)
    });
}

/// Stages 1-3 over the wave `rays` on `scene` at every level, each ray's footprint taken
/// as `lane_footprint(footprint, t, wants_st)` gives it, against the scalar path.
fn check_stages_1_to_3(
    scene: &Arc<SceneDescription>,
    rays: &[(TraceHit, Vec3, Vec3, Footprint, bool)],
    lane_footprint: impl Fn(&Footprint, f32, bool) -> LaneFootprint,
) {
    let lookup = SurfaceLookup::new(scene.clone(), GEOMETRIES.to_vec());
    // Read only by lanes whose differential the camera replaces, which these are not.
    let camera = crate::camera::Camera::new(
        &crate::scene::CameraDesc {
            eye: Vec3::ZERO,
            target: Vec3::NEG_Z,
            up: Vec3::Y,
            projection: crate::scene::Projection::Pinhole { vfov_degrees: 50.0 },
        },
        64,
        64,
    );
    for level in crate::simd::Level::supported() {
        let mut lanes = lanes_at(level, covered(true, 1.0), 2);
        let mut picks = LanePicks::default();
        for (index, (hit, _, _, footprint, wants_st)) in rays.iter().enumerate() {
            let (surface, material) = LaneSurface::at(&lookup, hit);
            let footprint = lane_footprint(footprint, hit.t, *wants_st);
            picks.push(index, material, surface, footprint);
        }
        let mut lane_of_ray = vec![u32::MAX; rays.len()];
        picks.place(&mut lanes, &mut lane_of_ray, |index, _| {
            let (hit, origin, direction, _, wants_st) = &rays[index];
            LaneHit::new(hit, (*origin, *direction), Vec3::ONE, *wants_st)
        });
        gather_triangles(&mut lanes, &scene.meshes);
        gather_spheres(&mut lanes, &scene.spheres);
        interpolate(&mut lanes);
        evaluate_patches(&mut lanes, &scene.patches, &scene.height_patches);
        differentials_at_hits(&mut lanes, &camera, 1);
        texture_gradients(&mut lanes, 16.0);
        for (index, ray) in rays.iter().enumerate() {
            compare_surface(&lookup, &lanes, lane_of_ray[index] as usize, ray);
        }
        // The cases the comparison is meant to cover did occur.
        let super::LaneSections {
            triangles,
            spheres,
            patches,
        } = lanes.sections();
        let filtered = |lanes_of: std::ops::Range<usize>| {
            lanes_of
                .filter(|&lane| lanes.gradients[lane] != [0.0; 4])
                .count()
        };
        assert!(filtered(triangles.clone()) > 100, "{level:?}");
        assert!(filtered(spheres.clone()) > 100, "{level:?}");
        assert!(filtered(patches.clone()) > 200, "{level:?}");
        assert_eq!(triangles.len(), 512);
        assert_eq!(patches.len(), 512);
        assert!(lanes.height_patch[patches.clone()].iter().any(|&h| h));
        assert!(lanes.height_patch[patches.clone()].iter().any(|&h| !h));
        assert!(lanes.has_st[triangles].iter().filter(|&&s| !s).count() == 256);
        assert!(lanes.has_st[spheres].iter().any(|&s| !s));
        assert!(lanes.has_st[patches].iter().any(|&s| !s));
    }
}

/// Lane `lane` against the scalar path's surface and gradients for `ray`.
fn compare_surface(
    lookup: &SurfaceLookup,
    lanes: &WaveLanes,
    lane: usize,
    (hit, origin, direction, footprint, wants_st): &(TraceHit, Vec3, Vec3, Footprint, bool),
) {
    let detail = if *wants_st {
        SurfaceDetail::Texturing
    } else {
        SurfaceDetail::Geometry
    };
    let surface = lookup.surface_hit(*origin, *direction, hit, detail);
    let spawn = surface.spawn_point();
    let same = |a: Vec3, b: Vec3| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits);
    assert!(
        same(lanes.position.get(lane), spawn.position),
        "lane {lane}"
    );
    assert!(same(lanes.error.get(lane), spawn.error), "lane {lane}");
    assert!(
        same(lanes.surface_point(lane), surface.position),
        "lane {lane}"
    );
    assert!(same(
        lanes.geometric_normal.get(lane),
        surface.geometric_normal
    ));
    assert!(
        same(lanes.shading_normal.get(lane), surface.shading_normal),
        "lane {lane}"
    );
    assert_eq!(
        lanes.st.get(lane).to_array().map(f32::to_bits),
        surface.st.to_array().map(f32::to_bits)
    );
    let mut moved = *footprint;
    moved.transfer(*direction, &surface);
    if let Footprint::Differential(expected) = moved {
        let at_hit = lanes.differential_at_hit[lane];
        let bits = |d: RayDifferential| {
            [d.dpdx, d.dpdy, d.dddx, d.dddy].map(|v| v.to_array().map(f32::to_bits))
        };
        assert_eq!(bits(at_hit), bits(expected), "lane {lane}");
    }
    let g = moved.texture_gradients(*direction, &surface, 16.0);
    let expected = if *wants_st {
        [g.dsdx, g.dtdx, g.dsdy, g.dtdy].map(f32::to_bits)
    } else {
        [0; 4]
    };
    assert_eq!(
        lanes.gradients[lane].map(f32::to_bits),
        expected,
        "lane {lane}"
    );
}

/// Materials of every lobe the lanes run: classic without and with a highlight, and
/// metallic-roughness.
fn lobe_materials() -> Vec<Material> {
    use crate::scene::{ClassicModel, MaterialModel, MetallicRoughnessModel};
    vec![
        Material::default(),
        Material {
            model: MaterialModel::Classic(ClassicModel {
                specular: 0.4,
                shininess: 20.0,
            }),
            ..Material::default()
        },
        Material {
            model: MaterialModel::MetallicRoughness(MetallicRoughnessModel::new(0.5, 0.3)),
            ..Material::default()
        },
    ]
}

/// A point light, a spot light and a directional light.
fn punctual_lights() -> Vec<Light> {
    vec![
        Light::Point {
            position: Vec3::new(1.0, 8.0, -2.0),
            color: Vec3::new(1.0, 0.9, 0.8),
            intensity: 30.0,
        },
        Light::Spot {
            position: Vec3::new(-3.0, 6.0, 1.0),
            direction: Vec3::new(0.3, -1.0, 0.1),
            color: Vec3::ONE,
            intensity: 50.0,
            inner_angle: 0.3,
            outer_angle: 0.9,
        },
        Light::Directional {
            direction: Vec3::new(-0.2, -1.0, 0.4),
            color: Vec3::new(0.5, 0.6, 0.7),
            intensity: 2.0,
        },
    ]
}

/// Stages 5 and 6 at every vector level give the bits of the scalar functions they stand
/// for: `sample_li`, the lobes' `eval`, `SpawnPoint::offset_origin` and
/// `shadow_ray_towards`, on triangle and sphere lanes of three materials pushed out of
/// order; with the second material's opaque lobe of weight 0 (a perfect mirror or clear
/// glass), its lanes are unlit and no light is sampled for them.
#[test]
fn lights_bsdf_and_shadow_rays_match_the_scalar_path_at_every_level() {
    for second_weight in [0.75, 0.0] {
        lights_bsdf_and_shadow_rays_at_every_level(second_weight);
    }
}

fn lights_bsdf_and_shadow_rays_at_every_level(second_weight: f32) {
    let mut numbers = Numbers(0x2545_f491);
    let scene = scene(&mut numbers);
    let materials = lobe_materials();
    let lights = punctual_lights();
    for level in crate::simd::Level::supported() {
        let mut lanes = lanes_at(level, covered(false, 0.75), materials.len());
        lanes.materials[1].opaque_weight = second_weight;
        let mut picks = LanePicks::default();
        let mut hits = Vec::new();
        for index in 0..300u32 {
            let (u, v) = (numbers.next() * 0.5, numbers.next() * 0.5);
            let direction = numbers.vec3(1.0).normalize();
            let throughput = Vec3::new(numbers.next(), 1.0, numbers.next());
            let material = (index * 7 + index / 5) % 3;
            let geometry = index % 3;
            let primitive = if geometry == 2 {
                index % 16
            } else {
                1 + index % 63
            };
            let hit = TraceHit {
                u,
                v,
                t: 1.0 + numbers.next(),
                geometry,
                primitive,
            };
            let surface = match GEOMETRIES[geometry as usize] {
                GeometryRef::Mesh(mesh) => LaneSurface::Mesh(mesh),
                _ => LaneSurface::Sphere,
            };
            picks.push(
                index as usize,
                material as usize,
                surface,
                LaneFootprint::Point,
            );
            let origin = numbers.vec3(30.0);
            hits.push(LaneHit::new(&hit, (origin, direction), throughput, false));
        }
        let mut lane_of_ray = vec![u32::MAX; hits.len()];
        picks.place(&mut lanes, &mut lane_of_ray, |index, _| hits[index]);
        // The materials were picked out of order: placing them reordered the lanes.
        assert!(lane_of_ray
            .iter()
            .enumerate()
            .any(|(i, &l)| i != l as usize));
        gather_triangles(&mut lanes, &scene.meshes);
        gather_spheres(&mut lanes, &scene.spheres);
        interpolate(&mut lanes);
        assert_eq!(lanes.sections().spheres.len(), 100);
        let len = lanes.len();
        lanes.albedo.resize(len);
        lanes.metallic.resize(len, 0.0);
        lanes.roughness.resize(len, 0.0);
        for lane in 0..len {
            lanes
                .albedo
                .set(lane, Vec3::new(numbers.next(), numbers.next(), 0.5));
            lanes.metallic[lane] = numbers.next();
            lanes.roughness[lane] = numbers.next();
        }
        incident_normals(&mut lanes);
        // Entries no light sample writes keep this.
        lanes.light_direction.resize(len * lights.len());
        for lane in 0..len * lights.len() {
            lanes.light_direction.set(lane, Vec3::NAN);
        }
        sample_lights(&mut lanes, &lights);
        eval_lights(&mut lanes, &materials, lights.len());
        shadow_rays(&mut lanes, &lights);
        let lit = compare_with_scalar(&lanes, &materials, &lights);
        let least = if second_weight > 0.0 { 100 } else { 60 };
        assert!(lit > least && lit < 3 * len - 100, "{level:?}: {lit} lit");
    }
}

/// Every lane and light of `lanes` against the scalar path; returns how many were lit.
fn compare_with_scalar(lanes: &WaveLanes, materials: &[Material], lights: &[Light]) -> usize {
    use crate::scene::MaterialModel;
    use crate::shading::{self, Bsdf, MetallicRoughnessBsdf, OpaqueBsdf, SpawnPoint};
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    let len = lanes.len();
    let mut lit = 0;
    for lane in 0..len {
        let direction = lanes.direction.get(lane);
        let (g, s) = (
            lanes.geometric_normal.get(lane),
            lanes.shading_normal.get(lane),
        );
        let front = direction.dot(g) < 0.0;
        let (ng, ns) = if front { (g, s) } else { (-g, -s) };
        assert_eq!(bits(lanes.incident_geometric.get(lane)), bits(ng));
        assert_eq!(bits(lanes.incident_shading.get(lane)), bits(ns));
        let spawn = SpawnPoint {
            position: lanes.position.get(lane),
            error: lanes.error.get(lane),
        };
        let origin = spawn.offset_origin(ng);
        assert_eq!(
            bits(lanes.shadow_origin.get(lane)),
            bits(origin),
            "lane {lane}"
        );
        let (albedo, material) = (lanes.albedo.get(lane), lanes.material[lane] as usize);
        let weight = lanes.materials[material].opaque_weight;
        if weight <= 0.0 {
            for index in 0..lights.len() {
                let at = index * len + lane;
                assert!(!lanes.lit[at], "lane {lane} light {index}: no opaque lobe");
                let sampled = lanes.light_direction.get(at);
                assert!(sampled.is_nan(), "lane {lane}: a light sampled, {sampled}");
            }
            continue;
        }
        let eval = |wi: Vec3| match &materials[material].model {
            MaterialModel::Classic(c) => OpaqueBsdf {
                n: ns,
                albedo,
                specular: c.specular,
                shininess: c.shininess,
            }
            .eval(-direction, wi),
            MaterialModel::MetallicRoughness(_) => {
                MetallicRoughnessBsdf::new(ns, albedo, lanes.roughness[lane], lanes.metallic[lane])
                    .eval(-direction, wi)
            }
        };
        for (index, light) in lights.iter().enumerate() {
            let at = index * len + lane;
            let sample = shading::sample_li(light, spawn.position);
            let wi = sample.direction_to_light;
            assert_eq!(bits(lanes.light_direction.get(at)), bits(wi));
            assert_eq!(bits(lanes.light_scale.get(at)), bits(sample.radiance_scale));
            let mut expected = (Vec3::ZERO, false);
            if !(wi.dot(ng) <= 0.0 || wi.dot(ns) <= 0.0) {
                let f = eval(wi) * ns.dot(wi);
                let c = lanes.throughput.get(lane) * weight * f * sample.radiance_scale;
                expected = (c, c.max_element() > 0.0);
            }
            let target = shading::light_position(light).map(|p| (p.as_dvec3(), 0.0));
            let segment = shading::shadow_ray_towards(origin, target, wi);
            expected.1 &= segment.is_some();
            assert_eq!(
                bits(lanes.contribution.get(at)),
                bits(expected.0),
                "lane {lane}"
            );
            assert_eq!(lanes.lit[at], expected.1, "lane {lane} light {index}");
            if let (true, Some((direction, tfar))) = (expected.1, segment) {
                assert_eq!(bits(lanes.shadow_direction.get(at)), bits(direction));
                assert_eq!(lanes.shadow_tfar[at].to_bits(), tfar.to_bits());
                lit += 1;
            }
        }
    }
    lit
}

/// A material both integrators' lanes cover.
fn covered(textured: bool, opaque_weight: f32) -> LaneMaterial {
    LaneMaterial {
        spawns: false,
        textured,
        normal_mapped: false,
        opaque_weight,
        emits: false,
    }
}

/// Empty lanes at the vector level `level`, for `count` materials alike.
fn lanes_at(level: crate::simd::Level, material: LaneMaterial, count: usize) -> WaveLanes {
    WaveLanes {
        materials: vec![material; count],
        level: Some(level),
        ..WaveLanes::default()
    }
}

/// [`scene`] with a camera, two textures (random colours, random tangent-space normals)
/// and both materials normal-mapped: the first a metallic-roughness emitter with base
/// colour and emission textures (on the mesh with texture coordinates and half the
/// spheres), the second classic and untextured otherwise (on the mesh without texture
/// coordinates, whose hits have no tangent frame, and the other spheres).
fn normal_mapped_scene(numbers: &mut Numbers) -> (SceneDescription, Vec<Arc<Texture>>) {
    use crate::scene::{
        CameraDesc, MaterialModel, MetallicRoughnessModel, Projection, TextureBinding, TextureDesc,
        TextureSource,
    };
    let mut scene = scene(numbers);
    let binding = |texture| {
        Some(TextureBinding {
            texture,
            transform: glam::Affine2::IDENTITY,
        })
    };
    scene.materials = vec![
        Material {
            model: MaterialModel::MetallicRoughness(MetallicRoughnessModel::new(0.4, 0.6)),
            base_color_texture: binding(0),
            emission: Vec3::new(2.0, 1.0, 0.5),
            emission_texture: binding(0),
            normal_texture: binding(1),
            normal_scale: 1.5,
            ..Material::default()
        },
        Material {
            normal_texture: binding(1),
            normal_scale: 0.8,
            ..Material::default()
        },
    ];
    scene.textures = ["colours", "normals"]
        .map(|name| TextureDesc {
            name: name.into(),
            source: TextureSource::Encoded {
                label: name.into(),
                bytes: Arc::new(Vec::new()),
            },
            color_space: Some(crate::scene::ColorSpace::Linear),
            wrap_s: crate::scene::WrapMode::Periodic,
            wrap_t: crate::scene::WrapMode::Periodic,
        })
        .to_vec();
    scene.camera = Some(CameraDesc {
        eye: Vec3::new(0.0, 0.0, 50.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        projection: Projection::Pinhole { vfov_degrees: 40.0 },
    });
    // The normals' blue channel mostly above 0.5: most texels point out of the surface.
    let mut texture = |blue_from: f32| {
        let texels = (0..256)
            .map(|_| {
                let blue = blue_from + (1.0 - blue_from) * numbers.next();
                [numbers.next(), numbers.next(), blue, 1.0]
            })
            .collect();
        Arc::new(Texture::from_rgba_f32(16, 16, texels).expect("a 16x16 texture"))
    };
    let textures = vec![texture(0.0), texture(0.4)];
    (scene, textures)
}

/// Stage 4 of a normal-mapped emitter and a normal-mapped diffuse material, after stages
/// 1-3 at every vector level, against the scalar path (`SurfaceLookup::surface_hit`,
/// `Footprint::texture_gradients`, `surface_textures::shading_inputs`): the same albedo,
/// metallic, roughness, emission and bent shading normal, bit for bit, from as many texture
/// lookups.
#[test]
fn normal_maps_and_emission_textures_match_the_scalar_path_at_every_level() {
    let mut numbers = Numbers(0x5bd1_e995);
    let (scene, textures) = normal_mapped_scene(&mut numbers);
    let scene = Arc::new(scene);
    let options = crate::render::RenderOptions::from_settings(&scene.settings);
    let context = crate::render::prepare_with_textures(scene.clone(), options, textures)
        .expect("prepare the scene");
    assert!(context.effects.footprints);
    let rays = wave(&mut numbers);
    for level in crate::simd::Level::supported() {
        let mut lanes = WaveLanes {
            level: Some(level),
            ..WaveLanes::default()
        };
        lanes.prepare(&context);
        assert!(lanes
            .materials
            .iter()
            .all(|m| m.normal_mapped && m.textured));
        let mut picks = LanePicks::default();
        for (index, (hit, _, _, footprint, _)) in rays.iter().enumerate() {
            let footprint = lane_footprint(footprint, hit.t);
            let (surface, material) = LaneSurface::at(&context.surfaces, hit);
            picks.push(index, material, surface, footprint);
        }
        let mut lane_of_ray = vec![u32::MAX; rays.len()];
        picks.place(&mut lanes, &mut lane_of_ray, |index, _| {
            let (hit, origin, direction, _, _) = &rays[index];
            LaneHit::new(hit, (*origin, *direction), Vec3::ONE, true)
        });
        let mut worker = WorkerState::default();
        gather_triangles(&mut lanes, &scene.meshes);
        gather_spheres(&mut lanes, &scene.spheres);
        interpolate(&mut lanes);
        evaluate_patches(&mut lanes, &scene.patches, &scene.height_patches);
        texture_gradients(&mut lanes, context.options.filter.max_aniso);
        shading_inputs(&context, &mut lanes, &mut worker);
        let mut scalar_worker = WorkerState::default();
        let mut bent = 0;
        for (index, ray) in rays.iter().enumerate() {
            let lane = lane_of_ray[index] as usize;
            let inputs = scalar_inputs(&context, ray, &mut scalar_worker);
            compare_inputs(&lanes, lane, &inputs, &scene.materials);
            let unbent =
                context
                    .surfaces
                    .surface_hit(ray.1, ray.2, &ray.0, SurfaceDetail::Geometry);
            bent += usize::from(inputs.shading_normal != unbent.shading_normal);
        }
        assert_eq!(
            worker.counters.texture_lookups,
            scalar_worker.counters.texture_lookups
        );
        // The normal maps bent most normals on the mesh with texture coordinates and on
        // the spheres (a steep texel below the surface leaves one alone).
        assert!(bent > 300, "{level:?}: {bent} normals bent");
    }
}

/// The scalar path's shading inputs for `ray` (`texturing::surface_inputs` with the
/// footprint carried to the hit).
fn scalar_inputs(
    context: &RenderContext,
    (hit, origin, direction, footprint, _): &(TraceHit, Vec3, Vec3, Footprint, bool),
    worker: &mut WorkerState,
) -> SurfaceInputs {
    let detail = context
        .surfaces
        .detail_needed(hit, false, context.effects.footprints);
    let surface = context
        .surfaces
        .surface_hit(*origin, *direction, hit, detail);
    let material = &context.scene.materials[surface.material as usize];
    let mut moved = *footprint;
    moved.transfer(*direction, &surface);
    let max_aniso = context.options.filter.max_aniso;
    let g = moved.texture_gradients(*direction, &surface, max_aniso);
    let gradients = [g.dsdx, g.dtdx, g.dsdy, g.dtdy];
    shading_inputs_at(
        context,
        material,
        &surface,
        gradients,
        false,
        worker,
        |_, _, _| {},
    )
}

/// Lane `lane`'s inputs against the scalar path's `inputs`, bit for bit.
fn compare_inputs(lanes: &WaveLanes, lane: usize, inputs: &SurfaceInputs, materials: &[Material]) {
    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
    let material = &materials[lanes.material[lane] as usize];
    assert_eq!(
        bits(lanes.albedo.get(lane)),
        bits(inputs.albedo),
        "lane {lane}"
    );
    assert_eq!(lanes.metallic[lane].to_bits(), inputs.metallic.to_bits());
    if let Some(roughness) = inputs.roughness {
        assert_eq!(lanes.roughness[lane].to_bits(), roughness.to_bits());
    }
    assert_eq!(
        bits(lane_emission(lanes, material, lane)),
        bits(inputs.emission),
        "lane {lane}"
    );
    assert_eq!(
        bits(lanes.shading_normal.get(lane)),
        bits(inputs.shading_normal),
        "lane {lane}"
    );
}
