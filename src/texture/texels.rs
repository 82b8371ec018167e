//! How a mip level's texels are stored: in the precision of the source image.
//!
//! An 8-bit image keeps one byte per channel, a half-float image two, a float image four;
//! every other source (16- and 32-bit integers, doubles) is stored as f32. Texels are
//! always RGBA, so a fetch is one aligned load of 4, 8 or 16 bytes whatever the source's
//! channel count. Conversion to linear f32 happens at fetch: an 8-bit channel goes through
//! a 256-entry table (byte / 255, or the sRGB decoding of IEC 61966-2-1 for the colour
//! channels of an sRGB texture; alpha is always byte / 255), a half through the `half`
//! crate's exact widening. The values a filter sees are therefore exactly the ones an
//! f32 copy decoded on load would hold.
//!
//! Every texel buffer is allocated fallibly ([`try_texel_vec`]): a texture too large for
//! memory is a [`TextureError::OutOfMemory`] naming it, not an abort.

use std::sync::{Arc, LazyLock};

use glam::Vec4;
use half::f16;

use super::aniso_lanes::{lanes, Lanes, ProbeBlocks};
use super::demand_tiles::DemandLevel;
use super::micro_cache::ThreadTiles;
use super::tile_layout::TileLayout;
use super::{ColorSpace, TextureError};
use crate::srgb::{nearest_byte, srgb_byte, srgb_to_linear};

/// Decoded value of each byte: byte / 255 (linear data and alpha). Evaluated at compile
/// time: a lazily built table is checked for initialisation at every use, and the alpha
/// table is found anew for every level a lookup reads.
static LINEAR_BYTES: [f32; 256] = linear_bytes();

/// byte / 255 for every byte, correctly rounded as at run time.
const fn linear_bytes() -> [f32; 256] {
    let mut table = [0.0f32; 256];
    let mut i = 0;
    while i < 256 {
        table[i] = i as f32 / 255.0;
        i += 1;
    }
    table
}

/// Decoded value of each byte of sRGB-encoded colour.
static SRGB_BYTES: LazyLock<[f32; 256]> =
    LazyLock::new(|| std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0)));

/// The table decoding the colour channels of 8-bit texels in `color_space`.
pub(crate) fn byte_table(color_space: ColorSpace) -> &'static [f32; 256] {
    match color_space {
        ColorSpace::Srgb => &SRGB_BYTES,
        ColorSpace::Linear => &LINEAR_BYTES,
    }
}

/// Evaluates `$body` with `$source` bound to the [`TexelSource`] of `$texels`'s storage
/// kind: one match, and `$body` compiled once per kind. A demand-loaded level fetches its
/// tiles through `$tiles`, the lookup's [`ThreadTiles`](super::micro_cache::ThreadTiles)
/// found once by its caller; without `$tiles`, `$body` runs inside the thread's micro-cache
/// access, found here (for readers outside a lookup, such as `MipLevel::texel`).
macro_rules! with_texel_source {
    ($texels:expr, |$source:ident| $body:expr) => {{
        match $texels {
            texels @ $crate::texture::texels::Texels::OnDemand(_) => {
                $crate::texture::micro_cache::with_thread_tiles(
                    #[inline(always)]
                    |tiles| {
                        $crate::texture::texels::with_texel_source!(texels, tiles, |$source| $body)
                    },
                )
            }
            texels => $crate::texture::texels::with_texel_source!(
                texels,
                $crate::texture::micro_cache::ThreadTiles::none(),
                |$source| $body
            ),
        }
    }};
    ($texels:expr, $tiles:expr, |$source:ident| $body:expr) => {{
        #[allow(unused_imports)]
        use $crate::texture::texels::{
            ByteTexels, FlatTexels, FloatTexels, HalfTexels, TexelSource, Texels,
        };
        match $texels {
            Texels::Float(t) => {
                let $source = FloatTexels(t);
                $body
            }
            Texels::Half(t) => {
                let $source = HalfTexels(t);
                $body
            }
            Texels::Byte { texels, colour, .. } => {
                let $source = ByteTexels::new(texels, *colour);
                $body
            }
            Texels::OnDemand(level) => {
                let $source = $crate::texture::demand_tiles::DemandTexels::new(level, $tiles);
                $body
            }
        }
    }};
}
pub(crate) use with_texel_source;

