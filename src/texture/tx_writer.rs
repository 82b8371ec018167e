//! Writing a mip pyramid as a tiled, mip-mapped TIFF (`.tx`), the file `conetrace maketx`
//! makes from an untiled image so that renders read it tile by tile (`demand_tiles`).
//!
//! The layout is the one OpenImageIO's `maketx` writes and `tiff_tile_reader` reads: one
//! TIFF directory (IFD) per mip level, finest first, each chained to the next down to 1x1;
//! every level cut into [`TEXTURE_TILE_SIZE`] x [`TEXTURE_TILE_SIZE`] tiles, row of tiles
//! by row of tiles, edge tiles padded with zeros to the full tile size (TIFF tiles are
//! always whole); samples interleaved (PlanarConfiguration 1), little-endian.
//!
//! The levels are written exactly as the [`MipPyramid`] holds them, in its precision:
//! 8-bit levels as bytes (BitsPerSample 8, unsigned), half levels as 16-bit IEEE floats,
//! float levels as 32-bit IEEE floats (SampleFormat 3). Reading the file back gives the
//! very texels the pyramid held, so a render from the file equals a render from the
//! pyramid bit for bit. Three channels (RGB) are written when every texel of every level
//! is opaque (the reader fills alpha with one), four (RGBA, alpha marked associated, as
//! `maketx` marks it, so readers use it as stored) otherwise.
//!
//! Tiles are deflate-compressed (TIFF compression 8, a zlib stream per tile) unless asked
//! otherwise; 8-bit tiles go through TIFF's horizontal predictor first (Predictor 2), as
//! `maketx` does. The `tiff` crate lays out the directories (classic TIFF, or BigTIFF when
//! the texels could pass 4 GiB); it writes no tiles itself, so the tiles are cut, encoded
//! and their offsets recorded here.
//!
//! ImageDescription carries `conetrace:ColorSpace=sRGB` (or `Linear`): the colour space
//! 8-bit colour was decoded in when the levels were averaged. An sRGB file also carries
//! the Exif ColorSpace tag `maketx` writes, which OpenImageIO reports as
//! `oiio:ColorSpace` "sRGB". A texture whose scene states no colour space is decoded in
//! the recorded one; one the scene states wins, and must be the source's for the levels to
//! match.

use std::io::{Seek, Write};

use rayon::prelude::*;
use tiff::encoder::{DirectoryEncoder, TiffEncoder, TiffKind};
use tiff::tags::Tag;

use super::mip_pyramid::{MipLevel, MipPyramid};
use super::texels::Texels;
use super::tile_layout::TileLayout;
use super::tiles::TEXTURE_TILE_SIZE;
use super::ColorSpace;

/// How tiles are compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TxCompression {
    /// Deflate (zlib), what `maketx` writes by default.
    #[default]
    Deflate,
    /// Stored as is: larger files, the fastest reads.
    None,
}

impl std::str::FromStr for TxCompression {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "deflate" | "zip" => Ok(TxCompression::Deflate),
            "none" => Ok(TxCompression::None),
            _ => Err(format!(
                "unknown compression '{s}' (expected one of: deflate, none)"
            )),
        }
    }
}

/// What goes into the file besides the texels.
#[derive(Clone, Debug)]
pub struct TxOptions {
    pub compression: TxCompression,
    /// The colour space 8-bit colour was decoded in to build the levels (recorded in
    /// ImageDescription).
    pub color_space: ColorSpace,
    /// The Software tag, e.g. the command line that made the file.
    pub software: String,
}

/// The sample type of a stored level.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum SampleKind {
    Byte,
    Half,
    Float,
}

impl SampleKind {
    fn of(texels: &Texels) -> Result<SampleKind, String> {
        match texels {
            Texels::Byte { .. } => Ok(SampleKind::Byte),
            Texels::Half(_) => Ok(SampleKind::Half),
            Texels::Float(_) => Ok(SampleKind::Float),
            Texels::OnDemand(_) => Err("the levels must be decoded in memory".to_string()),
        }
    }

