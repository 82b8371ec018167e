//! Reading a tiled, mip-mapped TIFF (`maketx`'s `.tx`) one tile at a time, so that a
//! texture cache can read the tiles its lookups touch instead of decoding every level
//! before the first ray.
//!
//! A file qualifies when its levels form a complete chain down to 1x1 and every level is
//! cut in [`TEXTURE_TILE_SIZE`] tiles with interleaved samples, which is what `maketx`
//! writes by default. A tile read here then holds exactly the texels of that tile in the
//! level's tile order (see `tile_layout`): the same values, in the same precision, as the
//! whole-level read of `tiled_tiff` puts there. Other files (strips, other tile sizes,
//! separate planes) are decoded whole by `tiled_tiff`.

use std::io::{Read, Seek};

use tiff::decoder::{ChunkType, Decoder};

use super::texels::Texels;
use super::tile_layout::TileLayout;
use super::tiled_tiff::{color_space_of, DirectoryFormat, SampleLayout};
use super::tiles::TEXTURE_TILE_SIZE;
use super::{ColorSpace, TextureError};

/// The size and samples of one stored level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct StoredLevel {
    width: u32,
    height: u32,
    channels: usize,
}

/// A `.tx` file opened for reading single tiles.
pub(crate) struct TiffTileReader<R: Read + Seek> {
    label: String,
    color_space: ColorSpace,
    decoder: Decoder<R>,
    levels: Vec<StoredLevel>,
    /// Per level, the bytes each tile takes in the file (empty when the file does not
    /// say).
    tile_bytes: Vec<Vec<u64>>,
    /// Per level, where each tile starts in the file.
    tile_offsets: Vec<Vec<u64>>,
    /// The directory (level) the decoder is positioned at.
    directory: usize,
}

impl<R: Read + Seek> TiffTileReader<R> {
    /// Reads the headers of every level of `source` (a TIFF); `Ok(None)` when the file
    /// does not qualify for tile-by-tile reading (see the module documentation).
    /// `label` names the file in errors; tiles are decoded in `color_space`, or when `None`
    /// in the one the file records (`tiled_tiff::color_space_of`).
    pub(crate) fn open(
        source: R,
        label: &str,
        color_space: impl Into<Option<ColorSpace>>,
    ) -> Result<Option<Self>, TextureError> {
        let tiff_error = |message: String| TextureError::Tiff {
            label: label.to_string(),
            message,
        };
        let mut decoder = Decoder::new(source).map_err(|e| tiff_error(e.to_string()))?;
        let color_space = color_space_of(color_space.into(), &mut decoder);
        let mut levels: Vec<StoredLevel> = Vec::new();
        let mut tile_bytes = Vec::new();
        let mut tile_offsets = Vec::new();
        loop {
            let format = DirectoryFormat::read(&mut decoder)
                .map_err(|m| tiff_error(format!("level {}: {m}", levels.len())))?;
            let tiled = decoder.get_chunk_type() == ChunkType::Tile
                && decoder.chunk_dimensions() == (TEXTURE_TILE_SIZE, TEXTURE_TILE_SIZE);
            if !tiled || format.separate_planes {
                return Ok(None);
            }
            if let Some(previous) = levels.last() {
                let halved = ((previous.width / 2).max(1), (previous.height / 2).max(1));
                if (format.width, format.height) != halved {
                    // Another page of a multi-page TIFF: the chain ended before 1x1.
                    break;
                }
            }
            levels.push(StoredLevel {
                width: format.width,
                height: format.height,
                channels: format.channels,
            });
            tile_bytes.push(
                decoder
                    .get_tag_u64_vec(tiff::tags::Tag::TileByteCounts)
                    .unwrap_or_default(),
            );
            tile_offsets.push(
                decoder
                    .get_tag_u64_vec(tiff::tags::Tag::TileOffsets)
                    .unwrap_or_default(),
            );
            if !decoder.more_images() || (format.width, format.height) == (1, 1) {
                break;
            }
            decoder
                .next_image()
                .map_err(|e| tiff_error(format!("directory {}: {e}", levels.len())))?;
        }
        let complete = levels.last().is_some_and(|l| (l.width, l.height) == (1, 1));
        if !complete {
            return Ok(None);
        }
        let directory = levels.len() - 1;
        Ok(Some(TiffTileReader {
            label: label.to_string(),
            color_space,
            decoder,
            levels,
            tile_bytes,
            tile_offsets,
            directory,
        }))
    }

