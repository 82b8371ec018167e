//! Camera rays of a tile for a run of sample indices, shared by the integrators: one per
//! pixel and sample, each with the footprint the camera gives it and the pixel's sampler
//! (which has drawn the camera's dimensions, so an integrator's own draws continue from
//! there).
//!
//! The rays are ordered so that each run of 16 is one coherent packet: a pixel's samples
//! follow one another, and the pixels go in 4x4 blocks. With 16 samples in flight a packet
//! is one pixel's 16 samples, rays that part only inside one pixel, which Embree's packet
//! traversal follows through the same BVH nodes and triangles (more than twice as fast
//! as a packet of 16 neighbouring pixels on the direct-lighting peer scene,
//! docs/benchmarks.md); with fewer, a packet is a run of pixels of one block, each with its
//! samples.

use std::ops::Range;

use glam::{Vec2, Vec3};

use crate::film::{block_order, PixelRect};
use crate::footprint::Footprint;
use crate::render::context::RenderContext;
use crate::sampler::{CameraLanes, PixelSampler, Sampler};
use crate::shading;
use crate::simd;

/// One camera ray of a tile.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CameraRay {
    pub origin: glam::Vec3,
    pub direction: glam::Vec3,
    /// Where tracing may start (`shading::entry_distance`).
    pub start: f32,
    pub footprint: Footprint,
    /// Where the ray's radiance goes in the tile's colour buffer ([`sample_slot`]). The
    /// first sample of a run has the pixel's own index.
    pub slot: u32,
    /// The sample's index.
    pub sample: u32,
    /// Whether the sample is one the render asked for. The others are traced only to fill
    /// their packets the same way in every render (see [`SampleRun`]) and are then dropped.
    pub kept: bool,
    /// The pixel's sampler for this sample, past the camera's dimensions.
    pub sampler: PixelSampler,
}

/// The most samples of a pixel traced together: a packet's worth.
pub(crate) const MAX_SAMPLES_IN_FLIGHT: u32 = 16;

/// Samples of every pixel of a tile traced together.
///
/// A render's samples fall into fixed blocks: with up to 16 in flight, sample 0, sample 1,
/// samples 2-3, 4-7 and 8-15, then blocks of 16 (with fewer in flight, the same up to that
/// count, then blocks of it), the last one cut at the render's sample count. The camera rays
/// of a whole block are traced as packets whichever of its samples the render keeps. So a
/// packet always holds the same rays, and a render of a sample range (a `--samples` part, a
/// progressive pass) traces every ray it keeps exactly as the whole render does: Embree's
/// choice between two triangles hit at the same distance (a ray through a shared edge)
/// depends on the packet a ray is traced in, and a split render must merge into the whole
/// one bit for bit. The passes of a progressive render (1, 1, 2, 4, 8, 16, 32, ... samples)
/// are whole blocks, so they trace no camera ray twice.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct SampleRun {
    /// The block's samples, all traced.
    pub traced: Range<u32>,
    /// The samples of `traced` the render keeps.
    pub kept: Range<u32>,
}

impl SampleRun {
    /// How many samples of each pixel are in flight.
    pub fn len(&self) -> usize {
        self.traced.len()
    }

    /// The places ([`sample_slot`]) of the kept samples.
    pub fn kept_places(&self) -> Range<usize> {
        (self.kept.start - self.traced.start) as usize..(self.kept.end - self.traced.start) as usize
    }
}

/// The block of sample indices `sample` belongs to ([`SampleRun`]) with up to `in_flight`
/// (a power of two) samples in flight, before it is cut at the render's sample count.
fn sample_block(sample: u32, in_flight: u32) -> Range<u32> {
    if sample >= in_flight {
        let start = sample / in_flight * in_flight;
        start..start.saturating_add(in_flight)
    } else if sample == 0 {
        0..1
    } else {
        let start = 1u32 << (31 - sample.leading_zeros());
        start..(2 * start).min(in_flight)
    }
}

