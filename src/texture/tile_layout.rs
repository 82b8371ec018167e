//! Where a texel of a mip level sits in memory: every level is stored as tiles of
//! [`TEXTURE_TILE_SIZE`] x [`TEXTURE_TILE_SIZE`] texels, the unit a texture cache loads
//! and the tile size `maketx` writes, so that a tile of a `.tx` file maps to one
//! contiguous run of a level's texels.
//!
//! Tiles follow each other row of tiles by row of tiles; inside a tile, texels are
//! row-major with the tile's own width as stride. Tiles on the right and bottom edges are
//! clipped to the level rather than padded, so a level still takes exactly width x height
//! texels, and a level at most one tile wide is plain row-major order.
//!
//! A fetch is the tile's start plus the offset inside it: shifts, masks and two
//! multiplications, no table.

use super::tiles::TEXTURE_TILE_SIZE;

/// log2 of [`TEXTURE_TILE_SIZE`].
const TILE_SHIFT: u32 = TEXTURE_TILE_SIZE.trailing_zeros();
/// Mask of a coordinate's position inside its tile.
const TILE_MASK: usize = TEXTURE_TILE_SIZE as usize - 1;
const TILE: usize = TEXTURE_TILE_SIZE as usize;

// The shifts and masks above need a power of two.
const _: () = assert!(TEXTURE_TILE_SIZE.is_power_of_two());

/// The tiling of one `width` x `height` level.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TileLayout {
    width: usize,
    height: usize,
}

impl TileLayout {
    /// The tiling of a `width` x `height` level (both at least 1).
    #[inline(always)]
    pub(crate) fn new(width: u32, height: u32) -> TileLayout {
        TileLayout {
            width: width as usize,
            height: height as usize,
        }
    }

    /// Number of tile columns.
    pub(crate) fn tiles_x(self) -> usize {
        self.width.div_ceil(TILE)
    }

    /// Number of tile rows.
    pub(crate) fn tiles_y(self) -> usize {
        self.height.div_ceil(TILE)
    }

    /// Width of the tiles in column `tile_x` (clipped at the right edge).
    #[inline(always)]
    pub(crate) fn tile_width(self, tile_x: usize) -> usize {
        (self.width - (tile_x << TILE_SHIFT)).min(TILE)
    }

    /// Height of the tiles in row `tile_y` (clipped at the bottom edge).
    #[inline(always)]
    pub(crate) fn tile_height(self, tile_y: usize) -> usize {
        (self.height - (tile_y << TILE_SHIFT)).min(TILE)
    }

    /// Index of the first texel of tile (`tile_x`, `tile_y`): the full rows of tiles
    /// above it, then the tiles to its left in its own row.
    #[inline(always)]
    pub(crate) fn tile_start(self, tile_x: usize, tile_y: usize) -> usize {
        (tile_y << TILE_SHIFT) * self.width + (tile_x << TILE_SHIFT) * self.tile_height(tile_y)
    }

    /// Tile column and row of texel (x, y), and its index inside that tile.
    #[inline(always)]
    pub(crate) fn locate(self, x: usize, y: usize) -> (usize, usize, usize) {
        let tile_x = x >> TILE_SHIFT;
        let offset = (y & TILE_MASK) * self.tile_width(tile_x) + (x & TILE_MASK);
        (tile_x, y >> TILE_SHIFT, offset)
    }

    /// Index of texel (x, y) (both in range); fetches go through [`TileLayout::locate`] and
    /// the tile's start, so only tests need the two joined.
    #[cfg(test)]
    pub(crate) fn index(self, x: usize, y: usize) -> usize {
        let (tile_x, tile_y, offset) = self.locate(x, y);
        self.tile_start(tile_x, tile_y) + offset
    }

    /// The (x, y) of the texel at `index` (in range): the inverse of [`TileLayout::index`].
    pub(crate) fn coordinates_of(self, index: usize) -> (usize, usize) {
        let band_len = TILE * self.width;
        let (tile_y, in_band) = (index / band_len, index % band_len);
        // Every tile left of the last one in a row of tiles is a full TILE wide.
        let full_tile_len = TILE * self.tile_height(tile_y);
        let (tile_x, in_tile) = (in_band / full_tile_len, in_band % full_tile_len);
        let tile_width = self.tile_width(tile_x);
        (
            (tile_x << TILE_SHIFT) + in_tile % tile_width,
            (tile_y << TILE_SHIFT) + in_tile / tile_width,
        )
    }

