//! Each thread's last few demand-loaded tiles, in front of the shared [`super::TileCache`]
//! as OpenImageIO keeps a per-thread micro-cache in front of its ImageCache: a fetch from
//! a tile the thread used lately touches only the thread's own memory (no lock, no shared
//! write, no reference count), so lookups scale with the cores.
//!
//! A lookup, or a batch of lookups, finds the thread's micro-cache once
//! ([`with_thread_tiles`]) and hands it down as a [`ThreadTiles`], as OpenImageIO hands its
//! per-thread info to every lookup; every fetch of its footprints goes to it directly. A hit compares the packed key (level id, tile
//! index) with the keys of the entries that served the last two fetches (a footprint's
//! fetches nearly always share its tile), else with all 8, adds one to a plain per-entry
//! counter and reads the tile through the entry's `Arc` without cloning it. An entry owns an `Arc` of its tile, so a tile stays valid while the thread
//! reads it even if the shared cache evicts it meanwhile. Entries are keyed by the level's
//! process-unique id and the tile's index, and tiles never change once read, so an entry
//! is never stale. Hits are counted in the entry, on the thread, and added to the file's
//! counters when the entry is replaced or the thread's micro-cache is flushed
//! ([`flush_all_threads`], at the end of every render).

use std::cell::RefCell;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use super::texels::Texels;
use super::tile_cache::FileTally;

/// Tiles a thread keeps: a trilinear lookup whose footprints straddle tile corners on
/// both levels reads 8.
pub(crate) const MICRO_TILES: usize = 8;

/// The key of an empty entry (no tile has it: see [`key_of`]).
const EMPTY: u64 = u64::MAX;

/// Tile `index` of the level with id `level` as one number, so that finding a tile is one
/// compare per entry over keys that share a cache line; `None` for ids and indices too
/// large to pack (more than 2^31 levels opened, or 2^32 tiles in a level), which bypass
/// the micro-cache.
#[inline(always)]
fn key_of(level: u64, index: usize) -> Option<u64> {
    (level < 1 << 31 && (index as u64) < 1 << 32).then_some(level << 32 | index as u64)
}

/// The keys of the tiles of a level with id `level` and `tile_count` tiles, decided once
/// when the level is opened rather than at every fetch: tile `index`'s key is the returned
/// base with `index` in its low bits. `None` when some tile's key cannot be packed (see
/// [`key_of`]): the level's fetches then bypass the micro-cache.
pub(crate) fn level_key_base(level: u64, tile_count: usize) -> Option<u64> {
    key_of(level, tile_count.saturating_sub(1)).map(|_| level << 32)
}

/// The entries as parallel arrays: the hit path scans `keys` (one cache line), bumps a
/// plain counter and reads the tile, with no atomic operation and no reference count.
struct MicroCache {
    keys: [u64; MICRO_TILES],
    tiles: [Option<Arc<Texels>>; MICRO_TILES],
    tallies: [Option<Arc<FileTally>>; MICRO_TILES],
    /// Fetches each entry served since it was made, not yet added to its tally.
    hits: [u64; MICRO_TILES],
    /// The entries that served the last two fetches, looked at before the others: the
    /// fetches of one footprint (the probes of an anisotropic lookup, the texels of an EWA
    /// one) and of neighbouring lookups nearly always read the tile the last fetch read.
    recent: [usize; 2],
    /// The entry a miss replaces next (round robin).
    victim: usize,
}

impl MicroCache {
    const fn new() -> MicroCache {
        MicroCache {
            keys: [EMPTY; MICRO_TILES],
            tiles: [const { None }; MICRO_TILES],
            tallies: [const { None }; MICRO_TILES],
            hits: [0; MICRO_TILES],
            recent: [0, 1],
            victim: 0,
        }
    }

    /// The entry holding `key`: one of the last two fetches' entries, or else any.
    #[inline(always)]
    fn find(&mut self, key: u64) -> Option<usize> {
        // The modulo keeps the indices provably in range: no bounds checks.
        let [last, before] = self.recent.map(|at| at % MICRO_TILES);
        if self.keys[last] == key {
            return Some(last);
        }
        if self.keys[before] == key {
            self.recent = [before, last];
            return Some(before);
        }
        let at = self.keys.iter().position(|&k| k == key)?;
        self.recent = [at, last];
        Some(at)
    }

    /// Adds entry `at`'s hits to its file's counters.
    fn flush_entry(&mut self, at: usize) {
        if let Some(tally) = &self.tallies[at] {
            if self.hits[at] > 0 {
                tally.micro_hits.fetch_add(self.hits[at], Ordering::Relaxed);
            }
        }
        self.hits[at] = 0;
    }

