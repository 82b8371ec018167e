//! Sample positions: Owen-scrambled Sobol points, drawn one dimension (or one pair of
//! dimensions) at a time along a path.
//!
//! Every value is a pure function of (seed, pixel, sample index, dimension): a tile renders
//! the same on any thread, a resumed render equals an uninterrupted one, and sample i of a
//! pixel does not depend on which other samples of it are rendered (a render split by sample
//! range and merged equals the whole). Nor does it depend on the sample count, so the first
//! N samples of a 4N-sample render are exactly the N-sample render's.
//!
//! # The construction
//!
//! Each pair of dimensions (the pixel position, the lens position, and whatever an
//! integrator draws after them) takes the first two Sobol dimensions ([`sobol`]), a
//! (0,2)-sequence, padded the way Burley describes ("Practical Hash-based Owen Scrambling",
//! JCGT 9(4), 2020, sections 4-5) and pbrt-v4's `PaddedSobolSampler` does:
//! - the sample index is shuffled by a nested uniform scramble keyed by (seed, pixel,
//!   dimension), which maps the first 2^k indices onto an aligned block of 2^k Sobol
//!   points, so the first 2^k samples of every pixel are still a (0,k,2)-net;
//! - both coordinates are then Owen-scrambled ([`scramble`]) with their own keys, which
//!   makes every point uniform on [0, 1)^2 and the pixels and pairs of dimensions
//!   statistically independent of one another.
//!
//! A single dimension takes the shuffled, scrambled van der Corput sequence (Sobol
//! dimension 0), stratified in 1D the same way.
//!
//! So in every pixel, every 2D projection that a pair draws is stratified like a progressive
//! multi-jittered (0,2) sequence (Christensen, Kensler & Kilpatrick 2018, "Progressive
//! Multi-Jittered Sample Sequences", who found Owen-scrambled Sobol and pmj02 to converge
//! alike in 2D): one point in every elementary interval of area 1/N for N a power of two,
//! and still well spread between powers of two. The error of a smooth pixel integrand then
//! falls like N^-1.5 instead of jitter's N^-1. Why this order and not pbrt-v4's
//! ZSobol (Morton) order, which spreads one global sequence over neighbouring pixels:
//! docs/benchmarks.md, "Sampler".
//!
//! # Dimensions
//!
//! [`PixelSampler::camera_sample`] always takes dimensions 0-1 (position in the pixel) and
//! 2-3 (position on the lens), whether the camera uses the lens or not, so an integrator's
//! own draws start at dimension 4 in every render and do not change when depth of field is
//! switched on.

mod scramble;
mod sobol;

use glam::Vec2;

use crate::simd;
use scramble::{
    hash_u32, hash_words, nested_uniform_scramble, scramble_mirrored, unit_float, HASH_START,
};

/// The sampler of one render: the seed every sample position derives from (`--seed`,
/// `[render] seed`). Equal seeds give bit-identical images.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sampler {
    seed: u32,
}

impl Sampler {
    pub fn new(seed: u32) -> Sampler {
        Sampler { seed }
    }

    pub fn seed(&self) -> u32 {
        self.seed
    }

    /// The sampler of sample `index` of pixel `pixel` (any number that identifies the pixel
    /// within the image, e.g. `y * width + x`), starting at dimension 0.
    #[inline]
    pub fn pixel(&self, pixel: u32, index: u32) -> PixelSampler {
        PixelSampler {
            pixel_state: pixel_state(hash_words(&[self.seed, pixel])),
            index,
            dimension: 0,
        }
    }
}

/// The camera draws of a packet of pixels for one sample index, lane by lane the values
/// [`Sampler::pixel`] and [`PixelSampler::camera_sample_drawing`] give, computed as
/// structure-of-arrays: the hashes and scrambles of the lanes are independent integer
/// work, which runs as vector instructions where the target has them.
#[derive(Clone, Copy, Debug)]
pub struct CameraLanes<const N: usize> {
    /// Each lane's sampler, past the camera's four dimensions.
    pub samplers: [PixelSampler; N],
    /// Position inside the pixel, x and y.
    pub offset: [[f32; N]; 2],
    /// Position on the lens, x and y.
    pub lens: [[f32; N]; 2],
}

