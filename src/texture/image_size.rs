//! A texture file's size in texels, read from its header without decoding it, so the memory
//! a texture will take can be estimated before any of it is allocated.

use std::io::{BufReader, Cursor, Read, Seek};
use std::path::Path;

use super::TextureError;

/// Width and height of level 0 of the image in `reader` (PNG, JPEG, OpenEXR or TIFF, sniffed
/// from the first bytes). `label` names the source in errors.
fn image_size<R: Read + Seek + std::io::BufRead>(
    mut reader: R,
    label: &str,
) -> Result<(u32, u32), TextureError> {
    let bad = |message: String| TextureError::Dimensions {
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
    let magic = &magic[..read];
    if magic.starts_with(&[0x76, 0x2f, 0x31, 0x01]) {
        let meta = exr::meta::MetaData::read_from_buffered(reader, false)
            .map_err(|e| bad(format!("OpenEXR header: {e}")))?;
        let header = meta
            .headers
            .first()
            .ok_or_else(|| bad("OpenEXR file without a header".into()))?;
        let size = header.layer_size;
        Ok((size.0 as u32, size.1 as u32))
    } else if magic.starts_with(b"II*\0") || magic.starts_with(b"MM\0*") {
        let mut decoder =
            tiff::decoder::Decoder::new(reader).map_err(|e| bad(format!("TIFF header: {e}")))?;
        decoder
            .dimensions()
            .map_err(|e| bad(format!("TIFF header: {e}")))
    } else {
        image::ImageReader::new(reader)
            .with_guessed_format()
            .map_err(|e| bad(format!("cannot read the header: {e}")))?
            .into_dimensions()
            .map_err(|e| bad(format!("image header: {e}")))
    }
}

/// Level-0 size of the texture file at `path`, from its header.
pub fn file_image_size(path: &Path) -> Result<(u32, u32), TextureError> {
    let label = path.display().to_string();
    let file = std::fs::File::open(path).map_err(|source| TextureError::Io {
        label: label.clone(),
        source,
    })?;
    image_size(BufReader::new(file), &label)
}

/// Level-0 size of encoded texture bytes, from their header.
pub fn encoded_image_size(bytes: &[u8], label: &str) -> Result<(u32, u32), TextureError> {
    image_size(Cursor::new(bytes), label)
}

/// Bytes a decoded texture of level-0 size `width` x `height` takes with its mip levels:
/// four f32 channels per texel, the pyramid adding at most a third.
pub fn decoded_texture_bytes(width: u32, height: u32) -> u64 {
    let level0 = u64::from(width) * u64::from(height) * 16;
    level0 + level0.div_ceil(3)
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
    fn decoded_bytes_bound_the_real_pyramid() {
        let texture =
            crate::texture::Texture::from_rgba_f32(37, 21, vec![[0.5; 4]; 37 * 21]).unwrap();
        let estimate = decoded_texture_bytes(37, 21);
        let real = texture.memory_bytes() as u64;
        assert!(
            estimate >= real && estimate <= real * 11 / 10,
            "{estimate} vs {real}"
        );
    }
}
