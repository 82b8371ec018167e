//! Bilinear blocks on a level, [`PROBE_LANES`] at a time: the anisotropic filter's probes (on
//! levels of every storage kind, resident or demand-loaded), and the bilinear lookups of a
//! batch on an 8-bit level (`Texture::sample_batch`).
//!
//! Texel coordinates, the integer floor, the wrap of each axis and the tile addressing of
//! each of a block's four texels run in lanes, one probe per lane, so that inside
//! `simd::dispatch` (where `aniso::sample` runs) they compile to vector instructions. The
//! texel reads, the byte decoding (256-entry tables: loads either way) and the bilinear
//! blend then run one probe at a time on its four texels as `Vec4`s, straight from the
//! reads: moving decoded texels into channel-major lanes went through the stack one lane at
//! a time, and the vector loads after those narrow stores stalled.
//!
//! A probe performs exactly the f32 and integer operations of the scalar probe,
//! `filter_closest_bilinear::bilinear_from` (and, for a block across an edge of the level,
//! its wrapped paths, which blend the same way), so its value has the same bits. Each of
//! the block's texels is addressed on its own, so a block across a tile edge or wrapped
//! across the level's edge is served like one inside a tile; only a probe more than one
//! period away from the level on an axis whose side is not a power of two and which
//! repeats (periodic or mirror), or 2^22 texels or more away (NaN included), is left to the
//! scalar path. The caller sums the probe values
//! in probe order, as the scalar loop does, so the filter's result is unchanged at every
//! vector level.

use glam::Vec4;

use super::mip_pyramid::MipLevel;
use super::texels::FlatTexels;
use super::tiles::{TexelObserver, TEXTURE_TILE_SIZE};
use super::WrapMode;

/// Probes computed per step: one AVX2 register of f32, half an AVX-512 one.
pub(crate) const PROBE_LANES: usize = 8;

/// Widths and heights up to this take the lane path (see [`floor_i32`]).
const MAX_EXTENT: u32 = 1 << 22;
const TILE_MASK: u32 = TEXTURE_TILE_SIZE - 1;

pub(crate) type Lanes<T> = [T; PROBE_LANES];

/// A lane mask: all ones where a condition holds, zero where not. Masks rather than bools:
/// LLVM kept lanes of bools one lane at a time, packing and unpacking bytes, while a
/// comparison's mask is what the vector instructions give.
pub(crate) type Mask = Lanes<u32>;

/// The mask lane of `condition`.
#[inline(always)]
fn mask(condition: bool) -> u32 {
    (condition as u32).wrapping_neg()
}

