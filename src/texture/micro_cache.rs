//! Each thread's last few demand-loaded tiles, in front of the shared [`super::TileCache`]
//! as OpenImageIO keeps a per-thread micro-cache in front of its ImageCache: a fetch from
//! a tile the thread used lately touches only the thread's own memory (no lock, no shared
//! write, no reference count), so lookups scale with the cores.
//!
//! A lookup, or a batch of lookups, finds the thread's micro-cache once
//! ([`with_thread_tiles`]) and hands it down as a [`ThreadTiles`], as OpenImageIO hands its
//! per-thread info to every lookup; every fetch of its footprints goes to it directly. A
//! hit compares the packed key (level id, tile index) with the keys of the entries that
//! served the last two fetches (a footprint's fetches nearly always share its tile), else
//! with all 8, adds one to a plain per-entry counter and reads the tile through the entry's
//! `Arc` without cloning it. An entry owns an `Arc` of its tile, so a tile stays valid while
//! the thread reads it even if the shared cache evicts it meanwhile. Entries are keyed by
//! the level's process-unique id and the tile's index, and tiles never change once read, so
//! an entry is never stale.
//!
//! The counters are the thread's too: hits, misses and the misses the shared cache served
//! are counted per file in plain integers and added to the files' atomic counters when the
//! thread's micro-cache is flushed ([`flush_all_threads`], at the end of every render). A
//! miss then makes no atomic operation of its own beyond taking its tile from the shared
//! cache; each one is a full barrier on x86, which would hold back the cache misses of the
//! lookups around it.

use std::cell::RefCell;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use super::texels::Texels;
use super::tile_cache::FileTally;

/// Tiles a thread keeps: a trilinear lookup whose footprints straddle tile corners on
/// both levels reads 8.
pub(crate) const MICRO_TILES: usize = 8;

/// Files whose counters a thread keeps at once; a thread that reads more files in turn
/// adds the oldest one's counts to its file and reuses its place.
const COUNTED_FILES: usize = 16;

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

/// A tile that a fetch missing the micro-cache found: in the shared cache, or read from
/// its file.
pub(crate) struct FetchedTile<'f> {
    pub(crate) tile: Arc<Texels>,
    /// The counters of the tile's file.
    pub(crate) tally: &'f Arc<FileTally>,
    /// Whether the shared cache held the tile (else this fetch read it from the file).
    pub(crate) from_cache: bool,
}

