//! The memory cap over demand-loaded texture tiles: a clock (second-chance) cache shared
//! by every texture opened through it, in the manner of OpenImageIO's ImageCache.
//!
//! Each tile of a demand-loaded level has a slot holding the tile (`Arc`'d) while it is
//! resident and a reference bit. Lookups never come here while their thread's micro-cache
//! holds the tile (see `micro_cache`); on a micro-cache miss they take the tile from its
//! slot (one uncontended slot lock, the reference bit set), and only a tile that is not
//! resident is read from the file and admitted here, under the cache's one lock. Admitting
//! a tile first evicts tiles in clock order until the new one fits under the cap: the hand
//! skips (and clears) a tile referenced since it last passed, and empties the slot of one
//! that was not. An evicted tile touched again is read from the file again, with the same
//! texels, so the cap changes what a render costs, never what it computes.
//!
//! Resident bytes are the tiles' texel bytes. They stay at or under the cap, except that a
//! tile larger than the whole cap is still admitted alone. Beyond them, each thread's
//! micro-cache may keep up to `micro_cache::MICRO_TILES` tiles alive after their eviction
//! (until the thread replaces them or the render ends), and each tile slot takes 24 bytes.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, LazyLock, Mutex, MutexGuard, PoisonError};

use super::texels::Texels;

/// The cap of a cache made without one: 256 MiB, OpenImageIO's ImageCache default
/// (`max_memory_MB`). It holds 4,096 float RGBA tiles of 64x64 texels (64 KiB each), or
/// 16,384 8-bit ones: many times the tiles a frame of cone-filtered lookups touches.
pub const DEFAULT_TEXTURE_CACHE_BYTES: u64 = 256 << 20;

/// Bytes of one tile slot (every tile of every demand-loaded level has one, resident or
/// not).
pub(crate) const SLOT_BYTES: u64 = std::mem::size_of::<Mutex<TileSlot>>() as u64;

static NEXT_FILE_ID: AtomicU64 = AtomicU64::new(0);

/// A texture tile cache with a memory cap, shared by the textures opened through it.
#[derive(Debug)]
pub struct TileCache {
    capacity: u64,
    clock: Mutex<Clock>,
}

/// The resident tiles in clock order, the hand, and their bytes.
#[derive(Debug, Default)]
struct Clock {
    ring: Vec<ResidentTile>,
    hand: usize,
    resident: u64,
    peak: u64,
}

/// One resident tile: where its slot is, and its size.
#[derive(Debug)]
struct ResidentTile {
    level: Arc<LevelTiles>,
    index: usize,
    bytes: u64,
}

/// The slots of one demand-loaded level and the counters of its file.
#[derive(Debug)]
pub(crate) struct LevelTiles {
    tally: Arc<FileTally>,
    slots: Box<[Mutex<TileSlot>]>,
}

#[derive(Debug, Default)]
struct TileSlot {
    tile: Option<Arc<Texels>>,
    /// Set by every lookup that takes the tile from the slot; cleared by the clock hand.
    referenced: bool,
}

/// What happened to the tiles of one file, counted as it happens (relaxed atomics, off
/// the micro-cache's hit path; micro-cache hits are counted per thread and added here when
/// a thread's micro-cache lets a tile go or is flushed).
#[derive(Debug)]
pub(crate) struct FileTally {
    id: u64,
    pub(crate) loads: AtomicU64,
    pub(crate) evictions: AtomicU64,
    pub(crate) bytes_read: AtomicU64,
    pub(crate) resident: AtomicU64,
    pub(crate) peak: AtomicU64,
    pub(crate) micro_hits: AtomicU64,
    pub(crate) micro_misses: AtomicU64,
    pub(crate) cache_hits: AtomicU64,
}

