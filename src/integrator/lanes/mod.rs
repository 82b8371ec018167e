//! Shading a wave's hits on triangles, analytic spheres and curved patches together, stage
//! by stage, over lane arrays (structure of arrays, one array per coordinate): each stage is a plain loop
//! over slices that reads the arrays the stages before it wrote, so no per-ray record
//! (`SurfaceHit` with its `Patch`, `SurfaceInputs`, `MaterialBsdf`) is built or copied
//! between stages, and the arrays live in the per-thread state, reused from wave to wave.
//!
//! The lanes are placed in three sections ([`LaneSections`]): the triangle lanes, the
//! sphere lanes, then the lanes on curved and height patches, each ordered by material
//! ([`picks::LanePicks::place`]), so a material's lanes on one kind of surface are one range
//! of every array and stages 1-3 run one loop per kind. The stages, in order:
//! 1. [`gather`]: the triangles' vertex positions, normals and texture coordinates, the
//!    spheres' centres and radii;
//! 2. [`interpolate`]: the point and its rounding-error bound, the geometric and shading
//!    normals, texture coordinates, the triangle's edges, and the sphere's dP/ds, dP/dt
//!    (the triangle's too where a normal map needs its tangent frame); and [`patches`]:
//!    stages 1 and 2 in one on patches, each lane's patch evaluated at its (u, v) in double
//!    precision, with the exact derivatives its footprint reads;
//! 3. [`differentials`] and [`footprints`]: each textured lane's footprint at the hit (a
//!    cone's width, a ray differential transferred there) and its texture gradients;
//! 4. [`textures`]: the lookups, each texture binding read for its material's range in one
//!    loop: albedo, metallic, roughness, emission, and the shading normal bent by a normal
//!    map;
//! 5. [`lights`]: the punctual lights' samples, one light at a time over all lanes;
//! 6. [`bsdf`]: the opaque lobe evaluated for every lane and light, one loop per material's
//!    range, so each loop runs one lobe's code.
//!
//! Stages 2, 3, 5 and 6 run through `simd::run_at` at [`WaveLanes::level`] (the level
//! `simd::dispatch` would pick), their loops and everything they call inlined into the
//! level's function, so they are compiled for AVX2 and AVX-512 as well as the baseline.
//!
//! The rays that leave the scene have the environment looked up together ([`misses`]).
//!
//! Accumulating into the film (stage 7) is the integrator's: it keeps the order in which
//! the wave's rays add to their pixels, so the sums are those of the scalar path.
//!
//! The arithmetic is the scalar path's (`render::prepared::SurfaceLookup::surface_hit`,
//! `footprint::Footprint::texture_gradients`, `shading::surface_inputs`, the lobes' `eval`),
//! operation for operation, so images are bit for bit the same at every level. Which hits
//! the lanes cover is the integrator's choice of lanes; the rest takes the scalar path.

pub(crate) mod bsdf;
pub(crate) mod differentials;
pub(crate) mod footprints;
pub(crate) mod gather;
pub(crate) mod interpolate;
pub(crate) mod lights;
pub(crate) mod misses;
pub(crate) mod patches;
pub(crate) mod picks;
pub(crate) mod soa;
pub(crate) mod textures;

use glam::{Vec3, Vec4};

use self::differentials::LaneDifferential;
use self::patches::PatchDerivatives;
use self::soa::{Vec2Lanes, Vec3Lanes};

use crate::footprint::RayDifferential;
use crate::render::context::RenderContext;
use crate::scene::Material;
use crate::simd;
use crate::texture::TextureQuery;

/// What the lanes need to know of a material, computed once per render.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct LaneMaterial {
    /// Whether Whitted's waves spawn rays at this material: its mirror lobe reflects or its
    /// dielectric boundary refracts and reflects in this render (see [`LaneMaterial::of`]),
    /// so a lane of it builds the material's BSDF for those rays.
    pub spawns: bool,
    /// Whether shading reads a texture (`render::surface_textures::reads_textures`).
    pub textured: bool,
    /// Whether a normal map bends the shading normal, so the triangle lanes need dP/ds and
    /// dP/dt (`interpolate`) and stage 4 bends the normal (`textures`).
    pub normal_mapped: bool,
    /// The opaque lobe's weight, `(1 - mirror) (1 - transmission)` as
    /// `shading::MaterialBsdf` computes it.
    pub opaque_weight: f32,
    /// Whether the material emits light (a nonzero `emission`): a hit on any other adds no
    /// emitted light, so its side and its emission are not looked at.
    pub emits: bool,
}

