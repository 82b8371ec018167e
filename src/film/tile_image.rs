//! The pixels of one work tile ([`crate::render::work_tiles`]) as an integrator produces
//! them: colour, alpha and the AOVs the render asked for.

use std::ops::Range;

use super::PixelRect;

/// The pixels of `tile` (offsets inside it) ordered so that each run of 16 is one 4x4 block:
/// the order camera rays are generated in, so a 16-wide packet is one block.
pub fn block_order(tile: PixelRect) -> impl Iterator<Item = (u32, u32)> {
    let blocks_x = tile.width.div_ceil(4);
    let blocks_y = tile.height.div_ceil(4);
    (0..blocks_y * blocks_x).flat_map(move |block| {
        let (bx, by) = ((block % blocks_x) * 4, (block / blocks_x) * 4);
        (0..16u32)
            .map(move |lane| (bx + lane % 4, by + lane / 4))
            .filter(move |&(x, y)| x < tile.width && y < tile.height)
    })
}

/// Which AOVs to fill (colour and alpha are always filled).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSelection {
    /// Z, N, albedo, uv.
    pub surface: bool,
    /// tex.s/t/dsdx/dtdx/dsdy/dtdy and texcolor.R/G/B/A of the first textured camera hit.
    pub texture_footprint: bool,
    /// lod and footprint.
    pub lod: bool,
}

impl AovSelection {
    /// Every AOV.
    pub const ALL: AovSelection = AovSelection {
        surface: true,
        texture_footprint: true,
        lod: true,
    };
}

/// Per-pixel values of a tile; AOVs are empty vectors when not selected.
/// AOVs describe the first camera sample of each pixel (the pixel centre at 1 spp).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TileImage {
    /// Which sample indices of each pixel to render; `None`: all of the render's samples.
    /// Set by the render loop for a render of a sample range.
    pub samples: Option<std::ops::Range<u32>>,
    /// Linear RGB radiance: while samples are traced, each sample in flight's radiance, one
    /// run of the tile's pixels per sample ([`TileImage::begin_samples`]); when the tile is
    /// done, the mean over the samples rendered (`film::sample_sum::mean_of_sum`).
    pub color: Vec<[f32; 3]>,
    /// Exact fixed-point sums of each pixel's sample radiances (`film::sample_sum`), in the
    /// same grouping-free form whatever range of samples the tile covers.
    pub color_sum: Vec<[i128; 3]>,
    /// 1 for a rendered pixel (the environment is part of the image).
    pub alpha: Vec<f32>,
    /// Camera-space depth of the first hit (f32::MAX where the camera ray missed).
    pub depth: Vec<f32>,
    pub normal: Vec<[f32; 3]>,
    pub albedo: Vec<[f32; 3]>,
    pub uv: Vec<[f32; 2]>,
    /// s, t, dsdx, dtdx, dsdy, dtdy of the first texture lookup on the camera path.
    pub tex: Vec<[f32; 6]>,
    /// Filtered RGB of that lookup and A = 1 where a lookup happened.
    pub texcolor: Vec<[f32; 4]>,
    /// Mip level used by that lookup (0 where none happened).
    pub lod: Vec<f32>,
    /// World-space footprint width at that hit (0 where none happened).
    pub footprint: Vec<f32>,
    /// Marks pixels whose first-lookup AOVs are already set.
    pub lookup_done: Vec<bool>,
}

impl TileImage {
    /// A zeroed image for `tile` with the selected AOVs.
    pub fn new(tile: PixelRect, aovs: AovSelection) -> TileImage {
        let mut image = TileImage::default();
        image.reset(tile, aovs);
        image
    }

    /// Makes this the zeroed image [`TileImage::new`] gives for `tile` and `aovs`, in the
    /// buffers it already has: a worker renders all its tiles into one image, which
    /// allocates nothing once its buffers have grown to a tile's size.
    pub fn reset(&mut self, tile: PixelRect, aovs: AovSelection) {
        fn refill<T: Clone>(buffer: &mut Vec<T>, len: usize, value: T) {
            buffer.clear();
            buffer.resize(len, value);
        }
        let n = tile.area();
        let take = |on: bool| if on { n } else { 0 };
        self.samples = None;
        refill(&mut self.color, n, [0.0; 3]);
        refill(&mut self.color_sum, n, [0; 3]);
        refill(&mut self.alpha, n, 0.0);
        refill(&mut self.depth, take(aovs.surface), f32::MAX);
        refill(&mut self.normal, take(aovs.surface), [0.0; 3]);
        refill(&mut self.albedo, take(aovs.surface), [0.0; 3]);
        refill(&mut self.uv, take(aovs.surface), [0.0; 2]);
        refill(&mut self.tex, take(aovs.texture_footprint), [0.0; 6]);
        refill(&mut self.texcolor, take(aovs.texture_footprint), [0.0; 4]);
        refill(&mut self.lod, take(aovs.lod), 0.0);
        refill(&mut self.footprint, take(aovs.lod), 0.0);
        refill(
            &mut self.lookup_done,
            take(aovs.texture_footprint || aovs.lod),
            false,
        );
    }

    /// The pixels of the tile.
    fn pixel_count(&self) -> usize {
        self.color_sum.len()
    }

    /// Makes room for `in_flight` samples of every pixel, each starting at zero radiance:
    /// sample `place` of pixel `p` goes to `color[p + place * pixels]`
    /// (`integrator::camera_sample::sample_slot`).
    pub fn begin_samples(&mut self, in_flight: usize) {
        let len = self.pixel_count() * in_flight;
        self.color.clear();
        self.color.resize(len, [0.0; 3]);
    }