impl FileTally {
    pub(crate) fn new() -> FileTally {
        FileTally {
            id: NEXT_FILE_ID.fetch_add(1, Ordering::Relaxed),
            loads: AtomicU64::new(0),
            evictions: AtomicU64::new(0),
            bytes_read: AtomicU64::new(0),
            resident: AtomicU64::new(0),
            peak: AtomicU64::new(0),
            micro_hits: AtomicU64::new(0),
            micro_misses: AtomicU64::new(0),
            cache_hits: AtomicU64::new(0),
        }
    }

    /// The counters as numbers.
    pub(crate) fn snapshot(&self) -> TextureCacheStats {
        let get = |counter: &AtomicU64| counter.load(Ordering::Relaxed);
        TextureCacheStats {
            tiles_loaded: get(&self.loads),
            tiles_evicted: get(&self.evictions),
            bytes_read: get(&self.bytes_read),
            resident_bytes: get(&self.resident),
            peak_resident_bytes: get(&self.peak),
            micro_cache_hits: get(&self.micro_hits),
            micro_cache_misses: get(&self.micro_misses),
            cache_hits: get(&self.cache_hits),
        }
    }
}

/// The cache counters of one demand-loaded texture (or a sum of them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TextureCacheStats {
    /// Tiles read from the file (a tile evicted and touched again counts again).
    pub tiles_loaded: u64,
    /// Tiles dropped from the cache to stay under its cap.
    pub tiles_evicted: u64,
    /// Bytes of the tiles read, as stored in the file (compressed).
    pub bytes_read: u64,
    /// Texel bytes of the texture's tiles resident now.
    pub resident_bytes: u64,
    /// Most texel bytes of the texture's tiles resident at once.
    pub peak_resident_bytes: u64,
    /// Tile fetches served by the fetching thread's micro-cache.
    pub micro_cache_hits: u64,
    /// Tile fetches that went past the micro-cache to the shared cache.
    pub micro_cache_misses: u64,
    /// Of those, the fetches that found the tile resident (the rest read it).
    pub cache_hits: u64,
}

impl TextureCacheStats {
    /// Share of tile fetches the micro-cache served (0 without fetches).
    pub fn micro_cache_hit_rate(&self) -> f64 {
        ratio(
            self.micro_cache_hits,
            self.micro_cache_hits + self.micro_cache_misses,
        )
    }

    /// Share of the shared cache's lookups (micro-cache misses) that found the tile
    /// resident (0 without lookups).
    pub fn cache_hit_rate(&self) -> f64 {
        ratio(self.cache_hits, self.micro_cache_misses)
    }

    /// The counters of `self` and `other` added (peaks too: a bound on the peak of the
    /// sum, which the cache itself reports exactly).
    pub fn plus(&self, other: &TextureCacheStats) -> TextureCacheStats {
        TextureCacheStats {
            tiles_loaded: self.tiles_loaded + other.tiles_loaded,
            tiles_evicted: self.tiles_evicted + other.tiles_evicted,
            bytes_read: self.bytes_read + other.bytes_read,
            resident_bytes: self.resident_bytes + other.resident_bytes,
            peak_resident_bytes: self.peak_resident_bytes + other.peak_resident_bytes,
            micro_cache_hits: self.micro_cache_hits + other.micro_cache_hits,
            micro_cache_misses: self.micro_cache_misses + other.micro_cache_misses,
            cache_hits: self.cache_hits + other.cache_hits,
        }
    }
}

fn ratio(part: u64, whole: u64) -> f64 {
    if whole == 0 {
        0.0
    } else {
        part as f64 / whole as f64
    }
}

fn locked<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(PoisonError::into_inner)
}

impl LevelTiles {
    /// `count` empty slots counted under `tally`.
    pub(crate) fn new(count: usize, tally: Arc<FileTally>) -> LevelTiles {
        LevelTiles {
            tally,
            slots: (0..count).map(|_| Mutex::default()).collect(),
        }
    }