    fn bytes(self) -> usize {
        match self {
            SampleKind::Byte => 1,
            SampleKind::Half => 2,
            SampleKind::Float => 4,
        }
    }
}

/// The format every level of the file shares.
#[derive(Clone, Copy, Debug)]
struct StoredFormat {
    kind: SampleKind,
    channels: usize,
    compression: TxCompression,
}

impl StoredFormat {
    /// Bytes of one whole (padded) tile before compression.
    fn tile_bytes(&self) -> usize {
        let side = TEXTURE_TILE_SIZE as usize;
        side * side * self.channels * self.kind.bytes()
    }

    /// The horizontal predictor helps 8-bit texels compress; floats are stored plain.
    fn predictor(&self) -> u16 {
        if self.compression == TxCompression::Deflate && self.kind == SampleKind::Byte {
            2
        } else {
            1
        }
    }
}

/// Writes every level of `pyramid` to `out` as a tiled, mip-mapped TIFF (see the module
/// documentation). The levels must be held in memory (not read on demand) and form a
/// complete chain down to 1x1.
pub fn write_tx<W: Write + Seek>(
    pyramid: &MipPyramid,
    out: W,
    options: &TxOptions,
) -> Result<(), String> {
    let levels = &pyramid.levels;
    if !MipPyramid::chain_is_valid(levels) {
        return Err("the mip levels do not halve down to 1x1".to_string());
    }
    let kind = SampleKind::of(&levels[0].texels)?;
    for level in levels {
        if SampleKind::of(&level.texels)? != kind {
            return Err("the mip levels do not share one sample type".to_string());
        }
    }
    let opaque = levels.iter().all(level_is_opaque);
    let format = StoredFormat {
        kind,
        channels: if opaque { 3 } else { 4 },
        compression: options.compression,
    };
    // Uncompressed size with padded tiles: classic TIFF's 32-bit offsets hold it with room
    // for the directories, or the file is a BigTIFF.
    let padded: u64 = levels
        .iter()
        .map(|l| {
            let layout = l.layout();
            (layout.tiles_x() * layout.tiles_y()) as u64 * format.tile_bytes() as u64
        })
        .sum();
    let tiff_error = |e: tiff::TiffError| e.to_string();
    if padded < (u32::MAX as u64) / 8 * 7 {
        let mut encoder = TiffEncoder::new(out).map_err(tiff_error)?;
        write_levels(&mut encoder, levels, format, options)
    } else {
        let mut encoder = TiffEncoder::new_big(out).map_err(tiff_error)?;
        write_levels(&mut encoder, levels, format, options)
    }
}

/// True when every texel's alpha is exactly one (so RGB alone loses nothing).
fn level_is_opaque(level: &MipLevel) -> bool {
    match &level.texels {
        Texels::Byte { texels, .. } => texels.iter().all(|t| t[3] == 255),
        Texels::Half(texels) => texels.iter().all(|t| t[3] == half::f16::ONE),
        Texels::Float(texels) => texels.iter().all(|t| t[3] == 1.0),
        Texels::OnDemand(_) => false,
    }
}