/// The runs that render `samples` of a render of `samples_per_pixel` samples per pixel, in
/// order, with up to `in_flight` samples of a pixel traced together ([`SampleRun`]).
pub(crate) fn sample_runs(
    samples: Range<u32>,
    samples_per_pixel: u32,
    in_flight: u32,
) -> impl Iterator<Item = SampleRun> {
    let in_flight = in_flight
        .clamp(1, MAX_SAMPLES_IN_FLIGHT)
        .next_power_of_two()
        .min(MAX_SAMPLES_IN_FLIGHT);
    let last = samples_per_pixel.max(samples.end);
    let mut next = samples.start;
    std::iter::from_fn(move || {
        if next >= samples.end {
            return None;
        }
        let block = sample_block(next, in_flight);
        let traced = block.start..block.end.min(last);
        let kept = next..traced.end.min(samples.end);
        next = traced.end;
        Some(SampleRun { traced, kept })
    })
}

/// Where the radiance of sample `place` (counted from the first sample of its run) of the
/// tile's pixel `pixel` goes in a colour buffer of `tile_pixels` pixels per sample.
#[inline]
pub(crate) fn sample_slot(pixel: u32, place: u32, tile_pixels: u32) -> u32 {
    pixel + place * tile_pixels
}

/// The place ([`sample_slot`]) of the sample whose radiance goes to `slot`.
#[inline]
pub(crate) fn slot_place(slot: u32, tile_pixels: u32) -> u32 {
    slot / tile_pixels
}

/// Calls `emit` with the camera ray of every pixel of `tile` for every sample of `run`, a
/// pixel's samples one after another, the pixels in 4x4 block order.
///
/// Sixteen rays are made together, as structure-of-arrays: the sampler's draws
/// (`Sampler::camera_lanes`), then, for a pinhole camera, the directions
/// (`Camera::pinhole_directions`), each the same bits as the one-ray functions give; then
/// each ray's start and footprint.
pub(crate) fn for_each_camera_ray(
    context: &RenderContext,
    tile: PixelRect,
    run: &SampleRun,
    image_width: u32,
    emit: impl FnMut(CameraRay),
) {
    camera_rays(context, tile, run, image_width).emit_packets(usize::MAX, emit);
}

/// The camera rays of `tile` for `run`, in the order of [`for_each_camera_ray`], made a
/// few packets at a time ([`CameraRays::emit_packets`]): a wave integrator makes each camera
/// wave's rays where the wave is traced, rather than making the whole run's up front and
/// copying each wave's out.
pub(crate) fn camera_rays<'a>(
    context: &'a RenderContext,
    tile: PixelRect,
    run: &'a SampleRun,
    image_width: u32,
) -> CameraRays<'a, impl Iterator<Item = (u32, u32)>> {
    CameraRays {
        context,
        tile,
        run,
        image_width,
        pixels: block_order(tile),
        pixel: (0, 0),
        sample: run.traced.end,
        block: CameraBlock::default(),
    }
}

/// Where [`camera_rays`] has got to in a tile's run of samples.
pub(crate) struct CameraRays<'a, P> {
    context: &'a RenderContext,
    tile: PixelRect,
    run: &'a SampleRun,
    image_width: u32,
    /// The tile's pixels in block order, and the one whose samples are being made (read
    /// only while `sample` is below `run.traced.end`).
    pixels: P,
    pixel: (u32, u32),
    /// The next sample of `pixel` (`run.traced.end` once its samples are made).
    sample: u32,
    block: CameraBlock,
}

impl<P: Iterator<Item = (u32, u32)>> CameraRays<'_, P> {
    /// Emits whole packets of the run's next camera rays until at least `rays` have been
    /// emitted, or the run's last (possibly partial) packet; returns how many it emitted
    /// (0 once the run is done). With `rays` a multiple of 16 every call but the last
    /// emits exactly `rays`, so packets are cut as a single call cuts them.
    pub fn emit_packets(&mut self, rays: usize, mut emit: impl FnMut(CameraRay)) -> usize {
        let tile_pixels = self.tile.area() as u32;
        let mut emitted = 0;
        loop {
            if self.sample == self.run.traced.end {
                match self.pixels.next() {
                    Some(pixel) => {
                        self.pixel = pixel;
                        self.sample = self.run.traced.start;
                    }
                    None => {
                        if self.block.len > 0 {
                            emitted += self.block.len;
                            self.block.emit(self.context, self.image_width, &mut emit);
                        }
                        return emitted;
                    }
                }
            }
            let (x, y) = self.pixel;
            let (block, sample) = (&mut self.block, self.sample);
            let lane = block.len;
            block.x[lane] = self.tile.x0 + x;
            block.y[lane] = self.tile.y0 + y;
            block.index[lane] = sample;
            block.kept[lane] = self.run.kept.contains(&sample);
            block.slot[lane] = sample_slot(
                y * self.tile.width + x,
                sample - self.run.traced.start,
                tile_pixels,
            );
            block.len += 1;
            self.sample += 1;
            if block.len == PACKET {
                block.emit(self.context, self.image_width, &mut emit);
                emitted += PACKET;
                if emitted >= rays {
                    return emitted;
                }
            }
        }
    }
}

