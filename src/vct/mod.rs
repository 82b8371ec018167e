//! Voxel cone tracing's scene representation (seed 003): the scene voxelised into a dense
//! grid of opacity and the direct radiance leaving its diffuse surfaces, pre-filtered into a
//! 3D mip pyramid that cones are marched through.
//!
//! The files follow the build: `grid` (the grid's frame, its resolution rule and the mip
//! pyramid with its quadrilinear lookup), `overlap` (triangle-box and sphere-box tests),
//! `voxelise` (which voxels every primitive touches, conservatively), `inject` (the direct
//! light leaving each touched surface, with shadow rays through Embree), `mipmap` (the
//! opacity-correct reduction), `cone` (marching one cone, seed 003's blend equation) and
//! `bounce` (optional extra bounces accumulated inside the voxels). `build` ties them
//! together for a prepared render.

pub mod bounce;
pub mod build;
pub mod cone;
pub mod grid;
pub mod inject;
pub mod mipmap;
pub mod overlap;
pub mod voxelise;

pub use build::{build_voxel_scene, VctBuildStats, VctError, VctSettings, VoxelScene};
pub use cone::{trace_cone, ConeResult};
pub use grid::{GridFrame, VoxelKind, VoxelPyramid};