/// Writes each level's tiles and then its directory, finest level first.
fn write_levels<W: Write + Seek, K: TiffKind>(
    encoder: &mut TiffEncoder<W, K>,
    levels: &[MipLevel],
    format: StoredFormat,
    options: &TxOptions,
) -> Result<(), String> {
    let tiff_error = |e: tiff::TiffError| e.to_string();
    let description = match options.color_space {
        ColorSpace::Srgb if format.kind == SampleKind::Byte => "sRGB",
        _ => "Linear",
    };
    let description = format!("{}{description}", super::tiled_tiff::COLOR_SPACE_PREFIX);
    // sRGB is also said the way maketx says it, which OpenImageIO reads as its
    // `oiio:ColorSpace`: an Exif directory with ColorSpace (tag 40961) = 1, sRGB.
    let exif = if description.ends_with("sRGB") {
        let mut exif = encoder.extra_directory().map_err(tiff_error)?;
        exif.write_tag(Tag::Unknown(40961), 1u16)
            .map_err(tiff_error)?;
        Some(exif.finish_with_offsets().map_err(tiff_error)?.offset)
    } else {
        None
    };
    for (index, level) in levels.iter().enumerate() {
        let mut directory = encoder.image_directory().map_err(tiff_error)?;
        let (offsets, counts) = write_tiles(&mut directory, level, format)
            .map_err(|e| format!("level {index}: {e}"))?;
        write_tags(&mut directory, level, format, options, &description)?;
        let offsets = offsets
            .into_iter()
            .map(K::convert_offset)
            .collect::<Result<Vec<_>, _>>()
            .map_err(tiff_error)?;
        let counts = counts
            .into_iter()
            .map(K::convert_offset)
            .collect::<Result<Vec<_>, _>>()
            .map_err(tiff_error)?;
        directory
            .write_tag(Tag::TileOffsets, K::convert_slice(&offsets))
            .map_err(tiff_error)?;
        directory
            .write_tag(Tag::TileByteCounts, K::convert_slice(&counts))
            .map_err(tiff_error)?;
        if let Some(exif) = &exif {
            directory
                .write_tag(Tag::ExifDirectory, exif)
                .map_err(tiff_error)?;
        }
        directory.finish().map_err(tiff_error)?;
    }
    Ok(())
}

/// The tags of one level's directory but for the tile offsets and byte counts.
fn write_tags<W: Write + Seek, K: TiffKind>(
    directory: &mut DirectoryEncoder<'_, W, K>,
    level: &MipLevel,
    format: StoredFormat,
    options: &TxOptions,
    description: &str,
) -> Result<(), String> {
    let tiff_error = |e: tiff::TiffError| e.to_string();
    let bits = (8 * format.kind.bytes()) as u16;
    let sample_format: u16 = if format.kind == SampleKind::Byte {
        1
    } else {
        3
    };
    let channels = format.channels;
    let side = TEXTURE_TILE_SIZE as u16;
    let compression: u16 = match format.compression {
        TxCompression::Deflate => 8,
        TxCompression::None => 1,
    };
    let tags: [(Tag, &[u16]); 8] = [
        (Tag::BitsPerSample, &[bits; 4][..channels]),
        (Tag::Compression, &[compression]),
        // RGB.
        (Tag::PhotometricInterpretation, &[2]),
        (Tag::SamplesPerPixel, &[channels as u16]),
        // Interleaved samples.
        (Tag::PlanarConfiguration, &[1]),
        (Tag::Predictor, &[format.predictor()]),
        (Tag::TileWidth, &[side]),
        (Tag::TileLength, &[side]),
    ];
    directory
        .write_tag(Tag::ImageWidth, level.width)
        .map_err(tiff_error)?;
    directory
        .write_tag(Tag::ImageLength, level.height)
        .map_err(tiff_error)?;
    for (tag, value) in tags {
        directory.write_tag(tag, value).map_err(tiff_error)?;
    }
    directory
        .write_tag(Tag::SampleFormat, &[sample_format; 4][..channels])
        .map_err(tiff_error)?;
    if channels == 4 {
        // Associated alpha: readers use it as stored (unassociated would be premultiplied).
        directory
            .write_tag(Tag::ExtraSamples, &[1u16][..])
            .map_err(tiff_error)?;
    }
    directory
        .write_tag(Tag::ImageDescription, description)
        .map_err(tiff_error)?;
    directory
        .write_tag(Tag::Software, options.software.as_str())
        .map_err(tiff_error)?;
    // Pixar's texture tags, which OpenImageIO reads to know the file is a texture and how
    // it wraps by default (conetrace's default, periodic; the scene's wrap modes rule).
    directory
        .write_tag(Tag::Unknown(33302), "Plain Texture")
        .map_err(tiff_error)?;
    directory
        .write_tag(Tag::Unknown(33303), "periodic,periodic")
        .map_err(tiff_error)?;
    Ok(())
}