/// Calls `trace` with the camera rays a render traces for `tile`, one sample run at a time
/// ([`sample_runs`], up to `in_flight` samples of a pixel together), as Embree is given
/// them: every sample of every pixel in the packets the integrators build. Nothing is
/// shaded; `conetrace bench render` times this as the traversal floor of the render's own
/// camera rays.
pub fn for_each_camera_run(
    context: &RenderContext,
    tile: PixelRect,
    in_flight: u32,
    rays: &mut Vec<crate::render::tracer::TraceRay>,
    mut trace: impl FnMut(&[crate::render::tracer::TraceRay]),
) {
    let spp = context.options.spp.max(1);
    for run in sample_runs(0..spp, spp, in_flight) {
        rays.clear();
        for_each_camera_ray(context, tile, &run, context.options.width, |ray| {
            let wave_ray = crate::integrator::trace_wave::WaveRay {
                origin: ray.origin,
                direction: ray.direction,
                start: ray.start,
                footprint: &ray.footprint,
            };
            rays.push(wave_ray.traced());
        });
        trace(rays);
    }
}

/// Lanes of one packet.
const PACKET: usize = 16;

/// The pixels and samples of up to 16 camera rays.
#[derive(Default)]
struct CameraBlock {
    len: usize,
    /// Image coordinates.
    x: [u32; PACKET],
    y: [u32; PACKET],
    /// Sample index.
    index: [u32; PACKET],
    /// Slot in the tile's colour buffer ([`sample_slot`]).
    slot: [u32; PACKET],
    /// Whether the render keeps the sample.
    kept: [bool; PACKET],
}

/// The lane values of a block's rays: the sampler's draws, the positions on the image and,
/// for a pinhole camera, the directions and starts.
struct BlockLanes {
    draws: CameraLanes<PACKET>,
    fx: [f32; PACKET],
    fy: [f32; PACKET],
    pinhole: Option<([[f32; PACKET]; 3], [f32; PACKET])>,
    /// `Camera::axis_cosine` of the pinhole's directions, when footprints are traced.
    axis_cosine: Option<[f32; PACKET]>,
}

impl BlockLanes {
    /// Origin, unit direction and start (where the scene's bounds begin) of lane `lane`'s
    /// ray.
    #[inline(always)]
    fn ray(&self, context: &RenderContext, lane: usize) -> (Vec3, Vec3, f32) {
        let camera = &context.camera;
        match &self.pinhole {
            Some((d, starts)) => (
                camera.eye(),
                Vec3::new(d[0][lane], d[1][lane], d[2][lane]),
                starts[lane],
            ),
            None => {
                let lens = Vec2::new(self.draws.lens[0][lane], self.draws.lens[1][lane]);
                let (origin, direction) = camera.generate_ray(self.fx[lane], self.fy[lane], lens);
                let start = context.surfaces.bounds.map_or(0.0, |bounds| {
                    shading::entry_distance(origin, direction, bounds)
                });
                (origin, direction, start)
            }
        }
    }
}

