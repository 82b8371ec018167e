//! Textures: loading, the mip pyramid, and footprint-filtered lookups.
//!
//! Every texture lookup in the renderer goes through [`Texture::sample`], which takes
//! a texture coordinate and its screen-space derivatives (seed 002, eqs. 25-26;
//! seed 000, "Texture Derivatives on a Triangle") and filters the mip pyramid with
//! one of the [`FilterMode`]s. The closest, bilinear, trilinear and anisotropic
//! filters reproduce OpenImageIO's `TextureSystem` (see `docs/texture-filtering.md`);
//! `ewa` is an elliptical Gaussian in the manner of Heckbert and pbrt.
//!
//! Conventions follow OpenImageIO: `s` grows to the right, `t` grows downwards,
//! (0,0) is the outer corner of the first texel, derivatives are in normalised
//! texture units.
//!
//! This module must not know about rays, cones or materials: callers turn their
//! footprint into a [`TextureQuery`].
//!
//! ```no_run
//! use conetrace::texture::{ColorSpace, FilterOptions, Texture, TextureQuery};
//! let tex = Texture::from_file(std::path::Path::new("wood.png"), ColorSpace::Srgb)?;
//! let q = TextureQuery { s: 0.3, t: 0.7, dsdx: 0.01, dtdx: 0.0, dsdy: 0.0, dtdy: 0.002 };
//! let rgba = tex.sample(&q, &FilterOptions::default());
//! # Ok::<(), conetrace::texture::TextureError>(())
//! ```

mod aniso;
mod aniso_lanes;
mod batch;
mod demand_tiles;
mod ellipse;
mod ewa;
mod filter_closest_bilinear;
mod image_load;
mod image_size;
mod micro_cache;
mod mip_pyramid;
mod texels;
mod tiff_tile_reader;
mod tile_cache;
mod tile_layout;
mod tiled_tiff;
mod tiles;
mod trilinear;
mod tx_writer;
mod wrap;

use std::fmt;
use std::path::Path;
use std::str::FromStr;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

use glam::Vec4;

pub use demand_tiles::demand_level_sizes;
pub use image_size::{
    encoded_image_size, encoded_texture_header, file_image_size, file_texture_header, TextureHeader,
};
pub use micro_cache::flush_all_threads as flush_micro_caches;
pub(crate) use micro_cache::MICRO_TILES;
pub use mip_pyramid::{MipLevel, MipPyramid};
pub use texels::Texels;
pub(crate) use tile_cache::SLOT_BYTES;
pub use tile_cache::{TextureCacheStats, TileCache, DEFAULT_TEXTURE_CACHE_BYTES};
pub use tiles::{TextureTileSet, TEXTURE_TILE_SIZE};
pub use tx_writer::{write_tx, TxCompression, TxOptions};

use demand_tiles::DemandFile;
use micro_cache::ThreadTiles;
use tiles::{NoTextureTiles, TexelObserver, TextureTileRecorder};

/// How 8-bit RGB texels are decoded on load (alpha is always linear).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ColorSpace {
    /// sRGB-encoded colour, converted to linear on load.
    #[default]
    Srgb,
    /// Values used as stored (byte / 255), like OpenImageIO does.
    Linear,
}

/// What a lookup sees outside [0,1) along one texture axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    /// The texture repeats.
    #[default]
    Periodic,
    /// Edge texels extend outward.
    Clamp,
    /// Texels outside count as zero (no renormalisation).
    Black,
    /// The texture repeats mirrored every other period.
    Mirror,
}

/// The filter a lookup uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FilterMode {
    /// Nearest texel of level 0 (OIIO: MipMode NoMIP, InterpMode Closest).
    Closest,
    /// Bilinear interpolation of level 0 (OIIO: MipMode NoMIP, InterpMode Bilinear).
    Bilinear,
    /// One bilinear probe on each of two blended levels (OIIO: MipMode Trilinear).
    Trilinear,
    /// Bilinear probes along the ellipse's major axis (OIIO: MipMode Aniso).
    #[default]
    Aniso,
    /// Elliptical weighted average with a Gaussian kernel (Heckbert; pbrt).
    Ewa,
}

