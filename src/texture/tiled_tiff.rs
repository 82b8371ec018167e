//! Reading TIFF textures, above all OpenImageIO's `maketx` output (`.tx`), with every
//! stored mip level.
//!
//! A `.tx` file is a TIFF whose directories (IFDs) are the mip levels, finest first,
//! each cut into tiles (64x64 by default) and deflate-compressed with a horizontal
//! (integer) or floating-point predictor. The `tiff` crate decodes the tiles and
//! predictors; this module walks the directories and turns each one into a linear RGBA
//! [`MipLevel`]. Directories are taken as levels while each one halves the previous
//! (integer division, minimum 1), the chain `maketx` writes; a following directory of
//! another size (a multi-page TIFF) ends the list. Whether the levels form a complete
//! pyramid is decided by the caller, as for mip-mapped OpenEXR.
//!
//! Samples: unsigned 8, 16 or 32 bit (scaled to 0..1 by the type's maximum, the sRGB
//! decoding of [`ColorSpace::Srgb`] applied to the colour channels as for PNG), or
//! half, float or double floating point (used as stored, as for OpenEXR). 8-bit levels
//! keep their bytes and half levels their halves ([`Texels`]); the others become f32. One channel
//! is grey, two are grey and alpha, three or more are R, G, B and then alpha; further
//! channels are ignored. Alpha is used as stored (`maketx` keeps the source's
//! associated alpha). Interleaved and separate planes (`maketx --separate`) are read,
//! in a grey or RGB photometric interpretation; anything else is a
//! [`TextureError::Tiff`] naming the file.
//!
//! This module must not filter or resample: it returns the levels exactly as stored.

use std::io::{Cursor, Read, Seek};

use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

use super::mip_pyramid::MipLevel;
use super::texels::Texels;
use super::{ColorSpace, TextureError};
use crate::srgb::srgb_to_linear;

/// Largest decoded level accepted, in bytes of stored samples: a 16384x16384 RGBA
/// float level. The `tiff` crate's default (256 MiB) would refuse ordinary 8k float
/// textures.
pub(crate) const MAX_LEVEL_BYTES: u64 = 16384 * 16384 * 4 * 4;

/// True when `bytes` start with a classic or BigTIFF signature, in either byte order.
pub(crate) fn is_tiff(bytes: &[u8]) -> bool {
    matches!(
        bytes.get(..4),
        Some(b"II*\0") | Some(b"MM\0*") | Some(b"II+\0") | Some(b"MM\0+")
    )
}

/// What a `.tx` written by `conetrace maketx` holds in its ImageDescription before the
/// colour space its 8-bit colour is encoded in (`sRGB` or `Linear`).
pub(crate) const COLOR_SPACE_PREFIX: &str = "conetrace:ColorSpace=";

/// The colour space the current directory's ImageDescription records
/// (`conetrace:ColorSpace=sRGB` or `=Linear`, among other words); `None` when it records
/// none. OpenImageIO's `maketx` records only sRGB, in the Exif ColorSpace tag, which needs
/// no reading: sRGB is what an unrecorded file gets anyway.
pub(crate) fn recorded_color_space<R: Read + Seek>(decoder: &mut Decoder<R>) -> Option<ColorSpace> {
    let description = decoder.get_tag_ascii_string(Tag::ImageDescription).ok()?;
    description
        .split_whitespace()
        .find_map(|word| match word.strip_prefix(COLOR_SPACE_PREFIX)? {
            "sRGB" => Some(ColorSpace::Srgb),
            "Linear" => Some(ColorSpace::Linear),
            _ => None,
        })
}

/// The colour space the TIFF at `path` records ([`recorded_color_space`]); `None` for a
/// file that records none, is not a TIFF or cannot be read (its loading reports that).
pub(crate) fn file_color_space(path: &std::path::Path) -> Option<ColorSpace> {
    let file = std::fs::File::open(path).ok()?;
    let mut decoder = Decoder::new(std::io::BufReader::new(file)).ok()?;
    recorded_color_space(&mut decoder)
}