impl Sampler {
    /// [`PixelSampler::camera_sample_drawing`] of sample `indices[lane]` of each of
    /// `pixels[lane]` (numbered as for [`Sampler::pixel`]): the same values, bit for bit.
    /// The lanes may be different pixels, different samples of one pixel, or both. Runs
    /// with the processor's widest vector instructions ([`simd::dispatch`]).
    pub fn camera_lanes<const N: usize>(
        &self,
        pixels: &[u32; N],
        indices: &[u32; N],
        samples_per_pixel: u32,
        lens: bool,
    ) -> CameraLanes<N> {
        simd::dispatch(
            #[inline(always)]
            || self.camera_lanes_inline(pixels, indices, samples_per_pixel, lens),
        )
    }

    /// [`Sampler::camera_lanes`] compiled into its caller, for a caller that is itself a
    /// [`simd::dispatch`] kernel.
    #[inline(always)]
    pub fn camera_lanes_inline<const N: usize>(
        &self,
        pixels: &[u32; N],
        indices: &[u32; N],
        samples_per_pixel: u32,
        lens: bool,
    ) -> CameraLanes<N> {
        // `hash_words(&[seed, pixel])` written out, its first step shared by every lane.
        // Lanes of one pixel (a pixel's samples in one packet) share its state: hashed once.
        let seed_state = hash_u32(HASH_START ^ hash_u32(self.seed));
        let mut states = [0u32; N];
        let mut last: Option<(u32, u32)> = None;
        for (state, &pixel) in states.iter_mut().zip(pixels) {
            *state = match last {
                Some((last_pixel, last_state)) if last_pixel == pixel => last_state,
                _ => pixel_state(hash_u32(seed_state ^ hash_u32(pixel))),
            };
            last = Some((pixel, *state));
        }
        let centre = [[0.5f32; N]; 2];
        let offset = if samples_per_pixel <= 1 {
            centre
        } else {
            next_2d_lanes(&states, indices, 0)
        };
        let lens = if lens {
            next_2d_lanes(&states, indices, 2)
        } else {
            centre
        };
        CameraLanes {
            samplers: std::array::from_fn(|lane| PixelSampler {
                pixel_state: states[lane],
                index: indices[lane],
                dimension: 4,
            }),
            offset,
            lens,
        }
    }
}

/// [`PixelSampler::next_2d`] at `dimension` for the pixel states `states` and sample
/// indices `indices`, lane by lane. A lane of the same pixel as the lane before it reuses
/// that lane's keys, which depend on the pixel and the dimension alone.
#[inline(always)]
fn next_2d_lanes<const N: usize>(
    states: &[u32; N],
    indices: &[u32; N],
    dimension: u32,
) -> [[f32; N]; 2] {
    // The keys first (a branch per lane), then the draws in a loop without branches, which
    // the compiler turns into vector instructions.
    let mut keys = [DrawKeys::default(); N];
    let mut last: Option<(u32, DrawKeys)> = None;
    for (lane_keys, &state) in keys.iter_mut().zip(states) {
        *lane_keys = match last {
            Some((last_state, last_keys)) if last_state == state => last_keys,
            _ => DrawKeys::new(draw_key(state, dimension)),
        };
        last = Some((state, *lane_keys));
    }
    draw_2d_lanes(&keys, indices)
}

/// Sample `indices[lane]` of each lane's scrambled first two Sobol dimensions, keyed by
/// `keys[lane]`: x, then y, in a loop without branches.
#[inline(always)]
fn draw_2d_lanes<const N: usize>(keys: &[DrawKeys; N], indices: &[u32; N]) -> [[f32; N]; 2] {
    let mut out = [[0.0f32; N]; 2];
    for lane in 0..N {
        let point = keys[lane].draw_2d(indices[lane]);
        out[0][lane] = point.x;
        out[1][lane] = point.y;
    }
    out
}