impl FetchedTile<'_> {
    /// Counts this miss straight into its file's counters: for fetches that bypass the
    /// micro-cache.
    fn count_in_file(&self) {
        self.tally.micro_misses.fetch_add(1, Ordering::Relaxed);
        if self.from_cache {
            self.tally.cache_hits.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// One file's counts on this thread, not yet added to its counters.
struct FileCounts {
    tally: Arc<FileTally>,
    micro_hits: u64,
    micro_misses: u64,
    cache_hits: u64,
}

impl FileCounts {
    fn new(tally: Arc<FileTally>) -> FileCounts {
        FileCounts {
            tally,
            micro_hits: 0,
            micro_misses: 0,
            cache_hits: 0,
        }
    }

    /// Adds the counts to the file's counters.
    fn flush(self) {
        for (counter, count) in [
            (&self.tally.micro_hits, self.micro_hits),
            (&self.tally.micro_misses, self.micro_misses),
            (&self.tally.cache_hits, self.cache_hits),
        ] {
            if count > 0 {
                counter.fetch_add(count, Ordering::Relaxed);
            }
        }
    }
}

/// The entries as parallel arrays: the hit path scans `keys` (one cache line), bumps a
/// plain counter and reads the tile, with no atomic operation and no reference count.
struct MicroCache {
    keys: [u64; MICRO_TILES],
    tiles: [Option<Arc<Texels>>; MICRO_TILES],
    /// The place in `files` of each entry's file.
    file_of: [usize; MICRO_TILES],
    /// Fetches each entry served since it was made, not yet added to its file's counts.
    hits: [u64; MICRO_TILES],
    /// The entries that served the last two fetches, looked at before the others: the
    /// fetches of one footprint (the probes of an anisotropic lookup, the texels of an EWA
    /// one) and of neighbouring lookups nearly always read the tile the last fetch read.
    recent: [usize; 2],
    /// The entry a miss replaces next (round robin).
    victim: usize,
    /// The counts of the files this thread read lately.
    files: [Option<FileCounts>; COUNTED_FILES],
    /// The place in `files` a new file takes next (round robin).
    file_victim: usize,
}

impl MicroCache {
    const fn new() -> MicroCache {
        MicroCache {
            keys: [EMPTY; MICRO_TILES],
            tiles: [const { None }; MICRO_TILES],
            file_of: [0; MICRO_TILES],
            hits: [0; MICRO_TILES],
            recent: [0, 1],
            victim: 0,
            files: [const { None }; COUNTED_FILES],
            file_victim: 0,
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

    /// Empties entry `at`, adding its hits to its file's counts.
    fn release(&mut self, at: usize) {
        if self.hits[at] > 0 {
            if let Some(counts) = self.files[self.file_of[at] % COUNTED_FILES].as_mut() {
                counts.micro_hits += self.hits[at];
            }
        }
        self.hits[at] = 0;
        self.keys[at] = EMPTY;
        self.tiles[at] = None;
    }

    /// The place in `files` of the file counted by `tally`, given one (the oldest file's
    /// place, its counts flushed and its entries released) if the thread has none.
    fn file_place(&mut self, tally: &Arc<FileTally>) -> usize {
        let counted = |counts: &Option<FileCounts>| {
            counts
                .as_ref()
                .is_some_and(|counts| Arc::ptr_eq(&counts.tally, tally))
        };
        if let Some(place) = self.files.iter().position(counted) {
            return place;
        }
        let place = self.file_victim;
        self.file_victim = (place + 1) % COUNTED_FILES;
        for at in 0..MICRO_TILES {
            if self.keys[at] != EMPTY && self.file_of[at] == place {
                self.release(at);
            }
        }
        if let Some(counts) = self.files[place].take() {
            counts.flush();
        }
        self.files[place] = Some(FileCounts::new(tally.clone()));
        place
    }

    /// Keeps `fetched` under `key` in place of the oldest entry, counting the miss.
    fn insert(&mut self, key: u64, fetched: FetchedTile<'_>) {
        let at = self.victim;
        self.victim = (self.victim + 1) % MICRO_TILES;
        self.release(at);
        let place = self.file_place(fetched.tally);
        if let Some(counts) = self.files[place].as_mut() {
            counts.micro_misses += 1;
            counts.cache_hits += u64::from(fetched.from_cache);
        }
        self.keys[at] = key;
        self.tiles[at] = Some(fetched.tile);
        self.file_of[at] = place;
        self.recent = [at, self.recent[0]];
    }

    /// Empties the entries and adds every count to the files' counters.
    fn flush(&mut self) {
        for at in 0..MICRO_TILES {
            self.release(at);
        }
        for counts in &mut self.files {
            if let Some(counts) = counts.take() {
                counts.flush();
            }
        }
        self.victim = 0;
        self.file_victim = 0;
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
    pub(crate) fn with_tile<'f, R>(
        self,
        key_base: Option<u64>,
        index: usize,
        fetch: impl FnOnce() -> Option<FetchedTile<'f>>,
        read: impl FnOnce(&Texels) -> Option<R>,
    ) -> Option<R> {
        let Some(base) = key_base else {
            return fetch().and_then(|fetched| {
                fetched.count_in_file();
                read(&fetched.tile)
            });
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
    /// up the stack, when the miss is counted in its file at once).
    #[cold]
    #[inline(never)]
    fn miss<'f, R>(
        self,
        key: u64,
        fetch: impl FnOnce() -> Option<FetchedTile<'f>>,
        read: impl FnOnce(&Texels) -> Option<R>,
    ) -> Option<R> {
        let fetched = fetch()?;
        let result = read(&fetched.tile);
        match self.0.and_then(|cell| cell.try_borrow_mut().ok()) {
            Some(mut micro) => micro.insert(key, fetched),
            None => fetched.count_in_file(),
        }
        result
    }
}

/// Adds the counts of this thread's micro-cache to the files' counters and empties it
/// (releasing the tiles it kept alive).
pub(crate) fn flush_this_thread() {
    let _ = MICRO.try_with(|cell| {
        if let Ok(mut micro) = cell.try_borrow_mut() {
            micro.flush();
        }
    });
}

/// [`flush_this_thread`] on every thread of the current rayon pool and on this one: after
/// a render, so that its statistics count every fetch and no evicted tile stays alive.
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

    /// A tile of `value` from the shared cache, counted in `tally`.
    fn cached(value: u8, tally: &Arc<FileTally>) -> Option<FetchedTile<'_>> {
        Some(FetchedTile {
            tile: tile(value),
            tally,
            from_cache: true,
        })
    }

    /// One fetch in a lookup of its own.
    fn fetch_tile<'f, R>(
        level: u64,
        index: usize,
        fetch: impl FnOnce() -> Option<FetchedTile<'f>>,
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
            let (tally, fetches) = (&tally, &fetches);
            move || {
                // The first fetch reads the file, the others find the tile in the cache.
                let first = fetches.fetch_add(1, Ordering::Relaxed) == 0;
                Some(FetchedTile {
                    tile: tile(value),
                    tally,
                    from_cache: !first,
                })
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
                    // Counted on the thread until it flushes.
                    assert_eq!(tally.snapshot(), Default::default());
                    flush_this_thread();
                })
                .join()
                .unwrap();
        });
        assert_eq!(fetches.load(Ordering::Relaxed), 1 + MICRO_TILES + 1);
        let stats = tally.snapshot();
        assert_eq!(stats.micro_cache_hits, 4);
        assert_eq!(stats.micro_cache_misses, 1 + MICRO_TILES as u64 + 1);
        assert_eq!(stats.cache_hits, MICRO_TILES as u64 + 1);
    }

    #[test]
    fn a_thread_reading_more_files_than_it_counts_at_once_counts_every_fetch() {
        let files = COUNTED_FILES + 5;
        let tallies: Vec<Arc<FileTally>> = (0..files).map(|_| Arc::new(FileTally::new())).collect();
        let level = |file: usize| (1 << 31) - 100 - file as u64;
        std::thread::scope(|scope| {
            scope
                .spawn(|| {
                    // Each file's tile twice in a row (a miss, then a hit), files in turn,
                    // twice over: the second round misses again, since 8 entries cannot
                    // hold 21 tiles.
                    for _ in 0..2 {
                        for (file, tally) in tallies.iter().enumerate() {
                            for _ in 0..2 {
                                let v =
                                    fetch_tile(level(file), 0, || cached(7, tally), |t| t.get(0).x);
                                assert_eq!(v, Some(7.0 / 255.0));
                            }
                        }
                    }
                    flush_this_thread();
                })
                .join()
                .unwrap();
        });
        for (file, tally) in tallies.iter().enumerate() {
            let stats = tally.snapshot();
            assert_eq!(
                (
                    stats.micro_cache_misses,
                    stats.micro_cache_hits,
                    stats.cache_hits
                ),
                (2, 2, 2),
                "file {file}"
            );
        }
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
                            let fetch = || cached(value(index), &tally);
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
            cached(5, &tally)
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
        let stats = tally.snapshot();
        assert_eq!((stats.micro_cache_hits, stats.micro_cache_misses), (0, 3));
    }
}