/// The colour space a TIFF is decoded in: the one `stated` (by the scene), else the one
/// the file records ([`recorded_color_space`], read from its first directory), else sRGB.
pub(crate) fn color_space_of<R: Read + Seek>(
    stated: Option<ColorSpace>,
    decoder: &mut Decoder<R>,
) -> ColorSpace {
    stated
        .or_else(|| recorded_color_space(decoder))
        .unwrap_or(ColorSpace::Srgb)
}

/// Decodes every level of a TIFF texture, finest first, in the colour space stated or
/// else recorded ([`color_space_of`]).
pub(crate) fn decode(
    bytes: &[u8],
    label: &str,
    color_space: impl Into<Option<ColorSpace>>,
) -> Result<Vec<MipLevel>, TextureError> {
    let tiff_error = |message: String| TextureError::Tiff {
        label: label.to_string(),
        message,
    };
    let mut limits = Limits::default();
    limits.decoding_buffer_size = usize::try_from(MAX_LEVEL_BYTES).unwrap_or(usize::MAX);
    let mut decoder = Decoder::new(Cursor::new(bytes))
        .map_err(|e| tiff_error(e.to_string()))?
        .with_limits(limits);
    let color_space = color_space_of(color_space.into(), &mut decoder);

    let mut levels: Vec<MipLevel> = Vec::new();
    loop {
        let level = decode_directory(&mut decoder, color_space).map_err(|m| {
            tiff_error(if levels.is_empty() {
                m
            } else {
                format!("level {}: {m}", levels.len())
            })
        })?;
        levels.push(level);
        if !decoder.more_images() {
            break;
        }
        decoder
            .next_image()
            .map_err(|e| tiff_error(format!("directory {}: {e}", levels.len())))?;
        let (w, h) = decoder
            .dimensions()
            .map_err(|e| tiff_error(e.to_string()))?;
        let previous = &levels[levels.len() - 1];
        let halved = ((previous.width / 2).max(1), (previous.height / 2).max(1));
        if (w, h) != halved || (previous.width, previous.height) == (1, 1) {
            // Not the next mip level: another page of a multi-page TIFF.
            break;
        }
    }
    Ok(levels)
}

/// How the samples of one TIFF directory (a level) are stored.
pub(crate) struct DirectoryFormat {
    /// Level size in texels.
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Samples per texel.
    pub(crate) channels: usize,
    /// Bytes per sample.
    pub(crate) bytes_per_sample: usize,
    /// All of channel 0, then all of channel 1, ... instead of interleaved texels.
    pub(crate) separate_planes: bool,
}

impl DirectoryFormat {
    /// The format of the decoder's current directory, or why a texture cannot use it.
    pub(crate) fn read<R: Read + Seek>(decoder: &mut Decoder<R>) -> Result<Self, String> {
        let (width, height) = decoder.dimensions().map_err(|e| e.to_string())?;
        let (channels, bits) = match decoder.colortype().map_err(|e| e.to_string())? {
            ColorType::Gray(b) => (1, b),
            ColorType::GrayA(b) => (2, b),
            ColorType::RGB(b) => (3, b),
            ColorType::RGBA(b) => (4, b),
            ColorType::Multiband {
                num_samples,
                bit_depth,
            } => (usize::from(num_samples), bit_depth),
            other => return Err(format!("unsupported colour type {other:?}")),
        };
        if !matches!(bits, 8 | 16 | 32 | 64) {
            return Err(format!("unsupported {bits}-bit samples"));
        }
        // Grey stored as 0 = white would need inverting; maketx never writes it.
        let photometric = decoder
            .find_tag_unsigned::<u16>(Tag::PhotometricInterpretation)
            .map_err(|e| e.to_string())?;
        if !matches!(photometric, Some(1) | Some(2)) {
            return Err(format!(
                "unsupported photometric interpretation {photometric:?} (expected grey or RGB)"
            ));
        }
        let separate_planes = match decoder
            .find_tag_unsigned::<u16>(Tag::PlanarConfiguration)
            .map_err(|e| e.to_string())?
        {
            None | Some(1) => false,
            Some(2) => true,
            Some(other) => return Err(format!("unknown planar configuration {other}")),
        };
        Ok(DirectoryFormat {
            width,
            height,
            channels,
            bytes_per_sample: usize::from(bits / 8),
            separate_planes,
        })
    }
}

