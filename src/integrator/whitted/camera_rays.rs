//! Camera rays of a tile: one per pixel and sample, in 4x4 blocks so that each run of 16
//! rays is one coherent packet, with the footprint the camera gives them.

use glam::{Vec2, Vec3};

use super::PathRay;
use crate::film::{block_order, PixelRect};
use crate::footprint::Footprint;
use crate::render::context::RenderContext;
use crate::render::stats::RayKind;
use crate::sampler::Sampler;
use crate::shading;

/// Camera rays of one sample for a tile, ordered so that each run of 16 is a 4x4 block.
pub(super) fn generate_camera_rays(
    context: &RenderContext,
    tile: PixelRect,
    sample: u32,
    image_width: u32,
    out: &mut Vec<PathRay>,
) {
    out.clear();
    let camera = &context.camera;
    let lod = context.options.lod;
    let spp = context.options.spp.max(1);
    let dof = context.effects.depth_of_field;
    let sampler = Sampler::new(context.options.seed);
    for (x, y) in block_order(tile) {
        let (px, py) = (tile.x0 + x, tile.y0 + y);
        let camera_sample = sampler
            .pixel(py * image_width + px, sample)
            .camera_sample(spp);
        let offset = camera_sample.pixel_offset;
        let lens = if dof {
            camera_sample.lens
        } else {
            Vec2::splat(0.5)
        };
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
        out.push(PathRay {
            origin,
            direction,
            start,
            throughput: Vec3::ONE,
            footprint,
            pixel: y * tile.width + x,
            depth: 0,
            kind: RayKind::Camera,
            sigma: Vec3::ZERO,
            first_sample: sample == 0,
        });
    }
}