    /// The tile in slot `index` if it is resident, marked as referenced.
    pub(crate) fn resident(&self, index: usize) -> Option<Arc<Texels>> {
        let mut slot = locked(self.slots.get(index)?);
        let tile = slot.tile.clone()?;
        slot.referenced = true;
        Some(tile)
    }

    /// Texel bytes of the level's resident tiles.
    pub(crate) fn resident_bytes(&self) -> usize {
        self.slots
            .iter()
            .filter_map(|slot| locked(slot).tile.as_ref().map(|t| t.memory_bytes()))
            .sum()
    }
}

impl TileCache {
    /// A cache holding at most `capacity` bytes of texels (see the module documentation
    /// for what comes on top).
    pub fn new(capacity: u64) -> TileCache {
        TileCache {
            capacity,
            clock: Mutex::default(),
        }
    }

    /// The process-wide cache, of [`DEFAULT_TEXTURE_CACHE_BYTES`], that
    /// `Texture::from_file` opens textures through.
    pub fn shared() -> Arc<TileCache> {
        static SHARED: LazyLock<Arc<TileCache>> =
            LazyLock::new(|| Arc::new(TileCache::new(DEFAULT_TEXTURE_CACHE_BYTES)));
        SHARED.clone()
    }

    /// The cap, in bytes.
    pub fn capacity(&self) -> u64 {
        self.capacity
    }

    /// Texel bytes resident now.
    pub fn resident_bytes(&self) -> u64 {
        locked(&self.clock).resident
    }

    /// Most texel bytes resident at once since the cache was made.
    pub fn peak_resident_bytes(&self) -> u64 {
        locked(&self.clock).peak
    }

    /// Makes `tile` resident in slot `index` of `level`, first evicting tiles in clock
    /// order until it fits under the cap.
    pub(crate) fn admit(&self, level: &Arc<LevelTiles>, index: usize, tile: Arc<Texels>) {
        let bytes = tile.memory_bytes() as u64;
        let mut clock = locked(&self.clock);
        while clock.resident + bytes > self.capacity && !clock.ring.is_empty() {
            clock.evict_one();
        }
        {
            let mut slot = locked(&level.slots[index]);
            if slot.tile.is_some() {
                // Another thread admitted it while this one read it.
                return;
            }
            slot.tile = Some(tile);
            slot.referenced = true;
        }
        clock.ring.push(ResidentTile {
            level: level.clone(),
            index,
            bytes,
        });
        clock.resident += bytes;
        clock.peak = clock.peak.max(clock.resident);
        let tally = &level.tally;
        let resident = tally.resident.fetch_add(bytes, Ordering::Relaxed) + bytes;
        tally.peak.fetch_max(resident, Ordering::Relaxed);
    }

    /// Drops every resident tile of the file counted by `tally` (its texture is gone).
    pub(crate) fn forget(&self, tally: &FileTally) {
        let mut clock = locked(&self.clock);
        let mut freed = 0;
        clock.ring.retain(|tile| {
            let keep = tile.level.tally.id != tally.id;
            if !keep {
                freed += tile.bytes;
            }
            keep
        });
        clock.resident -= freed;
        clock.hand = 0;
    }
}