/// Reads the decoder's current directory as one level.
fn decode_directory<R: Read + Seek>(
    decoder: &mut Decoder<R>,
    color_space: ColorSpace,
) -> Result<MipLevel, String> {
    let format = DirectoryFormat::read(decoder)?;
    let (width, height) = (format.width, format.height);
    let data = if format.separate_planes {
        read_separate_planes(
            decoder,
            width,
            height,
            format.channels,
            format.bytes_per_sample,
        )?
    } else {
        let mut data = DecodingResult::U8(Vec::new());
        decoder
            .read_image_to_buffer(&mut data)
            .map_err(|e| e.to_string())?;
        data
    };
    let layout = SampleLayout {
        width,
        height,
        channels: format.channels,
        separate_planes: format.separate_planes,
    };
    MipLevel::with_texels(width, height, layout.texels(data, color_space)?)
}

/// Reads a level stored as separate planes chunk by chunk (tile or strip), placing each
/// chunk's rows into one plane-major buffer: all of channel 0, then channel 1, ... The
/// `tiff` crate's whole-image read does not lay out tiled separate planes correctly, and
/// a chunk holds a single channel, so the assembly is done here.
fn read_separate_planes<R: Read + Seek>(
    decoder: &mut Decoder<R>,
    width: u32,
    height: u32,
    channels: usize,
    bytes_per_sample: usize,
) -> Result<DecodingResult, String> {
    let (chunk_w, chunk_h) = decoder.chunk_dimensions();
    if chunk_w == 0 || chunk_h == 0 {
        return Err(format!("chunks of {chunk_w}x{chunk_h} texels"));
    }
    let (across, down) = (width.div_ceil(chunk_w), height.div_ceil(chunk_h));
    let (w, h) = (width as usize, height as usize);
    let mut image: Option<DecodingResult> = None;
    for plane in 0..channels {
        for cy in 0..down {
            for cx in 0..across {
                let index = u32::try_from(plane)
                    .ok()
                    .and_then(|p| {
                        p.checked_mul(down)?
                            .checked_add(cy)?
                            .checked_mul(across)?
                            .checked_add(cx)
                    })
                    .ok_or("too many chunks")?;
                let mut chunk = decoder.read_chunk(index).map_err(|e| e.to_string())?;
                let image = match &mut image {
                    Some(image) => image,
                    None => image.insert(zeroed_like(
                        &chunk,
                        w.saturating_mul(h).saturating_mul(channels),
                    )?),
                };
                let (x0, y0) = ((cx * chunk_w) as usize, (cy * chunk_h) as usize);
                let data_w = (w - x0).min(chunk_w as usize);
                let data_h = (h - y0).min(chunk_h as usize);
                let row_bytes = data_w * bytes_per_sample;
                let source = chunk.as_buffer(0);
                let source = source.as_bytes();
                let mut target = image.as_buffer(0);
                let target = target.as_bytes_mut();
                if source.len() < row_bytes * data_h
                    || target.len() != w * h * channels * bytes_per_sample
                {
                    return Err(format!(
                        "chunk {index} holds {} bytes, expected {}",
                        source.len(),
                        row_bytes * data_h
                    ));
                }
                for row in 0..data_h {
                    let to = ((plane * h + y0 + row) * w + x0) * bytes_per_sample;
                    target[to..to + row_bytes]
                        .copy_from_slice(&source[row * row_bytes..(row + 1) * row_bytes]);
                }
            }
        }
    }
    image.ok_or_else(|| "no image data".to_string())
}