    /// (width, height) of every stored level, finest first.
    pub(crate) fn level_sizes(&self) -> Vec<(u32, u32)> {
        self.levels.iter().map(|l| (l.width, l.height)).collect()
    }

    /// The file's layout as numbers: per level its size and channels, then every tile's
    /// offset and byte count. Any change to a level's stored tiles that moves or resizes
    /// one changes it; read from the headers alone.
    pub(crate) fn layout_words(&self) -> Vec<u64> {
        let mut words = Vec::new();
        for (level, stored) in self.levels.iter().enumerate() {
            words.extend([
                u64::from(stored.width),
                u64::from(stored.height),
                stored.channels as u64,
            ]);
            for table in [&self.tile_offsets[level], &self.tile_bytes[level]] {
                words.push(table.len() as u64);
                words.extend_from_slice(table);
            }
        }
        words
    }

    /// Bytes tile `index` (row-major over the level's tiles) of `level` takes in the file;
    /// 0 when the file does not say.
    pub(crate) fn stored_bytes(&self, level: usize, index: usize) -> u64 {
        self.tile_bytes
            .get(level)
            .and_then(|counts| counts.get(index))
            .copied()
            .unwrap_or(0)
    }

    /// The texels of tile (`tile_x`, `tile_y`) of `level`, in the level's tile order.
    /// A tile that cannot be read is an error naming the file, the level and the tile.
    pub(crate) fn read_tile(
        &mut self,
        level: usize,
        tile_x: usize,
        tile_y: usize,
    ) -> Result<Texels, TextureError> {
        let tile_error = |message: String| TextureError::Tile {
            label: self.label.clone(),
            level,
            tile_x,
            tile_y,
            message,
        };
        let stored = *self
            .levels
            .get(level)
            .ok_or_else(|| tile_error(format!("the file has {} levels", self.levels.len())))?;
        let tiles = TileLayout::new(stored.width, stored.height);
        if tile_x >= tiles.tiles_x() || tile_y >= tiles.tiles_y() {
            return Err(tile_error(format!(
                "the level has {}x{} tiles",
                tiles.tiles_x(),
                tiles.tiles_y()
            )));
        }
        if self.directory != level {
            self.decoder
                .seek_to_image(level)
                .map_err(|e| tile_error(e.to_string()))?;
            self.directory = level;
        }
        let chunk = u32::try_from(tile_y * tiles.tiles_x() + tile_x)
            .map_err(|_| tile_error("too many tiles".to_string()))?;
        let data = self
            .decoder
            .read_chunk(chunk)
            .map_err(|e| tile_error(e.to_string()))?;
        let samples = SampleLayout {
            width: tiles.tile_width(tile_x) as u32,
            height: tiles.tile_height(tile_y) as u32,
            channels: stored.channels,
            separate_planes: false,
        };
        samples.texels(data, self.color_space).map_err(tile_error)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use std::fs::File;
    use std::io::{BufReader, Cursor};
    use std::path::{Path, PathBuf};
    use std::process::Command;

    use super::*;
    use crate::texture::image_load;

    /// A `width` x `height` RGB noise PNG turned into a `.tx` by `maketx` (which must be
    /// installed: scripts/setup.sh) with `extra` arguments.
    pub(crate) fn maketx(dir: &Path, width: u32, height: u32, extra: &[&str]) -> PathBuf {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let image = image::RgbImage::from_fn(width, height, |_, _| {
            image::Rgb(std::array::from_fn(|_| {
                (crate::test_rng::xorshift64_star(&mut state) >> 56) as u8
            }))
        });
        let png = dir.join("noise.png");
        image.save(&png).unwrap();
        let tx = dir.join("noise.tx");
        let status = Command::new("maketx")
            .arg(&png)
            .arg("-o")
            .arg(&tx)
            .args(extra)
            .status()
            .expect("maketx must be installed (scripts/setup.sh)");
        assert!(status.success(), "maketx failed");
        tx
    }

    fn open(path: &Path) -> Option<TiffTileReader<BufReader<File>>> {
        let file = BufReader::new(File::open(path).unwrap());
        TiffTileReader::open(file, "noise.tx", ColorSpace::Srgb).unwrap()
    }

    #[test]
    fn every_tile_holds_the_texels_of_the_whole_level_read() {
        let dir = tempfile::tempdir().unwrap();
        let tx = maketx(dir.path(), 200, 130, &[]);
        let whole =
            image_load::decode(&std::fs::read(&tx).unwrap(), "noise.tx", ColorSpace::Srgb).unwrap();
        let mut reader = open(&tx).expect("a default maketx file is read tile by tile");
        let sizes: Vec<(u32, u32)> = whole.iter().map(|l| (l.width, l.height)).collect();
        assert_eq!(reader.level_sizes(), sizes);
        // Levels out of order, so the reader moves between directories both ways.
        for level in (0..whole.len()).rev().chain(0..whole.len()) {
            let stored = &whole[level];
            let tiles = stored.layout();
            for tile_y in 0..tiles.tiles_y() {
                for tile_x in 0..tiles.tiles_x() {
                    let tile = reader.read_tile(level, tile_x, tile_y).unwrap();
                    let start = tiles.tile_start(tile_x, tile_y);
                    for (k, expected) in (start..start + tile.len()).enumerate() {
                        assert_eq!(tile.get(k), stored.texels.get(expected));
                    }
                    assert_eq!(tile.bytes_per_texel(), stored.texels.bytes_per_texel());
                }
            }
        }
        let e = reader.read_tile(0, 4, 0).unwrap_err().to_string();
        assert!(e.starts_with("noise.tx: level 0, tile (4, 0): "), "{e}");
    }

    #[test]
    fn other_tile_sizes_and_separate_planes_are_decoded_whole() {
        let dir = tempfile::tempdir().unwrap();
        let tx = maketx(dir.path(), 100, 100, &["--tile", "32", "32"]);
        assert!(open(&tx).is_none());
        let tx = maketx(dir.path(), 100, 100, &["--separate"]);
        assert!(open(&tx).is_none());
        // A strip TIFF, not mip-mapped.
        let mut out = Cursor::new(Vec::new());
        tiff::encoder::TiffEncoder::new(&mut out)
            .unwrap()
            .write_image::<tiff::encoder::colortype::RGB8>(2, 2, &[0; 12])
            .unwrap();
        out.set_position(0);
        assert!(TiffTileReader::open(out, "strips.tif", ColorSpace::Srgb)
            .unwrap()
            .is_none());
    }

    #[test]
    fn a_damaged_tile_is_an_error_naming_file_level_and_tile() {
        let dir = tempfile::tempdir().unwrap();
        let tx = maketx(dir.path(), 256, 256, &[]);
        // Overwrite the compressed bytes of tile (2, 1) of level 0 (chunk 1 * 4 + 2).
        let mut bytes = std::fs::read(&tx).unwrap();
        let (offset, length) = {
            let mut decoder = Decoder::new(Cursor::new(&bytes)).unwrap();
            let offsets = decoder
                .get_tag_u64_vec(tiff::tags::Tag::TileOffsets)
                .unwrap();
            let counts = decoder
                .get_tag_u64_vec(tiff::tags::Tag::TileByteCounts)
                .unwrap();
            (offsets[6] as usize, counts[6] as usize)
        };
        bytes[offset..offset + length].fill(0xff);
        std::fs::write(&tx, &bytes).unwrap();
        let mut reader = open(&tx).unwrap();
        assert!(reader.read_tile(0, 1, 1).is_ok());
        let e = reader.read_tile(0, 2, 1).unwrap_err().to_string();
        assert!(e.starts_with("noise.tx: level 0, tile (2, 1): "), "{e}");
    }
}
