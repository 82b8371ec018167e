//! Voxel cone tracing (seed 003): Whitted's camera and specular paths, with the light that
//! reaches diffuse and glossy surfaces from everything but the punctual lights gathered by
//! cones marched through the voxelised scene (`crate::vct`).
//!
//! At every hit the punctual lights' direct light is Whitted's (shadow rays); emission is
//! the surface's own. The opaque lobe then adds the diffuse cones (seed 003's sum with more
//! cones towards the horizon, `vct::cone::diffuse_cones`), `k_d sum_j W_j L_v(x, w_j, a_j)`,
//! and, when it has a highlight, one specular cone about
//! the mirror direction whose aperture follows the shininess (`glossy`). What a cone does
//! not see blocked (`1 - alpha`) sees the environment's mean radiance: cones replace
//! Whitted's constant ambient term with an occluded one.

mod glossy;

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use glam::Vec3;

use crate::film::{PixelRect, TileImage};
use crate::integrator::whitted::{render_tile_with, IndirectLight, IndirectQuery, Waves};
use crate::render::context::{RenderContext, WorkerState};
use crate::render::Integrator;
use crate::shading::OpaqueLobe;
use crate::vct::cone::{
    gather_diffuse, surface_cone, trace_cone_stepped, CONE_START, STEP_FRACTION,
};
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
        stop: Option<&AtomicBool>,
    ) -> bool {
        render_tile_with(context, tile, image, worker, waves, self, stop)
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
        let environment = if context.effects.environment {
            context.lights.environment.mean_radiance
        } else {
            Vec3::ZERO
        };
        let lobe = diffuse_and_specular(query.bsdf);
        let n = query.bsdf.normal();
        let position = query.position();
        let counters = &mut worker.counters;
        // Seed 003: L_o = k_d sum_j W_j L_v(x, w_j, a_j); what the cones leave open sees the
        // environment.
        let mut radiance = Vec3::ZERO;
        if lobe.diffuse.max_element() > 0.0 {
            let g = gather_diffuse(pyramid, position, n, CONE_START, STEP_FRACTION);
            counters.vct_cones_traced += crate::vct::cone::DIFFUSE_CONE_COUNT as u64;
            counters.vct_cone_steps += g.steps;
            radiance += lobe.diffuse * (g.radiance + g.open * environment);
        }
        // The specular lobe reflects about `specular` of what arrives around the mirror
        // direction: one cone there, started as the diffuse ones are.
        if lobe.specular.max_element() > 0.0 {
            let wo = query.outgoing;
            let reflected = 2.0 * n.dot(wo) * n - wo;
            if reflected.dot(query.geometric_normal) > 0.0 {
                let aperture = specular_cone_aperture(lobe.shininess);
                let cone = surface_cone(pyramid, position, n, reflected, aperture, CONE_START);
                let r = trace_cone_stepped(pyramid, &cone, STEP_FRACTION);
                counters.vct_cones_traced += 1;
                counters.vct_cone_steps += u64::from(r.steps);
                radiance += lobe.specular * (r.radiance + (1.0 - r.alpha) * environment);
            }
        }
        query.weight * radiance
    }
}

/// An opaque lobe as the cones see it: a diffuse reflectance, a specular reflectance and the
/// Blinn-Phong exponent that sets the specular cone's aperture.
struct ConeLobe {
    diffuse: Vec3,
    specular: Vec3,
    shininess: f32,
}

/// The classic lobe as it is; the metallic-roughness lobe as its diffuse part
/// `(1 - metallic) base colour`, its specular reflectance at normal incidence
/// `mix(0.04, base colour, metallic)`, and the Blinn-Phong exponent of the same highlight
/// width, `2 / alpha^2 - 2` (Walter et al. 2007, section 5.2's Beckmann-Phong relation, which
/// GGX shares near the peak).
fn diffuse_and_specular(lobe: &OpaqueLobe) -> ConeLobe {
    match lobe {
        OpaqueLobe::Classic(classic) => ConeLobe {
            diffuse: classic.albedo,
            specular: Vec3::splat(classic.specular),
            shininess: classic.shininess,
        },
        OpaqueLobe::MetallicRoughness(rough) => {
            let alpha = rough.ggx.alpha.max(1e-3);
            ConeLobe {
                diffuse: rough.base_color * (1.0 - rough.metallic),
                specular: Vec3::splat(0.04).lerp(rough.base_color, rough.metallic),
                shininess: (2.0 / (alpha * alpha) - 2.0).max(0.0),
            }
        }
    }
}