/// A zeroed buffer of `len` samples of the same type as `chunk`.
fn zeroed_like(chunk: &DecodingResult, len: usize) -> Result<DecodingResult, String> {
    // The size comes from the file's header (width x height x samples per pixel, up to 65535
    // samples): bounded like a whole-level read, so a crafted file is refused, not an abort.
    let bytes = (len as u64).saturating_mul(match chunk {
        DecodingResult::U8(_) => 1,
        DecodingResult::U16(_) | DecodingResult::F16(_) => 2,
        DecodingResult::U32(_) | DecodingResult::F32(_) => 4,
        _ => 8,
    });
    if bytes > MAX_LEVEL_BYTES {
        return Err(format!(
            "a level of {bytes} bytes exceeds the limit of {MAX_LEVEL_BYTES} bytes"
        ));
    }
    Ok(match chunk {
        DecodingResult::U8(_) => DecodingResult::U8(vec![0; len]),
        DecodingResult::U16(_) => DecodingResult::U16(vec![0; len]),
        DecodingResult::U32(_) => DecodingResult::U32(vec![0; len]),
        DecodingResult::F16(_) => DecodingResult::F16(vec![half::f16::ZERO; len]),
        DecodingResult::F32(_) => DecodingResult::F32(vec![0.0; len]),
        DecodingResult::F64(_) => DecodingResult::F64(vec![0.0; len]),
        _ => return Err(UNSUPPORTED_SAMPLES.to_string()),
    })
}

const UNSUPPORTED_SAMPLES: &str =
    "unsupported sample type (expected unsigned integer or floating point)";

/// What a stored sample becomes: colour (R, G, B or grey) or alpha.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Channel {
    Colour,
    Alpha,
}

/// Where the samples of one decoded level (or tile) are.
pub(crate) struct SampleLayout {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) channels: usize,
    /// All of channel 0, then all of channel 1, ... instead of interleaved texels.
    pub(crate) separate_planes: bool,
}

impl SampleLayout {
    /// RGBA texels, row-major, from the decoded samples `data` of a `width` x `height`
    /// region (a level or one tile).
    pub(crate) fn texels(
        &self,
        data: DecodingResult,
        color_space: ColorSpace,
    ) -> Result<Texels, String> {
        let srgb = color_space == ColorSpace::Srgb;
        let integer = |v: f32, role: Channel| {
            if srgb && role == Channel::Colour {
                srgb_to_linear(v)
            } else {
                v
            }
        };
        Ok(match data {
            // Bytes stay bytes: the colour space's table decodes them at fetch.
            DecodingResult::U8(v) => {
                Texels::bytes(self.assemble(v.len(), 255, |i, _| v[i])?, color_space)
            }
            DecodingResult::U16(v) => Texels::Float(self.assemble(v.len(), 1.0, |i, role| {
                integer((f64::from(v[i]) / 65535.0) as f32, role)
            })?),
            DecodingResult::U32(v) => Texels::Float(self.assemble(v.len(), 1.0, |i, role| {
                integer((f64::from(v[i]) / f64::from(u32::MAX)) as f32, role)
            })?),
            DecodingResult::F16(v) => {
                Texels::Half(self.assemble(v.len(), half::f16::ONE, |i, _| v[i])?)
            }
            DecodingResult::F32(v) => Texels::Float(self.assemble(v.len(), 1.0, |i, _| v[i])?),
            DecodingResult::F64(v) => {
                Texels::Float(self.assemble(v.len(), 1.0, |i, _| v[i] as f32)?)
            }
            _ => return Err(UNSUPPORTED_SAMPLES.to_string()),
        })
    }

    /// The role of channel `c`: the second of two, and the fourth of four or more, are alpha.
    fn role(&self, c: usize) -> Channel {
        match (self.channels, c) {
            (2, 1) | (4.., 3) => Channel::Alpha,
            _ => Channel::Colour,
        }
    }