impl LaneMaterial {
    /// What the lanes need of `material` in `context`'s render. A material spawns rays where
    /// `shading::MaterialBsdf::whitted_lobes` gives it a mirror or a dielectric boundary
    /// (a positive weight) that the render's effects keep.
    pub(crate) fn of(context: &RenderContext, material: &Material) -> LaneMaterial {
        let effects = &context.effects;
        let opaque_weight = (1.0 - material.mirror) * (1.0 - material.transmission);
        let spawns = (effects.mirror_reflection && material.mirror > 0.0)
            || (effects.refraction && material.transmission > 0.0);
        LaneMaterial {
            spawns,
            textured: crate::render::surface_textures::reads_textures(material),
            normal_mapped: material.normal_texture.is_some(),
            opaque_weight,
            emits: material.emission != glam::Vec3::ZERO,
        }
    }
}

/// The lane arrays of one wave, reused from wave to wave (nothing is allocated once they
/// have grown to the largest wave). Vectors are stored one array per coordinate
/// ([`soa::Vec3Lanes`]), and the lanes are ordered by material
/// ([`picks::LanePicks::place`]), so each stage is a straight loop over consecutive
/// floats and each material's lanes are one range.
#[derive(Default)]
pub(crate) struct WaveLanes {
    /// Per material of the scene being rendered.
    pub materials: Vec<LaneMaterial>,
    /// The scene the table was made for (its address), so a state reused for another
    /// scene rebuilds it.
    scene: usize,
    /// The vector level the stages run at; `None`: `simd::active()` (tests set each level).
    pub level: Option<simd::Level>,

    // Set by the integrator when it picks the lanes.
    /// Index of each lane's ray and hit in the wave.
    pub wave_index: Vec<u32>,
    pub material: Vec<u32>,
    /// The mesh (index into `SceneDescription::meshes`) of each triangle lane.
    pub mesh: Vec<u32>,
    /// Whether a patch lane's patch is a height patch (index into
    /// `SceneDescription::height_patches`) rather than a curved one (into `patches`).
    pub height_patch: Vec<bool>,
    /// The triangle of the lane's mesh, or the sphere (index into
    /// `SceneDescription::spheres`), or the patch.
    pub primitive: Vec<u32>,
    /// Barycentrics as the intersector reported them (triangle lanes), or the patch's
    /// (u, v).
    pub u: Vec<f32>,
    pub v: Vec<f32>,
    /// Hit distance along the ray, as the intersector reported it.
    pub t: Vec<f32>,
    /// The ray's origin (read by sphere lanes, whose point is projected from the ray's).
    pub origin: Vec3Lanes,
    /// Unit ray direction.
    pub direction: Vec3Lanes,
    /// Lanes `spheres_start..patches_start` lie on spheres, those before them on triangles,
    /// those after them on patches ([`LaneSections`]): each section ordered by material, so
    /// stages 1-3 run one straight loop per kind of surface.
    pub spheres_start: usize,
    pub patches_start: usize,
    /// Whether the lane needs texture coordinates (its material reads a texture, or the
    /// uv AOV is written from it).
    pub wants_st: Vec<bool>,
    /// The ray's throughput (what it carries from the camera).
    pub throughput: Vec3Lanes,
    /// The footprint's width at the hit, for a textured material under a cone-like
    /// footprint (`None`: a point sample).
    pub cone_width: Vec<Option<f32>>,
    /// The ray differential of each lane that carries one, and how it reaches the hit;
    /// empty when no lane of the wave does.
    pub differential: Vec<Option<LaneDifferential>>,