/// A level's texels, RGBA, in the source's precision. Decoders produce them row-major with
/// t = 0 first; a [`super::MipLevel`] holds them in the tile order of its `TileLayout`.
///
/// The kind is a byte of its own (`repr(u8)`) rather than hidden in a vector's capacity,
/// so that the fetches, which branch on it, read it in one load.
#[derive(Clone, Debug)]
#[repr(u8)]
pub enum Texels {
    /// One byte per channel; colour decoded through `colour` (linear or sRGB), alpha is
    /// byte / 255.
    Byte {
        /// The texels.
        texels: Vec<[u8; 4]>,
        /// Whether the colour bytes are sRGB-encoded.
        color_space: ColorSpace,
        /// Decoded value of each colour byte (from [`byte_table`]).
        colour: &'static [f32; 256],
    },
    /// IEEE half floats, used as stored.
    Half(Vec<[f16; 4]>),
    /// f32, used as stored.
    Float(Vec<[f32; 4]>),
    /// Tiles read from the texture's file when a lookup touches them and kept in its
    /// texture cache while the cap allows, each held in one of the kinds above.
    OnDemand(Arc<DemandLevel>),
}

impl Texels {
    /// 8-bit texels whose colour bytes are encoded in `color_space`.
    pub fn bytes(texels: Vec<[u8; 4]>, color_space: ColorSpace) -> Texels {
        Texels::Byte {
            texels,
            color_space,
            colour: byte_table(color_space),
        }
    }

    /// Number of texels.
    pub fn len(&self) -> usize {
        match self {
            Texels::Byte { texels, .. } => texels.len(),
            Texels::Half(t) => t.len(),
            Texels::Float(t) => t.len(),
            Texels::OnDemand(level) => level.texel_count(),
        }
    }

    /// True when there are no texels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The colour space 8-bit colour is decoded in; `None` for other kinds (linear as
    /// stored).
    pub fn color_space(&self) -> Option<ColorSpace> {
        match self {
            Texels::Byte { color_space, .. } => Some(*color_space),
            Texels::Half(_) | Texels::Float(_) => None,
            Texels::OnDemand(level) => level.kind().color_space(),
        }
    }

    /// Bytes one texel takes (4, 8 or 16).
    pub fn bytes_per_texel(&self) -> usize {
        match self {
            Texels::Byte { .. } => 4,
            Texels::Half(_) => 8,
            Texels::Float(_) => 16,
            Texels::OnDemand(level) => level.kind().bytes_per_texel(),
        }
    }

    /// Bytes of texel storage (of an on-demand level: of the tiles read so far).
    pub fn memory_bytes(&self) -> usize {
        match self {
            Texels::OnDemand(level) => level.resident_bytes(),
            _ => self.len() * self.bytes_per_texel(),
        }
    }

    /// Reorders row-major texels of a level laid out by `layout` into its tile order.
    pub(crate) fn rows_to_tiles(&mut self, layout: TileLayout) -> Result<(), String> {
        match self {
            Texels::Byte { texels, .. } => layout.rows_to_tiles(texels),
            Texels::Half(t) => layout.rows_to_tiles(t),
            Texels::Float(t) => layout.rows_to_tiles(t),
            // Read in tile order already.
            Texels::OnDemand(_) => Ok(()),
        }
    }

    /// Linear RGBA of texel `index` (in range; in a level, indices follow its tile order).
    #[inline(always)]
    pub fn get(&self, index: usize) -> Vec4 {
        match self {
            Texels::Float(t) => FloatTexels(t).texel(index),
            Texels::Half(t) => HalfTexels(t).texel(index),
            Texels::Byte { texels, colour, .. } => ByteTexels::new(texels, colour).texel(index),
            Texels::OnDemand(level) => level.texel_at_index(index),
        }
    }

