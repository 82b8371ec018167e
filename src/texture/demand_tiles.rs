//! Mip levels read from their file one tile at a time, when a lookup first touches the
//! tile, as OpenImageIO's ImageCache reads `.tx` files: start-up time and memory follow
//! what the image needs, not the size of the textures.
//!
//! A [`DemandFile`] owns the open file, its tile reader and the [`TileCache`] its tiles
//! live in; each [`DemandLevel`] keeps one cache slot per tile. A fetch goes through the
//! thread's micro-cache (`micro_cache`), then the tile's slot, and only then takes the
//! reader's lock to read the tile, which the cache admits under its cap (evicting others).
//! A tile evicted and touched again is read again: the same texels.
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

use super::aniso_lanes::{Lanes, ProbeBlocks, PROBE_LANES};
use super::image_load::{sniff_format, ImageFormat};
use super::micro_cache::{self, FetchedTile, ThreadTiles};
use super::mip_pyramid::{MipLevel, MipPyramid};
use super::texels::{ByteTexels, FloatTexels, HalfTexels, TexelSource, Texels, TileWork};
use super::tiff_tile_reader::TiffTileReader;
use super::tile_cache::{FileTally, LevelTiles, TextureCacheStats, TileCache};
use super::tile_layout::TileLayout;
use super::tiles::TEXTURE_TILE_SIZE;
use super::{ColorSpace, TextureError, CHANNEL_NAMES};

/// The open file of a demand-loaded texture, shared by its levels.
pub(crate) struct DemandFile {
    label: String,
    reader: Mutex<TiffTileReader<BufReader<File>>>,
    /// The first tile that could not be read, as its error message.
    failure: OnceLock<String>,
    cache: Arc<TileCache>,
    tally: Arc<FileTally>,
    tiles_in_file: u64,
    /// What identifies the file's contents without reading its tiles (see
    /// [`DemandFile::identity`]).
    identity: Vec<u64>,
}

impl Drop for DemandFile {
    fn drop(&mut self) {
        self.cache.forget(&self.tally);
    }
}

static NEXT_LEVEL_ID: AtomicU64 = AtomicU64::new(0);

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

    /// Tiles read from the file so far (a tile read again after its eviction counts
    /// again).
    pub(crate) fn tiles_read(&self) -> u64 {
        self.tally.loads.load(Ordering::Relaxed)
    }

    /// The file's cache counters.
    pub(crate) fn cache_stats(&self) -> TextureCacheStats {
        self.tally.snapshot()
    }

    /// The cache the file's tiles live in.
    pub(crate) fn cache(&self) -> &Arc<TileCache> {
        &self.cache
    }

    /// The file's length, modification time (seconds and nanoseconds since the epoch, 0
    /// where the file system keeps none) and layout (levels, tile offsets and byte counts):
    /// what a render's signature records of a demand-loaded file instead of a digest of
    /// all its bytes, so opening a large `.tx` reads kilobytes.
    pub(crate) fn identity(&self) -> &[u64] {
        &self.identity
    }

    /// Tiles the file holds over all levels.
    pub(crate) fn tiles_in_file(&self) -> u64 {
        self.tiles_in_file
    }
}