impl CameraBlock {
    /// Makes the block's rays, emits them in lane order and empties the block. Lanes past
    /// `len` keep the previous block's pixels: computed and ignored.
    fn emit(
        &mut self,
        context: &RenderContext,
        image_width: u32,
        emit: &mut impl FnMut(CameraRay),
    ) {
        let camera = &context.camera;
        let spp = context.options.spp.max(1);
        let lanes = simd::dispatch(
            #[inline(always)]
            || self.lanes(context, image_width),
        );
        let BlockLanes {
            fx,
            fy,
            axis_cosine,
            ..
        } = &lanes;
        // Two loops rather than a branch per lane: with the footprint chosen per lane, the
        // point sample's footprint (its tag alone) went through the stack and the ray's
        // copy of it stalled on store forwarding, on every camera ray.
        if context.effects.footprints {
            let lod = context.options.lod;
            for lane in 0..self.len {
                let (origin, direction, start) = lanes.ray(context, lane);
                let dw = match axis_cosine {
                    Some(dw) => dw[lane],
                    None => camera.axis_cosine(direction),
                };
                let footprint =
                    camera.sample_footprint_at(lod, fx[lane], fy[lane], origin, dw, spp);
                emit(self.ray(lane, (origin, direction, start), footprint, &lanes));
            }
        } else {
            for lane in 0..self.len {
                let ray = lanes.ray(context, lane);
                emit(self.ray(lane, ray, Footprint::none(), &lanes));
            }
        }
        self.len = 0;
    }

    /// Lane `lane`'s camera ray with the origin, direction and start `ray` and `footprint`.
    #[inline(always)]
    fn ray(
        &self,
        lane: usize,
        (origin, direction, start): (Vec3, Vec3, f32),
        footprint: Footprint,
        lanes: &BlockLanes,
    ) -> CameraRay {
        CameraRay {
            origin,
            direction,
            start,
            footprint,
            slot: self.slot[lane],
            sample: self.index[lane],
            kept: self.kept[lane],
            sampler: lanes.draws.samplers[lane],
        }
    }

