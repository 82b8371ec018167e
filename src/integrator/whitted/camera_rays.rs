//! Camera rays of a tile: one per pixel and sample, in 4x4 blocks so that each run of 16
//! rays is one coherent packet, with the footprint the camera gives them
//! (`integrator::camera_sample`).

use glam::Vec3;

use super::PathRay;
use crate::film::PixelRect;
use crate::integrator::camera_sample::for_each_camera_ray;
use crate::render::context::RenderContext;
use crate::render::stats::RayKind;

/// Camera rays of one sample for a tile, ordered so that each run of 16 is a 4x4 block.
pub(super) fn generate_camera_rays(
    context: &RenderContext,
    tile: PixelRect,
    sample: u32,
    image_width: u32,
    out: &mut Vec<PathRay>,
) {
    out.clear();
    for_each_camera_ray(context, tile, sample, image_width, |ray| {
        out.push(PathRay {
            origin: ray.origin,
            direction: ray.direction,
            start: ray.start,
            throughput: Vec3::ONE,
            footprint: ray.footprint,
            pixel: ray.pixel,
            depth: 0,
            kind: RayKind::Camera,
            sigma: Vec3::ZERO,
            first_sample: sample == 0,
        });
    });
}