    // Stage 1.
    pub p: [Vec3Lanes; 3],
    /// Vertex normals as stored (zero for meshes without them, which interpolate to zero
    /// and fall back to the geometric normal as the scalar path's missing normals do).
    pub n: [Vec3Lanes; 3],
    /// Vertex texture coordinates, read only for textured lanes.
    pub st_vertices: [Vec2Lanes; 3],
    /// Whether the lane wants texture coordinates and its mesh has them (every sphere has
    /// them).
    pub has_st: Vec<bool>,
    /// Sphere lanes: the sphere's centre and radius.
    pub center: Vec3Lanes,
    pub radius: Vec<f32>,

    // Stage 2.
    pub position: Vec3Lanes,
    /// The bound on the rounding error of `position` (`shading::SpawnPoint`).
    pub error: Vec3Lanes,
    pub edge1: Vec3Lanes,
    pub edge2: Vec3Lanes,
    /// `edge1 x edge2`, the triangle's unnormalised normal.
    pub area_normal: Vec3Lanes,
    /// Unit normals, facing outward (geometric) and to the same side (shading). Stage 4
    /// bends the shading normal of normal-mapped lanes (`SurfaceInputs::shading_normal`).
    pub geometric_normal: Vec3Lanes,
    pub shading_normal: Vec3Lanes,
    pub st: Vec2Lanes,
    /// Sphere lanes: the ray's point projected onto the sphere (`SurfaceHit::position`),
    /// from which `position`, the spawn point, is projected once more as
    /// `SurfaceHit::spawn_point` projects it.
    pub sphere_point: Vec3Lanes,
    /// Sphere lanes that want texture coordinates: dP/ds and dP/dt of the lat-long
    /// parameterisation (`footprint::lat_long_frame`). Triangle lanes of normal-mapped
    /// materials: the triangle's (`prepared::triangle_position_derivatives`, zero without
    /// texture coordinates). Other triangle lanes leave them unwritten: nothing reads them.
    /// Patch lanes that want texture coordinates: the patch's (zero elsewhere).
    pub dpds: Vec3Lanes,
    pub dpdt: Vec3Lanes,
    /// Patch lanes, from `patches_start`: the patch's exact derivatives at the hit, which
    /// their footprints map to st (`footprint::curved_st_offset`).
    pub patch_derivatives: Vec<PatchDerivatives>,

    // Stage 3.
    /// Each lane's differential at its hit (`differentials::differentials_at_hits`);
    /// empty when no lane carries one.
    pub differential_at_hit: Vec<RayDifferential>,
    /// `[ds/dx, dt/dx, ds/dy, dt/dy]`, zero for a point sample.
    pub gradients: Vec<[f32; 4]>,
    /// Textured lanes on triangles without barycentric offsets (degenerate), or on spheres
    /// without dP/ds and dP/dt, whose gradients take the lane-by-lane path.
    pub degenerate: Vec<bool>,

    // Stage 4.
    pub albedo: Vec3Lanes,
    pub metallic: Vec<f32>,
    /// Perceptual roughness of metallic-roughness lanes (unused by classic ones).
    pub roughness: Vec<f32>,
    /// Emitted radiance of the lanes of emitters with an emission texture (other lanes
    /// leave it unwritten: their emission is their material's, see
    /// [`textures::lane_emission`]).
    pub emission: Vec3Lanes,
    /// The lanes one lookup of a texture binding is for (a normal map is read only where
    /// the hit has a tangent frame), with their queries and texels.
    pub texture_lanes: Vec<u32>,
    pub texture_queries: Vec<TextureQuery>,
    pub texels: Vec<Vec4>,
    /// Whether stage 4 keeps each lane's base-colour lookup, for a render that writes the
    /// texture-lookup AOVs (set by the integrator as it picks the lanes).
    pub keeps_base_color_lookups: bool,
    /// When kept: each lane's base-colour lookup, its query and texel (`None` where the
    /// lane's material has no base-colour texture), which the integrator records as its
    /// pixel's first lookup in the wave's order.
    pub base_color_lookups: Vec<Option<(TextureQuery, Vec4)>>,

