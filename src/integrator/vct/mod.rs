//! Voxel cone tracing (seed 003): Whitted's camera and specular paths, with the light that
//! reaches diffuse and glossy surfaces from everything but the punctual lights gathered by
//! cones marched through the voxelised scene (`crate::vct`).
//!
//! At every hit the punctual lights' direct light is Whitted's (shadow rays); emission is
//! the surface's own. The opaque lobe then adds seed 003's six diffuse cones,
//! `k_d sum_j W_j L_v(x, w_j, pi/6)`, and, when it has a highlight, one specular cone about
//! the mirror direction whose aperture follows the shininess (`glossy`). What a cone does
//! not see blocked (`1 - alpha`) sees the environment's mean radiance: cones replace
//! Whitted's constant ambient term with an occluded one.

mod glossy;

use std::sync::Arc;

use glam::Vec3;

use crate::film::{PixelRect, TileImage};
use crate::integrator::whitted::{render_tile_with, IndirectLight, IndirectQuery, Waves};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::Integrator;
use crate::vct::cone::{diffuse_cones, trace_cone, DIFFUSE_APERTURE, START_OFFSET_VOXELS};
use crate::vct::VoxelScene;

pub use glossy::specular_cone_aperture;

/// The voxel cone tracing integrator over a built voxel scene.
#[derive(Clone, Debug)]
pub struct Vct {
    pub voxels: Arc<VoxelScene>,
}

impl Vct {
    pub fn new(voxels: VoxelScene) -> Vct {
        Vct {
            voxels: Arc::new(voxels),
        }
    }
}

impl Integrator for Vct {
    type ThreadState = Waves;

    fn thread_state(&self, _context: &RenderContext) -> Waves {
        Waves::default()
    }

    fn render_tile(
        &self,
        context: &RenderContext,
        tile: PixelRect,
        image: &mut TileImage,
        worker: &mut WorkerState,
        waves: &mut Waves,
    ) {
        render_tile_with(context, tile, image, worker, waves, self);
    }
}

impl IndirectLight for Vct {
    fn opaque_indirect(
        &self,
        context: &RenderContext,
        query: &IndirectQuery,
        worker: &mut WorkerState,
    ) -> Vec3 {
        let pyramid = &self.voxels.pyramid;
        let start = START_OFFSET_VOXELS * pyramid.frame.voxel_size;
        let environment = if context.effects.environment {
            context.lights.environment.mean_radiance
        } else {
            Vec3::ZERO
        };
        let bsdf = query.bsdf;
        let n = bsdf.n;
        let mut cone = |direction: Vec3, aperture: f32| {
            let r = trace_cone(pyramid, query.position, direction, aperture, start, f32::INFINITY);
            worker.counters.vct_cones_traced += 1;
            worker.counters.vct_cone_steps += u64::from(r.steps);
            r.radiance + (1.0 - r.alpha) * environment
        };
        // Seed 003: L_o = k_d sum_j W_j L_v(x, w_j, a_j).
        let mut diffuse = Vec3::ZERO;
        if bsdf.albedo.max_element() > 0.0 {
            for (direction, weight) in diffuse_cones(n) {
                diffuse += weight * cone(direction, DIFFUSE_APERTURE);
            }
        }
        let mut radiance = bsdf.albedo * diffuse;
        // The normalised Blinn-Phong lobe reflects about `specular` of what arrives around
        // the mirror direction: one cone there.
        if bsdf.specular > 0.0 {
            let wo = query.outgoing;
            let reflected = 2.0 * n.dot(wo) * n - wo;
            if reflected.dot(query.geometric_normal) > 0.0 {
                let aperture = specular_cone_aperture(bsdf.shininess);
                radiance += bsdf.specular * cone(reflected, aperture);
            }
        }
        query.weight * radiance
    }
}
