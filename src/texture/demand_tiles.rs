//! Mip levels read from their file one tile at a time, when a lookup first touches the
//! tile, as OpenImageIO's ImageCache reads `.tx` files: start-up time and memory follow
//! what the image needs, not the size of the textures.
//!
//! A [`DemandFile`] owns the open file and its tile reader; each [`DemandLevel`] keeps one
//! slot per tile, filled once. A lookup finds a tile already read with one atomic load
//! and no lock; the reader's lock is taken only to read a missing tile. Tiles stay until
//! the texture is dropped.
//!
//! A tile that cannot be read never becomes black texels in an image: the first failure
//! is kept on the file, lookups needing the tile return zero, and the render that made
//! them is refused with the failure, which names the file, the level and the tile (see
//! `Texture::tile_failure`).

use std::fmt;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use glam::Vec4;

use super::image_load::{sniff_format, ImageFormat};
use super::mip_pyramid::{MipLevel, MipPyramid};
use super::texels::{FlatTexels, TexelSource, Texels};
use super::tiff_tile_reader::TiffTileReader;
use super::tile_layout::TileLayout;
use super::tiles::TEXTURE_TILE_SIZE;
use super::{ColorSpace, TextureError, CHANNEL_NAMES};

/// The open file of a demand-loaded texture, shared by its levels.
pub(crate) struct DemandFile {
    label: String,
    reader: Mutex<TiffTileReader<BufReader<File>>>,
    /// The first tile that could not be read, as its error message.
    failure: OnceLock<String>,
    tiles_read: AtomicU64,
    tiles_in_file: u64,
}

impl fmt::Debug for DemandFile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "DemandFile({}: {} of {} tiles read)",
            self.label,
            self.tiles_read(),
            self.tiles_in_file
        )
    }
}

impl DemandFile {
    /// The message of the first tile that could not be read.
    pub(crate) fn failure(&self) -> Option<&str> {
        self.failure.get().map(String::as_str)
    }

    /// Tiles read from the file so far.
    pub(crate) fn tiles_read(&self) -> u64 {
        self.tiles_read.load(Ordering::Relaxed)
    }

    /// Tiles the file holds over all levels.
    pub(crate) fn tiles_in_file(&self) -> u64 {
        self.tiles_in_file
    }
}

/// One level of a demand-loaded texture.
pub struct DemandLevel {
    file: Arc<DemandFile>,
    level: usize,
    layout: TileLayout,
    tiles_x: usize,
    texel_count: usize,
    /// No texels, of the storage kind every tile of the level has.
    kind: Texels,
    tiles: Box<[OnceLock<Texels>]>,
}

impl fmt::Debug for DemandLevel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "DemandLevel({}, level {}, {} texels)",
            self.file.label, self.level, self.texel_count
        )
    }
}

/// The levels of the tiled, mip-mapped TIFF at `path`, each read tile by tile on demand,
/// and the file they share; `Ok(None)` when the file is not such a TIFF (it is then
/// decoded whole). `label` names the file in errors.
pub(crate) fn open(
    path: &Path,
    label: &str,
    color_space: ColorSpace,
) -> Result<Option<(MipPyramid, Arc<DemandFile>)>, TextureError> {
    let io_error = |source| TextureError::Io {
        label: label.to_string(),
        source,
    };
    let mut file = File::open(path).map_err(io_error)?;
    let mut signature = [0u8; 8];
    let read = file.read(&mut signature).map_err(io_error)?;
    if sniff_format(&signature[..read]) != Some(ImageFormat::Tiff) {
        return Ok(None);
    }
    let file = File::open(path).map_err(io_error)?;
    let Some(mut reader) = TiffTileReader::open(BufReader::new(file), label, color_space)? else {
        return Ok(None);
    };
    let sizes = reader.level_sizes();
    // The coarsest level's single tile tells the storage kind the levels share.
    let coarsest = sizes.len() - 1;
    let coarsest_tile = reader.read_tile(coarsest, 0, 0)?;
    let kind = coarsest_tile.same_kind_from(&[], label)?;
    let tiles_in_file = sizes
        .iter()
        .map(|&(w, h)| {
            let layout = TileLayout::new(w, h);
            (layout.tiles_x() * layout.tiles_y()) as u64
        })
        .sum();
    let file = Arc::new(DemandFile {
        label: label.to_string(),
        reader: Mutex::new(reader),
        failure: OnceLock::new(),
        tiles_read: AtomicU64::new(0),
        tiles_in_file,
    });
    let levels: Vec<MipLevel> = sizes
        .iter()
        .enumerate()
        .map(|(level, &(width, height))| {
            let layout = TileLayout::new(width, height);
            let tiles = (0..layout.tiles_x() * layout.tiles_y())
                .map(|_| OnceLock::new())
                .collect();
            let demand = DemandLevel {
                file: file.clone(),
                level,
                layout,
                tiles_x: layout.tiles_x(),
                texel_count: width as usize * height as usize,
                kind: kind.clone(),
                tiles,
            };
            MipLevel {
                width,
                height,
                texels: Texels::OnDemand(Arc::new(demand)),
            }
        })
        .collect();
    if let Some(Texels::OnDemand(last)) = levels.last().map(|l| &l.texels) {
        let tile = last.checked(coarsest_tile, 0, 0)?;
        let _ = last.tiles[0].set(tile);
        file.tiles_read.fetch_add(1, Ordering::Relaxed);
    }
    Ok(Some((MipPyramid::from_levels(levels), file)))
}