impl FilterMode {
    /// Every filter, from the cheapest.
    pub const ALL: [FilterMode; 5] = [
        FilterMode::Closest,
        FilterMode::Bilinear,
        FilterMode::Trilinear,
        FilterMode::Aniso,
        FilterMode::Ewa,
    ];
}

/// Options that travel with every lookup.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterOptions {
    /// Which filter to use.
    pub filter: FilterMode,
    /// Wrap along s.
    pub wrap_s: WrapMode,
    /// Wrap along t.
    pub wrap_t: WrapMode,
    /// Anisotropy limit (OIIO `TextureOpt::anisotropic`); values below 1 act as 1.
    pub max_aniso: f32,
}

impl Default for FilterOptions {
    fn default() -> Self {
        FilterOptions {
            filter: FilterMode::Aniso,
            wrap_s: WrapMode::Periodic,
            wrap_t: WrapMode::Periodic,
            max_aniso: 16.0,
        }
    }
}

/// One lookup: a texture coordinate and its derivatives along screen x and y.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct TextureQuery {
    /// Horizontal coordinate, 0..1 across the texture, growing to the right.
    pub s: f32,
    /// Vertical coordinate, 0..1 down the texture, growing downwards.
    pub t: f32,
    /// ds/dx: change of s from one pixel to the next along x.
    pub dsdx: f32,
    /// dt/dx.
    pub dtdx: f32,
    /// ds/dy.
    pub dsdy: f32,
    /// dt/dy.
    pub dtdy: f32,
}

/// Problems loading a texture; each message names the file or label.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file could not be read.
    #[error("{label}: cannot read file: {source}")]
    Io {
        /// File path or label.
        label: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// The bytes are not PNG, JPEG, OpenEXR or TIFF.
    #[error("{label}: unrecognised image format (expected PNG, JPEG, OpenEXR or TIFF)")]
    UnknownFormat {
        /// File path or label.
        label: String,
    },
    /// The PNG/JPEG decoder failed.
    #[error("{label}: cannot decode image: {message}")]
    Decode {
        /// File path or label.
        label: String,
        /// Decoder message.
        message: String,
    },
    /// The OpenEXR reader failed.
    #[error("{label}: cannot read OpenEXR: {message}")]
    Exr {
        /// File path or label.
        label: String,
        /// Reader message.
        message: String,
    },
    /// The TIFF reader failed, or the TIFF holds samples a texture cannot use.
    #[error("{label}: cannot read TIFF: {message}")]
    Tiff {
        /// File path or label.
        label: String,
        /// Reader message.
        message: String,
    },
    /// One tile of a tiled file could not be read (when a lookup first touched it).
    #[error("{label}: level {level}, tile ({tile_x}, {tile_y}): cannot read: {message}")]
    Tile {
        /// File path or label.
        label: String,
        /// Pyramid level (0 = full resolution).
        level: usize,
        /// Column and row of the tile, in tiles.
        tile_x: usize,
        tile_y: usize,
        /// Reader message.
        message: String,
    },
    /// The texels (with their mip levels) do not fit in memory.
    #[error("{label}: not enough memory for its texels ({bytes} bytes more were needed)")]
    OutOfMemory {
        /// File path or label.
        label: String,
        /// Size of the allocation that failed.
        bytes: u64,
    },
    /// A texel holds an infinity or a NaN, which every lookup near it would spread.
    #[error(
        "{label}: texel ({x}, {y}) of level {level} has {channel} = {value}; a texture must \
         hold finite values (a half-float EXR stores values above 65504 as inf)"
    )]
    NonFinite {
        /// File path or label.
        label: String,
        /// Pyramid level (0 = full resolution).
        level: usize,
        /// Column and row of the texel.
        x: u32,
        y: u32,
        /// R, G, B or A.
        channel: &'static str,
        /// The value found.
        value: f32,
    },
    /// Width or height is zero, too large, or does not match the texel count.
    #[error("{label}: bad dimensions: {message}")]
    Dimensions {
        /// File path or label.
        label: String,
        /// What is wrong.
        message: String,
    },
}