    /// Linear RGBA of texel `index` of a resident buffer (a tile; in range); zero for an
    /// on-demand level, which no tile is. Small enough to inline into every fetch, unlike
    /// [`Texels::get`].
    #[inline(always)]
    pub(crate) fn resident_texel(&self, index: usize) -> Vec4 {
        match self {
            Texels::Float(t) => FloatTexels(t).texel(index),
            Texels::Half(t) => HalfTexels(t).texel(index),
            Texels::Byte { texels, colour, .. } => ByteTexels::new(texels, colour).texel(index),
            Texels::OnDemand(_) => Vec4::ZERO,
        }
    }

    /// Texels `k`, `k + 1`, `k + row` and `k + row + 1` (a bilinear footprint), or `None`
    /// when they are not all inside: one storage dispatch and one bounds check for four.
    #[inline(always)]
    pub(crate) fn quad<R>(
        &self,
        k: usize,
        row: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> Option<R> {
        match self {
            Texels::Float(t) => FloatTexels(t).bilinear_quad(k, row, blend),
            Texels::Half(t) => HalfTexels(t).bilinear_quad(k, row, blend),
            Texels::Byte { texels, colour, .. } => {
                ByteTexels::new(texels, colour).bilinear_quad(k, row, blend)
            }
            Texels::OnDemand(_) => None,
        }
    }

    /// Texels of the same storage kind holding `values` (linear RGBA), each rounded to the
    /// nearest representable value: half by IEEE round-to-nearest-even; bytes by encoding
    /// (sRGB when the colour is sRGB) and rounding half up, as `maketx` rounds its 8-bit
    /// levels (measured against OpenImageIO 2.x: a level-1 texel of 86.5 / 255 is stored as
    /// 87; half-to-even would give 86).
    pub(crate) fn same_kind_from(
        &self,
        values: &[[f32; 4]],
        label: &str,
    ) -> Result<Texels, TextureError> {
        Ok(match self {
            Texels::Float(_) => {
                let mut out = try_texel_vec(values.len(), label)?;
                out.extend_from_slice(values);
                Texels::Float(out)
            }
            Texels::Half(_) => {
                let mut out = try_texel_vec(values.len(), label)?;
                out.extend(values.iter().map(|v| v.map(f16::from_f32)));
                Texels::Half(out)
            }
            Texels::Byte { color_space, .. } => {
                let srgb = *color_space == ColorSpace::Srgb;
                let mut out = try_texel_vec(values.len(), label)?;
                out.extend(values.iter().map(|v| {
                    let colour = |c: f32| if srgb { srgb_byte(c) } else { nearest_byte(c) };
                    [colour(v[0]), colour(v[1]), colour(v[2]), nearest_byte(v[3])]
                }));
                Texels::bytes(out, *color_space)
            }
            Texels::OnDemand(level) => level.kind().same_kind_from(values, label)?,
        })
    }
}

impl PartialEq for Texels {
    /// Equal storage and values; an on-demand level equals whatever holds its values
    /// (comparing reads every tile).
    fn eq(&self, other: &Texels) -> bool {
        match (self, other) {
            (Texels::Float(a), Texels::Float(b)) => a == b,
            (Texels::Half(a), Texels::Half(b)) => a == b,
            (
                Texels::Byte {
                    texels: a,
                    color_space: ca,
                    ..
                },
                Texels::Byte {
                    texels: b,
                    color_space: cb,
                    ..
                },
            ) => a == b && ca == cb,
            (Texels::OnDemand(_), _) | (_, Texels::OnDemand(_)) => {
                self.len() == other.len()
                    && self.bytes_per_texel() == other.bytes_per_texel()
                    && (0..self.len()).all(|i| self.get(i) == other.get(i))
            }
            _ => false,
        }
    }
}

/// One storage kind of texels in one buffer, borrowed, addressed by index. Filters are
/// generic over it and pick the kind once per lookup (see [`with_texel_source`]), so the
/// loops that fetch texels are compiled once per kind and a fetch does not branch on the
/// storage.
pub(crate) trait FlatTexels<'a>: Copy {
    /// The texels of `texels` when they are of this kind.
    fn view(texels: &'a Texels) -> Option<Self>;

    /// Linear RGBA of texel `index` (in range).
    fn texel(self, index: usize) -> Vec4;

    /// Number of texels.
    fn len(self) -> usize;

    /// These texels as 8-bit texels, when they are.
    #[inline(always)]
    fn as_byte_texels(self) -> Option<ByteTexels<'a>> {
        None
    }