    /// When texels (x, y) to (x + 1, y + 1) lie in one tile: that tile's column and row,
    /// the index of (x, y) inside it and the row stride that reaches (x, y + 1) from
    /// there. `None` when the block straddles a tile edge (its texels are then fetched
    /// one by one).
    #[inline(always)]
    pub(crate) fn block_in_one_tile(
        self,
        x: usize,
        y: usize,
    ) -> Option<(usize, usize, usize, usize)> {
        let (tile_x, tile_y) = (x >> TILE_SHIFT, y >> TILE_SHIFT);
        let (local_x, local_y) = (x & TILE_MASK, y & TILE_MASK);
        let stride = self.tile_width(tile_x);
        if local_x + 1 < stride && local_y + 1 < self.tile_height(tile_y) {
            Some((tile_x, tile_y, local_y * stride + local_x, stride))
        } else {
            None
        }
    }

    /// Reorders `texels` (width x height, row-major) into tile order in place, one row of
    /// tiles at a time through a buffer of one such row.
    pub(crate) fn rows_to_tiles<T: Copy>(self, texels: &mut [T]) -> Result<(), String> {
        if self.width <= TILE {
            return Ok(());
        }
        let band_len = TILE * self.width;
        let mut band: Vec<T> = Vec::new();
        band.try_reserve_exact(band_len.min(texels.len()))
            .map_err(|_| {
                format!(
                    "not enough memory to arrange {}x{} texels in tiles",
                    self.width, self.height
                )
            })?;
        for (tile_y, rows) in texels.chunks_mut(band_len).enumerate() {
            band.clear();
            band.extend_from_slice(rows);
            let mut out = 0;
            for tile_x in 0..self.tiles_x() {
                let (x0, tile_width) = (tile_x << TILE_SHIFT, self.tile_width(tile_x));
                for local_y in 0..self.tile_height(tile_y) {
                    let start = local_y * self.width + x0;
                    rows[out..out + tile_width].copy_from_slice(&band[start..start + tile_width]);
                    out += tile_width;
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SIZES: [(u32, u32); 7] = [
        (1, 1),
        (64, 64),
        (65, 3),
        (3, 130),
        (200, 130),
        (128, 64),
        (257, 191),
    ];

    #[test]
    fn every_texel_has_its_own_index_and_the_indices_fill_the_level() {
        for (w, h) in SIZES {
            let layout = TileLayout::new(w, h);
            let mut seen = vec![false; (w * h) as usize];
            for y in 0..h as usize {
                for x in 0..w as usize {
                    let i = layout.index(x, y);
                    assert!(!seen[i], "{w}x{h}: ({x}, {y}) -> {i} twice");
                    assert_eq!(layout.coordinates_of(i), (x, y), "{w}x{h}");
                    seen[i] = true;
                }
            }
            assert!(seen.iter().all(|&s| s), "{w}x{h}");
        }
    }

    #[test]
    fn reordered_rows_are_found_at_their_index() {
        for (w, h) in SIZES {
            let layout = TileLayout::new(w, h);
            let mut texels: Vec<u32> = (0..w * h).collect();
            layout.rows_to_tiles(&mut texels).unwrap();
            for y in 0..h as usize {
                for x in 0..w as usize {
                    assert_eq!(texels[layout.index(x, y)], (y * w as usize + x) as u32);
                }
            }
            assert_eq!(layout.tiles_x(), (w as usize).div_ceil(64));
            assert_eq!(layout.tiles_y(), (h as usize).div_ceil(64));
        }
    }

    #[test]
    fn a_block_inside_a_tile_is_reached_by_its_stride() {
        for (w, h) in SIZES {
            let layout = TileLayout::new(w, h);
            for y in 0..(h as usize).saturating_sub(1) {
                for x in 0..(w as usize).saturating_sub(1) {
                    let straddles = x % 64 == 63 || y % 64 == 63;
                    match layout.block_in_one_tile(x, y) {
                        Some((tile_x, tile_y, offset, stride)) => {
                            assert!(!straddles, "{w}x{h} ({x}, {y})");
                            let k = layout.tile_start(tile_x, tile_y) + offset;
                            assert_eq!(k, layout.index(x, y));
                            assert_eq!(k + 1, layout.index(x + 1, y));
                            assert_eq!(k + stride, layout.index(x, y + 1));
                            assert_eq!(k + stride + 1, layout.index(x + 1, y + 1));
                        }
                        None => assert!(straddles, "{w}x{h} ({x}, {y})"),
                    }
                }
            }
        }
    }
}