/// Channel names in texel order, for messages.
pub const CHANNEL_NAMES: [&str; 4] = ["R", "G", "B", "A"];

static NEXT_TEXTURE_ID: AtomicU64 = AtomicU64::new(0);

/// A loaded texture with its mip pyramid; shareable across threads, and immutable but
/// for the tiles of a demand-loaded texture, read on first use.
#[derive(Debug)]
pub struct Texture {
    id: u64,
    label: String,
    pyramid: MipPyramid,
    /// The file whose tiles the levels read on demand (a tiled, mip-mapped TIFF).
    demand: Option<Arc<DemandFile>>,
}

/// The colour space the TIFF at `path` records (`conetrace:ColorSpace=` in its
/// ImageDescription, as `conetrace maketx` writes it): what a texture loaded from it with
/// no stated colour space is decoded in. `None` when it records none (sRGB then applies),
/// is not a TIFF or cannot be read.
pub fn file_color_space(path: &Path) -> Option<ColorSpace> {
    tiled_tiff::file_color_space(path)
}

impl Texture {
    /// Loads PNG, JPEG, OpenEXR or TIFF from a file (format sniffed from the bytes). A
    /// tiled, mip-mapped TIFF in 64x64 tiles (`maketx`'s `.tx`) is read tile by tile as
    /// lookups first touch them, into the process-wide [`TileCache::shared`]; every other
    /// file is decoded whole, with every level.
    ///
    /// `color_space` is the one stated for the texture (a `ColorSpace`, or `Some` of one);
    /// `None` takes the one a `.tx` written by `conetrace maketx` records, else sRGB.
    pub fn from_file(
        path: &Path,
        color_space: impl Into<Option<ColorSpace>>,
    ) -> Result<Texture, TextureError> {
        Self::from_file_in(path, color_space, &TileCache::shared())
    }

    /// [`Texture::from_file`] with the tiles of a `.tx` kept in `cache`, under its cap
    /// (a texture decoded whole does not count against it).
    pub fn from_file_in(
        path: &Path,
        color_space: impl Into<Option<ColorSpace>>,
        cache: &Arc<TileCache>,
    ) -> Result<Texture, TextureError> {
        let color_space = color_space.into();
        match Self::from_file_on_demand(path, color_space, cache)? {
            Some(texture) => Ok(texture),
            None => Self::from_file_whole(path, color_space),
        }
    }

    /// The texture of a tiled, mip-mapped TIFF in 64x64 tiles, read tile by tile into
    /// `cache` as lookups touch them; `Ok(None)` for any other file (which only
    /// [`Texture::from_file_whole`] reads). Reads the file's headers and its coarsest tile.
    pub fn from_file_on_demand(
        path: &Path,
        color_space: impl Into<Option<ColorSpace>>,
        cache: &Arc<TileCache>,
    ) -> Result<Option<Texture>, TextureError> {
        let label = path.display().to_string();
        Ok(
            demand_tiles::open(path, &label, color_space.into(), cache)?.map(|(pyramid, file)| {
                let mut texture = Self::with_pyramid(&label, pyramid);
                texture.demand = Some(file);
                texture
            }),
        )
    }