    /// `blend` of texels `k`, `k + 1`, `k + row` and `k + row + 1` (a bilinear
    /// footprint), or `None` when they are not all inside: one bounds check for four.
    fn bilinear_quad<R>(
        self,
        k: usize,
        row: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> Option<R>;
}

/// A level's texels as the filters read them: by coordinates, through the tile that holds
/// them (a fetch is a tile lookup plus an offset in the tile). Resident kinds find every
/// tile in their one buffer; a demand-loaded level fetches it through the texture cache.
pub(crate) trait TexelSource<'a>: Copy {
    /// The texels of `texels` (another level of the same lookup) when they are of this
    /// kind, read in the same way as `self`'s.
    fn view(self, texels: &'a Texels) -> Option<Self>;

    /// Linear RGBA of texel (x, y) of a level tiled by `layout` (in range); zero when its
    /// tile cannot be read (the failure is recorded where the texture reports it).
    fn texel_at(self, layout: TileLayout, x: usize, y: usize) -> Vec4;

    /// `blend` of texels (x, y), (x + 1, y), (x, y + 1) and (x + 1, y + 1), all inside the
    /// level: one bounds check for four when they share a tile. `None` when a tile cannot
    /// be read.
    fn bilinear_block<R>(
        self,
        layout: TileLayout,
        x: usize,
        y: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> Option<R>;

    /// These texels as resident 8-bit texels, when they are: the kind whose batched
    /// bilinear lookups run in vector lanes (`Texture::sample_batch`).
    #[inline(always)]
    fn as_byte_texels(self) -> Option<ByteTexels<'a>> {
        None
    }

    /// The micro-cache these texels' tiles are fetched through (none for a resident kind):
    /// what a filter hands on when it reads another level of the lookup.
    #[inline(always)]
    fn thread_tiles(self) -> ThreadTiles<'a> {
        ThreadTiles::none()
    }

    /// Length of the buffer `aniso_lanes::blocks` addresses these texels in: the level's
    /// texel count for a resident kind, `usize::MAX` for a demand-loaded level (read tile by
    /// tile, with no buffer of its own).
    fn lane_buffer_len(self) -> usize;

    /// The bilinear values of the blocks of `blocks` (addressed on these texels' level with
    /// [`TexelSource::lane_buffer_len`]) that these texels serve, and which lanes those are;
    /// the others are left to the scalar path.
    fn block_values(self, blocks: &ProbeBlocks) -> (Lanes<Vec4>, Lanes<bool>);

    /// Texels (xs\[0\], ys\[0\]), (xs\[1\], ys\[0\]), (xs\[0\], ys\[1\]) and
    /// (xs\[1\], ys\[1\]) of a level tiled by `layout` (all in range): a bilinear footprint
    /// wrapped across the level's edge. One fetch each; a demand-loaded level fetches a tile
    /// holding all four once.
    #[inline(always)]
    fn corner_texels(self, layout: TileLayout, xs: [usize; 2], ys: [usize; 2]) -> [Vec4; 4] {
        [
            self.texel_at(layout, xs[0], ys[0]),
            self.texel_at(layout, xs[1], ys[0]),
            self.texel_at(layout, xs[0], ys[1]),
            self.texel_at(layout, xs[1], ys[1]),
        ]
    }

    /// `work` run on the texels of tile (`tile_x`, `tile_y`) of a level tiled by `layout`:
    /// one fetch of the tile, and one storage dispatch, for a footprint that lies in it.
    /// `None` when the tile cannot be read (`work` has not run).
    fn with_tile_texels<W: TileWork>(
        self,
        layout: TileLayout,
        tile_x: usize,
        tile_y: usize,
        work: &mut W,
    ) -> Option<W::Output>;

