//! Bilinear blocks on an 8-bit level, [`PROBE_LANES`] at a time: the anisotropic filter's
//! probes, and the bilinear lookups of a batch (`Texture::sample_batch`).
//!
//! Texel coordinates, the integer floor, the in-bounds and same-tile tests, the tile
//! addressing and the bilinear blend run in lanes, one probe per lane, so that inside
//! `simd::dispatch` (where `aniso::sample` runs) they compile to vector instructions; the
//! texel reads and byte decoding stay one lane at a time (the 256-entry tables are
//! loads either way).
//!
//! A lane performs exactly the f32 and integer operations
//! `filter_closest_bilinear::bilinear_from` performs for its probe, so its value has the
//! same bits; a probe whose block crosses a tile or level edge is left to that scalar
//! path. The caller sums the probe values in probe order, as the scalar loop does, so the
//! filter's result is unchanged at every vector level.

use glam::Vec4;

use super::mip_pyramid::MipLevel;
use super::texels::{ByteTexels, FlatTexels};
use super::tiles::TEXTURE_TILE_SIZE;

/// Probes computed per step: one AVX2 register of f32, half an AVX-512 one.
pub(crate) const PROBE_LANES: usize = 8;

/// Widths and heights up to this take the lane path (see [`floor_i32`]).
const MAX_EXTENT: u32 = 1 << 22;
const TILE_MASK: u32 = TEXTURE_TILE_SIZE - 1;

pub(crate) type Lanes<T> = [T; PROBE_LANES];

/// The lanes `f(0)`, `f(1)`, ... A plain loop rather than `array::from_fn` or `map`,
/// which the release build left out of line (`core::array::try_from_fn`), so compiled at
/// the baseline level and called per step.
#[inline(always)]
fn lanes<T: Copy + Default>(mut f: impl FnMut(usize) -> T) -> Lanes<T> {
    let mut out = [T::default(); PROBE_LANES];
    for (lane, value) in out.iter_mut().enumerate() {
        *value = f(lane);
    }
    out
}

/// Probes `first..first + PROBE_LANES` of a line of `count` probes at
/// (s, t) + p (ds, dt), p = 2 (i + 1/2) / n - 1 (with `inv_n` = 1 / n), the same positions
/// `aniso::probes` computes.
#[derive(Clone, Copy)]
pub(crate) struct ProbeStep {
    pub(crate) first: usize,
    pub(crate) count: usize,
    pub(crate) s: f32,
    pub(crate) t: f32,
    pub(crate) ds: f32,
    pub(crate) dt: f32,
    pub(crate) inv_n: f32,
}

/// Bilinear values of one step's probes, channel-major, with the texel block each served
/// probe read (for the observer) and which probes were served.
pub(crate) struct ProbeValues {
    rgba: [Lanes<f32>; 4],
    block: [Lanes<u32>; 2],
    served: Lanes<bool>,
}

impl ProbeValues {
    /// The value of probe `first + lane` and the upper-left texel of its block, or `None`
    /// when the scalar path must compute it.
    #[inline(always)]
    pub(crate) fn get(&self, lane: usize) -> Option<(Vec4, usize, usize)> {
        self.served[lane].then(|| {
            let [r, g, b, a] = &self.rgba;
            let v = Vec4::new(r[lane], g[lane], b[lane], a[lane]);
            (
                v,
                self.block[0][lane] as usize,
                self.block[1][lane] as usize,
            )
        })
    }
}

/// Whether [`byte_probes`] can address `level`: its texel indices fit in u32 and its
/// sides in [`MAX_EXTENT`].
#[inline(always)]
pub(crate) fn addressable(level: &MipLevel) -> bool {
    level.width <= MAX_EXTENT
        && level.height <= MAX_EXTENT
        && u32::try_from(level.width as u64 * level.height as u64).is_ok()
}

/// The step's probes on `level` (its texels `texels`; [`addressable`]).
#[inline(always)]
pub(crate) fn byte_probes(level: &MipLevel, texels: ByteTexels, step: &ProbeStep) -> ProbeValues {
    let (x, y) = texel_positions(level, step);
    byte_bilinear(level, texels, x, y, step.count.saturating_sub(step.first))
}

/// Bilinear values at the texel-space positions (`x`, `y`) (x = s * width - 0.5) of the
/// first `count` lanes on `level` (its texels `texels`; [`addressable`]): the anisotropic
/// probes, and the batched bilinear lookups of `Texture::sample_batch`.
#[inline(always)]
pub(crate) fn byte_bilinear(
    level: &MipLevel,
    texels: ByteTexels,
    x: Lanes<f32>,
    y: Lanes<f32>,
    count: usize,
) -> ProbeValues {
    let (i, j) = (lanes(|l| floor_i32(x[l])), lanes(|l| floor_i32(y[l])));
    let (index, stride, mut served) = block_addresses(level, count, i, j);
    let corners = read_blocks(texels, index, stride, &mut served);
    let fs = lanes(|l| x[l] - i[l] as f32);
    let ft = lanes(|l| y[l] - j[l] as f32);
    ProbeValues {
        rgba: [
            blend(&corners, 0, &fs, &ft),
            blend(&corners, 1, &fs, &ft),
            blend(&corners, 2, &fs, &ft),
            blend(&corners, 3, &fs, &ft),
        ],
        block: [lanes(|l| i[l] as u32), lanes(|l| j[l] as u32)],
        served,
    }
}