    /// The block's lane values, every lane the same bits as the one-ray functions give. A
    /// [`simd::dispatch`] kernel: the lanes' hashing, bit reversals, divisions and square
    /// roots run as vector instructions.
    #[inline(always)]
    fn lanes(&self, context: &RenderContext, image_width: u32) -> BlockLanes {
        let camera = &context.camera;
        let image_pixels: [u32; PACKET] =
            std::array::from_fn(|lane| self.y[lane] * image_width + self.x[lane]);
        // Only the values the camera uses are computed (the lens centre without depth of
        // field); the samplers' dimensions move on the same either way.
        let draws = Sampler::new(context.options.seed).camera_lanes_inline(
            &image_pixels,
            &self.index,
            context.options.spp.max(1),
            context.effects.depth_of_field,
        );
        let fx: [f32; PACKET] =
            std::array::from_fn(|lane| self.x[lane] as f32 + draws.offset[0][lane]);
        let fy: [f32; PACKET] =
            std::array::from_fn(|lane| self.y[lane] as f32 + draws.offset[1][lane]);
        let bounds = context.surfaces.bounds;
        // A pinhole's rays share their origin: their starts are computed lane by lane too.
        // A `match`, not closures: a closure the compiler leaves out of line would run
        // at the baseline level.
        let pinhole = match camera.pinhole_directions(&fx, &fy) {
            Some(d) => {
                let starts = match bounds {
                    Some(b) => shading::entry_distances(camera.eye(), &d, b),
                    None => [0.0; PACKET],
                };
                Some((d, starts))
            }
            None => None,
        };
        let axis_cosine = match &pinhole {
            Some((d, _)) if context.effects.footprints => Some(std::array::from_fn(|lane| {
                camera.axis_cosine(Vec3::new(d[0][lane], d[1][lane], d[2][lane]))
            })),
            _ => None,
        };
        BlockLanes {
            draws,
            fx,
            fy,
            pinhole,
            axis_cosine,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn runs(samples: Range<u32>, spp: u32, in_flight: u32) -> Vec<(Range<u32>, Range<u32>)> {
        sample_runs(samples, spp, in_flight)
            .map(|run| (run.traced, run.kept))
            .collect()
    }

    #[test]
    fn runs_are_fixed_blocks_whatever_range_is_rendered() {
        // The whole render: 0, 1, 2-3, 4-7, 8-15, then blocks of 16, the last one short.
        assert_eq!(
            runs(0..40, 40, 16),
            vec![
                (0..1, 0..1),
                (1..2, 1..2),
                (2..4, 2..4),
                (4..8, 4..8),
                (8..16, 8..16),
                (16..32, 16..32),
                (32..40, 32..40)
            ]
        );
        // A part traces the same blocks and keeps its own samples.
        assert_eq!(
            runs(5..20, 40, 16),
            vec![(4..8, 5..8), (8..16, 8..16), (16..32, 16..20)]
        );
        assert_eq!(runs(17..18, 40, 16), vec![(16..32, 17..18)]);
        // Progressive passes are whole blocks.
        for pass in [0..1, 1..2, 2..4, 4..8, 8..16, 16..32, 32..64] {
            assert!(runs(pass.clone(), u32::MAX, 16)
                .iter()
                .all(|(traced, kept)| traced == kept));
        }
        // A block is cut at the render's sample count.
        assert_eq!(runs(1..3, 3, 16), vec![(1..2, 1..2), (2..3, 2..3)]);
        assert_eq!(runs(9..10, 10, 16), vec![(8..10, 9..10)]);
        // One sample in flight: one run per sample.
        assert_eq!(runs(2..4, 8, 1), vec![(2..3, 2..3), (3..4, 3..4)]);
        // Nothing to render; the end of the index range.
        assert!(runs(3..3, 8, 16).is_empty());
        assert_eq!(
            runs(u32::MAX - 2..u32::MAX, u32::MAX, 16),
            vec![(u32::MAX - 15..u32::MAX, u32::MAX - 2..u32::MAX)]
        );
    }

    #[test]
    fn kept_places_and_slots_follow_the_block() {
        let run = SampleRun {
            traced: 16..32,
            kept: 20..23,
        };
        assert_eq!(run.len(), 16);
        assert_eq!(run.kept_places(), 4..7);
        assert_eq!(sample_slot(5, 4, 256), 5 + 4 * 256);
        assert_eq!(slot_place(sample_slot(255, 15, 256), 256), 15);
        assert_eq!(slot_place(sample_slot(3, 0, 256), 256), 0);
    }

    /// A run's camera rays made a few packets at a time (as the wave integrators make each
    /// camera wave's) are the rays one call makes, bit for bit and in the same packets, on
    /// a tile whose 4x4 blocks are cut at its edges, for runs of 1, 2 and 16 samples with
    /// some samples not kept.
    #[test]
    fn camera_rays_made_a_few_packets_at_a_time_are_the_rays_of_one_call() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/assets/scenes/teapot_textured.toml"
        );
        let scene = crate::scene::load::load_scene(std::path::Path::new(path))
            .expect("load the shipped textured teapot");
        let mut options = crate::render::RenderOptions::from_settings(&scene.settings);
        options.spp = 32;
        let context =
            crate::render::prepare(std::sync::Arc::new(scene), options).expect("prepare it");
        assert!(context.effects.footprints);
        let tile = PixelRect {
            x0: 19,
            y0: 5,
            width: 13,
            height: 7,
        };
        let runs = [
            SampleRun {
                traced: 0..1,
                kept: 0..1,
            },
            SampleRun {
                traced: 2..4,
                kept: 3..4,
            },
            SampleRun {
                traced: 16..32,
                kept: 20..23,
            },
        ];
        let width = context.options.width;
        for run in &runs {
            let mut whole = Vec::new();
            for_each_camera_ray(&context, tile, run, width, |ray| {
                whole.push(format!("{ray:?}"))
            });
            assert_eq!(whole.len(), tile.area() * run.len());
            for chunk in [16, 48, 256] {
                let mut rays = camera_rays(&context, tile, run, width);
                let (mut parts, mut calls) = (Vec::new(), Vec::new());
                loop {
                    let made = rays.emit_packets(chunk, |ray| parts.push(format!("{ray:?}")));
                    if made == 0 {
                        break;
                    }
                    calls.push(made);
                }
                assert_eq!(parts, whole, "{chunk} rays a call, run {run:?}");
                // Every call but the last makes exactly `chunk` rays: whole packets.
                let (last, full) = calls.split_last().expect("at least one call");
                assert!(full.iter().all(|&made| made == chunk), "{calls:?}");
                assert!(*last <= chunk && *last > 0, "{calls:?}");
                assert_eq!(rays.emit_packets(chunk, |_| panic!("no ray is left")), 0);
            }
        }
    }
}
