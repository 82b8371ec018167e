//! Each thread's last few demand-loaded tiles, in front of the shared [`super::TileCache`]
//! as OpenImageIO keeps a per-thread micro-cache in front of its ImageCache: a fetch from
//! a tile the thread used lately touches only the thread's own memory (no lock, no shared
//! write, no reference count), so lookups scale with the cores.
//!
//! A hit compares the packed key (level id, tile index) with the thread's 8 keys, adds one
//! to a plain per-entry counter and reads the tile through the entry's `Arc` without
//! cloning it. An entry owns an `Arc` of its tile, so a tile stays valid while the thread
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

/// The entries as parallel arrays: the hit path scans `keys` (one cache line), bumps a
/// plain counter and reads the tile, with no atomic operation and no reference count.
struct MicroCache {
    keys: [u64; MICRO_TILES],
    tiles: [Option<Arc<Texels>>; MICRO_TILES],
    tallies: [Option<Arc<FileTally>>; MICRO_TILES],
    /// Fetches each entry served since it was made, not yet added to its tally.
    hits: [u64; MICRO_TILES],
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
            victim: 0,
        }
    }

    #[inline(always)]
    fn find(&self, key: u64) -> Option<usize> {
        self.keys.iter().position(|&k| k == key)
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

/// `read` of tile `index` of the level with id `level`: from this thread's micro-cache,
/// or else from `fetch` (the shared cache or the file), kept for the next fetches. `None`
/// when `fetch` finds no tile (it cannot be read).
#[inline(always)]
pub(crate) fn with_tile<R>(
    level: u64,
    index: usize,
    fetch: impl FnOnce() -> Option<(Arc<Texels>, Arc<FileTally>)>,
    read: impl FnOnce(&Texels) -> R,
) -> Option<R> {
    let Some(key) = key_of(level, index) else {
        return fetch().map(|(tile, _)| read(&tile));
    };
    let mut read = Some(read);
    let hit = MICRO.try_with(
        #[inline(always)]
        |cell| {
            let mut micro = cell.try_borrow_mut().ok()?;
            let at = micro.find(key)?;
            micro.hits[at] += 1;
            let tile = micro.tiles[at].as_deref()?;
            read.take().map(|read| read(tile))
        },
    );
    match (hit, read) {
        (Ok(Some(result)), _) => Some(result),
        (_, Some(read)) => miss(key, fetch, read),
        // `read` ran: it returned its result above.
        (_, None) => None,
    }
}

/// A fetch the micro-cache did not serve: the tile from `fetch`, kept in the micro-cache
/// (unless the thread has none usable: being torn down, or in use further up the stack).
#[cold]
#[inline(never)]
fn miss<R>(
    key: u64,
    fetch: impl FnOnce() -> Option<(Arc<Texels>, Arc<FileTally>)>,
    read: impl FnOnce(&Texels) -> R,
) -> Option<R> {
    let (tile, tally) = fetch()?;
    let result = read(&tile);
    let _ = MICRO.try_with(|cell| {
        if let Ok(mut micro) = cell.try_borrow_mut() {
            micro.insert(key, tile, tally);
        }
    });
    Some(result)
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
                        let v = with_tile(level, 3, fetch(9), |t| t.get(0).x);
                        assert_eq!(v, Some(9.0 / 255.0));
                    }
                    // More tiles than the micro-cache holds: tile 3 goes and comes back.
                    for index in 10..10 + MICRO_TILES {
                        with_tile(level, index, fetch(1), |_| ());
                    }
                    with_tile(level, 3, fetch(9), |_| ());
                    assert_eq!(with_tile(level, 99, || None, |_| ()), None);
                    flush_this_thread();
                })
                .join()
                .unwrap();
        });
        assert_eq!(fetches.load(Ordering::Relaxed), 1 + MICRO_TILES + 1);
        assert_eq!(tally.snapshot().micro_cache_hits, 4);
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
        std::thread::scope(|scope| {
            scope
                .spawn(|| {
                    for _ in 0..3 {
                        let v = with_tile(1 << 31, 0, fetch, |t| t.get(0).x);
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