/// Encodes and writes every tile of `level`, one row of tiles at a time (the tiles of a
/// row encoded in parallel); returns each tile's offset and byte count, row-major.
fn write_tiles<W: Write + Seek, K: TiffKind>(
    directory: &mut DirectoryEncoder<'_, W, K>,
    level: &MipLevel,
    format: StoredFormat,
) -> Result<(Vec<u64>, Vec<u64>), String> {
    let layout = level.layout();
    let (tiles_x, tiles_y) = (layout.tiles_x(), layout.tiles_y());
    let mut offsets = Vec::with_capacity(tiles_x * tiles_y);
    let mut counts = Vec::with_capacity(tiles_x * tiles_y);
    for tile_y in 0..tiles_y {
        let row: Vec<Vec<u8>> = (0..tiles_x)
            .into_par_iter()
            .map(|tile_x| encode_tile(level, layout, tile_x, tile_y, format))
            .collect::<Result<_, String>>()?;
        for tile in row {
            let offset = directory.write_data(&tile[..]).map_err(|e| e.to_string())?;
            offsets.push(offset);
            counts.push(tile.len() as u64);
        }
    }
    Ok((offsets, counts))
}

/// One tile's stored bytes: its texels' samples, padded to the whole tile with zeros,
/// through the predictor and the compression.
fn encode_tile(
    level: &MipLevel,
    layout: TileLayout,
    tile_x: usize,
    tile_y: usize,
    format: StoredFormat,
) -> Result<Vec<u8>, String> {
    let side = TEXTURE_TILE_SIZE as usize;
    let (width, height) = (layout.tile_width(tile_x), layout.tile_height(tile_y));
    let start = layout.tile_start(tile_x, tile_y);
    let channels = format.channels;
    let sample_bytes = format.kind.bytes();
    let row_bytes = side * channels * sample_bytes;
    let mut raw = vec![0u8; format.tile_bytes()];
    for y in 0..height {
        let row = &mut raw[y * row_bytes..(y + 1) * row_bytes];
        for x in 0..width {
            let texel = start + y * width + x;
            let at = &mut row[x * channels * sample_bytes..(x + 1) * channels * sample_bytes];
            put_samples(&level.texels, texel, channels, at);
        }
        if format.predictor() == 2 {
            // Each byte sample becomes its difference from the same channel of the texel to
            // its left (TIFF 6.0, section 14), right to left so the sources are unchanged.
            for i in (channels..row.len()).rev() {
                row[i] = row[i].wrapping_sub(row[i - channels]);
            }
        }
    }
    match format.compression {
        TxCompression::None => Ok(raw),
        TxCompression::Deflate => {
            let mut encoder = flate2::write::ZlibEncoder::new(
                Vec::with_capacity(raw.len() / 2),
                flate2::Compression::fast(),
            );
            encoder.write_all(&raw).map_err(|e| e.to_string())?;
            encoder.finish().map_err(|e| e.to_string())
        }
    }
}