    // Stage 5.
    /// Per light and lane (light-major): unit direction to the light and its irradiance
    /// scale (`shading::LightSample`).
    pub light_direction: Vec3Lanes,
    pub light_scale: Vec3Lanes,
    /// Per lane: where its shadow rays start; per light and lane: their direction and far
    /// end.
    pub shadow_origin: Vec3Lanes,
    pub shadow_direction: Vec3Lanes,
    pub shadow_tfar: Vec<f32>,

    // Stage 6.
    /// The normals on the viewer's side.
    pub incident_geometric: Vec3Lanes,
    pub incident_shading: Vec3Lanes,
    /// Per light and lane: what the light delivers if unoccluded, and whether it delivers
    /// anything (a shadow ray is traced).
    pub contribution: Vec3Lanes,
    pub lit: Vec<bool>,

    /// The runs of one material in lane order: `(material, end)`.
    pub material_runs: Vec<(u32, usize)>,
    material_counts: Vec<usize>,
    /// The lane of each picked hit, in the wave's order (`lay_out_by_material`).
    lane_of_pick: Vec<u32>,
    /// Each picked hit's place in the layout: its material, counted after every material's
    /// triangle lanes when it lies on a sphere.
    section_keys: Vec<u32>,
}

impl WaveLanes {
    /// Make the material table for `context`'s scene unless it was made for it already.
    pub(crate) fn prepare(&mut self, context: &RenderContext) {
        let scene = std::sync::Arc::as_ptr(&context.scene) as usize;
        if self.scene == scene && self.materials.len() == context.scene.materials.len() {
            return;
        }
        self.scene = scene;
        self.materials.clear();
        self.materials.extend(
            context
                .scene
                .materials
                .iter()
                .map(|m| LaneMaterial::of(context, m)),
        );
    }

    /// The vector level the stages run at.
    #[inline]
    pub(crate) fn level(&self) -> simd::Level {
        self.level.unwrap_or_else(simd::active)
    }

    /// Number of lanes.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.wave_index.len()
    }

    /// Forget the previous wave's lanes.
    pub(crate) fn clear(&mut self) {
        self.wave_index.clear();
        self.material.clear();
        self.mesh.clear();
        self.primitive.clear();
        self.u.clear();
        self.v.clear();
        self.t.clear();
        self.origin.clear();
        self.direction.clear();
        self.spheres_start = 0;
        self.patches_start = 0;
        self.throughput.clear();
        self.wants_st.clear();
        self.cone_width.clear();
        self.differential.clear();
    }

    /// Lay out one lane for each picked hit, `materials` holding their materials and
    /// `sections` the section of their surface ([`LaneSections`]: 0 triangles, 1 spheres,
    /// 2 patches), in the wave's order: one section after the other, each ordered by
    /// material (stably), the runs recorded in `material_runs`, and `lane_of_pick[k]` set
    /// to the lane of the `k`-th picked hit, for [`picks::LanePicks::place`] to fill.
    fn lay_out_by_material(&mut self, materials: &[u32], sections: &[u32]) {
        let scene_materials = self.materials.len();
        self.section_keys.clear();
        self.section_keys.extend(
            materials
                .iter()
                .zip(sections)
                .map(|(&m, &section)| m + section * scene_materials as u32),
        );
        count_material_runs(
            &mut self.material_counts,
            &mut self.material_runs,
            scene_materials,
            &self.section_keys,
        );
        self.spheres_start = sections.iter().filter(|&&section| section == 0).count();
        self.patches_start = sections.iter().filter(|&&section| section <= 1).count();
        self.lane_of_pick.clear();
        self.lane_of_pick
            .extend(self.section_keys.iter().map(|&key| {
                let next = &mut self.material_counts[key as usize];
                *next += 1;
                (*next - 1) as u32
            }));
        let len = materials.len();
        for values in [
            &mut self.wave_index,
            &mut self.material,
            &mut self.mesh,
            &mut self.primitive,
        ] {
            values.resize_lanes(len, 0);
        }
        for values in [&mut self.u, &mut self.v, &mut self.t] {
            values.resize_lanes(len, 0.0);
        }
        self.origin.resize(len);
        self.direction.resize(len);
        self.throughput.resize(len);
        self.wants_st.resize_lanes(len, false);
        self.height_patch.resize_lanes(len, false);
        self.cone_width.resize_lanes(len, None);
    }

    /// The lanes of each kind of surface.
    #[inline]
    pub(crate) fn sections(&self) -> LaneSections {
        LaneSections {
            triangles: 0..self.spheres_start,
            spheres: self.spheres_start..self.patches_start,
            patches: self.patches_start..self.len(),
        }
    }

    /// The point on the surface at lane `lane` (`SurfaceHit::position`): the spawn point's
    /// on triangles and patches, the first projection of the ray's point on spheres.
    #[inline]
    pub(crate) fn surface_point(&self, lane: usize) -> Vec3 {
        if (self.spheres_start..self.patches_start).contains(&lane) {
            self.sphere_point.get(lane)
        } else {
            self.position.get(lane)
        }
    }

    /// Run `run` of the ordered lanes: its material and its range of lanes (a material
    /// with lanes on several kinds of surface has a run in each section).
    pub(crate) fn material_run(&self, run: usize) -> (u32, std::ops::Range<usize>) {
        let start = match run {
            0 => 0,
            _ => self.material_runs[run - 1].1,
        };
        let (material, end) = self.material_runs[run];
        (material, start..end)
    }

    /// The lanes of material run `run` if its material has an opaque lobe (of positive
    /// weight): the lanes that punctual lights can light.
    pub(crate) fn opaque_run(&self, run: usize) -> Option<std::ops::Range<usize>> {
        let (material, range) = self.material_run(run);
        (self.materials[material as usize].opaque_weight > 0.0).then_some(range)
    }
}