    /// Loads a file like [`Texture::from_file`], but decodes every level up front even
    /// for a tiled, mip-mapped TIFF (the resident reference the demand path must match).
    pub fn from_file_whole(
        path: &Path,
        color_space: impl Into<Option<ColorSpace>>,
    ) -> Result<Texture, TextureError> {
        let label = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| TextureError::Io {
            label: label.clone(),
            source,
        })?;
        Self::from_encoded(&bytes, &label, color_space)
    }

    /// Decodes PNG, JPEG, OpenEXR or TIFF bytes; `label` names the source in errors.
    /// Mip-mapped OpenEXR and `.tx` files (e.g. written by `maketx`) keep their own levels.
    pub fn from_encoded(
        bytes: &[u8],
        label: &str,
        color_space: impl Into<Option<ColorSpace>>,
    ) -> Result<Texture, TextureError> {
        let levels = image_load::decode(bytes, label, color_space)?;
        let pyramid = if levels.len() > 1 && MipPyramid::chain_is_valid(&levels) {
            MipPyramid::from_levels(levels)
        } else {
            let base = levels
                .into_iter()
                .next()
                .ok_or_else(|| TextureError::Dimensions {
                    label: label.to_string(),
                    message: "no image levels".to_string(),
                })?;
            MipPyramid::build(base, label)?
        };
        // Stored levels (a `.tx` whose maker overflowed holds an inf in one) and levels
        // built here are checked alike.
        for (index, level) in pyramid.levels.iter().enumerate() {
            if let Some((x, y, channel, value)) = level.find_texel(4, |v| !v.is_finite()) {
                return Err(TextureError::NonFinite {
                    label: label.to_string(),
                    level: index,
                    x,
                    y,
                    channel: CHANNEL_NAMES[channel],
                    value,
                });
            }
        }
        Ok(Self::with_pyramid(label, pyramid))
    }

    /// Builds a texture from linear RGBA texels, row-major with t = 0 first.
    pub fn from_rgba_f32(
        width: u32,
        height: u32,
        texels: Vec<[f32; 4]>,
    ) -> Result<Texture, TextureError> {
        let base =
            MipLevel::new(width, height, texels).map_err(|message| TextureError::Dimensions {
                label: "in-memory texture".to_string(),
                message,
            })?;
        Ok(Self::with_pyramid(
            "in-memory texture",
            MipPyramid::build(base, "in-memory texture")?,
        ))
    }

    /// This texture with its mip levels rebuilt from level 0 by the `maketx` box rule, in
    /// level 0's precision (for a file whose stored levels are not box reductions).
    pub fn with_rebuilt_pyramid(&self) -> Result<Texture, TextureError> {
        let base = self.pyramid.levels[0].clone();
        Ok(Self::with_pyramid(
            &self.label,
            MipPyramid::build(base, &self.label)?,
        ))
    }

    fn with_pyramid(label: &str, pyramid: MipPyramid) -> Texture {
        Texture {
            id: NEXT_TEXTURE_ID.fetch_add(1, Ordering::Relaxed),
            label: label.to_string(),
            pyramid,
            demand: None,
        }
    }

    /// True when the texture's tiles are read from its file as lookups touch them.
    pub fn is_demand_loaded(&self) -> bool {
        self.demand.is_some()
    }

    /// Tiles read from the file so far, a tile read again after its eviction counted
    /// again (0 for a texture decoded whole).
    pub fn tiles_read(&self) -> u64 {
        self.demand.as_ref().map_or(0, |file| file.tiles_read())
    }

    /// The cache counters of a demand-loaded texture since it was opened (`None` for a
    /// texture decoded whole). Micro-cache hits are counted per thread and arrive here
    /// after [`flush_micro_caches`] (every render calls it at its end).
    pub fn cache_stats(&self) -> Option<TextureCacheStats> {
        self.demand.as_ref().map(|file| file.cache_stats())
    }

    /// The cache a demand-loaded texture's tiles live in.
    pub fn tile_cache(&self) -> Option<&Arc<TileCache>> {
        self.demand.as_ref().map(|file| file.cache())
    }

    /// Of a demand-loaded texture, what identifies its file without reading its tiles:
    /// length, modification time and the tile layout of every level (offsets and byte
    /// counts). `None` for a texture decoded whole.
    pub fn file_identity(&self) -> Option<&[u64]> {
        self.demand.as_ref().map(|file| file.identity())
    }

    /// Tiles the file of a demand-loaded texture holds over all levels (0 for a texture
    /// decoded whole).
    pub fn tiles_in_file(&self) -> u64 {
        self.demand.as_ref().map_or(0, |file| file.tiles_in_file())
    }

    /// The first tile of a demand-loaded texture that could not be read, as a message
    /// naming the file, the level and the tile. Lookups that needed it returned zero, so
    /// a render that made them must be refused.
    pub fn tile_failure(&self) -> Option<&str> {
        self.demand.as_ref().and_then(|file| file.failure())
    }

    /// The colour space the texture's 8-bit colour is decoded in (stated, or recorded by
    /// its `.tx`); `None` when its texels are not 8-bit (used as stored).
    pub fn color_space(&self) -> Option<ColorSpace> {
        self.pyramid.levels[0].texels.color_space()
    }

    /// Width of level 0 in texels.
    pub fn width(&self) -> u32 {
        self.pyramid.levels[0].width
    }

    /// Height of level 0 in texels.
    pub fn height(&self) -> u32 {
        self.pyramid.levels[0].height
    }

    /// Number of mip levels (level 0 included).
    pub fn level_count(&self) -> usize {
        self.pyramid.levels.len()
    }

    /// The pyramid, for inspection (tests, tools).
    pub fn pyramid(&self) -> &MipPyramid {
        &self.pyramid
    }

    /// The file path or label the texture came from.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// Process-unique id; [`TextureTileSet`] keys tiles by it.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Bytes of texel storage over all levels.
    pub fn memory_bytes(&self) -> usize {
        self.pyramid.memory_bytes()
    }

    /// Average alpha of level 0.
    pub fn mean_alpha(&self) -> f32 {
        let level = &self.pyramid.levels[0];
        let sum: f64 = level
            .coordinates()
            .map(|(x, y)| f64::from(level.texel(x, y)[3]))
            .sum();
        (sum / level.texels.len() as f64) as f32
    }

    /// Filtered RGBA at the query's footprint: the one texture-sampling entry point.
    #[inline]
    pub fn sample(&self, q: &TextureQuery, opts: &FilterOptions) -> Vec4 {
        self.sample_observed(q, opts, &mut NoTextureTiles)
    }

    /// Same result as [`Texture::sample`]; also records every 64x64-texel tile read.
    pub fn sample_recording(
        &self,
        q: &TextureQuery,
        opts: &FilterOptions,
        tiles: &mut TextureTileSet,
    ) -> Vec4 {
        let mut recorder = TextureTileRecorder::new(self.id, tiles);
        self.sample_observed(q, opts, &mut recorder)
    }

    /// The fractional mip level the filter reads (0 = finest), for the `lod` AOV.
    pub fn lod(&self, q: &TextureQuery, opts: &FilterOptions) -> f32 {
        match opts.filter {
            FilterMode::Closest | FilterMode::Bilinear => 0.0,
            FilterMode::Trilinear => trilinear::level_choice(&self.pyramid, q).fractional(),
            FilterMode::Aniso | FilterMode::Ewa => {
                aniso::footprint(&self.pyramid, q, opts.max_aniso)
                    .levels
                    .fractional()
            }
        }
    }

    // Out of line, as LLVM compiled it before the lookups took their tiles as an argument:
    // inlined into a caller's loop, it left `closest` out of line and a call per lookup.
    #[inline(never)]
    fn sample_observed<O: TexelObserver>(
        &self,
        q: &TextureQuery,
        opts: &FilterOptions,
        obs: &mut O,
    ) -> Vec4 {
        self.sample_in(q, opts, None, obs)
    }

    /// [`Texture::sample_observed`] with the lookup's tiles fetched through `tiles`, or with
    /// `None` through the thread's micro-cache found for this lookup: by each mip-mapped
    /// filter before it starts (before the anisotropic filter's vector dispatch, whose code
    /// inlined into the out-of-line thread-local access would lose its vector level), and by
    /// closest and bilinear at their single fetch (see `filter_closest_bilinear::fetch`).
    #[inline(always)]
    fn sample_in<O: TexelObserver>(
        &self,
        q: &TextureQuery,
        opts: &FilterOptions,
        tiles: Option<ThreadTiles<'_>>,
        obs: &mut O,
    ) -> Vec4 {
        let wrap = (opts.wrap_s, opts.wrap_t);
        let q = &TextureQuery {
            s: wrap::reduce_coordinate(q.s, opts.wrap_s),
            t: wrap::reduce_coordinate(q.t, opts.wrap_t),
            ..*q
        };
        let p = &self.pyramid;
        match opts.filter {
            FilterMode::Closest => {
                filter_closest_bilinear::closest(&p.levels[0], 0, q.s, q.t, wrap, tiles, obs)
            }
            FilterMode::Bilinear => {
                filter_closest_bilinear::bilinear(&p.levels[0], 0, q.s, q.t, wrap, tiles, obs)
            }
            FilterMode::Trilinear => self.with_tiles(
                tiles,
                #[inline(always)]
                |tiles| trilinear::sample(p, q, wrap, tiles, obs),
            ),
            FilterMode::Aniso => self.with_tiles(
                tiles,
                #[inline(always)]
                |tiles| aniso::sample(p, q, opts.max_aniso, wrap, tiles, obs),
            ),
            FilterMode::Ewa => self.with_tiles(
                tiles,
                #[inline(always)]
                |tiles| ewa::sample(p, q, opts.max_aniso, wrap, tiles, obs),
            ),
        }
    }

    /// `body` given `tiles`, or else the micro-cache the lookups of this texture fetch their
    /// tiles through ([`Texture::with_lookup_tiles`]).
    #[inline(always)]
    fn with_tiles<R>(
        &self,
        tiles: Option<ThreadTiles<'_>>,
        body: impl FnOnce(ThreadTiles<'_>) -> R,
    ) -> R {
        match tiles {
            Some(tiles) => body(tiles),
            None => self.with_lookup_tiles(body),
        }
    }

    /// `body` given the micro-cache the lookups of this texture fetch their tiles through:
    /// the thread's, found once, for a demand-loaded texture; none for a resident one, which
    /// then makes no thread-local access.
    #[inline(always)]
    fn with_lookup_tiles<R>(&self, body: impl FnOnce(ThreadTiles<'_>) -> R) -> R {
        match self.demand {
            Some(_) => micro_cache::with_thread_tiles(body),
            None => body(ThreadTiles::none()),
        }
    }
}

macro_rules! lowercase_names {
    ($ty:ident, $what:literal, $($variant:ident => $name:literal),+) => {
        impl fmt::Display for $ty {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(match self { $($ty::$variant => $name),+ })
            }
        }
        impl FromStr for $ty {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                match s.to_ascii_lowercase().as_str() {
                    $($name => Ok($ty::$variant),)+
                    _ => Err(format!(
                        concat!("unknown ", $what, " '{}' (expected one of: {})"),
                        s,
                        [$($name),+].join(", ")
                    )),
                }
            }
        }
    };
}

