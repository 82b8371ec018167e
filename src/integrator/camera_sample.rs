//! Camera rays of a tile for one sample index, shared by the integrators: one per pixel, in
//! 4x4 blocks so that each run of 16 rays is one coherent packet, each with the footprint
//! the camera gives it and the pixel's sampler (which has drawn the camera's dimensions, so
//! an integrator's own draws continue from there).

use glam::{Vec2, Vec3};

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
///
/// A block's 16 rays are made together, as structure-of-arrays: the sampler's draws
/// (`Sampler::camera_lanes`), then, for a pinhole camera, the directions
/// (`Camera::pinhole_directions`), each the same bits as the one-ray functions give; then
/// each ray's start and footprint.
pub(crate) fn for_each_camera_ray(
    context: &RenderContext,
    tile: PixelRect,
    sample: u32,
    image_width: u32,
    mut emit: impl FnMut(CameraRay),
) {
    let mut block = CameraBlock::default();
    for (x, y) in block_order(tile) {
        let lane = block.len;
        block.x[lane] = tile.x0 + x;
        block.y[lane] = tile.y0 + y;
        block.pixel[lane] = y * tile.width + x;
        block.len += 1;
        if block.len == PACKET {
            block.emit(context, sample, image_width, &mut emit);
        }
    }
    if block.len > 0 {
        block.emit(context, sample, image_width, &mut emit);
    }
}

/// Lanes of one 4x4 block (`block_order` yields the pixels of a block in a run of 16, fewer
/// at a tile's ragged edge).
const PACKET: usize = 16;

/// The pixels of up to 16 camera rays.
#[derive(Default)]
struct CameraBlock {
    len: usize,
    /// Image coordinates.
    x: [u32; PACKET],
    y: [u32; PACKET],
    /// Index inside the tile.
    pixel: [u32; PACKET],
}

impl CameraBlock {
    /// Makes the block's rays, emits them in lane order and empties the block. Lanes past
    /// `len` keep the previous block's pixels: computed and ignored.
    fn emit(
        &mut self,
        context: &RenderContext,
        sample: u32,
        image_width: u32,
        emit: &mut impl FnMut(CameraRay),
    ) {
        let camera = &context.camera;
        let spp = context.options.spp.max(1);
        let image_pixels: [u32; PACKET] =
            std::array::from_fn(|lane| self.y[lane] * image_width + self.x[lane]);
        // Only the values the camera uses are computed (the lens centre without depth of
        // field); the samplers' dimensions move on the same either way.
        let draws = Sampler::new(context.options.seed).camera_lanes(
            &image_pixels,
            sample,
            spp,
            context.effects.depth_of_field,
        );
        let fx: [f32; PACKET] =
            std::array::from_fn(|lane| self.x[lane] as f32 + draws.offset[0][lane]);
        let fy: [f32; PACKET] =
            std::array::from_fn(|lane| self.y[lane] as f32 + draws.offset[1][lane]);
        let bounds = context.surfaces.bounds;
        // A pinhole's rays share their origin: their starts are computed lane by lane too.
        let pinhole = camera.pinhole_directions(&fx, &fy).map(|d| {
            let starts = bounds.map_or([0.0; PACKET], |b| {
                shading::entry_distances(camera.eye(), &d, b)
            });
            (d, starts)
        });
        for lane in 0..self.len {
            let (origin, direction, start) = match &pinhole {
                Some((d, starts)) => (
                    camera.eye(),
                    Vec3::new(d[0][lane], d[1][lane], d[2][lane]),
                    starts[lane],
                ),
                None => {
                    let lens = Vec2::new(draws.lens[0][lane], draws.lens[1][lane]);
                    let (origin, direction) = camera.generate_ray(fx[lane], fy[lane], lens);
                    let start = bounds.map_or(0.0, |bounds| {
                        shading::entry_distance(origin, direction, bounds)
                    });
                    (origin, direction, start)
                }
            };
            let footprint = if context.effects.footprints {
                let lod = context.options.lod;
                camera.sample_footprint(lod, fx[lane], fy[lane], origin, direction, spp)
            } else {
                Footprint::none()
            };
            emit(CameraRay {
                origin,
                direction,
                start,
                footprint,
                pixel: self.pixel[lane],
                sampler: draws.samplers[lane],
            });
        }
        self.len = 0;
    }
}
