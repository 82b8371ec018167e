//! Integrators: what a tile of pixels is worth, given a prepared scene.
//!
//! An integrator implements [`crate::render::Integrator`]: it turns a work tile into a
//! [`crate::film::TileImage`] (colour plus the AOVs the film asked for). Today there is the
//! Whitted ray tracer (seeds 001 and 004); a Monte Carlo path tracer and voxel cone tracing
//! plug in beside it, reusing the same scene, tracer, footprints, BSDFs and lights
//! ([`crate::shading`]) and film. Integrators depend on the render stage, never the reverse.

pub mod whitted;

pub use whitted::Whitted;
