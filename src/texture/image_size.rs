//! A texture file's size in texels and its sample type, read from its header without
//! decoding it, so the memory a texture will take can be estimated before any of it is
//! allocated. The estimate follows the storage of [`super::Texels`]: 4 bytes per texel for
//! 8-bit sources, 8 for half-float ones, 16 for everything else, over every mip level.

use std::io::{BufReader, Cursor, Read, Seek};
use std::path::Path;

use super::image_load::{sniff_format, ImageFormat};
use super::TextureError;

/// What a texture file's header says about its decoded storage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureHeader {
    /// Width of level 0 in texels.
    pub width: u32,
    /// Height of level 0 in texels.
    pub height: u32,
    /// Bytes a decoded texel takes: 4 (8-bit samples), 8 (half) or 16 (anything else).
    pub bytes_per_texel: u64,
}

/// Bytes per stored texel for 8-bit, half-float and other samples.
const BYTE_TEXEL: u64 = 4;
const HALF_TEXEL: u64 = 8;
const FLOAT_TEXEL: u64 = 16;

/// The header of the image in `reader` (PNG, JPEG, OpenEXR or TIFF, sniffed from the
/// first bytes). `label` names the source in errors.
fn image_header<R: Read + Seek + std::io::BufRead>(
    mut reader: R,
    label: &str,
) -> Result<TextureHeader, TextureError> {
    // A header that cannot be read is an image that cannot be decoded, whatever the
    // reader's complaint (it is not a question of dimensions).
    let bad = |message: String| TextureError::Decode {
        label: label.to_string(),
        message,
    };
    let mut magic = [0u8; 8];
    let read = reader
        .read(&mut magic)
        .map_err(|e| bad(format!("cannot read the header: {e}")))?;
    reader
        .rewind()
        .map_err(|e| bad(format!("cannot read the header: {e}")))?;
    let format = sniff_format(&magic[..read]).ok_or_else(|| TextureError::UnknownFormat {
        label: label.to_string(),
    })?;
    if format == ImageFormat::OpenExr {
        let meta = exr::meta::MetaData::read_from_buffered(reader, false)
            .map_err(|e| bad(format!("OpenEXR header: {e}")))?;
        let header = meta
            .headers
            .first()
            .ok_or_else(|| bad("OpenEXR file without a header".into()))?;
        let size = header.layer_size;
        let all_half = header
            .channels
            .list
            .iter()
            .all(|c| c.sample_type == exr::meta::attribute::SampleType::F16);
        Ok(TextureHeader {
            width: size.0 as u32,
            height: size.1 as u32,
            bytes_per_texel: if all_half { HALF_TEXEL } else { FLOAT_TEXEL },
        })
    } else if format == ImageFormat::Tiff {
        let mut decoder =
            tiff::decoder::Decoder::new(reader).map_err(|e| bad(format!("TIFF header: {e}")))?;
        let tiff_bad = |e: tiff::TiffError| bad(format!("TIFF header: {e}"));
        let (width, height) = decoder.dimensions().map_err(tiff_bad)?;
        let bits = match decoder.colortype().map_err(tiff_bad)? {
            tiff::ColorType::Gray(b)
            | tiff::ColorType::GrayA(b)
            | tiff::ColorType::RGB(b)
            | tiff::ColorType::RGBA(b) => b,
            tiff::ColorType::Multiband { bit_depth, .. } => bit_depth,
            _ => 32,
        };
        // SampleFormat 3 is IEEE floating point. libtiff (and so OpenImageIO and maketx)
        // writes one value per channel, other writers a single one.
        let sample_formats = match decoder
            .find_tag(tiff::tags::Tag::SampleFormat)
            .map_err(tiff_bad)?
        {
            Some(value) => value.into_u16_vec().map_err(tiff_bad)?,
            None => Vec::new(),
        };
        let float = sample_formats.first() == Some(&3);
        let bytes_per_texel = match (bits, float) {
            (8, false) => BYTE_TEXEL,
            (16, true) => HALF_TEXEL,
            _ => FLOAT_TEXEL,
        };
        Ok(TextureHeader {
            width,
            height,
            bytes_per_texel,
        })
    } else {
        use image::ImageDecoder;
        let decoder = image::ImageReader::new(reader)
            .with_guessed_format()
            .map_err(|e| bad(format!("cannot read the header: {e}")))?
            .into_decoder()
            .map_err(|e| bad(format!("image header: {e}")))?;
        let (width, height) = decoder.dimensions();
        let colour = decoder.color_type();
        let eight_bit = colour.bytes_per_pixel() == colour.channel_count();
        Ok(TextureHeader {
            width,
            height,
            bytes_per_texel: if eight_bit { BYTE_TEXEL } else { FLOAT_TEXEL },
        })
    }
}