    /// Builds RGBA texels from `count` decoded samples; `sample(i, role)` gives the value
    /// of sample `i` as stored (bytes, halves) or as linear f32, `one` is opaque alpha.
    fn assemble<T: Copy>(
        &self,
        count: usize,
        one: T,
        sample: impl Fn(usize, Channel) -> T,
    ) -> Result<Vec<[T; 4]>, String> {
        let (width, height, channels) = (self.width, self.height, self.channels);
        let texel_count = width as usize * height as usize;
        if channels == 0 || count != texel_count * channels {
            return Err(format!(
                "{width}x{height} with {channels} channels needs {} samples, the image holds {count}",
                texel_count * channels
            ));
        }
        let mut texels = Vec::new();
        texels
            .try_reserve_exact(texel_count)
            .map_err(|_| format!("not enough memory for {width}x{height} texels"))?;
        texels.extend((0..texel_count).map(|t| {
            let at = |c: usize| {
                let i = if self.separate_planes {
                    c * texel_count + t
                } else {
                    t * channels + c
                };
                sample(i, self.role(c))
            };
            match channels {
                1 => {
                    let g = at(0);
                    [g, g, g, one]
                }
                2 => {
                    let g = at(0);
                    [g, g, g, at(1)]
                }
                3 => [at(0), at(1), at(2), one],
                _ => [at(0), at(1), at(2), at(3)],
            }
        }));
        Ok(texels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tiff::encoder::{colortype, TiffEncoder};

    /// A strip-based multi-directory TIFF of 16-bit RGB levels 4x2, 2x1, 1x1, then a
    /// 3x3 page that is not part of the chain.
    fn three_levels_and_a_page() -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut out).unwrap();
        let l0: Vec<u16> = (0..4 * 2 * 3).map(|i| (i * 2000) as u16).collect();
        enc.write_image::<colortype::RGB16>(4, 2, &l0).unwrap();
        enc.write_image::<colortype::RGB16>(2, 1, &[65535; 6])
            .unwrap();
        enc.write_image::<colortype::RGB16>(1, 1, &[0, 32768, 65535])
            .unwrap();
        enc.write_image::<colortype::RGB16>(3, 3, &[7; 27]).unwrap();
        out.into_inner()
    }

    #[test]
    fn every_halving_directory_is_a_level_and_other_pages_are_not() {
        let bytes = three_levels_and_a_page();
        assert!(is_tiff(&bytes));
        let levels = decode(&bytes, "t.tif", ColorSpace::Linear).unwrap();
        let sizes: Vec<_> = levels.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(sizes, [(4, 2), (2, 1), (1, 1)]);
        assert_eq!(levels[0].texel(1, 1)[1], 16.0 * 2000.0 / 65535.0);
        assert_eq!(levels[2].texel(0, 0), [0.0, 32768.0 / 65535.0, 1.0, 1.0]);
    }

    #[test]
    fn integer_colour_is_srgb_decoded_on_request_and_alpha_never() {
        let mut out = Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut out).unwrap();
        enc.write_image::<colortype::RGBA8>(1, 1, &[188, 0, 255, 188])
            .unwrap();
        let bytes = out.into_inner();
        let srgb = decode(&bytes, "a.tif", ColorSpace::Srgb).unwrap();
        let t = srgb[0].texel(0, 0);
        assert!((t[0] - 0.5029).abs() < 1e-3, "{t:?}");
        assert_eq!((t[1], t[2], t[3]), (0.0, 1.0, 188.0 / 255.0));
        let linear = decode(&bytes, "a.tif", ColorSpace::Linear).unwrap();
        assert_eq!(linear[0].texel(0, 0)[0], 188.0 / 255.0);
    }

    #[test]
    fn float_grey_is_used_as_stored() {
        let mut out = Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut out).unwrap();
        enc.write_image::<colortype::Gray32Float>(2, 1, &[-0.5, 3.25])
            .unwrap();
        let levels = decode(out.get_ref(), "g.tif", ColorSpace::Srgb).unwrap();
        assert_eq!(levels[0].texel(1, 0), [3.25, 3.25, 3.25, 1.0]);
        assert_eq!(levels[0].texel(0, 0)[0], -0.5);
    }

    #[test]
    fn truncated_and_unsupported_files_are_errors_naming_the_file() {
        let bytes = three_levels_and_a_page();
        for cut in [4, 8, 20, bytes.len() / 2] {
            let e = decode(&bytes[..cut], "cut.tx", ColorSpace::Linear).unwrap_err();
            assert!(e.to_string().starts_with("cut.tx: "), "{e}");
        }
        let mut out = Cursor::new(Vec::new());
        let mut enc = TiffEncoder::new(&mut out).unwrap();
        enc.write_image::<colortype::GrayI16>(1, 1, &[-3]).unwrap();
        let e = decode(out.get_ref(), "signed.tif", ColorSpace::Linear).unwrap_err();
        assert!(e.to_string().starts_with("signed.tif: "), "{e}");
    }
}
