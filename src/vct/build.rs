//! Building the voxel scene of a prepared render: grid frame, conservative voxelisation,
//! direct-light injection, the mip pyramid and optional extra bounces, timed and measured
//! for `--stats`.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::bounce::{add_bounce, gather_groups, GatherGroups, SurfaceVoxel, GATHER_LEVEL};
use super::grid::{
    default_resolution, GridFrame, VoxelKind, VoxelLevel, VoxelPyramid, DEFAULT_MEMORY_BUDGET,
};
use super::inject::{light_fragments, LitFragment};
use super::mipmap::build_pyramid;
use super::voxelise::{sphere_fragments, triangle_fragments, Fragment};
use crate::render::context::RenderContext;
use crate::scene::SceneDescription;

/// Triangles voxelised per parallel task.
const TRIANGLES_PER_TASK: usize = 256;

/// The largest accepted `--vct-resolution`.
pub const MAX_RESOLUTION: u32 = 1024;
/// The largest pyramid an explicit resolution may ask for.
pub const MAX_PYRAMID_BYTES: u64 = 4 << 30;

/// Light bounces the voxels hold unless told otherwise: direct light and two extra bounces.
/// On the Cornell boxes (64x64, against the path tracer at 64 spp) vct's mean is 76.5 / 78.8 %
/// of the path tracer's with 1, 88.6 / 91.0 % with 2, 94.4 / 97.2 % with 3 and 97.3 / 100.3 %
/// with 4 (`docs/vct.md`); each extra bounce costs one shared gather per block
/// ([`super::bounce::GATHER_LEVEL`]).
pub const DEFAULT_BOUNCES: u32 = 3;

/// What the user chose for the voxelisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VctSettings {
    /// Voxels across the longest side of the scene; `None`: the default rule
    /// ([`default_resolution`]).
    pub resolution: Option<u32>,
    /// Light bounces held by the voxels: 1 = direct light only, 2 = one extra bounce
    /// ([`DEFAULT_BOUNCES`] by default).
    pub bounces: u32,
    /// What a voxel above level 0 holds (`--vct-voxels`).
    pub voxels: VoxelKind,
}

impl Default for VctSettings {
    fn default() -> Self {
        VctSettings {
            resolution: None,
            bounces: DEFAULT_BOUNCES,
            voxels: VoxelKind::default(),
        }
    }
}

/// Why the voxel scene could not be built.
#[derive(Debug, thiserror::Error)]
pub enum VctError {
    #[error("--vct-resolution must be between 2 and {MAX_RESOLUTION}, got {0}")]
    Resolution(u32),
    #[error("--vct-bounces must be between 1 and 8, got {0}")]
    Bounces(u32),
    #[error("a voxel grid of resolution {resolution} needs {bytes} bytes, more than the {MAX_PYRAMID_BYTES} allowed")]
    TooLarge { resolution: u32, bytes: u64 },
    #[error("tracing shadow rays for the voxels failed: {0}")]
    Trace(String),
}

/// What building the voxel scene did and cost (`--stats`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct VctBuildStats {
    pub resolution: u32,
    /// `directional` or `isotropic` ([`VoxelKind::name`]).
    pub voxels: &'static str,
    pub dims: [u32; 3],
    pub voxel_size: f32,
    pub levels: usize,
    /// Level-0 voxels some surface touches.
    pub occupied_voxels: u64,
    /// Primitive-voxel overlaps found by the voxelisation.
    pub fragments: u64,
    pub shadow_rays: u64,
    pub bounces: u32,
    pub bounce_cones: u64,
    pub bounce_cone_steps: u64,
    /// Bytes of the pyramid kept for rendering (all levels).
    pub pyramid_bytes: u64,
    /// Largest transient memory of the build (fragments and lit fragments), bytes.
    pub build_peak_bytes: u64,
    pub voxelise_seconds: f64,
    pub inject_seconds: f64,
    pub mipmap_seconds: f64,
    pub bounce_seconds: f64,
    pub seconds: f64,
}

/// The voxelised scene an integrator traces cones through.
#[derive(Clone, Debug)]
pub struct VoxelScene {
    pub pyramid: VoxelPyramid,
    pub stats: VctBuildStats,
}

