//! Integrators: what a tile of pixels is worth, given a prepared scene.
//!
//! An integrator turns a tile of pixels into a [`TileImage`] (colour plus the AOVs the film
//! asked for). Today there is the Whitted ray tracer (seeds 001 and 004); a Monte Carlo path
//! tracer and voxel cone tracing plug in beside it by implementing [`Integrator`], reusing the
//! same scene, tracer, footprints and film.

pub mod tile_image;
pub mod whitted;

pub use tile_image::{block_order, AovSelection, PixelRect, TileImage};
pub use whitted::Whitted;

use crate::render::context::RenderContext;
use crate::render::context::WorkerState;

/// A light-transport algorithm that renders one tile at a time, from any thread.
pub trait Integrator: Sync {
    /// Render `tile` into `image` (already sized for it), counting work in `worker`.
    fn render_tile(
        &self,
        context: &RenderContext,
        tile: PixelRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
    );
}
