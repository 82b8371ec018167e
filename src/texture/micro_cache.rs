//! Each thread's last few demand-loaded tiles, in front of the shared [`super::TileCache`]
//! as OpenImageIO keeps a per-thread micro-cache in front of its ImageCache: a fetch from
//! a tile the thread used lately touches only the thread's own memory (no lock, no shared
//! write, no reference count), so lookups scale with the cores.
//!
//! An entry owns an `Arc` of its tile, so a tile stays valid while the thread reads it
//! even if the shared cache evicts it meanwhile. Entries are keyed by the level's
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

struct Entry {
    level: u64,
    index: usize,
    tile: Arc<Texels>,
    tally: Arc<FileTally>,
    /// Fetches served since the entry was made, not yet added to `tally`.
    hits: u64,
}

impl Entry {
    fn flush(&mut self) {
        if self.hits > 0 {
            self.tally
                .micro_hits
                .fetch_add(self.hits, Ordering::Relaxed);
            self.hits = 0;
        }
    }
}

struct MicroCache {
    entries: Vec<Entry>,
    /// The entry that served the last fetch: looked at first.
    last: usize,
    /// The entry a miss replaces next (round robin) once all are in use.
    victim: usize,
}

impl MicroCache {
    const fn new() -> MicroCache {
        MicroCache {
            entries: Vec::new(),
            last: 0,
            victim: 0,
        }
    }

    #[inline(always)]
    fn find(&self, level: u64, index: usize) -> Option<usize> {
        let is = |e: &Entry| e.level == level && e.index == index;
        match self.entries.get(self.last) {
            Some(e) if is(e) => Some(self.last),
            _ => self.entries.iter().position(is),
        }
    }

    /// Keeps `tile`, replacing the oldest entry when all are in use; its position.
    fn insert(
        &mut self,
        level: u64,
        index: usize,
        tile: Arc<Texels>,
        tally: Arc<FileTally>,
    ) -> usize {
        let entry = Entry {
            level,
            index,
            tile,
            tally,
            hits: 0,
        };
        if self.entries.len() < MICRO_TILES {
            self.entries.push(entry);
            return self.entries.len() - 1;
        }
        let at = self.victim;
        self.victim = (self.victim + 1) % MICRO_TILES;
        self.entries[at].flush();
        self.entries[at] = entry;
        at
    }

    fn flush(&mut self) {
        for entry in &mut self.entries {
            entry.flush();
        }
        self.entries.clear();
        self.last = 0;
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
    let mut fetch = Some(fetch);
    let mut read = Some(read);
    let served = MICRO.try_with(|cell| {
        let Ok(mut micro) = cell.try_borrow_mut() else {
            return None;
        };
        let at = match micro.find(level, index) {
            Some(at) => {
                micro.entries[at].hits += 1;
                at
            }
            None => {
                let (tile, tally) = (fetch.take()?)()?;
                micro.insert(level, index, tile, tally)
            }
        };
        micro.last = at;
        Some(read.take().map(|read| read(&micro.entries[at].tile)))
    });
    match (served, fetch, read) {
        (Ok(Some(result)), _, _) => result,
        // The fetch ran and found nothing.
        (Ok(None), None, _) => None,
        // No micro-cache on this thread (being torn down, or in use further up the stack):
        // the shared cache alone.
        (_, Some(fetch), Some(read)) => fetch().map(|(tile, _)| read(&tile)),
        _ => None,
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
        // A level id no other test uses.
        let level = u64::MAX - 7;
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
}