/// Draws of many paths' samplers at once, each lane at its own sampler's dimension plus
/// `offset`, without moving the samplers on: lane by lane the values [`PixelSampler::next_1d`]
/// and [`PixelSampler::next_2d`] give at that dimension, bit for bit. Every lane's keys and
/// scrambles are hashed without a branch, so a caller compiled inside a [`simd::dispatch`]
/// kernel runs them as vector instructions.
#[derive(Clone, Copy, Debug)]
pub struct SamplerLanes<const N: usize> {
    states: [u32; N],
    indices: [u32; N],
    dimensions: [u32; N],
}

impl<const N: usize> SamplerLanes<N> {
    /// The lanes of `samplers`.
    #[inline(always)]
    pub fn new(samplers: &[PixelSampler; N]) -> SamplerLanes<N> {
        SamplerLanes {
            states: samplers.map(|s| s.pixel_state),
            indices: samplers.map(|s| s.index),
            dimensions: samplers.map(|s| s.dimension),
        }
    }

    /// Each lane's draw keys at its dimension plus `offset` ([`draw_key`]).
    #[inline(always)]
    fn keys(&self, offset: u32) -> [u32; N] {
        std::array::from_fn(|lane| {
            draw_key(
                self.states[lane],
                self.dimensions[lane].wrapping_add(offset),
            )
        })
    }

    /// [`PixelSampler::next_1d`] of every lane at its dimension plus `offset`.
    #[inline(always)]
    pub fn draw_1d(&self, offset: u32) -> [f32; N] {
        let keys = self.keys(offset);
        std::array::from_fn(|lane| draw_1d(keys[lane], self.indices[lane]))
    }

    /// [`PixelSampler::next_2d`] of every lane at its dimension plus `offset`: x, then y.
    #[inline(always)]
    pub fn draw_2d(&self, offset: u32) -> [[f32; N]; 2] {
        let keys = self.keys(offset);
        let keys: [DrawKeys; N] = std::array::from_fn(|lane| DrawKeys::new(keys[lane]));
        draw_2d_lanes(&keys, &self.indices)
    }
}

/// The key of the draw at `dimension`: `hash_words(&[pixel_key, dimension])`, its first
/// step (`pixel_state`) done once per pixel.
#[inline]
fn draw_key(pixel_state: u32, dimension: u32) -> u32 {
    hash_u32(pixel_state ^ hash_u32(dimension))
}

/// Sample `index` of the Owen-scrambled first Sobol dimension, keyed by `key`.
#[inline(always)]
fn draw_1d(key: u32, index: u32) -> f32 {
    let shuffled = nested_uniform_scramble(index, key);
    // Sobol dimension 0 mirrored is the (shuffled) index itself.
    unit_float(scramble_mirrored(shuffled, hash_u32(key ^ X_SCRAMBLE_SALT)))
}

/// Sample `index` of the Owen-scrambled first two Sobol dimensions, keyed by `key`.
#[inline]
fn draw_2d(key: u32, index: u32) -> Vec2 {
    DrawKeys::new(key).draw_2d(index)
}

/// Mixed into a draw's key for the scramble of its first coordinate (also a 1D draw's).
const X_SCRAMBLE_SALT: u32 = 0x5bd1_e995;
/// Mixed into a draw's key for the scramble of its second coordinate.
const Y_SCRAMBLE_SALT: u32 = 0x1b87_3593;

/// The scrambles of one 2D draw: of the sample index and of each coordinate, all derived
/// from the draw's key.
#[derive(Clone, Copy, Default)]
struct DrawKeys {
    index: u32,
    x: u32,
    y: u32,
}

impl DrawKeys {
    #[inline]
    fn new(key: u32) -> DrawKeys {
        DrawKeys {
            index: key,
            x: hash_u32(key ^ X_SCRAMBLE_SALT),
            y: hash_u32(key ^ Y_SCRAMBLE_SALT),
        }
    }