/// One level of a demand-loaded texture.
pub struct DemandLevel {
    file: Arc<DemandFile>,
    /// The micro-cache key of the level's first tile, from its process-unique id
    /// (`micro_cache::level_key_base`).
    key_base: Option<u64>,
    level: usize,
    layout: TileLayout,
    tiles_x: usize,
    /// Tiles of the level: a fetch checks its index against this field rather than
    /// following `tiles` to the slots' length.
    tile_count: usize,
    texel_count: usize,
    /// No texels, of the storage kind every tile of the level has.
    kind: Texels,
    tiles: Arc<LevelTiles>,
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

/// The file at `path`, opened afresh, when its first bytes say TIFF; `None` for any other
/// format (decoded whole). `label` names the file in errors.
fn open_tiff(path: &Path, label: &str) -> Result<Option<File>, TextureError> {
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
    File::open(path).map(Some).map_err(io_error)
}

/// What opening the file at `path` through a cache would hold on demand: the (width,
/// height) of every stored level when it is a tiled, mip-mapped TIFF read tile by tile,
/// `Ok(None)` when it is decoded whole. Reads the file's directories, no tile.
pub fn demand_level_sizes(path: &Path) -> Result<Option<Vec<(u32, u32)>>, TextureError> {
    let label = path.display().to_string();
    let Some(file) = open_tiff(path, &label)? else {
        return Ok(None);
    };
    let reader = TiffTileReader::open(BufReader::new(file), &label, ColorSpace::Linear)?;
    Ok(reader.map(|reader| reader.level_sizes()))
}

/// The levels of the tiled, mip-mapped TIFF at `path`, each read tile by tile on demand
/// into `cache`, and the file they share; `Ok(None)` when the file is not such a TIFF (it
/// is then decoded whole). `label` names the file in errors; `color_space` is the one
/// stated, `None` for the one the file records.
pub(crate) fn open(
    path: &Path,
    label: &str,
    color_space: Option<ColorSpace>,
    cache: &Arc<TileCache>,
) -> Result<Option<(MipPyramid, Arc<DemandFile>)>, TextureError> {
    let io_error = |source| TextureError::Io {
        label: label.to_string(),
        source,
    };
    let Some(file) = open_tiff(path, label)? else {
        return Ok(None);
    };
    let metadata = file.metadata().map_err(io_error)?;
    let modified = metadata
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .unwrap_or_default();
    let Some(mut reader) = TiffTileReader::open(BufReader::new(file), label, color_space)? else {
        return Ok(None);
    };
    let sizes = reader.level_sizes();
    let mut identity = vec![
        metadata.len(),
        modified.as_secs(),
        u64::from(modified.subsec_nanos()),
    ];
    identity.extend(reader.layout_words());
    // The coarsest level's single tile tells the storage kind the levels share.
    let coarsest = sizes.len() - 1;
    let coarsest_tile = reader.read_tile(coarsest, 0, 0)?;
    let coarsest_bytes = reader.stored_bytes(coarsest, 0);
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
        cache: cache.clone(),
        tally: Arc::new(FileTally::new()),
        tiles_in_file,
        identity,
    });
    let levels: Vec<MipLevel> = sizes
        .iter()
        .enumerate()
        .map(|(level, &(width, height))| {
            let layout = TileLayout::new(width, height);
            let tile_count = layout.tiles_x() * layout.tiles_y();
            let tiles = LevelTiles::new(tile_count, file.tally.clone());
            let id = NEXT_LEVEL_ID.fetch_add(1, Ordering::Relaxed);
            let demand = DemandLevel {
                file: file.clone(),
                key_base: micro_cache::level_key_base(id, tile_count),
                level,
                layout,
                tiles_x: layout.tiles_x(),
                tile_count,
                texel_count: width as usize * height as usize,
                kind: kind.clone(),
                tiles: Arc::new(tiles),
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
        last.admit(0, Arc::new(tile), coarsest_bytes);
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

    /// Bytes of the level's tiles resident in the cache.
    pub(crate) fn resident_bytes(&self) -> usize {
        self.tiles.resident_bytes()
    }

    /// Linear RGBA of the texel at `index` in tile order (zero when its tile cannot be
    /// read).
    pub(crate) fn texel_at_index(&self, index: usize) -> Vec4 {
        let (x, y) = self.layout.coordinates_of(index);
        micro_cache::with_thread_tiles(|tiles| {
            DemandTexels::new(self, tiles).texel_at(self.layout, x, y)
        })
    }

    /// `read` of the texels of tile (`tile_x`, `tile_y`), fetched through the thread's
    /// micro-cache `tiles` and the shared cache, or read from the file; `None` when the tile
    /// cannot be read or `read` gives none.
    #[inline(always)]
    fn with_tile<R>(
        &self,
        tiles: ThreadTiles<'_>,
        tile_x: usize,
        tile_y: usize,
        read: impl FnOnce(&Texels) -> Option<R>,
    ) -> Option<R> {
        let index = tile_y * self.tiles_x + tile_x;
        if tile_x >= self.tiles_x || index >= self.tile_count {
            return None;
        }
        // `move`: the miss path's arguments stay in registers on the hit path.
        let fetch = move || self.fetch(index, tile_x, tile_y);
        tiles.with_tile(self.key_base, index, fetch, read)
    }

    /// [`DemandLevel::with_tile`] of the tile numbered `index` (row of tiles times tiles
    /// per row, plus column).
    #[inline(always)]
    fn with_tile_numbered<R>(
        &self,
        tiles: ThreadTiles<'_>,
        index: usize,
        read: impl FnOnce(&Texels) -> Option<R>,
    ) -> Option<R> {
        if index >= self.tile_count {
            return None;
        }
        let fetch = move || self.fetch(index, index % self.tiles_x, index / self.tiles_x);
        tiles.with_tile(self.key_base, index, fetch, read)
    }

    /// A micro-cache miss: the tile from its slot, or else from the file.
    #[cold]
    #[inline(never)]
    fn fetch(&self, index: usize, tile_x: usize, tile_y: usize) -> Option<FetchedTile<'_>> {
        let (tile, from_cache) = match self.tiles.resident(index) {
            Some(tile) => (tile, true),
            None => self.read(index, tile_x, tile_y)?,
        };
        Some(FetchedTile {
            tile,
            tally: &self.file.tally,
            from_cache,
        })
    }

    /// Reads a tile that is not resident and admits it to the cache; `true` with it when
    /// another thread read it meanwhile, so the cache served it after all.
    fn read(&self, index: usize, tile_x: usize, tile_y: usize) -> Option<(Arc<Texels>, bool)> {
        if self.file.failure.get().is_some() {
            return None;
        }
        let mut reader = self
            .file
            .reader
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        if let Some(tile) = self.tiles.resident(index) {
            return Some((tile, true));
        }
        let read = reader
            .read_tile(self.level, tile_x, tile_y)
            .and_then(|tile| self.checked(tile, tile_x, tile_y));
        match read {
            Ok(tile) => {
                let tile = Arc::new(tile);
                self.admit(index, tile.clone(), reader.stored_bytes(self.level, index));
                Some((tile, false))
            }
            Err(error) => {
                let _ = self.file.failure.set(error.to_string());
                None
            }
        }
    }

    /// Puts a tile just read (`stored_bytes` of the file) in the cache, and counts it.
    fn admit(&self, index: usize, tile: Arc<Texels>, stored_bytes: u64) {
        self.file.cache.admit(&self.tiles, index, tile);
        let tally = &self.file.tally;
        tally.loads.fetch_add(1, Ordering::Relaxed);
        tally.bytes_read.fetch_add(stored_bytes, Ordering::Relaxed);
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

/// The filters' view of a demand-loaded level during one lookup: the level and the
/// thread's micro-cache, found once for the lookup.
#[derive(Clone, Copy)]
pub(crate) struct DemandTexels<'a> {
    level: &'a DemandLevel,
    tiles: ThreadTiles<'a>,
}

impl<'a> DemandTexels<'a> {
    #[inline(always)]
    pub(crate) fn new(level: &'a DemandLevel, tiles: ThreadTiles<'a>) -> Self {
        DemandTexels { level, tiles }
    }
}

impl<'a> TexelSource<'a> for DemandTexels<'a> {
    #[inline(always)]
    fn view(self, texels: &'a Texels) -> Option<Self> {
        match texels {
            Texels::OnDemand(level) => Some(DemandTexels::new(level, self.tiles)),
            _ => None,
        }
    }

    #[inline(always)]
    fn texel_at(self, layout: TileLayout, x: usize, y: usize) -> Vec4 {
        let (tile_x, tile_y, offset) = layout.locate(x, y);
        self.level
            .with_tile(
                self.tiles,
                tile_x,
                tile_y,
                #[inline(always)]
                move |tile| Some(tile.resident_texel(offset)),
            )
            .unwrap_or(Vec4::ZERO)
    }

    #[inline(always)]
    fn thread_tiles(self) -> ThreadTiles<'a> {
        self.tiles
    }

    #[inline(always)]
    fn lane_buffer_len(self) -> usize {
        usize::MAX
    }

    /// One fetch per tile for all the lanes whose blocks lie in it; a lane whose block
    /// straddles a tile edge is left to the scalar path.
    #[inline(always)]
    fn block_values(self, blocks: &ProbeBlocks) -> (Lanes<Vec4>, Lanes<bool>) {
        let mut values = [Vec4::ZERO; PROBE_LANES];
        let mut served = [false; PROBE_LANES];
        let mut pending = blocks.single_tile();
        for lane in 0..PROBE_LANES {
            if !pending[lane] {
                continue;
            }
            let tile = blocks.tile(lane);
            let mut in_this_tile = [false; PROBE_LANES];
            for l in lane..PROBE_LANES {
                in_this_tile[l] = pending[l] & (blocks.tile(l) == tile);
                pending[l] &= !in_this_tile[l];
            }
            self.level.with_tile_numbered(
                self.tiles,
                tile as usize,
                #[inline(always)]
                |texels| {
                    let mut serve = |l: usize, value: Option<Vec4>| {
                        if let Some(value) = value {
                            values[l] = value;
                            served[l] = true;
                        }
                    };
                    // The lane indexes the values and flags of `serve` as well.
                    #[allow(clippy::needless_range_loop)]
                    for l in lane..PROBE_LANES {
                        if in_this_tile[l] {
                            serve(l, value_in_tile(blocks, texels, l));
                        }
                    }
                    Some(())
                },
            );
        }
        (values, served)
    }

    #[inline(always)]
    fn corner_texels(self, layout: TileLayout, xs: [usize; 2], ys: [usize; 2]) -> [Vec4; 4] {
        let (tile_x, tile_y, _) = layout.locate(xs[0], ys[0]);
        let shift = TEXTURE_TILE_SIZE.trailing_zeros();
        let one_tile = (xs[1] >> shift == tile_x) & (ys[1] >> shift == tile_y);
        let offset = |x: usize, y: usize| layout.locate(x, y).2;
        let offsets = one_tile.then(|| {
            [
                offset(xs[0], ys[0]),
                offset(xs[1], ys[0]),
                offset(xs[0], ys[1]),
                offset(xs[1], ys[1]),
            ]
        });
        let read = offsets.and_then(|offsets| {
            self.level.with_tile(
                self.tiles,
                tile_x,
                tile_y,
                #[inline(always)]
                |tile| {
                    let texel = |k: usize| tile.resident_texel(offsets[k]);
                    let inside = offsets.iter().all(|&k| k < tile.len());
                    inside.then(|| [texel(0), texel(1), texel(2), texel(3)])
                },
            )
        });
        read.unwrap_or_else(|| {
            [
                self.texel_at(layout, xs[0], ys[0]),
                self.texel_at(layout, xs[1], ys[0]),
                self.texel_at(layout, xs[0], ys[1]),
                self.texel_at(layout, xs[1], ys[1]),
            ]
        })
    }

    #[inline(always)]
    fn with_tile_texels<W: TileWork>(
        self,
        _layout: TileLayout,
        tile_x: usize,
        tile_y: usize,
        work: &mut W,
    ) -> Option<W::Output> {
        self.level.with_tile(
            self.tiles,
            tile_x,
            tile_y,
            #[inline(always)]
            move |tile| match tile {
                Texels::Float(t) => Some(work.run(FloatTexels(t), 0)),
                Texels::Half(t) => Some(work.run(HalfTexels(t), 0)),
                Texels::Byte { texels, colour, .. } => {
                    Some(work.run(ByteTexels::new(texels, colour), 0))
                }
                Texels::OnDemand(_) => None,
            },
        )
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
            Some((tile_x, tile_y, offset, stride)) => self.level.with_tile(
                self.tiles,
                tile_x,
                tile_y,
                // Inline: out of line, every fetch paid a call and a result returned
                // through memory (a quarter of `bench textures`' cached bilinear time).
                #[inline(always)]
                move |tile| tile.quad(offset, stride, blend),
            ),
            None => Some(self.four_texels(layout, x, y, blend)),
        }
    }
}

