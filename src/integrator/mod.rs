//! Integrators: what a tile of pixels is worth, given a prepared scene.
//!
//! An integrator implements [`crate::render::Integrator`]: it turns a work tile into a
//! [`crate::film::TileImage`] (colour plus the AOVs the film asked for). Today there are the
//! Whitted ray tracer (seeds 001 and 004) and voxel cone tracing (seed 003, over Whitted's
//! waves); a Monte Carlo path tracer plugs in beside them, reusing the same scene, tracer, footprints, BSDFs and lights
//! ([`crate::shading`]) and film. Integrators depend on the render stage, never the reverse.

pub mod selection;
pub mod vct;
pub mod whitted;

pub use vct::Vct;
pub use whitted::Whitted;