    /// Sample `index` of the scrambled first two Sobol dimensions.
    #[inline]
    fn draw_2d(&self, index: u32) -> Vec2 {
        let shuffled = nested_uniform_scramble(index, self.index);
        // The scramble works on mirrored bits: Sobol dimension 0 mirrored is the index, and
        // dimension 1 mirrored has a closed form (`sobol::dimension_1_mirrored`).
        let x = scramble_mirrored(shuffled, self.x);
        let y = scramble_mirrored(sobol::dimension_1_mirrored(shuffled), self.y);
        Vec2::new(unit_float(x), unit_float(y))
    }
}

/// The state `hash_words(&[pixel_key, dimension])` has after folding in `pixel_key`: every
/// draw's key starts from it (`PixelSampler::take`).
#[inline]
fn pixel_state(pixel_key: u32) -> u32 {
    hash_u32(HASH_START ^ hash_u32(pixel_key))
}

/// Where a camera ray starts: the position inside the pixel and on the lens, each in
/// [0, 1)^2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSample {
    pub pixel_offset: Vec2,
    pub lens: Vec2,
}

/// The sample values of one sample of one pixel, drawn in order: each call takes the next
/// one or two dimensions. Small and `Copy`, so a path can carry it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelSampler {
    /// The seed and the pixel, hashed together (the pixel key), then carried through the
    /// first step of every draw's key (`pixel_state`), which depends on the pixel alone.
    pixel_state: u32,
    index: u32,
    dimension: u32,
}

impl PixelSampler {
    /// The sample index within the pixel.
    pub fn index(&self) -> u32 {
        self.index
    }

    /// The next dimension to be drawn.
    pub fn dimension(&self) -> u32 {
        self.dimension
    }

    /// Key of the draw starting at the current dimension, and the dimension moved on.
    #[inline]
    fn take(&mut self, count: u32) -> u32 {
        let key = draw_key(self.pixel_state, self.dimension);
        self.dimension += count;
        key
    }

    /// Moves past `count` dimensions without drawing them, so that an estimator that uses
    /// fewer dimensions on some paths still starts its next step at the same dimension.
    #[inline]
    pub fn skip_dimensions(&mut self, count: u32) {
        self.dimension += count;
    }

    /// The next dimension: a value in [0, 1).
    #[inline]
    pub fn next_1d(&mut self) -> f32 {
        let key = self.take(1);
        draw_1d(key, self.index)
    }

    /// The next two dimensions: a point in [0, 1)^2.
    #[inline]
    pub fn next_2d(&mut self) -> Vec2 {
        let key = self.take(2);
        draw_2d(key, self.index)
    }

    /// The camera's dimensions 0-3 (see the module's doc). With one sample per pixel the
    /// sample sits at the pixel centre: a footprint-filtered ray then covers its pixel
    /// symmetrically, and the single-sample image is the texture filtered around each pixel
    /// centre, as OpenImageIO's lookups with the same footprint are.
    #[inline]
    pub fn camera_sample(&mut self, samples_per_pixel: u32) -> CameraSample {
        self.camera_sample_drawing(samples_per_pixel, true)
    }

    /// [`camera_sample`](Self::camera_sample) computing only the values the camera uses: the
    /// position in the pixel only with more than one sample per pixel, the lens position only
    /// when `lens` (a thin-lens camera); an undrawn lens position is the lens centre (0.5,
    /// 0.5). Both pairs of dimensions are taken either way, so later draws are the same.
    #[inline]
    pub fn camera_sample_drawing(&mut self, samples_per_pixel: u32, lens: bool) -> CameraSample {
        let pixel_offset = if samples_per_pixel <= 1 {
            self.skip(2);
            Vec2::splat(0.5)
        } else {
            self.next_2d()
        };
        let lens = if lens {
            self.next_2d()
        } else {
            self.skip(2);
            Vec2::splat(0.5)
        };
        CameraSample { pixel_offset, lens }
    }

    /// Takes `count` dimensions without drawing them.
    #[inline]
    fn skip(&mut self, count: u32) {
        self.dimension += count;
    }
}

#[cfg(test)]
mod tests;