/// [`ProbeBlocks::value_in_tile`] of lane `lane` read from `tile` in its storage kind.
#[inline(always)]
fn value_in_tile(blocks: &ProbeBlocks, tile: &Texels, lane: usize) -> Option<Vec4> {
    match tile {
        Texels::Float(t) => blocks.value_in_tile(FloatTexels(t), lane),
        Texels::Half(t) => blocks.value_in_tile(HalfTexels(t), lane),
        Texels::Byte { texels, colour, .. } => {
            blocks.value_in_tile(ByteTexels::new(texels, colour), lane)
        }
        Texels::OnDemand(_) => None,
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use crate::texture::tiff_tile_reader::tests::maketx;
    use crate::texture::{
        ColorSpace, FilterMode, FilterOptions, Texture, TextureQuery, TextureTileSet, TileCache,
        WrapMode,
    };

    /// Bytes of a full 64x64 tile of 8-bit RGBA texels.
    const BYTE_TILE: u64 = 64 * 64 * 4;

    #[test]
    fn under_a_cap_of_three_tiles_every_texel_is_read_again_with_the_same_value() {
        let dir = tempfile::tempdir().unwrap();
        let tx = maketx(dir.path(), 300, 300, &[]);
        let cap = 3 * BYTE_TILE;
        let cache = Arc::new(TileCache::new(cap));
        let demand = Texture::from_file_in(&tx, ColorSpace::Srgb, &cache).unwrap();
        let whole = Texture::from_file_whole(&tx, ColorSpace::Srgb).unwrap();
        let (level, reference) = (&demand.pyramid().levels[0], &whole.pyramid().levels[0]);
        // Two passes over level 0's 5x5 tiles, row by row: a band of 5 tiles fits the
        // thread's micro-cache, the 25 do not, nor does the cap, so the second pass reads
        // every tile again.
        for _ in 0..2 {
            for (x, y) in level.coordinates() {
                assert_eq!(level.texel(x, y), reference.texel(x, y), "({x}, {y})");
            }
            assert!(cache.resident_bytes() <= cap);
        }
        let stats = demand.cache_stats().unwrap();
        assert_eq!(stats.tiles_loaded, 1 + 2 * 25, "{stats:?}");
        assert!(stats.tiles_evicted > 40, "{stats:?}");
        assert!(stats.peak_resident_bytes <= cap, "{stats:?}");
        assert!(cache.peak_resident_bytes() <= cap);
        assert!(stats.bytes_read > 0);
        assert!(demand.tile_failure().is_none());
        drop(demand);
        assert_eq!(
            cache.resident_bytes(),
            0,
            "a dropped texture frees its tiles"
        );
    }

    #[test]
    fn threads_sampling_under_a_cap_of_two_tiles_get_the_resident_answers() {
        let dir = tempfile::tempdir().unwrap();
        let tx = maketx(dir.path(), 256, 192, &["-d", "half"]);
        // Half RGBA tiles take 32 KiB.
        let cache = Arc::new(TileCache::new(2 * 2 * BYTE_TILE));
        let demand = Texture::from_file_in(&tx, ColorSpace::Linear, &cache).unwrap();
        let whole = Texture::from_file_whole(&tx, ColorSpace::Linear).unwrap();
        std::thread::scope(|scope| {
            for thread in 0..4u64 {
                let (demand, whole) = (&demand, &whole);
                scope.spawn(move || {
                    let mut state = 0x9e37_79b9_7f4a_7c15u64 ^ thread;
                    let mut next = || {
                        (crate::test_rng::xorshift64_star(&mut state) >> 40) as f32
                            / (1u64 << 24) as f32
                    };
                    for filter in [
                        FilterMode::Closest,
                        FilterMode::Bilinear,
                        FilterMode::Trilinear,
                        FilterMode::Aniso,
                        FilterMode::Ewa,
                    ] {
                        let opts = FilterOptions {
                            filter,
                            wrap_s: WrapMode::Periodic,
                            wrap_t: WrapMode::Mirror,
                            max_aniso: 8.0,
                        };
                        for _ in 0..400 {
                            let scale = 0.1 * next().powi(3);
                            let q = TextureQuery {
                                s: 2.0 * next() - 0.5,
                                t: 2.0 * next() - 0.5,
                                dsdx: scale * (next() - 0.5),
                                dtdx: scale * (next() - 0.5),
                                dsdy: 0.3 * scale * (next() - 0.5),
                                dtdy: 0.3 * scale * (next() - 0.5),
                            };
                            let (a, b) = (demand.sample(&q, &opts), whole.sample(&q, &opts));
                            assert_eq!(
                                a.to_array().map(f32::to_bits),
                                b.to_array().map(f32::to_bits),
                                "{filter} {q:?}"
                            );
                        }
                    }
                });
            }
        });
        let stats = demand.cache_stats().unwrap();
        assert!(stats.tiles_evicted > 0, "{stats:?}");
        assert!(cache.peak_resident_bytes() <= 4 * BYTE_TILE);
        assert!(demand.tile_failure().is_none());
    }

    /// Anisotropic lookups of many probes (read in lanes, one tile fetch per tile a step's
    /// blocks lie in), wrapped bilinear footprints (one fetch for four texels sharing a
    /// tile) and EWA footprints (one fetch for an ellipse inside a tile) give the bits and
    /// the recorded tiles of the resident levels, for 8-bit, half and f32 files, every wrap
    /// mode, under the default cap and a cap of 3 tiles.
    #[test]
    fn many_probes_and_wrapped_footprints_read_by_tile_equal_the_resident_levels() {
        let wraps = [
            WrapMode::Periodic,
            WrapMode::Clamp,
            WrapMode::Black,
            WrapMode::Mirror,
        ];
        for kind in [&[][..], &["-d", "half"], &["-d", "float"]] {
            let dir = tempfile::tempdir().unwrap();
            let tx = maketx(dir.path(), 300, 200, kind);
            let whole = Texture::from_file_whole(&tx, ColorSpace::Srgb).unwrap();
            for cap in [u64::MAX, 3 * 4 * BYTE_TILE] {
                let cache = Arc::new(TileCache::new(cap));
                let demand = Texture::from_file_in(&tx, ColorSpace::Srgb, &cache).unwrap();
                let mut state = 0x5851_f42d_4c95_7f2du64;
                let mut next = || {
                    (crate::test_rng::xorshift64_star(&mut state) >> 40) as f32
                        / (1u64 << 24) as f32
                };
                for k in 0..600 {
                    let filter = [FilterMode::Aniso, FilterMode::Trilinear, FilterMode::Ewa][k % 3];
                    let opts = FilterOptions {
                        filter,
                        wrap_s: wraps[k % 4],
                        wrap_t: wraps[(k / 4) % 4],
                        max_aniso: 64.0,
                    };
                    let minor = 0.002 * 2f32.powf(6.0 * next());
                    let major = minor * (1.0 + 60.0 * next());
                    let angle = std::f32::consts::TAU * next();
                    let q = TextureQuery {
                        s: 1.6 * next() - 0.3,
                        t: 1.6 * next() - 0.3,
                        dsdx: major * angle.cos(),
                        dtdx: major * angle.sin(),
                        dsdy: -minor * angle.sin(),
                        dtdy: minor * angle.cos(),
                    };
                    let (mut a_tiles, mut b_tiles) = (TextureTileSet::new(), TextureTileSet::new());
                    let a = demand.sample_recording(&q, &opts, &mut a_tiles);
                    let b = whole.sample_recording(&q, &opts, &mut b_tiles);
                    assert_eq!(
                        a.to_array().map(f32::to_bits),
                        b.to_array().map(f32::to_bits),
                        "{kind:?} cap {cap} {opts:?} {q:?}"
                    );
                    assert_eq!(
                        (a_tiles.count(), a_tiles.touches()),
                        (b_tiles.count(), b_tiles.touches()),
                        "{kind:?} {opts:?} {q:?}"
                    );
                    assert_eq!(demand.sample(&q, &opts), a);
                }
                assert!(demand.tile_failure().is_none());
            }
        }
    }
}
