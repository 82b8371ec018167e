//! Recording which 64x64-texel tiles the filters touch (seed 000, figures 4-7: the
//! tile-count metric of a demand-loaded texture cache).
//!
//! Filters read texels through a [`TexelObserver`] type parameter. The plain lookup
//! passes [`NoTextureTiles`], whose `touch` is empty and vanishes after monomorphisation, so
//! `Texture::sample` pays nothing for this; `sample_recording` passes a
//! [`TextureTileRecorder`]. A [`TextureTileSet`] is kept per thread and keyed by
//! (texture id, level, tile x, tile y), so one set can hold tiles of many textures;
//! merge the per-thread sets at the end of a render. The set is a bitmap per texture and mip
//! level, grown on demand, so recording a tile is a bit test and a bit set: `--stats` turns
//! recording on, and the render times it reports must stay those of a plain render.
//!
//! Besides the distinct tiles, a set counts *tile touches*: for every lookup, the number of
//! distinct tiles that lookup reads, summed over lookups. That is how many tile requests a
//! demand-loaded cache (OpenImageIO's `TextureSystem` with 64x64 tiles) would serve, while
//! the distinct tiles are what it would have to load.

/// Edge length of a texture tile, a texture cache's unit, in texels (OpenImageIO's `maketx`
/// default). Not to be confused with the render's 16x16-pixel work tiles.
pub const TEXTURE_TILE_SIZE: u32 = 64;

/// Something told about every texel a filter reads.
pub(crate) trait TexelObserver {
    /// Texel (x, y) of mip level `level` is read.
    fn touch(&mut self, level: usize, x: usize, y: usize);

    /// The next lookup starts: an observer that counts each lookup's distinct tiles starts
    /// a new count (one observer can then serve a batch of lookups).
    #[inline(always)]
    fn begin_lookup(&mut self) {}

    /// The texels of a bilinear block on mip level `level` are read: (xs\[c\], ys\[r\])
    /// wherever `inside[r][c]`, row by row, left to right (the order of the scalar probe).
    #[inline(always)]
    fn touch_block(
        &mut self,
        level: usize,
        xs: [usize; 2],
        ys: [usize; 2],
        inside: [[bool; 2]; 2],
    ) {
        touch_each(self, level, xs, ys, inside);
    }
}

/// [`TexelObserver::touch_block`] as touches of each texel read.
#[inline(always)]
fn touch_each<O: TexelObserver + ?Sized>(
    obs: &mut O,
    level: usize,
    xs: [usize; 2],
    ys: [usize; 2],
    inside: [[bool; 2]; 2],
) {
    for (row, &y) in ys.iter().enumerate() {
        for (column, &x) in xs.iter().enumerate() {
            if inside[row][column] {
                obs.touch(level, x, y);
            }
        }
    }
}

/// The observer of plain lookups: does nothing.
pub(crate) struct NoTextureTiles;

impl TexelObserver for NoTextureTiles {
    #[inline(always)]
    fn touch(&mut self, _level: usize, _x: usize, _y: usize) {}

    #[inline(always)]
    fn touch_block(&mut self, _: usize, _: [usize; 2], _: [usize; 2], _: [[bool; 2]; 2]) {}
}

/// How many tiles of one lookup a recorder remembers to count each of them once. A
/// bilinear or trilinear lookup reads at most 8 tiles (4 per level where its texels straddle
/// a tile corner); wide anisotropic lookups that read more are counted once per tile while
/// they read at most this many in turn.
const TILES_REMEMBERED: usize = 8;

/// The observer of recording lookups: adds the texel's tile to a [`TextureTileSet`]. One
/// recorder serves one lookup at a time (`begin_lookup` starts the next), so it also counts
/// each lookup's distinct tiles (touches).
pub(crate) struct TextureTileRecorder<'a> {
    /// The bitmaps of the looked-up texture, found once per lookup.
    texture: &'a mut TextureTiles,
    touches: &'a mut u64,
    /// The last `TILES_REMEMBERED` tiles this lookup recorded, in a ring (slot `seen_count %
    /// TILES_REMEMBERED` is written next).
    seen: [(usize, usize, usize); TILES_REMEMBERED],
    seen_count: usize,
    /// The tile of this lookup's last touch ([`NO_TILE`] before its first): a texel's
    /// neighbours are nearly always in its tile, and an anisotropic lookup reads hundreds
    /// of texels, so most touches end at this one comparison instead of a search of
    /// `seen` (under `--stats`, that search took a quarter of a cone + aniso frame).
    last: (usize, usize, usize),
}

/// A key no tile has: mip levels are numbered from 0 up, never to `usize::MAX`.
const NO_TILE: (usize, usize, usize) = (usize::MAX, 0, 0);

impl<'a> TextureTileRecorder<'a> {
    pub(crate) fn new(texture_id: u64, tiles: &'a mut TextureTileSet) -> Self {
        let TextureTileSet { textures, touches } = tiles;
        TextureTileRecorder {
            texture: TextureTileSet::texture_in(textures, texture_id),
            touches,
            seen: [(0, 0, 0); TILES_REMEMBERED],
            seen_count: 0,
            last: NO_TILE,
        }
    }
}

