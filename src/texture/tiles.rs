//! Recording which 64x64-texel tiles the filters touch (seed 000, figures 4-7: the
//! tile-count metric of a demand-loaded texture cache).
//!
//! Filters read texels through a [`TexelObserver`] type parameter. The plain lookup
//! passes [`NoTextureTiles`], whose `touch` is empty and vanishes after monomorphisation, so
//! `Texture::sample` pays nothing for this; `sample_recording` passes a
//! [`TextureTileRecorder`]. A [`TextureTileSet`] is kept per thread and keyed by
//! (texture id, level, tile x, tile y), so one set can hold tiles of many textures;
//! merge the per-thread sets at the end of a render.
//!
//! Besides the distinct tiles, a set counts *tile touches*: for every lookup, the number of
//! distinct tiles that lookup reads, summed over lookups. That is how many tile requests a
//! demand-loaded cache (OpenImageIO's `TextureSystem` with 64x64 tiles) would serve, while
//! the distinct tiles are what it would have to load.

use std::collections::HashSet;

/// Edge length of a texture tile, a texture cache's unit, in texels (OpenImageIO's `maketx`
/// default). Not to be confused with the render's 16x16-pixel work tiles.
pub const TEXTURE_TILE_SIZE: u32 = 64;

/// Something told about every texel a filter reads.
pub(crate) trait TexelObserver {
    /// Texel (x, y) of mip level `level` is read.
    fn touch(&mut self, level: usize, x: usize, y: usize);
}

/// The observer of plain lookups: does nothing.
pub(crate) struct NoTextureTiles;

impl TexelObserver for NoTextureTiles {
    #[inline(always)]
    fn touch(&mut self, _level: usize, _x: usize, _y: usize) {}
}

/// How many tiles of one lookup a recorder remembers to count each of them once. A
/// bilinear or trilinear lookup reads at most 8 tiles (4 per level where its texels straddle
/// a tile corner); wide anisotropic lookups that read more are counted once per tile while
/// they read at most this many in turn.
const TILES_REMEMBERED: usize = 8;

/// The observer of recording lookups: adds the texel's tile to a [`TextureTileSet`]. One
/// recorder serves one lookup, so it also counts that lookup's distinct tiles (touches).
pub(crate) struct TextureTileRecorder<'a> {
    texture_id: u64,
    tiles: &'a mut TextureTileSet,
    /// The last `TILES_REMEMBERED` tiles this lookup recorded, in a ring (slot `seen_count %
    /// TILES_REMEMBERED` is written next).
    seen: [(usize, usize, usize); TILES_REMEMBERED],
    seen_count: usize,
}

impl<'a> TextureTileRecorder<'a> {
    pub(crate) fn new(texture_id: u64, tiles: &'a mut TextureTileSet) -> Self {
        TextureTileRecorder {
            texture_id,
            tiles,
            seen: [(0, 0, 0); TILES_REMEMBERED],
            seen_count: 0,
        }
    }
}

impl TexelObserver for TextureTileRecorder<'_> {
    #[inline]
    fn touch(&mut self, level: usize, x: usize, y: usize) {
        let key = (
            level,
            x / TEXTURE_TILE_SIZE as usize,
            y / TEXTURE_TILE_SIZE as usize,
        );
        // Neighbouring texels mostly share a tile: skip the hash (and the touch count) for
        // tiles this lookup already read.
        let remembered = self.seen_count.min(TILES_REMEMBERED);
        if self.seen[..remembered].contains(&key) {
            return;
        }
        self.seen[self.seen_count % TILES_REMEMBERED] = key;
        self.seen_count += 1;
        self.tiles.touches += 1;
        self.tiles.record(self.texture_id, key.0, key.1, key.2);
    }
}

/// A set of touched tiles over any number of textures (one per thread, then merged).
#[derive(Clone, Debug, Default)]
pub struct TextureTileSet {
    tiles: HashSet<(u64, u32, u32, u32)>,
    /// Tile touches: distinct tiles per lookup, summed over the lookups recorded.
    touches: u64,
}

impl TextureTileSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Marks tile (tile_x, tile_y) of `level` of texture `texture_id` as touched.
    pub fn record(&mut self, texture_id: u64, level: usize, tile_x: usize, tile_y: usize) {
        self.tiles
            .insert((texture_id, level as u32, tile_x as u32, tile_y as u32));
    }

    /// Adds every tile of `other`.
    pub fn merge(&mut self, other: TextureTileSet) {
        self.touches += other.touches;
        if self.tiles.len() < other.tiles.len() {
            let mine = std::mem::replace(&mut self.tiles, other.tiles);
            self.tiles.extend(mine);
        } else {
            self.tiles.extend(other.tiles);
        }
    }

    /// Number of distinct tiles over all textures and levels.
    pub fn count(&self) -> u64 {
        self.tiles.len() as u64
    }

    /// Tile touches: for every recorded lookup, the distinct tiles it read, summed.
    pub fn touches(&self) -> u64 {
        self.touches
    }

    /// Distinct tiles per mip level (summed over textures); index = level.
    pub fn count_per_level(&self) -> Vec<u64> {
        let mut counts = Vec::new();
        for &(_, level, _, _) in &self.tiles {
            let level = level as usize;
            if counts.len() <= level {
                counts.resize(level + 1, 0);
            }
            counts[level] += 1;
        }
        counts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_distinct_tiles_per_texture_and_level() {
        let mut a = TextureTileSet::new();
        {
            let mut r = TextureTileRecorder::new(7, &mut a);
            r.touch(0, 0, 0);
            r.touch(0, 63, 63); // same tile
            r.touch(0, 64, 0); // next tile
            r.touch(2, 1, 1);
        }
        assert_eq!(a.count(), 3);
        assert_eq!(a.touches(), 3);
        {
            // A second lookup of a tile already in the set: one more touch, no new tile.
            let mut r = TextureTileRecorder::new(7, &mut a);
            r.touch(0, 10, 10);
            r.touch(0, 64, 10);
            r.touch(0, 11, 10); // back to the first tile: still one touch for it
        }
        assert_eq!(a.count(), 3);
        assert_eq!(a.touches(), 5);
        let mut b = TextureTileSet::new();
        b.record(8, 0, 0, 0); // other texture, same tile coordinates
        b.record(7, 0, 0, 0); // duplicate of a's
        a.merge(b);
        assert_eq!(a.count(), 4);
        assert_eq!(a.touches(), 5, "record() adds a tile, not a touch");
        assert_eq!(a.count_per_level(), vec![3, 0, 1]);
    }
}
