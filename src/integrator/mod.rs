//! Integrators: what a tile of pixels is worth, given a prepared scene.
//!
//! An integrator implements [`crate::render::Integrator`]: it turns a work tile into a
//! [`crate::film::TileImage`] (colour plus the AOVs the film asked for). Today there are the
//! Whitted ray tracer (seeds 001 and 004), a Monte Carlo path tracer ([`path`]) and voxel
//! cone tracing ([`vct`], seed 003, over Whitted's waves), sharing the same scene, tracer,
//! footprints, BSDFs and lights ([`crate::shading`]) and film. Integrators depend on the
//! render stage, never the reverse. [`selection`] picks one for a scene (`--integrator`,
//! `[render] integrator`) and says why; `camera_sample` and `texturing` hold what every
//! integrator shares (camera rays, filtered texture lookups); `wave_integrator` is the layer
//! every wave integrator renders a tile through (the tile loop, the wave state, radiance and
//! AOVs reaching the film), `trace_wave` and `wave_order` how it traces a wave and in which
//! order the waves run.

mod camera_sample;
pub(crate) mod lanes;
pub mod path;
pub mod selection;
mod texturing;
mod trace_wave;
pub mod vct;
mod wave_integrator;
mod wave_order;
pub mod whitted;

pub use camera_sample::for_each_camera_run;
pub use path::PathTracer;
pub use selection::{IntegratorChoice, IntegratorKind, SelectedIntegrator};
pub use vct::Vct;
pub use whitted::Whitted;