/// Check the settings and pick the resolution for `context`'s scene.
pub fn resolution_for(
    scene: &SceneDescription,
    settings: &VctSettings,
) -> Result<(GridFrame, u32), VctError> {
    if !(1..=8).contains(&settings.bounces) {
        return Err(VctError::Bounces(settings.bounces));
    }
    let (lo, hi) = scene.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let resolution = match settings.resolution {
        Some(r) if !(2..=MAX_RESOLUTION).contains(&r) => return Err(VctError::Resolution(r)),
        Some(r) => r,
        None => default_resolution(lo, hi, DEFAULT_MEMORY_BUDGET, settings.voxels),
    };
    let frame = GridFrame::for_bounds(lo, hi, resolution);
    let bytes = frame.pyramid_bytes(settings.voxels);
    if bytes > MAX_PYRAMID_BYTES {
        return Err(VctError::TooLarge { resolution, bytes });
    }
    Ok((frame, resolution))
}

/// The bytes the voxel pyramid of `scene` under `settings` will take, known before anything
/// is built (the memory estimate counts them), or why no grid can be built.
pub fn pyramid_bytes_for(
    scene: &SceneDescription,
    settings: &VctSettings,
) -> Result<u64, VctError> {
    Ok(resolution_for(scene, settings)?
        .0
        .pyramid_bytes(settings.voxels))
}

/// Voxelise `context`'s scene (triangles and spheres; curved patches are not voxelised),
/// light it and build its pyramid, in parallel.
pub fn build_voxel_scene(
    context: &RenderContext,
    settings: &VctSettings,
) -> Result<VoxelScene, VctError> {
    let started = Instant::now();
    let (frame, resolution) = resolution_for(&context.scene, settings)?;
    let scene = &context.scene;

    let voxelising = Instant::now();
    // Parallel over chunks of triangles (a scene is often one large mesh), then spheres.
    let mut fragments: Vec<Fragment> = Vec::new();
    for mesh in &scene.meshes {
        let material = mesh.material as u32;
        let mesh_fragments: Vec<Fragment> = mesh
            .triangles
            .par_chunks(TRIANGLES_PER_TASK)
            .flat_map_iter(|chunk| {
                let mut out = Vec::new();
                for t in chunk {
                    let tri = t.map(|i| mesh.positions[i as usize]);
                    triangle_fragments(&frame, tri, material, &mut out);
                }
                out
            })
            .collect();
        fragments.extend(mesh_fragments);
    }
    let sphere_fragments_all: Vec<Fragment> = scene
        .spheres
        .par_iter()
        .flat_map_iter(|sphere| {
            let mut out = Vec::new();
            let material = sphere.material as u32;
            sphere_fragments(&frame, sphere.center, sphere.radius, material, &mut out);
            out
        })
        .collect();
    fragments.extend(sphere_fragments_all);
    let voxelise_seconds = voxelising.elapsed().as_secs_f64();

    let injecting = Instant::now();
    let grid_center = frame.origin
        + Vec3::new(
            frame.dims[0] as f32,
            frame.dims[1] as f32,
            frame.dims[2] as f32,
        ) * (0.5 * frame.voxel_size);
    let (mut lit, shadow_rays) = light_fragments(context, &fragments, grid_center);
    if let Some(error) = context.tracer.take_failure() {
        return Err(VctError::Trace(error.to_string()));
    }
    let build_peak_bytes = (fragments.capacity() * std::mem::size_of::<Fragment>()
        + lit.capacity() * std::mem::size_of::<LitFragment>()) as u64;
    let fragment_count = fragments.len() as u64;
    drop(fragments);
    lit.par_sort_unstable_by_key(|f| f.voxel);
    let surfaces = merge_fragments(&frame, &lit);
    drop(lit);
    let inject_seconds = injecting.elapsed().as_secs_f64();

    let mipmapping = Instant::now();
    let mut level0 = VoxelLevel::empty(frame.dims);
    for s in &surfaces {
        let (a, l) = (s.opacity, s.direct);
        level0.voxels[s.index as usize] = [a * l.x, a * l.y, a * l.z, a];
    }
    let mut pyramid = build_pyramid(frame, level0, settings.voxels);
    let mipmap_seconds = mipmapping.elapsed().as_secs_f64();

    let bouncing = Instant::now();
    let (mut bounce_cones, mut bounce_cone_steps) = (0, 0);
    let groups = if settings.bounces > 1 {
        gather_groups(&frame, &surfaces, GATHER_LEVEL)
    } else {
        GatherGroups::default()
    };
    for _ in 1..settings.bounces {
        let (next, work) = add_bounce(&pyramid, &surfaces, &groups);
        pyramid = next;
        bounce_cones += work.cones;
        bounce_cone_steps += work.steps;
    }
    let bounce_seconds = bouncing.elapsed().as_secs_f64();

    let stats = VctBuildStats {
        resolution,
        voxels: settings.voxels.name(),
        dims: frame.dims,
        voxel_size: frame.voxel_size,
        levels: pyramid.levels.len(),
        occupied_voxels: surfaces.len() as u64,
        fragments: fragment_count,
        shadow_rays,
        bounces: settings.bounces,
        bounce_cones,
        bounce_cone_steps,
        pyramid_bytes: pyramid.bytes(),
        build_peak_bytes,
        voxelise_seconds,
        inject_seconds,
        mipmap_seconds,
        bounce_seconds,
        seconds: started.elapsed().as_secs_f64(),
    };
    Ok(VoxelScene { pyramid, stats })
}