/// The `(material, end)` runs of lanes with section keys `keys` (a material, plus
/// `scene_materials` times the section) once ordered by key into `runs`, and in `counts`
/// (one per key) where each key's first lane goes.
fn count_material_runs(
    counts: &mut Vec<usize>,
    runs: &mut Vec<(u32, usize)>,
    scene_materials: usize,
    keys: &[u32],
) {
    counts.clear();
    counts.resize(LaneSections::COUNT * scene_materials, 0);
    for &key in keys {
        counts[key as usize] += 1;
    }
    runs.clear();
    let mut end = 0;
    for (key, count) in counts.iter_mut().enumerate() {
        let start = end;
        end += *count;
        if *count > 0 {
            runs.push(((key % scene_materials) as u32, end));
        }
        *count = start;
    }
}

/// The lanes of a wave by the kind of surface they lie on, one range after the other.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct LaneSections {
    pub triangles: std::ops::Range<usize>,
    pub spheres: std::ops::Range<usize>,
    /// Curved and height patches.
    pub patches: std::ops::Range<usize>,
}

impl LaneSections {
    /// How many sections there are.
    const COUNT: usize = 3;
}

/// Lanes a lane array makes room for when it first grows: a whole camera wave (a work tile
/// of 16 x 16 pixels with 16 samples in flight), so that a render's arrays take their size
/// in one step, whichever tile's wave is the largest, and grow again only for larger
/// secondary waves (by powers of two).
const WAVE_LANES: usize = 16 * 16 * 16;

/// Resizing a lane array with room for [`WAVE_LANES`] at least.
pub(crate) trait LaneArray<T> {
    /// `Vec::resize`, growing the capacity to a power of two of at least [`WAVE_LANES`].
    fn resize_lanes(&mut self, len: usize, value: T);
}

impl<T: Clone> LaneArray<T> for Vec<T> {
    #[inline]
    fn resize_lanes(&mut self, len: usize, value: T) {
        if self.capacity() < len {
            let room = len.next_power_of_two().max(WAVE_LANES);
            self.reserve_exact(room - self.len());
        }
        self.resize(len, value);
    }
}

/// `buffer` cleared and filled with `len` copies of `value`, reusing its allocation.
#[inline]
pub(crate) fn refill<T: Copy>(buffer: &mut Vec<T>, len: usize, value: T) {
    buffer.clear();
    buffer.resize_lanes(len, value);
}

#[cfg(test)]
mod tests;