    /// Adds the radiance of the samples in flight at `places` to each pixel's exact sum
    /// (`film::sample_sum`), each first scaled by [`clamp_sample`] when `clamp` is given;
    /// with `drop_nonfinite`, a sample with a NaN or infinite channel is left out instead.
    /// Returns how many were left out.
    pub fn add_samples_in_flight(
        &mut self,
        places: Range<usize>,
        drop_nonfinite: bool,
        clamp: Option<f32>,
    ) -> u64 {
        let pixels = self.pixel_count();
        let mut dropped = 0;
        if pixels == 0 {
            return 0;
        }
        let samples = &self.color[places.start * pixels..places.end * pixels];
        for sample in samples.chunks_exact(pixels) {
            for (sum, color) in self.color_sum.iter_mut().zip(sample) {
                // Black (a miss towards a black environment, a shadowed point) adds 0 to
                // the exact sum: skipping it changes no bit.
                if *color == [0.0; 3] {
                    continue;
                }
                if drop_nonfinite && !color.iter().all(|c| c.is_finite()) {
                    dropped += 1;
                } else {
                    let color = clamp.map_or(*color, |max| clamp_sample(*color, max));
                    super::sample_sum::add_sample(sum, color);
                }
            }
        }
        dropped
    }

    /// Ends the tile: every pixel's colour becomes the mean of its `sample_count` summed
    /// samples.
    pub fn finish_mean(&mut self, sample_count: u32) {
        let pixels = self.pixel_count();
        self.color.truncate(pixels);
        self.color.resize(pixels, [0.0; 3]);
        for (color, sum) in self.color.iter_mut().zip(&self.color_sum) {
            *color = sum.map(|s| super::sample_sum::mean_of_sum(s, sample_count));
        }
    }
}

/// One camera sample's radiance with no component above `max_component`: a sample whose
/// largest component exceeds it is scaled down to it as a whole, so its hue is kept
/// (pbrt-v4's film clamp, `maxcomponentvalue`: Pharr, Jakob and Humphreys 2023, Physically
/// Based Rendering, 4th ed., section 5.4, its RGB film). An infinite component becomes
/// `max_component` and the finite ones 0, the limit of that scaling; NaN is left to the
/// caller's rule.
pub fn clamp_sample(color: [f32; 3], max_component: f32) -> [f32; 3] {
    let largest = color.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    if largest <= max_component {
        color
    } else if largest.is_infinite() {
        color.map(|c| {
            if c == f32::INFINITY {
                max_component
            } else {
                0.0
            }
        })
    } else {
        let scale = max_component / largest;
        color.map(|c| (c * scale).min(max_component))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clamped_sample_keeps_its_hue_below_the_limit() {
        // Under the limit (and at it) nothing changes.
        assert_eq!(clamp_sample([0.5, 2.0, 1.0], 2.0), [0.5, 2.0, 1.0]);
        // Above it, every component is scaled by limit / largest.
        assert_eq!(clamp_sample([40.0, 10.0, 0.0], 4.0), [4.0, 1.0, 0.0]);
        let bright = [17.4, 3.1, 0.2];
        let clamped = clamp_sample(bright, 1.5);
        assert!(clamped.iter().all(|&c| c <= 1.5), "{clamped:?}");
        assert_eq!(clamped[0], 1.5);
        for (c, b) in clamped.iter().zip(bright) {
            assert!((c / b - 1.5 / 17.4).abs() < 1e-6, "{clamped:?}");
        }
        // An infinite component: the limit of the scaling.
        assert_eq!(
            clamp_sample([f32::INFINITY, 3.0, 0.0], 2.0),
            [2.0, 0.0, 0.0]
        );
        // Every sample of a pixel clamped: its mean cannot exceed the limit.
        let mut image = TileImage::new(
            PixelRect {
                x0: 0,
                y0: 0,
                width: 1,
                height: 1,
            },
            AovSelection::default(),
        );
        image.begin_samples(3);
        image.color = vec![[1e6, 0.0, 0.0], [0.0, 1e9, 3.0], [0.25, 0.5, 0.0]];
        image.add_samples_in_flight(0..3, true, Some(1.0));
        image.finish_mean(3);
        let mean = image.color[0];
        assert!(mean.iter().all(|&c| c <= 1.0), "{mean:?}");
        assert!((mean[0] - 1.25 / 3.0).abs() < 1e-6, "{mean:?}");
    }

    #[test]
    fn a_reset_image_is_a_new_one_in_the_same_buffers() {
        let big = PixelRect {
            x0: 0,
            y0: 0,
            width: 16,
            height: 16,
        };
        let small = PixelRect {
            x0: 16,
            y0: 0,
            width: 5,
            height: 3,
        };
        let mut image = TileImage::new(big, AovSelection::ALL);
        image.color.fill([1.0; 3]);
        image.depth.fill(2.0);
        image.samples = Some(0..4);
        let buffer = image.color.as_ptr();
        image.reset(small, AovSelection::ALL);
        assert_eq!(image, TileImage::new(small, AovSelection::ALL));
        assert_eq!(
            image.color.as_ptr(),
            buffer,
            "the colour buffer was reallocated"
        );
        image.reset(big, AovSelection::default());
        assert_eq!(image, TileImage::new(big, AovSelection::default()));
    }

    #[test]
    fn block_order_visits_every_pixel_once_in_4x4_blocks() {
        let tile = PixelRect {
            x0: 32,
            y0: 16,
            width: 10,
            height: 7,
        };
        let order: Vec<(u32, u32)> = block_order(tile).collect();
        assert_eq!(order.len(), 70);
        let mut seen = std::collections::HashSet::new();
        assert!(order.iter().all(|p| seen.insert(*p)));
        // The first 16 pixels are the first full 4x4 block.
        assert!(order[..16].iter().all(|&(x, y)| x < 4 && y < 4));
    }
}
