//! Decoding texture files into RGBA levels in the source's precision.
//!
//! PNG and JPEG (8 or 16 bit; grey, grey-alpha, RGB, RGBA) go through the `image`
//! crate; OpenEXR (half, float or uint channels) through the `exr` crate; TIFF,
//! including `maketx`'s tiled, mip-mapped `.tx`, through [`super::tiled_tiff`]. The
//! format is sniffed from the bytes, not the file name. Missing alpha is 1; grey is
//! copied to R, G and B. With [`ColorSpace::Srgb`] the colour channels of PNG/JPEG and
//! of integer TIFF are decoded from sRGB to linear; alpha, OpenEXR and floating-point
//! TIFF data are always used as stored. A mip-mapped OpenEXR or `.tx` (as `maketx`
//! writes) returns all its levels, finest first.
//!
//! Storage follows the source ([`Texels`]): 8-bit images keep their bytes (the sRGB
//! decoding is a table applied at fetch), OpenEXR whose channels are all half stays
//! half, everything else becomes f32.

use std::io::Cursor;

use exr::prelude::{FlatSamples, Levels, ReadChannels, ReadLayers};
use image::DynamicImage;

use super::mip_pyramid::MipLevel;
use super::texels::{try_texel_vec, Texels};
use super::{tiled_tiff, ColorSpace, TextureError};
use crate::srgb::srgb_to_linear;

/// The image formats textures are read from, told apart by their first 8 bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum ImageFormat {
    OpenExr,
    PngOrJpeg,
    Tiff,
}

/// The format of an image starting with `bytes` (8 are enough), if it is one we read.
pub(crate) fn sniff_format(bytes: &[u8]) -> Option<ImageFormat> {
    if bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        Some(ImageFormat::OpenExr)
    } else if bytes.starts_with(b"\x89PNG\r\n\x1a\n") || bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some(ImageFormat::PngOrJpeg)
    } else if tiled_tiff::is_tiff(bytes) {
        Some(ImageFormat::Tiff)
    } else {
        None
    }
}

/// Decodes `bytes` (PNG, JPEG, OpenEXR or TIFF) into one or more levels, finest first.
/// `color_space` is the one stated for the texture; `None` takes the one a TIFF records
/// (a `.tx` written by `conetrace maketx`), else sRGB.
pub(crate) fn decode(
    bytes: &[u8],
    label: &str,
    color_space: impl Into<Option<ColorSpace>>,
) -> Result<Vec<MipLevel>, TextureError> {
    let color_space = color_space.into();
    match sniff_format(bytes) {
        Some(ImageFormat::OpenExr) => decode_exr(bytes, label),
        Some(ImageFormat::PngOrJpeg) => {
            decode_png_jpeg(bytes, label, color_space.unwrap_or(ColorSpace::Srgb)).map(|l| vec![l])
        }
        Some(ImageFormat::Tiff) => tiled_tiff::decode(bytes, label, color_space),
        None => Err(TextureError::UnknownFormat {
            label: label.to_string(),
        }),
    }
}

fn dimensions_error(label: &str, message: String) -> TextureError {
    TextureError::Dimensions {
        label: label.to_string(),
        message,
    }
}