/// Texel-space positions x = s * width - 0.5, y = t * height - 0.5 of the step's probes.
#[inline(always)]
fn texel_positions(level: &MipLevel, step: &ProbeStep) -> (Lanes<f32>, Lanes<f32>) {
    let first = step.first as i32;
    let p = lanes(|l| 2.0 * ((first + l as i32) as f32 + 0.5) * step.inv_n - 1.0);
    let (w, h) = (level.width as f32, level.height as f32);
    let x = lanes(|l| (step.s + p[l] * step.ds) * w - 0.5);
    let y = lanes(|l| (step.t + p[l] * step.dt) * h - 0.5);
    (x, y)
}

/// floor(x) for x in [0, 2^22), the probes that can be served, as
/// `filter_closest_bilinear::floor_i32` gives it there; anything else (NaN included) gives
/// -1 or at least 2^22, which no served block has. Written without a float-to-integer
/// cast, whose saturation Rust defines and LLVM left scalar: adding 1.5 * 2^23 rounds x to
/// an integer held in the low mantissa bits, and a rounding upward is stepped back.
#[inline(always)]
fn floor_i32(x: f32) -> i32 {
    const MAGIC: f32 = 12_582_912.0; // 1.5 * 2^23
    let clamped = x.max(-1.0).min(MAX_EXTENT as f32);
    let rounded = (clamped + MAGIC).to_bits() as i32 - MAGIC.to_bits() as i32;
    rounded - ((rounded as f32 > clamped) as i32)
}

/// Index of each block's upper-left texel and its tile's row stride (as
/// `TileLayout::block_in_one_tile` and `tile_start` give them), and whether the probe is
/// one of the first `count` with its block inside the level and inside one tile.
#[inline(always)]
fn block_addresses(
    level: &MipLevel,
    count: usize,
    i: Lanes<i32>,
    j: Lanes<i32>,
) -> (Lanes<u32>, Lanes<u32>, Lanes<bool>) {
    let (w, h) = (level.width, level.height);
    let tile_extent = |start: u32, size: u32| size.wrapping_sub(start).min(TEXTURE_TILE_SIZE);
    let (x, y) = (lanes(|l| i[l] as u32), lanes(|l| j[l] as u32));
    let stride = lanes(|l| tile_extent(x[l] & !TILE_MASK, w));
    let tile_h = lanes(|l| tile_extent(y[l] & !TILE_MASK, h));
    let (local_x, local_y) = (lanes(|l| x[l] & TILE_MASK), lanes(|l| y[l] & TILE_MASK));
    let index = lanes(|l| {
        let tile_start = (y[l] & !TILE_MASK)
            .wrapping_mul(w)
            .wrapping_add((x[l] & !TILE_MASK).wrapping_mul(tile_h[l]));
        tile_start.wrapping_add(local_y[l].wrapping_mul(stride[l]).wrapping_add(local_x[l]))
    });
    let served = lanes(|l| {
        (l < count)
            & (x[l] < w - 1)
            & (y[l] < h - 1)
            & (local_x[l] + 1 < stride[l])
            & (local_y[l] + 1 < tile_h[l])
    });
    (index, stride, served)
}

/// The four decoded texels of each served probe's block, corner-major then channel-major;
/// a block the buffer does not hold is left to the scalar path.
#[inline(always)]
fn read_blocks(
    texels: ByteTexels,
    index: Lanes<u32>,
    stride: Lanes<u32>,
    served: &mut Lanes<bool>,
) -> [[Lanes<f32>; 4]; 4] {
    let mut corners = [[[0.0f32; PROBE_LANES]; 4]; 4];
    for l in 0..PROBE_LANES {
        if !served[l] {
            continue;
        }
        let block = texels.bilinear_quad(index[l] as usize, stride[l] as usize, |a, b, c, d| {
            [a, b, c, d]
        });
        match block {
            Some(block) => {
                for (corner, texel) in corners.iter_mut().zip(block) {
                    for (channel, value) in corner.iter_mut().zip(texel.to_array()) {
                        channel[l] = value;
                    }
                }
            }
            None => served[l] = false,
        }
    }
    corners
}

/// Channel `c` of the bilinear blend, the operations of `bilinear_from`'s blend.
#[inline(always)]
fn blend(corners: &[[Lanes<f32>; 4]; 4], c: usize, fs: &Lanes<f32>, ft: &Lanes<f32>) -> Lanes<f32> {
    let [a, b, cc, d] = [
        &corners[0][c],
        &corners[1][c],
        &corners[2][c],
        &corners[3][c],
    ];
    lanes(|l| {
        let top = a[l] * (1.0 - fs[l]) + b[l] * fs[l];
        let bottom = cc[l] * (1.0 - fs[l]) + d[l] * fs[l];
        top * (1.0 - ft[l]) + bottom * ft[l]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_matches_the_scalar_floor_where_blocks_can_be_served() {
        let mut x = 0.0f32;
        while x < MAX_EXTENT as f32 {
            for v in [
                x,
                x.next_up(),
                x.next_down().max(0.0),
                x + 0.5,
                x + 0.999_999,
            ] {
                if v < MAX_EXTENT as f32 {
                    assert_eq!(floor_i32(v), v.floor() as i32, "{v}");
                }
            }
            x = if x < 4.0 { x + 0.25 } else { x * 1.37 };
        }
        for outside in [-0.0001f32, -1.0, -1e9, f32::NAN, f32::NEG_INFINITY] {
            assert_eq!(floor_i32(outside), -1, "{outside}");
        }
        for beyond in [MAX_EXTENT as f32, 1e9, f32::INFINITY] {
            assert!(floor_i32(beyond) >= MAX_EXTENT as i32, "{beyond}");
        }
    }
}