    /// Keeps `tile` in place of the oldest entry; its position.
    fn insert(&mut self, key: u64, tile: Arc<Texels>, tally: Arc<FileTally>) -> usize {
        let at = self.victim;
        self.victim = (self.victim + 1) % MICRO_TILES;
        self.flush_entry(at);
        self.keys[at] = key;
        self.tiles[at] = Some(tile);
        self.tallies[at] = Some(tally);
        self.recent = [at, self.recent[0]];
        at
    }

    fn flush(&mut self) {
        for at in 0..MICRO_TILES {
            self.flush_entry(at);
            self.keys[at] = EMPTY;
            self.tiles[at] = None;
            self.tallies[at] = None;
        }
        self.victim = 0;
    }
}

impl Drop for MicroCache {
    fn drop(&mut self) {
        self.flush();
    }
}

thread_local! {
    static MICRO: RefCell<MicroCache> = const { RefCell::new(MicroCache::new()) };
}

/// This thread's micro-cache, found once for a whole lookup or batch of lookups (the
/// counterpart of OpenImageIO's per-thread `Perthread` info handed to every lookup): the
/// filters' fetches then reach it without a thread-local access each (one lookup makes one
/// fetch per bilinear block, per step of anisotropic probes, per EWA texel), and code that
/// runs inside `simd::dispatch` receives it as an argument rather than being inlined into
/// the thread-local access, which is compiled at the baseline vector level. `None` while
/// the thread is being torn down: fetches then go to the shared cache every time.
#[derive(Clone, Copy)]
pub(crate) struct ThreadTiles<'t>(Option<&'t RefCell<MicroCache>>);

/// `body` given this thread's micro-cache: the scope of one lookup.
#[inline(always)]
pub(crate) fn with_thread_tiles<R>(body: impl FnOnce(ThreadTiles<'_>) -> R) -> R {
    let mut body = Some(body);
    let mut result = None;
    let _ = MICRO.try_with(
        #[inline(always)]
        |cell| {
            result = body.take().map(|body| body(ThreadTiles(Some(cell))));
        },
    );
    match (result, body) {
        (Some(result), _) => result,
        (None, Some(body)) => body(ThreadTiles(None)),
        (None, None) => unreachable!("the lookup ran inside the thread-local access"),
    }
}

impl ThreadTiles<'_> {
    /// No micro-cache: the lookups of a resident texture, which fetch no tile, and fetches
    /// that go to the shared cache every time.
    #[inline(always)]
    pub(crate) const fn none() -> Self {
        ThreadTiles(None)
    }

    /// `read` of tile `index` of a level whose tiles' keys start at `key_base` (from
    /// [`level_key_base`]; `index` is below the level's tile count): from the micro-cache
    /// (the tiles of the last fetches first), or else from `fetch` (the shared cache or
    /// the file), kept for the next fetches. `None` when `fetch` finds no tile (it cannot
    /// be read) or `read` gives none. (`read` returns an `Option` itself: an
    /// `Option<Option<_>>` to flatten went through memory on every fetch.)
    #[inline(always)]
    pub(crate) fn with_tile<R>(
        self,
        key_base: Option<u64>,
        index: usize,
        fetch: impl FnOnce() -> Option<(Arc<Texels>, Arc<FileTally>)>,
        read: impl FnOnce(&Texels) -> Option<R>,
    ) -> Option<R> {
        let Some(base) = key_base else {
            return fetch().and_then(|(tile, _)| read(&tile));
        };
        let key = base | index as u64;
        if let Some(mut micro) = self.0.and_then(|cell| cell.try_borrow_mut().ok()) {
            if let Some(at) = micro.find(key) {
                micro.hits[at] += 1;
                if let Some(tile) = micro.tiles[at].as_deref() {
                    return read(tile);
                }
            }
        }
        self.miss(key, fetch, read)
    }

    /// A fetch the micro-cache did not serve: the tile from `fetch`, kept in the
    /// micro-cache (unless the thread has none usable: being torn down, or in use further
    /// up the stack).
    #[cold]
    #[inline(never)]
    fn miss<R>(
        self,
        key: u64,
        fetch: impl FnOnce() -> Option<(Arc<Texels>, Arc<FileTally>)>,
        read: impl FnOnce(&Texels) -> Option<R>,
    ) -> Option<R> {
        let (tile, tally) = fetch()?;
        let result = read(&tile);
        if let Some(mut micro) = self.0.and_then(|cell| cell.try_borrow_mut().ok()) {
            micro.insert(key, tile, tally);
        }
        result
    }
}

/// Adds the hits counted in this thread's micro-cache to the files' counters and empties
/// it (releasing the tiles it kept alive).
pub(crate) fn flush_this_thread() {
    let _ = MICRO.try_with(|cell| {
        if let Ok(mut micro) = cell.try_borrow_mut() {
            micro.flush();
        }
    });
}