/// One [`SurfaceVoxel`] per run of fragments with the same voxel (`lit` sorted by voxel):
/// the mean of their reflected light, reflectance and normal, the largest emission and the
/// largest opacity.
///
/// Emission is not averaged: surfaces sharing a voxel hide each other, and an emitter
/// sharing one with an unlit surface is a lamp mounted on it, seen from the room in front
/// of it (cornell.toml's lamp lies 0.005 under its ceiling, a third of a voxel at 128; the
/// mean halved its light).
fn merge_fragments(frame: &GridFrame, lit: &[LitFragment]) -> Vec<SurfaceVoxel> {
    let mut out = Vec::new();
    for run in lit.chunk_by(|a, b| a.voxel == b.voxel) {
        let n = run.len() as f32;
        let index = run[0].voxel;
        let (dx, dy) = (frame.dims[0], frame.dims[1]);
        let (x, y, z) = (index % dx, (index / dx) % dy, index / (dx * dy));
        let normal_sum: Vec3 = run.iter().map(|f| f.normal).sum();
        out.push(SurfaceVoxel {
            index,
            center: frame.voxel_center(x, y, z),
            normal: normal_sum.normalize_or(run[0].normal),
            reflectance: run.iter().map(|f| f.reflectance).sum::<Vec3>() / n,
            direct: run.iter().map(|f| f.radiance).sum::<Vec3>() / n
                + run.iter().map(|f| f.emission).fold(Vec3::ZERO, Vec3::max),
            opacity: run.iter().map(|f| f.opacity).fold(0.0, f32::max),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fragment(voxel: u32, emission: f32, reflected: f32) -> LitFragment {
        LitFragment {
            voxel,
            emission: Vec3::splat(emission),
            radiance: Vec3::splat(reflected),
            opacity: 1.0,
            reflectance: Vec3::splat(0.5),
            normal: Vec3::Y,
        }
    }

    #[test]
    fn a_lamp_sharing_a_voxel_with_its_ceiling_keeps_its_emission() {
        let frame = GridFrame {
            origin: Vec3::ZERO,
            voxel_size: 1.0,
            dims: [2, 2, 2],
        };
        // Voxel 3: a lamp of emission 8 and the unlit ceiling it hangs from. Voxel 5: two
        // lit surfaces, whose reflected light is averaged.
        let lit = [
            fragment(3, 8.0, 0.0),
            fragment(3, 0.0, 0.0),
            fragment(5, 0.0, 1.0),
            fragment(5, 0.0, 3.0),
        ];
        let merged = merge_fragments(&frame, &lit);
        assert_eq!(merged.len(), 2);
        assert_eq!(merged[0].direct, Vec3::splat(8.0));
        assert_eq!(merged[1].direct, Vec3::splat(2.0));
    }
}