    /// [`TexelSource::bilinear_block`] across a tile edge (about 1 block in 32): four
    /// fetches.
    #[inline(always)]
    fn four_texels<R>(
        self,
        layout: TileLayout,
        x: usize,
        y: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> R {
        blend(
            self.texel_at(layout, x, y),
            self.texel_at(layout, x + 1, y),
            self.texel_at(layout, x, y + 1),
            self.texel_at(layout, x + 1, y + 1),
        )
    }
}

/// Reads of many texels of one tile, compiled once per storage kind: a filter whose
/// footprint lies in one tile fetches the tile once for all of them
/// ([`TexelSource::with_tile_texels`]) instead of once per texel.
pub(crate) trait TileWork {
    /// What the work gives.
    type Output;

    /// The work on a tile whose texels are those of `texels` from index `start` on: texel
    /// (x, y) of the tile is `texels.texel(start + offset)`, with `offset` from
    /// [`TileLayout::locate`].
    fn run<'t, T: FlatTexels<'t>>(&mut self, texels: T, start: usize) -> Self::Output;
}

/// A resident kind is its own tile source: every tile lies in the one buffer.
macro_rules! resident_texel_source {
    ($($kind:ident),+) => {$(
        impl<'a> TexelSource<'a> for $kind<'a> {
            #[inline(always)]
            fn view(self, texels: &'a Texels) -> Option<Self> {
                <Self as FlatTexels<'a>>::view(texels)
            }

            #[inline(always)]
            fn as_byte_texels(self) -> Option<ByteTexels<'a>> {
                <Self as FlatTexels<'a>>::as_byte_texels(self)
            }

            #[inline(always)]
            fn lane_buffer_len(self) -> usize {
                FlatTexels::len(self)
            }

            #[inline(always)]
            fn block_values(self, blocks: &ProbeBlocks) -> (Lanes<Vec4>, Lanes<bool>) {
                let served = lanes(|l| blocks.served(l));
                let values = lanes(|l| {
                    if served[l] {
                        blocks.value(self, l)
                    } else {
                        Vec4::ZERO
                    }
                });
                (values, served)
            }

            #[inline(always)]
            fn texel_at(self, layout: TileLayout, x: usize, y: usize) -> Vec4 {
                let (tile_x, tile_y, offset) = layout.locate(x, y);
                self.texel(layout.tile_start(tile_x, tile_y) + offset)
            }

            #[inline(always)]
            fn with_tile_texels<W: TileWork>(
                self,
                layout: TileLayout,
                tile_x: usize,
                tile_y: usize,
                work: &mut W,
            ) -> Option<W::Output> {
                Some(work.run(self, layout.tile_start(tile_x, tile_y)))
            }

            #[inline(always)]
            fn bilinear_block<R>(
                self,
                layout: TileLayout,
                x: usize,
                y: usize,
                blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
            ) -> Option<R> {
                match layout.block_in_one_tile(x, y) {
                    Some((tile_x, tile_y, offset, stride)) => self.bilinear_quad(
                        layout.tile_start(tile_x, tile_y) + offset,
                        stride,
                        blend,
                    ),
                    None => Some(self.four_texels(layout, x, y, blend)),
                }
            }
        }
    )+};
}
resident_texel_source!(FloatTexels, HalfTexels, ByteTexels);

/// f32 texels, used as stored.
#[derive(Clone, Copy)]
pub(crate) struct FloatTexels<'a>(pub(crate) &'a [[f32; 4]]);

/// Half-float texels, widened exactly at fetch.
#[derive(Clone, Copy)]
pub(crate) struct HalfTexels<'a>(pub(crate) &'a [[f16; 4]]);

/// 8-bit texels with the tables decoding their colour and alpha bytes.
#[derive(Clone, Copy)]
pub(crate) struct ByteTexels<'a> {
    texels: &'a [[u8; 4]],
    colour: &'static [f32; 256],
    alpha: &'static [f32; 256],
}