/// The header of the texture file at `path`.
pub fn file_texture_header(path: &Path) -> Result<TextureHeader, TextureError> {
    let label = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|source| TextureError::Io {
        label: label.clone(),
        source,
    })?;
    image_header(BufReader::new(file), &label)
}

/// The header of encoded texture bytes.
pub fn encoded_texture_header(bytes: &[u8], label: &str) -> Result<TextureHeader, TextureError> {
    image_header(Cursor::new(bytes), label)
}

/// Level-0 size of the texture file at `path`, from its header.
pub fn file_image_size(path: &Path) -> Result<(u32, u32), TextureError> {
    file_texture_header(path).map(|h| (h.width, h.height))
}

/// Level-0 size of encoded texture bytes, from their header.
pub fn encoded_image_size(bytes: &[u8], label: &str) -> Result<(u32, u32), TextureError> {
    encoded_texture_header(bytes, label).map(|h| (h.width, h.height))
}

impl TextureHeader {
    /// Bytes the decoded texture takes with all its mip levels: every level of the
    /// halving chain (integer division, minimum 1, down to 1x1) at `bytes_per_texel`.
    pub fn decoded_bytes(&self) -> u64 {
        let (mut w, mut h) = (u64::from(self.width), u64::from(self.height));
        let mut texels = w * h;
        while w > 1 || h > 1 {
            w = (w / 2).max(1);
            h = (h / 2).max(1);
            texels += w * h;
        }
        texels.saturating_mul(self.bytes_per_texel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_come_from_headers_of_every_format() {
        let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures");
        let png = file_image_size(&assets.join("checker.png")).unwrap();
        let decoded = crate::texture::Texture::from_file(
            &assets.join("checker.png"),
            crate::texture::ColorSpace::Srgb,
        )
        .unwrap();
        assert_eq!(png, (decoded.width(), decoded.height()));
        let exr = file_image_size(&assets.join("miplevels.exr")).unwrap();
        let decoded = crate::texture::Texture::from_file(
            &assets.join("miplevels.exr"),
            crate::texture::ColorSpace::Linear,
        )
        .unwrap();
        assert_eq!(exr, (decoded.width(), decoded.height()));
        assert!(encoded_image_size(b"not an image", "x").is_err());
    }

    #[test]
    fn decoded_bytes_equal_the_real_pyramid() {
        let texture =
            crate::texture::Texture::from_rgba_f32(37, 21, vec![[0.5; 4]; 37 * 21]).unwrap();
        let header = TextureHeader {
            width: 37,
            height: 21,
            bytes_per_texel: FLOAT_TEXEL,
        };
        assert_eq!(header.decoded_bytes(), texture.memory_bytes() as u64);
        // A thin texture's levels add up to almost twice level 0, not a third.
        let thin = TextureHeader {
            width: 1024,
            height: 1,
            bytes_per_texel: BYTE_TEXEL,
        };
        assert_eq!(thin.decoded_bytes(), 2047 * 4);
    }

    #[test]
    fn headers_give_the_stored_precision() {
        let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures");
        for (name, space) in [
            ("checker.png", crate::texture::ColorSpace::Srgb),
            ("miplevels.exr", crate::texture::ColorSpace::Linear),
        ] {
            let header = file_texture_header(&assets.join(name)).unwrap();
            let decoded = crate::texture::Texture::from_file(&assets.join(name), space).unwrap();
            assert_eq!(
                header.decoded_bytes(),
                decoded.memory_bytes() as u64,
                "{name}: {header:?}"
            );
        }
        let png = file_texture_header(&assets.join("checker.png")).unwrap();
        assert_eq!(png.bytes_per_texel, BYTE_TEXEL);
    }
}