/// [`flush_this_thread`] on every thread of the current rayon pool and on this one: after
/// a render, so that its statistics count every hit and no evicted tile stays alive.
pub fn flush_all_threads() {
    rayon::broadcast(|_| flush_this_thread());
    flush_this_thread();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::ColorSpace;

    fn tile(value: u8) -> Arc<Texels> {
        Arc::new(Texels::bytes(vec![[value; 4]; 4], ColorSpace::Linear))
    }

    /// One fetch in a lookup of its own.
    fn fetch_tile<R>(
        level: u64,
        index: usize,
        fetch: impl FnOnce() -> Option<(Arc<Texels>, Arc<FileTally>)>,
        read: impl FnOnce(&Texels) -> R,
    ) -> Option<R> {
        let base = level_key_base(level, index + 1);
        with_thread_tiles(|tiles| tiles.with_tile(base, index, fetch, |tile| Some(read(tile))))
    }

    #[test]
    fn repeated_fetches_hit_and_the_hits_reach_the_file_when_flushed() {
        let tally = Arc::new(FileTally::new());
        let fetches = std::sync::atomic::AtomicUsize::new(0);
        let fetch = |value| {
            let tally = tally.clone();
            let fetches = &fetches;
            move || {
                fetches.fetch_add(1, Ordering::Relaxed);
                Some((tile(value), tally))
            }
        };
        // A level id no texture opened in the tests reaches.
        let level = (1 << 31) - 7;
        std::thread::scope(|scope| {
            scope
                .spawn(|| {
                    for _ in 0..5 {
                        let v = fetch_tile(level, 3, fetch(9), |t| t.get(0).x);
                        assert_eq!(v, Some(9.0 / 255.0));
                    }
                    // More tiles than the micro-cache holds: tile 3 goes and comes back.
                    for index in 10..10 + MICRO_TILES {
                        fetch_tile(level, index, fetch(1), |_| ());
                    }
                    fetch_tile(level, 3, fetch(9), |_| ());
                    assert_eq!(fetch_tile(level, 99, || None, |_| ()), None);
                    flush_this_thread();
                })
                .join()
                .unwrap();
        });
        assert_eq!(fetches.load(Ordering::Relaxed), 1 + MICRO_TILES + 1);
        assert_eq!(tally.snapshot().micro_cache_hits, 4);
    }

    #[test]
    fn fetches_of_one_lookup_get_their_own_tile_after_the_recent_ones_are_replaced() {
        let tally = Arc::new(FileTally::new());
        let level = (1 << 31) - 9;
        let value = |index: usize| (index % 200) as u8;
        std::thread::scope(|scope| {
            scope
                .spawn(|| {
                    with_thread_tiles(|tiles| {
                        // Tile 0, then more tiles than the micro-cache holds (replacing
                        // the entries the last fetches used), then tile 0 again, twice.
                        for index in [0, 0].into_iter().chain(1..=MICRO_TILES).chain([0, 0]) {
                            let fetch = || Some((tile(value(index)), tally.clone()));
                            let base = level_key_base(level, MICRO_TILES + 1);
                            let v = tiles.with_tile(base, index, fetch, |t| Some(t.get(0).x));
                            assert_eq!(v, Some(f32::from(value(index)) / 255.0), "{index}");
                        }
                    });
                    flush_this_thread();
                })
                .join()
                .unwrap();
        });
        // Tile 0's second and fourth fetches were hits; the others read a tile.
        assert_eq!(tally.snapshot().micro_cache_hits, 2);
    }

    #[test]
    fn a_key_too_large_to_pack_bypasses_the_micro_cache_with_the_same_answers() {
        let tally = Arc::new(FileTally::new());
        let fetches = std::sync::atomic::AtomicUsize::new(0);
        let fetch = || {
            fetches.fetch_add(1, Ordering::Relaxed);
            Some((tile(5), tally.clone()))
        };
        assert_eq!(key_of(1 << 31, 0), None);
        assert_eq!(key_of(3, 1 << 32), None);
        assert_eq!(key_of(3, 2), Some(3 << 32 | 2));
        assert_eq!(level_key_base(3, 1 << 32), Some(3 << 32));
        assert_eq!(level_key_base(3, (1 << 32) + 1), None);
        assert_eq!(level_key_base(1 << 31, 1), None);
        std::thread::scope(|scope| {
            scope
                .spawn(|| {
                    for _ in 0..3 {
                        let v = fetch_tile(1 << 31, 0, fetch, |t| t.get(0).x);
                        assert_eq!(v, Some(5.0 / 255.0));
                    }
                    flush_this_thread();
                })
                .join()
                .unwrap();
        });
        assert_eq!(fetches.load(Ordering::Relaxed), 3);
        assert_eq!(tally.snapshot().micro_cache_hits, 0);
    }
}