impl<'a> FlatTexels<'a> for FloatTexels<'a> {
    #[inline(always)]
    fn view(texels: &'a Texels) -> Option<Self> {
        match texels {
            Texels::Float(t) => Some(FloatTexels(t)),
            _ => None,
        }
    }

    #[inline(always)]
    fn texel(self, index: usize) -> Vec4 {
        Vec4::from_array(self.0[index])
    }

    #[inline(always)]
    fn len(self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn bilinear_quad<R>(
        self,
        k: usize,
        row: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> Option<R> {
        let b = self.0.get(k..k.checked_add(row)?.checked_add(2)?)?;
        Some(blend(
            Vec4::from_array(b[0]),
            Vec4::from_array(b[1]),
            Vec4::from_array(b[row]),
            Vec4::from_array(b[row + 1]),
        ))
    }
}

impl<'a> FlatTexels<'a> for HalfTexels<'a> {
    #[inline(always)]
    fn view(texels: &'a Texels) -> Option<Self> {
        match texels {
            Texels::Half(t) => Some(HalfTexels(t)),
            _ => None,
        }
    }

    #[inline(always)]
    fn texel(self, index: usize) -> Vec4 {
        half_texel(&self.0[index])
    }

    #[inline(always)]
    fn len(self) -> usize {
        self.0.len()
    }

    #[inline(always)]
    fn bilinear_quad<R>(
        self,
        k: usize,
        row: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> Option<R> {
        let b = self.0.get(k..k.checked_add(row)?.checked_add(2)?)?;
        // Each pair of neighbours widened in one call (vectorised where the CPU
        // converts halves).
        let (upper, lower) = (half_pair(&b[..2]), half_pair(&b[row..row + 2]));
        Some(blend(upper[0], upper[1], lower[0], lower[1]))
    }
}

impl<'a> ByteTexels<'a> {
    /// `texels` with colour bytes decoded through `colour`.
    #[inline(always)]
    pub(crate) fn new(texels: &'a [[u8; 4]], colour: &'static [f32; 256]) -> Self {
        ByteTexels {
            texels,
            colour,
            alpha: &LINEAR_BYTES,
        }
    }
}

impl<'a> FlatTexels<'a> for ByteTexels<'a> {
    #[inline(always)]
    fn view(texels: &'a Texels) -> Option<Self> {
        match texels {
            Texels::Byte { texels, colour, .. } => Some(ByteTexels::new(texels, colour)),
            _ => None,
        }
    }

    #[inline(always)]
    fn texel(self, index: usize) -> Vec4 {
        byte_texel(self.texels[index], self.colour, self.alpha)
    }

    #[inline(always)]
    fn len(self) -> usize {
        self.texels.len()
    }

    #[inline(always)]
    fn as_byte_texels(self) -> Option<ByteTexels<'a>> {
        Some(self)
    }

    #[inline(always)]
    fn bilinear_quad<R>(
        self,
        k: usize,
        row: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> Option<R> {
        let b = self.texels.get(k..k.checked_add(row)?.checked_add(2)?)?;
        let decode = |t| byte_texel(t, self.colour, self.alpha);
        Some(blend(
            decode(b[0]),
            decode(b[1]),
            decode(b[row]),
            decode(b[row + 1]),
        ))
    }
}

/// Linear RGBA of one 8-bit texel.
#[inline(always)]
fn byte_texel(t: [u8; 4], colour: &[f32; 256], alpha: &[f32; 256]) -> Vec4 {
    Vec4::new(
        colour[usize::from(t[0])],
        colour[usize::from(t[1])],
        colour[usize::from(t[2])],
        alpha[usize::from(t[3])],
    )
}

/// Two neighbouring half-float texels widened to f32 (exact) in one conversion.
#[inline(always)]
fn half_pair(pair: &[[f16; 4]]) -> [Vec4; 2] {
    use half::slice::HalfFloatSliceExt;
    let mut wide = [0.0f32; 8];
    pair.as_flattened().convert_to_f32_slice(&mut wide);
    [Vec4::from_slice(&wide[..4]), Vec4::from_slice(&wide[4..])]
}

/// One half-float texel widened to f32 (exact).
#[inline(always)]
fn half_texel(t: &[f16; 4]) -> Vec4 {
    use half::slice::HalfFloatSliceExt;
    let mut wide = [0.0f32; 4];
    t.convert_to_f32_slice(&mut wide);
    Vec4::from_array(wide)
}