impl DemandLevel {
    /// Number of texels of the level.
    pub(crate) fn texel_count(&self) -> usize {
        self.texel_count
    }

    /// No texels, of the level's storage kind.
    pub(crate) fn kind(&self) -> &Texels {
        &self.kind
    }

    /// Bytes of the tiles read so far.
    pub(crate) fn resident_bytes(&self) -> usize {
        self.tiles
            .iter()
            .filter_map(OnceLock::get)
            .map(Texels::memory_bytes)
            .sum()
    }

    /// Linear RGBA of the texel at `index` in tile order (zero when its tile cannot be
    /// read).
    pub(crate) fn texel_at_index(&self, index: usize) -> Vec4 {
        let (x, y) = self.layout.coordinates_of(index);
        DemandTexels(self).texel_at(self.layout, x, y)
    }

    /// Tile (`tile_x`, `tile_y`), read from the file if this is its first use; `None`
    /// when it cannot be read.
    #[inline(always)]
    fn tile(&self, tile_x: usize, tile_y: usize) -> Option<&Texels> {
        let slot = self.tiles.get(tile_y * self.tiles_x + tile_x)?;
        match slot.get() {
            Some(tile) => Some(tile),
            None => self.read(slot, tile_x, tile_y),
        }
    }

    /// Reads a missing tile into `slot` (once, whichever thread gets the reader first).
    #[cold]
    #[inline(never)]
    fn read<'s>(
        &'s self,
        slot: &'s OnceLock<Texels>,
        tile_x: usize,
        tile_y: usize,
    ) -> Option<&'s Texels> {
        if self.file.failure.get().is_some() {
            return None;
        }
        let mut reader = self
            .file
            .reader
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if let Some(tile) = slot.get() {
            return Some(tile);
        }
        let read = reader
            .read_tile(self.level, tile_x, tile_y)
            .and_then(|tile| self.checked(tile, tile_x, tile_y));
        match read {
            Ok(tile) => {
                self.file.tiles_read.fetch_add(1, Ordering::Relaxed);
                Some(slot.get_or_init(|| tile))
            }
            Err(error) => {
                let _ = self.file.failure.set(error.to_string());
                None
            }
        }
    }

    /// `tile` if it has the level's storage kind and size and holds only finite values
    /// (what a whole-level read checks on load).
    fn checked(&self, tile: Texels, tile_x: usize, tile_y: usize) -> Result<Texels, TextureError> {
        let (width, height) = (
            self.layout.tile_width(tile_x),
            self.layout.tile_height(tile_y),
        );
        let error = |message: String| TextureError::Tile {
            label: self.file.label.clone(),
            level: self.level,
            tile_x,
            tile_y,
            message,
        };
        if std::mem::discriminant(&tile) != std::mem::discriminant(&self.kind)
            || tile.len() != width * height
        {
            return Err(error(format!(
                "holds {} texels of {} bytes, expected {} of {} bytes",
                tile.len(),
                tile.bytes_per_texel(),
                width * height,
                self.kind.bytes_per_texel()
            )));
        }
        if !matches!(tile, Texels::Byte { .. }) {
            for index in 0..tile.len() {
                let texel = tile.get(index).to_array();
                if let Some(channel) = texel.iter().position(|v| !v.is_finite()) {
                    return Err(error(format!(
                        "texel ({}, {}) has {} = {}; a texture must hold finite values",
                        tile_x * TEXTURE_TILE_SIZE as usize + index % width,
                        tile_y * TEXTURE_TILE_SIZE as usize + index / width,
                        CHANNEL_NAMES[channel],
                        texel[channel]
                    )));
                }
            }
        }
        Ok(tile)
    }
}

/// The filters' view of a demand-loaded level.
#[derive(Clone, Copy)]
pub(crate) struct DemandTexels<'a>(&'a DemandLevel);

impl<'a> DemandTexels<'a> {
    #[inline(always)]
    pub(crate) fn new(level: &'a DemandLevel) -> Self {
        DemandTexels(level)
    }
}

impl<'a> TexelSource<'a> for DemandTexels<'a> {
    type Tile = TileTexels<'a>;

    #[inline(always)]
    fn view(texels: &'a Texels) -> Option<Self> {
        match texels {
            Texels::OnDemand(level) => Some(DemandTexels(level)),
            _ => None,
        }
    }

    #[inline(always)]
    fn tile(
        self,
        _layout: TileLayout,
        tile_x: usize,
        tile_y: usize,
    ) -> Option<(TileTexels<'a>, usize)> {
        self.0
            .tile(tile_x, tile_y)
            .map(|tile| (TileTexels(tile), 0))
    }
}

/// The texels of one tile read from a file (a resident kind, picked per fetch).
#[derive(Clone, Copy)]
pub(crate) struct TileTexels<'a>(&'a Texels);

impl<'a> FlatTexels<'a> for TileTexels<'a> {
    #[inline(always)]
    fn view(texels: &'a Texels) -> Option<Self> {
        Some(TileTexels(texels))
    }

    #[inline(always)]
    fn texel(self, index: usize) -> Vec4 {
        self.0.get(index)
    }

    #[inline(always)]
    fn bilinear_quad<R>(
        self,
        k: usize,
        row: usize,
        blend: impl FnOnce(Vec4, Vec4, Vec4, Vec4) -> R,
    ) -> Option<R> {
        self.0.quad(k, row, blend)
    }
}