/// Writes the first `channels` samples of texel `index` (tile order) into `out`,
/// little-endian.
fn put_samples(texels: &Texels, index: usize, channels: usize, out: &mut [u8]) {
    match texels {
        Texels::Byte { texels, .. } => out.copy_from_slice(&texels[index][..channels]),
        Texels::Half(texels) => {
            for (c, sample) in texels[index][..channels].iter().enumerate() {
                out[2 * c..2 * c + 2].copy_from_slice(&sample.to_bits().to_le_bytes());
            }
        }
        Texels::Float(texels) => {
            for (c, sample) in texels[index][..channels].iter().enumerate() {
                out[4 * c..4 * c + 4].copy_from_slice(&sample.to_le_bytes());
            }
        }
        // Refused before any tile is written.
        Texels::OnDemand(_) => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::tiff_tile_reader::TiffTileReader;
    use crate::texture::{image_load, Texture};
    use std::io::Cursor;

    fn noise_rgba(width: u32, height: u32, alpha: bool) -> Vec<[u8; 4]> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        (0..width * height)
            .map(|_| {
                let v = crate::test_rng::xorshift64_star(&mut state).to_le_bytes();
                [v[0], v[1], v[2], if alpha { v[3] } else { 255 }]
            })
            .collect()
    }

    fn written(pyramid: &MipPyramid, compression: TxCompression) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        let options = TxOptions {
            compression,
            color_space: ColorSpace::Srgb,
            software: "test".to_string(),
        };
        write_tx(pyramid, &mut out, &options).unwrap();
        out.into_inner()
    }

    fn byte_pyramid(width: u32, height: u32, alpha: bool) -> MipPyramid {
        let base = MipLevel::with_texels(
            width,
            height,
            Texels::bytes(noise_rgba(width, height, alpha), ColorSpace::Srgb),
        )
        .unwrap();
        MipPyramid::build(base, "noise").unwrap()
    }

    #[test]
    fn bytes_read_back_whole_and_tile_by_tile_as_written() {
        for (alpha, compression) in [
            (false, TxCompression::Deflate),
            (true, TxCompression::Deflate),
            (true, TxCompression::None),
        ] {
            let pyramid = byte_pyramid(200, 130, alpha);
            let bytes = written(&pyramid, compression);
            let levels = image_load::decode(&bytes, "w.tx", ColorSpace::Srgb).unwrap();
            assert_eq!(levels, pyramid.levels, "alpha {alpha}, {compression:?}");
            let reader = TiffTileReader::open(Cursor::new(&bytes), "w.tx", ColorSpace::Srgb)
                .unwrap()
                .expect("read tile by tile");
            let sizes: Vec<_> = pyramid.levels.iter().map(|l| (l.width, l.height)).collect();
            assert_eq!(reader.level_sizes(), sizes);
        }
    }

    #[test]
    fn half_and_float_levels_keep_their_precision() {
        let texels: Vec<[f32; 4]> = (0..70 * 67)
            .map(|i| [i as f32 * 0.37, -1.5, 1e-3 * i as f32, 0.25])
            .collect();
        let float = Texture::from_rgba_f32(70, 67, texels.clone()).unwrap();
        let bytes = written(float.pyramid(), TxCompression::Deflate);
        let levels = image_load::decode(&bytes, "f.tx", ColorSpace::Srgb).unwrap();
        assert_eq!(levels, float.pyramid().levels);
        assert!(matches!(levels[0].texels, Texels::Float(_)));

        let halves = Texels::Half(texels.iter().map(|t| t.map(half::f16::from_f32)).collect());
        let base = MipLevel::with_texels(70, 67, halves).unwrap();
        let pyramid = MipPyramid::build(base, "h").unwrap();
        let bytes = written(&pyramid, TxCompression::None);
        let levels = image_load::decode(&bytes, "h.tx", ColorSpace::Srgb).unwrap();
        assert_eq!(levels, pyramid.levels);
        assert!(matches!(levels[3].texels, Texels::Half(_)));
    }

    #[test]
    fn a_one_texel_image_is_one_level() {
        let pyramid = byte_pyramid(1, 1, true);
        let bytes = written(&pyramid, TxCompression::Deflate);
        let levels = image_load::decode(&bytes, "1.tx", ColorSpace::Srgb).unwrap();
        assert_eq!(levels, pyramid.levels);
    }

    #[test]
    fn an_incomplete_chain_is_refused() {
        let mut pyramid = byte_pyramid(8, 8, false);
        pyramid.levels.pop();
        let options = TxOptions {
            compression: TxCompression::None,
            color_space: ColorSpace::Srgb,
            software: String::new(),
        };
        let e = write_tx(&pyramid, Cursor::new(Vec::new()), &options).unwrap_err();
        assert!(e.contains("1x1"), "{e}");
    }
}