/// The lanes `f(0)`, `f(1)`, ... A plain loop rather than `array::from_fn` or `map`,
/// which the release build left out of line (`core::array::try_from_fn`), so compiled at
/// the baseline level and called per step.
#[inline(always)]
pub(crate) fn lanes<T: Copy + Default>(mut f: impl FnMut(usize) -> T) -> Lanes<T> {
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

/// The columns (or rows) of the two texels of each lane's block along one axis, as
/// `wrap::wrap_texel` maps them, and whether each is inside the level (only a black wrap
/// leaves one outside, and it then counts as zero).
#[derive(Clone, Copy)]
struct AxisTexels {
    texel: [Lanes<u32>; 2],
    inside: [Mask; 2],
    /// Lanes whose texels these are (the others take the scalar path).
    served: Mask,
}

/// Where one step's probes read: the index of each of a block's four texels (corner-major:
/// upper left, upper right, lower left, lower right) in the level's buffer, and the number
/// of its tile with its index inside that tile; the blend fractions, which texels are
/// inside the level, and which probes are served.
pub(crate) struct ProbeBlocks {
    index: [Lanes<u32>; 4],
    tile: [Lanes<u32>; 4],
    in_tile: [Lanes<u32>; 4],
    fraction: [Lanes<f32>; 2],
    columns: AxisTexels,
    rows: AxisTexels,
    served: Mask,
    /// A black wrap on either axis, so a texel may be outside (the other modes map every
    /// texel inside, and [`ProbeBlocks::value`] skips the test).
    black: bool,
}

impl ProbeBlocks {
    /// Whether probe `first + lane` is served here (else the scalar path computes it).
    #[inline(always)]
    pub(crate) fn served(&self, lane: usize) -> bool {
        self.served[lane] != 0
    }

    /// The bilinear value of served probe `first + lane`, read from `texels` (the buffer
    /// the blocks were addressed in).
    #[inline(always)]
    pub(crate) fn value<'a, F: FlatTexels<'a>>(&self, texels: F, lane: usize) -> Vec4 {
        self.blend(lane, |corner| {
            texels.texel(self.index[corner][lane] as usize)
        })
    }

    /// The served lanes whose four texels lie in one tile (that of corner 0, [`Self::tile`]),
    /// which [`ProbeBlocks::value_in_tile`] reads from that tile alone.
    #[inline(always)]
    pub(crate) fn single_tile(&self) -> Lanes<bool> {
        let [a, b, c, d] = &self.tile;
        lanes(|l| (self.served[l] != 0) & (a[l] == b[l]) & (a[l] == c[l]) & (a[l] == d[l]))
    }

    /// The number of the tile (row of tiles times tiles per row, plus column) holding the
    /// upper-left texel of lane `lane`'s block.
    #[inline(always)]
    pub(crate) fn tile(&self, lane: usize) -> u32 {
        self.tile[0][lane]
    }

    /// [`ProbeBlocks::value`] of a [`ProbeBlocks::single_tile`] lane read from `tile`, the
    /// texels of its tile; `None` when an index lies past them (a tile of another size than
    /// the layout's, which the scalar path then reads).
    #[inline(always)]
    pub(crate) fn value_in_tile<'a, F: FlatTexels<'a>>(
        &self,
        tile: F,
        lane: usize,
    ) -> Option<Vec4> {
        let len = u32::try_from(tile.len()).unwrap_or(u32::MAX);
        let [a, b, c, d] = &self.in_tile;
        ((a[lane] < len) & (b[lane] < len) & (c[lane] < len) & (d[lane] < len)).then(|| {
            self.blend(lane, |corner| {
                tile.texel(self.in_tile[corner][lane] as usize)
            })
        })
    }

    /// `bilinear_from`'s blend of lane `lane`'s four texels, each read by `texel(corner)`
    /// unless it lies outside under a black wrap (zero).
    #[inline(always)]
    fn blend(&self, lane: usize, texel: impl Fn(usize) -> Vec4) -> Vec4 {
        let texel = |corner: usize| {
            let inside = !self.black
                || self.columns.inside[corner & 1][lane] & self.rows.inside[corner >> 1][lane] != 0;
            if inside {
                texel(corner)
            } else {
                Vec4::ZERO
            }
        };
        let (a, b, c, d) = (texel(0), texel(1), texel(2), texel(3));
        let (fs, ft) = (self.fraction[0][lane], self.fraction[1][lane]);
        let top = a * (1.0 - fs) + b * fs;
        let bottom = c * (1.0 - fs) + d * fs;
        top * (1.0 - ft) + bottom * ft
    }

    /// Tells `obs` of the texels served probe `first + lane` read on mip level `level`,
    /// in the order the scalar probe reads them (row by row, left to right; a texel outside
    /// under a black wrap is not read).
    #[inline(always)]
    pub(crate) fn touch_texels_read<O: TexelObserver>(
        &self,
        lane: usize,
        level: usize,
        obs: &mut O,
    ) {
        // Written out rather than mapped: `map` may be left out of line (see `lanes`).
        let (columns, rows) = (&self.columns, &self.rows);
        let xs = [
            columns.texel[0][lane] as usize,
            columns.texel[1][lane] as usize,
        ];
        let ys = [rows.texel[0][lane] as usize, rows.texel[1][lane] as usize];
        let inside = |r: usize, c: usize| rows.inside[r][lane] & columns.inside[c][lane] != 0;
        let inside = [[inside(0, 0), inside(0, 1)], [inside(1, 0), inside(1, 1)]];
        obs.touch_block(level, xs, ys, inside);
    }
}

/// Whether [`probe_blocks`] can address `level`: its texel indices fit in u32 and its
/// sides in [`MAX_EXTENT`].
#[inline(always)]
pub(crate) fn addressable(level: &MipLevel) -> bool {
    level.width <= MAX_EXTENT
        && level.height <= MAX_EXTENT
        && u32::try_from(level.width as u64 * level.height as u64).is_ok()
}

/// Where the step's probes on `level` ([`addressable`]) read under `wrap`; `len` is the
/// length of the buffer the level's texels are indexed in (a demand-loaded level, whose
/// texels are read by tile, has none: `usize::MAX`).
#[inline(always)]
pub(crate) fn probe_blocks(
    level: &MipLevel,
    len: usize,
    step: &ProbeStep,
    wrap: (WrapMode, WrapMode),
) -> ProbeBlocks {
    let (x, y) = texel_positions(level, step);
    blocks(
        level,
        len,
        x,
        y,
        step.count.saturating_sub(step.first),
        wrap,
    )
}

/// Where bilinear lookups at the texel-space positions (`x`, `y`) (x = s * width - 0.5) of
/// the first `count` lanes read on `level` ([`addressable`]; its texels in a buffer of `len`)
/// under `wrap`: the anisotropic probes, and the bilinear lookups of `Texture::sample_batch`.
#[inline(always)]
pub(crate) fn blocks(
    level: &MipLevel,
    len: usize,
    x: Lanes<f32>,
    y: Lanes<f32>,
    count: usize,
    wrap: (WrapMode, WrapMode),
) -> ProbeBlocks {
    let (i, j) = (lanes(|l| floor_i32(x[l])), lanes(|l| floor_i32(y[l])));
    let columns = wrap_axis(&i, level.width, wrap.0);
    let rows = wrap_axis(&j, level.height, wrap.1);
    let mut served = lanes(|l| mask(l < count) & columns.served[l] & rows.served[l]);
    let addresses = block_addresses(level, &columns, &rows, len, &mut served);
    ProbeBlocks {
        index: addresses.index,
        tile: addresses.tile,
        in_tile: addresses.in_tile,
        fraction: [lanes(|l| x[l] - i[l] as f32), lanes(|l| y[l] - j[l] as f32)],
        columns,
        rows,
        served,
        black: wrap.0 == WrapMode::Black || wrap.1 == WrapMode::Black,
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

/// floor(x) for x in [-2^22, 2^22], as `filter_closest_bilinear::floor_i32` and
/// `wrap::floor_f32` give it there; x beyond (NaN included) gives -2^22 or 2^22, which
/// [`wrap_axis`] refuses. Written without a float-to-integer cast, whose saturation
/// Rust defines and LLVM left scalar: adding 1.5 * 2^23 rounds x to an integer held in the
/// low mantissa bits (the sum stays in [2^23, 2^24], where the spacing is 1), and a
/// rounding upward is stepped back.
#[inline(always)]
fn floor_i32(x: f32) -> i32 {
    const MAGIC: f32 = 12_582_912.0; // 1.5 * 2^23
    let limit = MAX_EXTENT as f32;
    let clamped = x.max(-limit).min(limit);
    let rounded = (clamped + MAGIC).to_bits() as i32 - MAGIC.to_bits() as i32;
    rounded - ((rounded as f32 > clamped) as i32)
}

/// Both texels of each lane's block along an axis of `n` texels, from the block's first
/// texel `i`, as `wrap::wrap_texel` maps texels i and i + 1, and whether the lane can be
/// served: |i| < 2^22 ([`floor_i32`]'s range), and for a periodic or mirrored axis whose
/// side is not a power of two i in [-n, n) (where the wrap needs no division; the range
/// the scalar periodic path serves too). A power-of-two side wraps any i with a mask, as
/// `rem_euclid` does. One loop per mode, so the mode is not decided per lane.
#[inline(always)]
fn wrap_axis(i: &Lanes<i32>, n: u32, mode: WrapMode) -> AxisTexels {
    let n = n as i32;
    let limit = MAX_EXTENT as i32;
    let in_range = |i: i32| (i > -limit) & (i < limit);
    let within_a_period = |i: i32| (i >= -n) & (i < n);
    let inside = |_: i32| true;
    let power_of_two = n.count_ones() == 1;
    match mode {
        WrapMode::Periodic if power_of_two => axis_texels(i, in_range, |k| k & (n - 1), inside),
        WrapMode::Periodic => axis_texels(
            i,
            within_a_period,
            |k| {
                let k = if k < 0 { k + n } else { k };
                if k >= n {
                    k - n
                } else {
                    k
                }
            },
            inside,
        ),
        WrapMode::Clamp => axis_texels(i, in_range, |k| k.clamp(0, n - 1), inside),
        WrapMode::Black => axis_texels(
            i,
            in_range,
            |k| if (k >= 0) & (k < n) { k } else { 0 },
            |k| (k >= 0) & (k < n),
        ),
        WrapMode::Mirror if power_of_two => axis_texels(
            i,
            in_range,
            |k| {
                let k = k & (2 * n - 1);
                if k >= n {
                    2 * n - 1 - k
                } else {
                    k
                }
            },
            inside,
        ),
        WrapMode::Mirror => axis_texels(
            i,
            within_a_period,
            |k| {
                // rem_euclid(k, 2n) folded back into [0, n), for k in [-n, n].
                let k = if k < 0 { -1 - k } else { k };
                if k >= n {
                    2 * n - 1 - k
                } else {
                    k
                }
            },
            inside,
        ),
    }
}

/// [`wrap_axis`] for one mode: the lanes `served` serves, and for texel coordinate k the
/// stored texel `texel(k)` and whether it is `inside`.
#[inline(always)]
fn axis_texels(
    i: &Lanes<i32>,
    served: impl Fn(i32) -> bool,
    texel: impl Fn(i32) -> i32,
    inside: impl Fn(i32) -> bool,
) -> AxisTexels {
    let next = lanes(|l| i[l].wrapping_add(1));
    AxisTexels {
        texel: [
            lanes(|l| texel(i[l]) as u32),
            lanes(|l| texel(next[l]) as u32),
        ],
        inside: [
            lanes(|l| mask(inside(i[l]))),
            lanes(|l| mask(inside(next[l]))),
        ],
        served: lanes(|l| mask(served(i[l]))),
    }
}

/// Where each of the four texels of each lane's block lies, corner-major (upper left, upper
/// right, lower left, lower right).
struct BlockAddresses {
    /// Index in the level's buffer, as `TileLayout::locate` and `tile_start` give it.
    index: [Lanes<u32>; 4],
    /// Number of the texel's tile: row of tiles times tiles per row, plus column.
    tile: [Lanes<u32>; 4],
    /// Index inside the tile (row-major with the tile's own width).
    in_tile: [Lanes<u32>; 4],
}

/// [`BlockAddresses`] of each lane's block; a lane with a buffer index past the buffer
/// (`len` texels) is left to the scalar path.
#[inline(always)]
fn block_addresses(
    level: &MipLevel,
    columns: &AxisTexels,
    rows: &AxisTexels,
    len: usize,
    served: &mut Mask,
) -> BlockAddresses {
    let (w, h) = (level.width, level.height);
    let tiles_x = w.div_ceil(TEXTURE_TILE_SIZE);
    let tile_extent = |start: u32, size: u32| size.wrapping_sub(start).min(TEXTURE_TILE_SIZE);
    let column = |k: usize| {
        let x = &columns.texel[k];
        let start = lanes(|l| x[l] & !TILE_MASK);
        let width = lanes(|l| tile_extent(start[l], w));
        (start, width, lanes(|l| x[l] & TILE_MASK))
    };
    let row = |k: usize| {
        let y = &rows.texel[k];
        let start = lanes(|l| y[l] & !TILE_MASK);
        let height = lanes(|l| tile_extent(start[l], h));
        (start, height, lanes(|l| y[l] & TILE_MASK))
    };
    let (cols, rws) = ([column(0), column(1)], [row(0), row(1)]);
    let in_tile = |c: usize, r: usize| {
        let (_, tile_w, local_x) = &cols[c];
        let (_, _, local_y) = &rws[r];
        lanes(|l| local_y[l].wrapping_mul(tile_w[l]).wrapping_add(local_x[l]))
    };
    let tile = |c: usize, r: usize| {
        let (x_start, ..) = &cols[c];
        let (y_start, ..) = &rws[r];
        let shift = TEXTURE_TILE_SIZE.trailing_zeros();
        lanes(|l| {
            (y_start[l] >> shift)
                .wrapping_mul(tiles_x)
                .wrapping_add(x_start[l] >> shift)
        })
    };
    let index = |c: usize, r: usize, in_tile: &Lanes<u32>| {
        let (x_start, ..) = &cols[c];
        let (y_start, tile_h, _) = &rws[r];
        lanes(|l| {
            let tile_start = y_start[l]
                .wrapping_mul(w)
                .wrapping_add(x_start[l].wrapping_mul(tile_h[l]));
            tile_start.wrapping_add(in_tile[l])
        })
    };
    // Written out rather than mapped over the corners: `map` may be left out of line (see
    // `lanes`).
    let in_tile = [in_tile(0, 0), in_tile(1, 0), in_tile(0, 1), in_tile(1, 1)];
    let tile = [tile(0, 0), tile(1, 0), tile(0, 1), tile(1, 1)];
    let index = [
        index(0, 0, &in_tile[0]),
        index(1, 0, &in_tile[1]),
        index(0, 1, &in_tile[2]),
        index(1, 1, &in_tile[3]),
    ];
    let len = u32::try_from(len).unwrap_or(u32::MAX);
    // `&` rather than `all`, whose early exit kept the test one lane at a time.
    let [a, b, c, d] = &index;
    *served =
        lanes(|l| served[l] & mask((a[l] < len) & (b[l] < len) & (c[l] < len) & (d[l] < len)));
    BlockAddresses {
        index,
        tile,
        in_tile,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_matches_the_scalar_floor_where_blocks_can_be_served() {
        let limit = MAX_EXTENT as f32;
        let mut x = 0.0f32;
        while x < limit {
            for v in [
                x,
                x.next_up(),
                x.next_down(),
                x + 0.5,
                x + 0.999_999,
                -x,
                -x - 0.5,
                (-x).next_down(),
            ] {
                if v.abs() < limit {
                    assert_eq!(floor_i32(v), v.floor() as i32, "{v}");
                }
            }
            x = if x < 4.0 { x + 0.25 } else { x * 1.37 };
        }
        for beyond in [
            limit,
            1e9,
            f32::INFINITY,
            -limit,
            -1e9,
            f32::NEG_INFINITY,
            f32::NAN,
        ] {
            assert!(floor_i32(beyond).unsigned_abs() >= MAX_EXTENT, "{beyond}");
        }
    }

    /// Every mode's lane wrap maps the texels of the blocks it serves as
    /// `wrap::wrap_texel` does, and serves every block within a period, and every block on
    /// a power-of-two side.
    #[test]
    fn axis_wrap_matches_wrap_texel() {
        for n in [1u32, 2, 3, 7, 64, 65] {
            for mode in [
                WrapMode::Periodic,
                WrapMode::Clamp,
                WrapMode::Black,
                WrapMode::Mirror,
            ] {
                let side = n as i32;
                let starts: Vec<i32> = (-3 * side - 2..3 * side + 2).collect();
                for chunk in starts.chunks(PROBE_LANES) {
                    let i = lanes(|l| chunk.get(l).copied().unwrap_or(0));
                    let axis = wrap_axis(&i, n, mode);
                    for (l, &start) in chunk.iter().enumerate() {
                        let repeats = matches!(mode, WrapMode::Periodic | WrapMode::Mirror);
                        let must_serve =
                            !repeats || n.is_power_of_two() || (-side..side).contains(&start);
                        assert!(
                            !must_serve || axis.served[l] != 0,
                            "{mode:?} n {n} start {start}"
                        );
                        if axis.served[l] == 0 {
                            continue;
                        }
                        for k in 0..2 {
                            let scalar =
                                super::super::wrap::wrap_texel((start + k as i32) as f32, n, mode);
                            let lane =
                                (axis.inside[k][l] != 0).then_some(axis.texel[k][l] as usize);
                            assert_eq!(lane, scalar, "{mode:?} n {n} texel {}", start + k as i32);
                        }
                    }
                }
            }
        }
    }
}
