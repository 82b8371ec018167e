//! The interface between the render loop and a light-transport algorithm.
//!
//! The render loop ([`crate::render::render`]) hands work tiles to rayon workers; each worker
//! keeps a [`WorkerState`] (the counters and texture-tile records the render reports) and
//! one [`Integrator::ThreadState`] of the integrator's own (its reusable buffers, later its
//! sampler state), created once per worker and reused for every tile it renders. The
//! integrators themselves live in `crate::integrator`, which depends on this stage; this
//! module knows none of them.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::film::{PixelRect, TileImage};
use crate::render::context::{RenderContext, WorkerState};

/// A light-transport algorithm that renders one tile at a time, from any thread.
pub trait Integrator: Sync {
    /// What one worker thread keeps between the tiles it renders (reused buffers, sampler
    /// state); never shared between threads.
    type ThreadState: Send;

    /// A fresh per-thread state for rendering `context`.
    fn thread_state(&self, context: &RenderContext) -> Self::ThreadState;

    /// Render `tile` into `image` (already sized for it and zeroed), counting work in
    /// `worker` and reusing `state`. The render loop holds this thread's worker state while
    /// the call runs, so it must not start rayon work of its own (a nested job stolen by
    /// this thread would find that state taken).
    ///
    /// `stop`, when set, is read between runs of samples: once it is raised the call
    /// returns early with `false`, and the tile's image is incomplete (the render loop
    /// drops it). A tile with many samples per pixel then stops within one run of samples,
    /// not at its end. `true` means the tile was rendered whole.
    fn render_tile(
        &self,
        context: &RenderContext,
        tile: PixelRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
        state: &mut Self::ThreadState,
        stop: Option<&AtomicBool>,
    ) -> bool;
}

/// True when `stop` is raised.
#[inline]
pub fn stop_requested(stop: Option<&AtomicBool>) -> bool {
    stop.is_some_and(|s| s.load(Ordering::Relaxed))
}
