//! Which integrator renders: `--integrator` or the scene's `[render] integrator`, and the
//! one place that builds it. Only the voxel cone tracer needs work before rendering (its
//! voxel scene); a Whitted render builds nothing extra.

use crate::film::{PixelRect, TileImage};
use crate::integrator::vct::Vct;
use crate::integrator::whitted::Waves;
use crate::integrator::Whitted;
use crate::render::context::{RenderContext, WorkerState};
use crate::render::Integrator;
use crate::vct::{build_voxel_scene, VctBuildStats, VctError, VctSettings};

/// The integrators a render can select.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorKind {
    #[default]
    Whitted,
    Vct,
}

impl IntegratorKind {
    pub const NAMES: [&'static str; 2] = ["whitted", "vct"];

    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Whitted => "whitted",
            IntegratorKind::Vct => "vct",
        }
    }
}

impl std::str::FromStr for IntegratorKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "whitted" => Ok(IntegratorKind::Whitted),
            "vct" => Ok(IntegratorKind::Vct),
            other => Err(format!(
                "unknown integrator '{other}' ({})",
                IntegratorKind::NAMES.join(", ")
            )),
        }
    }
}

/// The selected integrator, ready to render.
pub enum SelectedIntegrator {
    Whitted(Whitted),
    Vct(Vct),
}

impl SelectedIntegrator {
    /// The voxel scene's build statistics (vct only).
    pub fn vct_stats(&self) -> Option<&VctBuildStats> {
        match self {
            SelectedIntegrator::Whitted(_) => None,
            SelectedIntegrator::Vct(vct) => Some(&vct.voxels.stats),
        }
    }
}

/// Build the integrator `kind` for `context`: voxelise the scene for vct, nothing for
/// Whitted.
pub fn select(
    kind: IntegratorKind,
    context: &RenderContext,
    vct: &VctSettings,
) -> Result<SelectedIntegrator, VctError> {
    Ok(match kind {
        IntegratorKind::Whitted => SelectedIntegrator::Whitted(Whitted),
        IntegratorKind::Vct => SelectedIntegrator::Vct(Vct::new(build_voxel_scene(context, vct)?)),
    })
}

impl Integrator for SelectedIntegrator {
    type ThreadState = Waves;

    fn thread_state(&self, context: &RenderContext) -> Waves {
        match self {
            SelectedIntegrator::Whitted(w) => w.thread_state(context),
            SelectedIntegrator::Vct(v) => v.thread_state(context),
        }
    }

    fn render_tile(
        &self,
        context: &RenderContext,
        tile: PixelRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
        state: &mut Waves,
    ) {
        match self {
            SelectedIntegrator::Whitted(w) => w.render_tile(context, tile, image, worker, state),
            SelectedIntegrator::Vct(v) => v.render_tile(context, tile, image, worker, state),
        }
    }
}