/// An empty vector with room for `len` texels, or [`TextureError::OutOfMemory`] naming
/// `label` when that much cannot be allocated.
pub(crate) fn try_texel_vec<T>(len: usize, label: &str) -> Result<Vec<T>, TextureError> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| TextureError::OutOfMemory {
            label: label.to_string(),
            bytes: (len as u64).saturating_mul(std::mem::size_of::<T>() as u64),
        })?;
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_compile_time_byte_table_is_the_run_time_division() {
        for (byte, &value) in LINEAR_BYTES.iter().enumerate() {
            let divided = std::hint::black_box(byte as f32) / std::hint::black_box(255.0f32);
            assert_eq!(value.to_bits(), divided.to_bits(), "byte {byte}");
        }
    }

    #[test]
    fn byte_fetch_equals_the_decoded_f32_value() {
        let srgb = Texels::bytes(vec![[188, 0, 255, 128]], ColorSpace::Srgb);
        let v = srgb.get(0);
        assert_eq!(v.x, srgb_to_linear(188.0 / 255.0));
        assert_eq!((v.y, v.z, v.w), (0.0, 1.0, 128.0 / 255.0));
        let linear = Texels::bytes(vec![[188, 0, 255, 128]], ColorSpace::Linear);
        assert_eq!(linear.get(0).x, 188.0 / 255.0);
        assert_eq!(linear.memory_bytes(), 4);
    }

    #[test]
    fn every_byte_survives_a_round_trip_through_its_encoding() {
        for space in [ColorSpace::Linear, ColorSpace::Srgb] {
            let bytes: Vec<[u8; 4]> = (0..=255u8).map(|b| [b, b, b, b]).collect();
            let texels = Texels::bytes(bytes.clone(), space);
            let decoded: Vec<[f32; 4]> = (0..256).map(|i| texels.get(i).to_array()).collect();
            let again = texels.same_kind_from(&decoded, "t").unwrap();
            assert_eq!(again, texels, "{space}");
        }
    }

    #[test]
    fn bytes_round_half_up_and_clamp() {
        // A 2x2 level of 86 and 87 averages to 86.5 / 255 (exactly 86.5 after * 255 in
        // f32): maketx stores 87, so ties go up.
        let base = super::super::MipLevel::with_texels(
            2,
            2,
            Texels::bytes(
                vec![
                    [86, 87, 0, 255],
                    [87, 86, 255, 255],
                    [86, 87, 0, 255],
                    [87, 86, 255, 255],
                ],
                ColorSpace::Linear,
            ),
        )
        .unwrap();
        let p = super::super::MipPyramid::build(base, "t").unwrap();
        assert_eq!(
            p.levels[1].texels,
            Texels::bytes(vec![[87, 87, 128, 255]], ColorSpace::Linear)
        );
        let t = Texels::bytes(vec![], ColorSpace::Linear);
        let clamped = t.same_kind_from(&[[-1.0, 2.0, 0.0, 1.0]], "t").unwrap();
        assert_eq!(
            clamped,
            Texels::bytes(vec![[0, 255, 0, 255]], ColorSpace::Linear)
        );
    }

    #[test]
    fn quad_reads_a_two_by_two_block_of_every_kind() {
        let values: Vec<[f32; 4]> = (0..6).map(|i| [i as f32 / 8.0, 0.0, 0.0, 1.0]).collect();
        let float = Texels::Float(values.clone());
        for texels in [
            float.clone(),
            float.same_kind_from(&values, "t").unwrap(),
            Texels::Half(vec![]).same_kind_from(&values, "t").unwrap(),
        ] {
            let q = texels.quad(1, 3, |a, b, c, d| [a, b, c, d]).unwrap();
            assert_eq!(q.map(|v| v.x), [1.0 / 8.0, 2.0 / 8.0, 4.0 / 8.0, 5.0 / 8.0]);
            assert!(texels.quad(2, 3, |a, _, _, _| a).is_none());
            assert!(texels.quad(usize::MAX - 1, 3, |a, _, _, _| a).is_none());
        }
    }

    #[test]
    fn an_allocation_too_large_is_an_error_naming_the_texture() {
        let e = try_texel_vec::<[f32; 4]>(usize::MAX / 32, "huge.exr").unwrap_err();
        let message = e.to_string();
        assert!(message.starts_with("huge.exr: "), "{message}");
        assert!(try_texel_vec::<[u8; 4]>(16, "small.png").is_ok());
    }
}