fn decode_png_jpeg(
    bytes: &[u8],
    label: &str,
    color_space: ColorSpace,
) -> Result<MipLevel, TextureError> {
    let decode_error = |e: image::ImageError| TextureError::Decode {
        label: label.to_string(),
        message: e.to_string(),
    };
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| decode_error(e.into()))?;
    // The decoder's own buffer is bounded like a TIFF level (the `image` crate's default,
    // 512 MiB, would refuse an ordinary 16k 8-bit texture); larger ones are refused with
    // an error, never an aborting allocation.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(tiled_tiff::MAX_LEVEL_BYTES);
    reader.limits(limits);
    let img = reader.decode().map_err(decode_error)?;
    let (w, h) = (img.width(), img.height());
    let count = w as usize * h as usize;
    // 8-bit images keep their bytes (decoded at fetch through the colour space's table).
    let bytes = |raw: &[u8], channels: usize, expand: fn(&[u8]) -> [u8; 4]| {
        let mut texels = try_texel_vec(count, label)?;
        texels.extend(raw.chunks_exact(channels).map(expand));
        Ok::<_, TextureError>(Texels::bytes(texels, color_space))
    };
    let texels = match &img {
        DynamicImage::ImageLuma8(b) => bytes(b.as_raw(), 1, |p| [p[0], p[0], p[0], 255])?,
        DynamicImage::ImageLumaA8(b) => bytes(b.as_raw(), 2, |p| [p[0], p[0], p[0], p[1]])?,
        DynamicImage::ImageRgb8(b) => bytes(b.as_raw(), 3, |p| [p[0], p[1], p[2], 255])?,
        DynamicImage::ImageRgba8(b) => bytes(b.as_raw(), 4, |p| [p[0], p[1], p[2], p[3]])?,
        _ => {
            let srgb = color_space == ColorSpace::Srgb;
            let decode = |v: u16| {
                let v = v as f32 / 65535.0;
                if srgb {
                    srgb_to_linear(v)
                } else {
                    v
                }
            };
            let mut texels = try_texel_vec(count, label)?;
            texels.extend(img.to_rgba16().pixels().map(|p| {
                [
                    decode(p[0]),
                    decode(p[1]),
                    decode(p[2]),
                    p[3] as f32 / 65535.0,
                ]
            }));
            Texels::Float(texels)
        }
    };
    MipLevel::with_texels(w, h, texels).map_err(|m| dimensions_error(label, m))
}

