//! Camera rays of a tile for one sample index, shared by the integrators: one per pixel, in
//! 4x4 blocks so that each run of 16 rays is one coherent packet, each with the footprint
//! the camera gives it and the pixel's sampler (which has drawn the camera's dimensions, so
//! an integrator's own draws continue from there).

use crate::film::{block_order, PixelRect};
use crate::footprint::Footprint;
use crate::render::context::RenderContext;
use crate::sampler::{PixelSampler, Sampler};
use crate::shading;

/// One camera ray of a tile.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CameraRay {
    pub origin: glam::Vec3,
    pub direction: glam::Vec3,
    /// Where tracing may start (`shading::entry_distance`).
    pub start: f32,
    pub footprint: Footprint,
    /// Index of the pixel inside the tile.
    pub pixel: u32,
    /// The pixel's sampler for this sample, past the camera's dimensions.
    pub sampler: PixelSampler,
}

/// Calls `emit` with the camera ray of every pixel of `tile` for sample `sample`, in 4x4
/// block order.
pub(crate) fn for_each_camera_ray(
    context: &RenderContext,
    tile: PixelRect,
    sample: u32,
    image_width: u32,
    mut emit: impl FnMut(CameraRay),
) {
    let camera = &context.camera;
    let lod = context.options.lod;
    let spp = context.options.spp.max(1);
    let dof = context.effects.depth_of_field;
    let sampler = Sampler::new(context.options.seed);
    for (x, y) in block_order(tile) {
        let (px, py) = (tile.x0 + x, tile.y0 + y);
        let mut pixel_sampler = sampler.pixel(py * image_width + px, sample);
        // Only the values the camera uses are computed (the lens centre without depth of
        // field); the sampler's dimensions move on the same either way.
        let camera_sample = pixel_sampler.camera_sample_drawing(spp, dof);
        let offset = camera_sample.pixel_offset;
        let lens = camera_sample.lens;
        let (fx, fy) = (px as f32 + offset.x, py as f32 + offset.y);
        let (origin, direction) = camera.generate_ray(fx, fy, lens);
        let start = context.surfaces.bounds.map_or(0.0, |bounds| {
            shading::entry_distance(origin, direction, bounds)
        });
        let footprint = if context.effects.footprints {
            camera.sample_footprint(lod, fx, fy, origin, direction, spp)
        } else {
            Footprint::none()
        };
        emit(CameraRay {
            origin,
            direction,
            start,
            footprint,
            pixel: y * tile.width + x,
            sampler: pixel_sampler,
        });
    }
}
