//! Camera rays of a tile: one per pixel and sample in flight, ordered so that each run of
//! 16 rays is one coherent packet, with the footprint the camera gives them
//! (`integrator::camera_sample`).

use glam::Vec3;

use super::{PathRay, Waves};
use crate::film::PixelRect;
use crate::integrator::camera_sample::{for_each_camera_ray, SampleRun};
use crate::render::context::RenderContext;
use crate::render::stats::RayKind;

/// Camera rays of the samples of `run` for a tile, in packet order, into
/// `waves.rays.camera`, and whether the render keeps each into `waves.rays.kept`
/// (`integrator::camera_sample`).
pub(super) fn generate_camera_rays(
    context: &RenderContext,
    tile: PixelRect,
    run: &SampleRun,
    image_width: u32,
    waves: &mut Waves,
) {
    let out = &mut waves.rays.camera;
    let kept = &mut waves.rays.kept;
    out.clear();
    kept.clear();
    for_each_camera_ray(context, tile, run, image_width, |ray| {
        kept.push(ray.kept);
        out.push(PathRay {
            origin: ray.origin,
            direction: ray.direction,
            start: ray.start,
            throughput: Vec3::ONE,
            footprint: ray.footprint,
            slot: ray.slot,
            depth: 0,
            kind: RayKind::Camera,
            sigma: Vec3::ZERO,
            first_sample: ray.sample == 0,
        });
    });
}