impl TexelObserver for TextureTileRecorder<'_> {
    #[inline(always)]
    fn begin_lookup(&mut self) {
        self.seen_count = 0;
        self.last = NO_TILE;
    }

    /// A block read whole inside one tile (all but about one in 32) is one touch of that
    /// tile, which the other three texels' touches would only have found again.
    #[inline(always)]
    fn touch_block(
        &mut self,
        level: usize,
        xs: [usize; 2],
        ys: [usize; 2],
        inside: [[bool; 2]; 2],
    ) {
        let tile = |v: usize| v / TEXTURE_TILE_SIZE as usize;
        let one_tile = tile(xs[0]) == tile(xs[1]) && tile(ys[0]) == tile(ys[1]);
        if one_tile && inside == [[true; 2]; 2] {
            self.touch(level, xs[0], ys[0]);
        } else {
            touch_each(self, level, xs, ys, inside);
        }
    }

    #[inline]
    fn touch(&mut self, level: usize, x: usize, y: usize) {
        let key = (
            level,
            x / TEXTURE_TILE_SIZE as usize,
            y / TEXTURE_TILE_SIZE as usize,
        );
        // The last touch's tile was found in or added to `seen`, and stays there until
        // the next addition.
        if key == self.last {
            return;
        }
        self.last = key;
        // Neighbouring texels mostly share a tile: skip the bitmap (and the touch count) for
        // tiles this lookup already read.
        let remembered = self.seen_count.min(TILES_REMEMBERED);
        if self.seen[..remembered].contains(&key) {
            return;
        }
        self.seen[self.seen_count % TILES_REMEMBERED] = key;
        self.seen_count += 1;
        *self.touches += 1;
        self.texture.insert(key.0, key.1, key.2);
    }
}

/// The touched tiles of one texture: per mip level, one bitmap row of tile columns per row
/// of tiles, each grown when a tile beyond it is recorded.
#[derive(Clone, Debug, Default)]
struct TextureTiles {
    texture_id: u64,
    /// `levels[level][tile_y]`: bit `tile_x` of that row's words.
    levels: Vec<Vec<Vec<u64>>>,
    /// Number of bits set over all levels.
    count: u64,
}

impl TextureTiles {
    /// Sets the tile's bit; counts it if it was not set.
    #[inline]
    fn insert(&mut self, level: usize, tile_x: usize, tile_y: usize) {
        if self.levels.len() <= level {
            self.levels.resize_with(level + 1, Vec::new);
        }
        let rows = &mut self.levels[level];
        if rows.len() <= tile_y {
            rows.resize_with(tile_y + 1, Vec::new);
        }
        let words = &mut rows[tile_y];
        let word = tile_x / 64;
        if words.len() <= word {
            words.resize(word + 1, 0);
        }
        let bit = 1u64 << (tile_x % 64);
        if words[word] & bit == 0 {
            words[word] |= bit;
            self.count += 1;
        }
    }

    /// Adds every tile of `other` (the same texture's).
    fn merge(&mut self, other: &TextureTiles) {
        for (level, rows) in other.levels.iter().enumerate() {
            for (tile_y, words) in rows.iter().enumerate() {
                for (word, &bits) in words.iter().enumerate() {
                    let mut rest = bits;
                    while rest != 0 {
                        let tile_x = word * 64 + rest.trailing_zeros() as usize;
                        self.insert(level, tile_x, tile_y);
                        rest &= rest - 1;
                    }
                }
            }
        }
    }

    /// Distinct tiles of one level.
    fn count_at(&self, level: usize) -> u64 {
        self.levels.get(level).map_or(0, |rows| {
            rows.iter()
                .flatten()
                .map(|w| u64::from(w.count_ones()))
                .sum()
        })
    }
}

/// A set of touched tiles over any number of textures (one per thread, then merged).
#[derive(Clone, Debug, Default)]
pub struct TextureTileSet {
    /// One entry per texture recorded, in the order first seen (a worker's set usually
    /// holds one texture: the render keeps a set per texture).
    textures: Vec<TextureTiles>,
    /// Tile touches: distinct tiles per lookup, summed over the lookups recorded.
    touches: u64,
}