lowercase_names!(ColorSpace, "color space", Srgb => "srgb", Linear => "linear");
lowercase_names!(WrapMode, "wrap mode", Periodic => "periodic", Clamp => "clamp", Black => "black", Mirror => "mirror");
lowercase_names!(FilterMode, "filter", Closest => "closest", Bilinear => "bilinear", Trilinear => "trilinear", Aniso => "aniso", Ewa => "ewa");

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(w: u32, h: u32) -> Texture {
        let texels = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                let v = ((x + y) % 2) as f32;
                [v, 1.0 - v, (x as f32) / w as f32, 0.25 + 0.5 * v]
            })
            .collect();
        Texture::from_rgba_f32(w, h, texels).unwrap()
    }

    #[test]
    fn texture_is_shareable_across_threads() {
        fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<Texture>();
        assert_send_sync::<TextureTileSet>();
    }

    #[test]
    fn names_round_trip() {
        for f in [
            FilterMode::Closest,
            FilterMode::Bilinear,
            FilterMode::Trilinear,
            FilterMode::Aniso,
            FilterMode::Ewa,
        ] {
            assert_eq!(f.to_string().parse::<FilterMode>().unwrap(), f);
        }
        for w in [
            WrapMode::Periodic,
            WrapMode::Clamp,
            WrapMode::Black,
            WrapMode::Mirror,
        ] {
            assert_eq!(w.to_string().parse::<WrapMode>().unwrap(), w);
        }
        assert_eq!("srgb".parse::<ColorSpace>().unwrap(), ColorSpace::Srgb);
        assert!("box".parse::<FilterMode>().is_err());
        assert_eq!(FilterMode::default(), FilterMode::Aniso);
    }

    #[test]
    fn zero_derivatives_equal_bilinear_level0() {
        let tex = checker(37, 20);
        let q = TextureQuery {
            s: 0.3127,
            t: 0.771,
            ..Default::default()
        };
        let bil = tex.sample(
            &q,
            &FilterOptions {
                filter: FilterMode::Bilinear,
                ..Default::default()
            },
        );
        for filter in [FilterMode::Trilinear, FilterMode::Aniso, FilterMode::Ewa] {
            let opts = FilterOptions {
                filter,
                ..Default::default()
            };
            let v = tex.sample(&q, &opts);
            assert!(
                (v - bil).abs().max_element() < 1e-5,
                "{filter}: {v} vs {bil}"
            );
            assert_eq!(tex.lod(&q, &opts), 0.0);
        }
    }

    #[test]
    fn recording_gives_the_same_result_and_counts_tiles() {
        let tex = checker(200, 130);
        let mut tiles = TextureTileSet::new();
        let opts = FilterOptions::default();
        let q = TextureQuery {
            s: 0.5,
            t: 0.5,
            dsdx: 0.2,
            dtdx: 0.01,
            dsdy: 0.0,
            dtdy: 0.02,
        };
        assert_eq!(
            tex.sample(&q, &opts),
            tex.sample_recording(&q, &opts, &mut tiles)
        );
        assert!(tiles.count() >= 1);
        let per_level = tiles.count_per_level();
        assert_eq!(per_level.iter().sum::<u64>(), tiles.count());
    }

    #[test]
    fn mean_alpha_and_memory() {
        let tex = checker(4, 4);
        assert!((tex.mean_alpha() - 0.5).abs() < 1e-6);
        // 4x4 + 2x2 + 1x1 texels of 16 bytes.
        assert_eq!(tex.memory_bytes(), (16 + 4 + 1) * 16);
        assert_eq!(tex.level_count(), 3);
    }

    #[test]
    fn one_by_one_and_one_by_n() {
        let one = Texture::from_rgba_f32(1, 1, vec![[0.2, 0.4, 0.6, 1.0]]).unwrap();
        let col = checker(1, 9);
        for filter in [
            FilterMode::Closest,
            FilterMode::Bilinear,
            FilterMode::Trilinear,
            FilterMode::Aniso,
            FilterMode::Ewa,
        ] {
            let opts = FilterOptions {
                filter,
                ..Default::default()
            };
            let q = TextureQuery {
                s: 0.9,
                t: -3.2,
                dsdx: 0.5,
                dtdx: 0.1,
                dsdy: -0.2,
                dtdy: 3.0,
            };
            let v = one.sample(&q, &opts);
            assert!((v - Vec4::new(0.2, 0.4, 0.6, 1.0)).abs().max_element() < 1e-5);
            let c = col.sample(&q, &opts);
            assert!(c.is_finite() && c.min_element() >= -1e-6 && c.max_element() <= 1.0 + 1e-6);
        }
    }

    #[test]
    fn huge_coordinates_stay_finite_and_wrap() {
        let tex = checker(16, 16);
        for filter in [
            FilterMode::Closest,
            FilterMode::Bilinear,
            FilterMode::Trilinear,
            FilterMode::Aniso,
            FilterMode::Ewa,
        ] {
            for wrap in [
                WrapMode::Periodic,
                WrapMode::Clamp,
                WrapMode::Black,
                WrapMode::Mirror,
            ] {
                let opts = FilterOptions {
                    filter,
                    wrap_s: wrap,
                    wrap_t: wrap,
                    max_aniso: 16.0,
                };
                // 1e7 is a whole number in f32: periodic gives the value at s = 0 exactly.
                let far = TextureQuery {
                    s: 1.0e7,
                    t: -1.0e7,
                    dsdx: 1e-3,
                    dtdx: 0.0,
                    dsdy: 0.0,
                    dtdy: 1e-3 * 1e-6,
                };
                let v = tex.sample(&far, &opts);
                assert!(v.is_finite(), "{filter} {wrap}: {v}");
                if wrap == WrapMode::Periodic {
                    let near = TextureQuery {
                        s: 0.0,
                        t: 0.0,
                        ..far
                    };
                    assert!((v - tex.sample(&near, &opts)).abs().max_element() < 1e-6);
                }
            }
        }
    }

    mod convexity {
        use super::*;
        use proptest::prelude::*;
        use std::sync::OnceLock;

        /// High-frequency pseudo-random texture in [0.1, 0.9] (so black wrap, which
        /// adds zeros, widens the bound to [0, 0.9]).
        fn noise() -> &'static Texture {
            static TEX: OnceLock<Texture> = OnceLock::new();
            TEX.get_or_init(|| {
                let (w, h) = (23u32, 16u32);
                let mut x = 12345u32;
                let texels = (0..w * h)
                    .map(|_| {
                        std::array::from_fn(|_| {
                            x = x.wrapping_mul(1664525).wrapping_add(1013904223);
                            0.1 + 0.8 * (x >> 8) as f32 / (1u32 << 24) as f32
                        })
                    })
                    .collect();
                Texture::from_rgba_f32(w, h, texels).unwrap()
            })
        }

        fn deriv() -> impl Strategy<Value = f32> {
            prop_oneof![
                Just(0.0f32),
                -1.0f32..1.0,
                (-30.0f32..30.0).prop_map(|e| 10f32.powf(e)),
                (-30.0f32..30.0).prop_map(|e| -(10f32.powf(e))),
            ]
        }

        proptest! {
            #[test]
            fn every_lookup_lies_within_the_texel_range(
                s in -1.0e7f32..1.0e7, t in -3.0f32..3.0,
                dsdx in deriv(), dtdx in deriv(), dsdy in deriv(), dtdy in deriv(),
                filter in 0usize..5, wrap in 0usize..4, max_aniso in 1.0f32..64.0,
            ) {
                let filters = [FilterMode::Closest, FilterMode::Bilinear, FilterMode::Trilinear, FilterMode::Aniso, FilterMode::Ewa];
                let wraps = [WrapMode::Periodic, WrapMode::Clamp, WrapMode::Black, WrapMode::Mirror];
                let opts = FilterOptions { filter: filters[filter], wrap_s: wraps[wrap], wrap_t: wraps[(wrap + 1) % 4], max_aniso };
                let q = TextureQuery { s, t, dsdx, dtdx, dsdy, dtdy };
                let v = noise().sample(&q, &opts);
                prop_assert!(v.is_finite(), "{v}");
                let lo = if wraps[wrap] == WrapMode::Black || wraps[(wrap + 1) % 4] == WrapMode::Black { 0.0 } else { 0.1 };
                prop_assert!(v.min_element() >= lo - 1e-5 && v.max_element() <= 0.9 + 1e-5, "{v}");
                prop_assert!(noise().lod(&q, &opts).is_finite());
            }
        }
    }
}