impl Clock {
    /// Advances the hand to the first tile not referenced since the hand last passed it
    /// (clearing the bits of those that were) and evicts it. After two full turns without
    /// one, because lookups keep setting bits, the tile under the hand goes regardless.
    fn evict_one(&mut self) {
        let mut steps = 0;
        loop {
            if self.hand >= self.ring.len() {
                self.hand = 0;
            }
            let entry = &self.ring[self.hand];
            let mut slot = locked(&entry.level.slots[entry.index]);
            if slot.referenced && steps < 2 * self.ring.len() {
                slot.referenced = false;
                drop(slot);
                self.hand += 1;
                steps += 1;
                continue;
            }
            slot.tile = None;
            slot.referenced = false;
            drop(slot);
            let evicted = self.ring.swap_remove(self.hand);
            self.resident -= evicted.bytes;
            let tally = &evicted.level.tally;
            tally.evictions.fetch_add(1, Ordering::Relaxed);
            tally.resident.fetch_sub(evicted.bytes, Ordering::Relaxed);
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::ColorSpace;

    fn tile(value: u8) -> Arc<Texels> {
        Arc::new(Texels::bytes(vec![[value; 4]; 64 * 64], ColorSpace::Linear))
    }

    const TILE_BYTES: u64 = 64 * 64 * 4;

    #[test]
    fn resident_bytes_stay_under_the_cap_and_evictions_are_counted() {
        let cache = TileCache::new(3 * TILE_BYTES);
        let tally = Arc::new(FileTally::new());
        let level = Arc::new(LevelTiles::new(10, tally.clone()));
        for index in 0..10 {
            cache.admit(&level, index, tile(index as u8));
            assert!(cache.resident_bytes() <= 3 * TILE_BYTES);
        }
        let resident: Vec<usize> = (0..10).filter(|&i| level.resident(i).is_some()).collect();
        assert_eq!(resident.len(), 3, "{resident:?}");
        let stats = tally.snapshot();
        assert_eq!(stats.tiles_evicted, 7);
        assert_eq!(stats.resident_bytes, 3 * TILE_BYTES);
        assert_eq!(stats.peak_resident_bytes, 3 * TILE_BYTES);
        assert_eq!(cache.peak_resident_bytes(), 3 * TILE_BYTES);
        assert_eq!(level.resident_bytes() as u64, 3 * TILE_BYTES);
    }

    #[test]
    fn the_clock_spares_a_tile_referenced_since_the_hand_passed() {
        let cache = TileCache::new(2 * TILE_BYTES);
        let level = Arc::new(LevelTiles::new(4, Arc::new(FileTally::new())));
        cache.admit(&level, 0, tile(0));
        cache.admit(&level, 1, tile(1));
        // Admitting tile 2 clears both bits, then evicts tile 0 (first under the hand).
        cache.admit(&level, 2, tile(2));
        assert!(level.resident(0).is_none());
        // Tile 1 is used again; tile 2 is not: tile 2 goes for tile 3.
        assert!(level.resident(1).is_some());
        {
            let mut slot = locked(&level.slots[2]);
            slot.referenced = false;
        }
        cache.admit(&level, 3, tile(3));
        assert!(level.resident(1).is_some(), "referenced: spared");
        assert!(level.resident(2).is_none(), "unreferenced: evicted");
        assert!(level.resident(3).is_some());
    }

    #[test]
    fn a_tile_larger_than_the_cap_is_admitted_alone() {
        let cache = TileCache::new(100);
        let level = Arc::new(LevelTiles::new(2, Arc::new(FileTally::new())));
        cache.admit(&level, 0, tile(0));
        cache.admit(&level, 1, tile(1));
        assert!(level.resident(0).is_none() && level.resident(1).is_some());
        assert_eq!(cache.resident_bytes(), TILE_BYTES);
    }

    #[test]
    fn a_slot_takes_the_bytes_the_documentation_states() {
        assert_eq!(std::mem::size_of::<Mutex<TileSlot>>(), 24);
    }

    #[test]
    fn forgetting_a_file_frees_its_bytes_only() {
        let cache = TileCache::new(10 * TILE_BYTES);
        let (a, b) = (Arc::new(FileTally::new()), Arc::new(FileTally::new()));
        let level_a = Arc::new(LevelTiles::new(2, a.clone()));
        let level_b = Arc::new(LevelTiles::new(2, b));
        cache.admit(&level_a, 0, tile(0));
        cache.admit(&level_a, 1, tile(1));
        cache.admit(&level_b, 0, tile(2));
        cache.forget(&a);
        assert_eq!(cache.resident_bytes(), TILE_BYTES);
        assert_eq!(cache.peak_resident_bytes(), 3 * TILE_BYTES);
    }
}
