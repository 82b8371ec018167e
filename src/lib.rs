//! conetrace: a CPU ray tracer that traces packets of rays through Embree and filters every
//! texture lookup by the ray's footprint (ray cones, ray differentials).
//!
//! The modules follow the data flow: [`scene`] (description and loaders) -> [`embree`] (the
//! one safe layer over Embree) -> [`camera`] rays with [`footprint`]s -> packets through
//! [`render::tracer`] -> [`hit`]s -> [`shading`] in an [`integrator`] (with [`texture`]
//! filtering) -> [`film`] -> EXR/PNG. [`cli`] is the command line.

pub mod camera;
pub mod capi;
pub mod cli;
pub mod embree;
pub mod film;
pub mod footprint;
pub mod hit;
pub mod integrator;
pub mod render;
pub mod scene;
pub mod shading;
pub mod texture;