// Levels are indexed across the per-channel level lists, hence the index loop.
#[allow(clippy::needless_range_loop)]
fn decode_exr(bytes: &[u8], label: &str) -> Result<Vec<MipLevel>, TextureError> {
    let exr_error = |e: exr::error::Error| TextureError::Exr {
        label: label.to_string(),
        message: e.to_string(),
    };
    let image = exr::prelude::read()
        .no_deep_data()
        .all_resolution_levels()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(exr_error)?;
    let layer = &image.layer_data;
    let channels = &layer.channel_data.list;
    let find = |names: &[&str]| {
        channels.iter().position(|c| {
            let n = c.name.to_string();
            let short = n.rsplit('.').next().unwrap_or(&n).to_string();
            names.iter().any(|want| short.eq_ignore_ascii_case(want))
        })
    };
    let grey = find(&["Y", "L"]).or(if channels.len() == 1 { Some(0) } else { None });
    let sources: [Option<usize>; 4] = [
        find(&["R"]).or(grey),
        find(&["G"]).or(grey),
        find(&["B"]).or(grey),
        find(&["A"]),
    ];
    if sources[..3].iter().all(Option::is_none) {
        return Err(TextureError::Exr {
            label: label.to_string(),
            message: "no R, G, B or Y channel".to_string(),
        });
    }

    // Per channel, the list of levels (finest first).
    let level_lists: Vec<Vec<&FlatSamples>> = channels
        .iter()
        .map(|c| match &c.sample_data {
            Levels::Singular(s) => vec![s],
            Levels::Mip { level_data, .. } => level_data.iter().collect(),
            Levels::Rip { level_data, .. } => level_data.map_data.iter().take(1).collect(),
        })
        .collect();
    let n_levels = level_lists.iter().map(Vec::len).min().unwrap_or(0);
    let (mut w, mut h) = (layer.size.0, layer.size.1);
    let mut levels = Vec::with_capacity(n_levels);
    // Half channels stay half when every channel read is half; anything else is f32.
    let all_half = sources.iter().flatten().all(|&ci| {
        level_lists[ci]
            .iter()
            .all(|samples| matches!(samples, FlatSamples::F16(_)))
    });
    for li in 0..n_levels {
        let count = w * h;
        for src in sources.iter().flatten() {
            let samples = level_lists[*src][li];
            if samples.len() != count {
                if li == 0 {
                    return Err(dimensions_error(
                        label,
                        format!("channel has {} samples, expected {w}x{h}", samples.len()),
                    ));
                }
                // Level sizes not in the halving chain (e.g. rounded up): use level 0 only.
                return Ok(levels.into_iter().take(1).collect());
            }
        }
        let texels = if all_half {
            let one = half::f16::ONE;
            let mut texels = try_texel_vec(count, label)?;
            texels.resize(
                count,
                [half::f16::ZERO, half::f16::ZERO, half::f16::ZERO, one],
            );
            for (k, src) in sources.iter().enumerate() {
                let Some(ci) = *src else { continue };
                if let FlatSamples::F16(values) = level_lists[ci][li] {
                    for (t, v) in texels.iter_mut().zip(values) {
                        t[k] = *v;
                    }
                }
            }
            Texels::Half(texels)
        } else {
            let mut texels = try_texel_vec(count, label)?;
            texels.resize(count, [0.0f32, 0.0, 0.0, 1.0]);
            for (k, src) in sources.iter().enumerate() {
                let Some(ci) = *src else { continue };
                for (t, v) in texels.iter_mut().zip(level_lists[ci][li].values_as_f32()) {
                    t[k] = v;
                }
            }
            Texels::Float(texels)
        };
        let level = MipLevel::with_texels(w as u32, h as u32, texels)
            .map_err(|m| dimensions_error(label, m))?;
        levels.push(level);
        w = (w / 2).max(1);
        h = (h / 2).max(1);
    }
    if levels.is_empty() {
        return Err(dimensions_error(label, "no image data".to_string()));
    }
    Ok(levels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png_bytes(img: DynamicImage) -> Vec<u8> {
        let mut out = Cursor::new(Vec::new());
        img.write_to(&mut out, image::ImageFormat::Png).unwrap();
        out.into_inner()
    }

    #[test]
    fn grey_png_expands_to_rgba_and_decodes_srgb() {
        let grey = image::GrayImage::from_raw(2, 1, vec![0, 188]).unwrap();
        let bytes = png_bytes(DynamicImage::ImageLuma8(grey));
        let lin = decode(&bytes, "g.png", ColorSpace::Linear).unwrap();
        assert_eq!(
            lin[0].texel(1, 0),
            [188.0 / 255.0, 188.0 / 255.0, 188.0 / 255.0, 1.0]
        );
        let srgb = decode(&bytes, "g.png", ColorSpace::Srgb).unwrap();
        let v = srgb[0].texel(1, 0);
        assert!((v[0] - 0.5029).abs() < 1e-3 && v[3] == 1.0);
    }

    #[test]
    fn alpha_stays_linear_and_sixteen_bit_is_read() {
        let rgba = image::RgbaImage::from_raw(1, 1, vec![255, 0, 128, 128]).unwrap();
        let l = decode(
            &png_bytes(DynamicImage::ImageRgba8(rgba)),
            "a.png",
            ColorSpace::Srgb,
        )
        .unwrap();
        assert_eq!(l[0].texel(0, 0)[3], 128.0 / 255.0);
        assert_eq!(l[0].texel(0, 0)[0], 1.0);
        let rgb16 =
            image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(1, 1, vec![65535u16, 0, 32768])
                .unwrap();
        let l = decode(
            &png_bytes(DynamicImage::ImageRgb16(rgb16)),
            "b.png",
            ColorSpace::Linear,
        )
        .unwrap();
        let t = l[0].texel(0, 0);
        assert!((t[2] - 32768.0 / 65535.0).abs() < 1e-7 && t[3] == 1.0);
    }

    #[test]
    fn jpeg_is_decoded() {
        let grey = image::GrayImage::from_raw(8, 8, vec![200; 64]).unwrap();
        let mut out = Cursor::new(Vec::new());
        DynamicImage::ImageLuma8(grey)
            .write_to(&mut out, image::ImageFormat::Jpeg)
            .unwrap();
        let l = decode(out.get_ref(), "g.jpg", ColorSpace::Linear).unwrap();
        assert_eq!((l[0].width, l[0].height), (8, 8));
        let t = l[0].texel(3, 4);
        assert!(
            (t[0] - 200.0 / 255.0).abs() < 3.0 / 255.0 && t[3] == 1.0,
            "{t:?}"
        );
    }

    #[test]
    fn garbage_is_rejected_with_label() {
        let e = decode(b"hello", "junk.bin", ColorSpace::Linear).unwrap_err();
        assert!(e.to_string().contains("junk.bin"));
        let e = decode(b"\x89PNG\r\n\x1a\nbroken", "bad.png", ColorSpace::Linear).unwrap_err();
        assert!(e.to_string().starts_with("bad.png"));
    }
}