impl TextureTileSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// The bitmaps of texture `texture_id` in `textures`, added if missing.
    fn texture_in(textures: &mut Vec<TextureTiles>, texture_id: u64) -> &mut TextureTiles {
        let index = match textures.iter().position(|t| t.texture_id == texture_id) {
            Some(index) => index,
            None => {
                textures.push(TextureTiles {
                    texture_id,
                    ..TextureTiles::default()
                });
                textures.len() - 1
            }
        };
        &mut textures[index]
    }

    /// Marks tile (tile_x, tile_y) of `level` of texture `texture_id` as touched.
    pub fn record(&mut self, texture_id: u64, level: usize, tile_x: usize, tile_y: usize) {
        Self::texture_in(&mut self.textures, texture_id).insert(level, tile_x, tile_y);
    }

    /// Adds every tile of `other`.
    pub fn merge(&mut self, other: TextureTileSet) {
        self.touches += other.touches;
        for texture in &other.textures {
            Self::texture_in(&mut self.textures, texture.texture_id).merge(texture);
        }
    }

    /// Number of distinct tiles over all textures and levels.
    pub fn count(&self) -> u64 {
        self.textures.iter().map(|t| t.count).sum()
    }

    /// Tile touches: for every recorded lookup, the distinct tiles it read, summed.
    pub fn touches(&self) -> u64 {
        self.touches
    }

    /// Distinct tiles per mip level (summed over textures); index = level.
    pub fn count_per_level(&self) -> Vec<u64> {
        let levels = self
            .textures
            .iter()
            .map(|t| t.levels.len())
            .max()
            .unwrap_or(0);
        (0..levels)
            .map(|level| self.textures.iter().map(|t| t.count_at(level)).sum())
            .collect()
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

    /// The recorder counts the touches of a plain model: per lookup, a tile is counted
    /// unless it is among the last `TILES_REMEMBERED` distinct tiles that lookup counted.
    /// Runs of touches in one tile (which the recorder ends at its last-tile check),
    /// returns to older tiles and lookups of more tiles than it remembers are all mixed.
    #[test]
    fn touches_count_as_the_ring_of_remembered_tiles_counts() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |bound: u64| crate::test_rng::xorshift64_star(&mut state) % bound;
        let mut set = TextureTileSet::new();
        let mut expected = 0u64;
        let mut recorder = TextureTileRecorder::new(3, &mut set);
        for _ in 0..400 {
            recorder.begin_lookup();
            let mut ring: Vec<(usize, usize, usize)> = Vec::new();
            let tiles = 1 + next(14) as usize;
            for _ in 0..next(60) {
                let (level, tx, ty) = (
                    next(2) as usize,
                    next(tiles as u64) as usize,
                    next(3) as usize,
                );
                for _ in 0..1 + next(5) {
                    let x = tx * TEXTURE_TILE_SIZE as usize + next(64) as usize;
                    let y = ty * TEXTURE_TILE_SIZE as usize + next(64) as usize;
                    recorder.touch(level, x, y);
                    let key = (level, tx, ty);
                    let remembered = &ring[ring.len().saturating_sub(TILES_REMEMBERED)..];
                    if !remembered.contains(&key) {
                        ring.push(key);
                        expected += 1;
                    }
                }
            }
        }
        assert_eq!(set.touches(), expected);
    }

    /// A recorder told of whole bilinear blocks records the tiles and touches it records
    /// when told of each texel of them: blocks inside one tile, across tile edges and with
    /// texels outside (a black wrap).
    #[test]
    fn blocks_record_what_their_texels_record() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |bound: u64| crate::test_rng::xorshift64_star(&mut state) % bound;
        let (mut by_block, mut by_texel) = (TextureTileSet::new(), TextureTileSet::new());
        let mut blocks = TextureTileRecorder::new(1, &mut by_block);
        let mut texels = TextureTileRecorder::new(1, &mut by_texel);
        for _ in 0..300 {
            blocks.begin_lookup();
            texels.begin_lookup();
            for _ in 0..next(40) {
                let level = next(3) as usize;
                let (x, y) = (next(300) as usize, next(200) as usize);
                let (xs, ys) = ([x, x + 1], [y, y + 1]);
                let all = next(4) != 0;
                let inside = [[all || next(2) == 0, all || next(2) == 0], [all, true]];
                blocks.touch_block(level, xs, ys, inside);
                touch_each(&mut texels, level, xs, ys, inside);
            }
        }
        assert_eq!(by_block.touches(), by_texel.touches());
        assert_eq!(by_block.count_per_level(), by_texel.count_per_level());
        assert!(by_block.count() > 20, "{}", by_block.count());
    }

    #[test]
    fn bitmaps_count_what_a_set_of_keys_counts_over_random_records_and_merges() {
        use std::collections::HashSet;
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = |bound: u64| crate::test_rng::xorshift64_star(&mut state) % bound;
        let mut parts = Vec::new();
        let mut reference = HashSet::new();
        for _ in 0..3 {
            let mut part = TextureTileSet::new();
            for _ in 0..2000 {
                // Three textures, 12 levels, rows and columns past one 64-bit word.
                let key = (
                    next(3),
                    next(12) as usize,
                    next(150) as usize,
                    next(40) as usize,
                );
                part.record(key.0, key.1, key.2, key.3);
                reference.insert(key);
            }
            parts.push(part);
        }
        let mut total = TextureTileSet::new();
        for part in parts {
            total.merge(part);
        }
        assert_eq!(total.count(), reference.len() as u64);
        let mut per_level = vec![0u64; 12];
        for &(_, level, _, _) in &reference {
            per_level[level] += 1;
        }
        assert_eq!(total.count_per_level(), per_level);
    }
}
