//! `conetrace bench textures`: single-thread lookups per second for every filter, printed
//! as a markdown table, on one tiled, mip-mapped `.tx` (made by `maketx`) read three ways:
//! decoded whole (resident), tile by tile through the texture cache under a cap (cached),
//! and by OpenImageIO's TextureSystem with its ImageCache under the same cap, all on the
//! same queries. OpenImageIO is called from C++: bench/oiio_texture_bench.cpp, whose text is
//! built into the program (so that it runs from any directory) and compiled against
//! Debian's libopenimageio-dev when the benchmark starts.
//!
//! Query sets decide the cache's hit rate: lookups laid out as a render makes them
//! (neighbouring lookups read the same tiles, so nearly every tile fetch hits the thread's
//! micro-cache) and lookups at random places (nearly every fetch misses it); a second,
//! small cap adds evictions and reads from the file. Each row reports the micro-cache hit
//! rate and tiles loaded that the cached run measured, so the rate is read beside the hit
//! rate that produced it.
//!
//! The C++ side calls `TextureSystem::texture()` with a texture handle resolved once and the
//! thread's `Perthread` info, the fastest calls OpenImageIO offers a renderer, so its rate
//! is OpenImageIO's own, with no interpreter in between. This is a measurement tool, never
//! a test.
//!
//! Both sides are timed by the CPU time of the measuring thread (Linux
//! `CLOCK_THREAD_CPUTIME_ID`), not by the wall clock:
//! on a shared machine with more runnable jobs than cores, wall time mostly measures
//! the other jobs. `--wall-clock` restores wall-clock timing on both sides. Each row times
//! its resident and cached lookups in alternating slices, so that the other jobs' weight
//! on the caches (which CPU time does not remove) changes both alike and the ratio of the
//! two holds still while each rate moves with the load.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use std::sync::Arc;

use crate::texture::{
    ColorSpace, FilterMode, FilterOptions, Texture, TextureQuery, TileCache, WrapMode,
};

/// Arguments of `bench-textures`.
#[derive(clap::Args, Debug)]
pub struct BenchTexturesArgs {
    /// Texture to benchmark (made into a 64x64-tiled `.tx` by `maketx --filter box`);
    /// default: a generated 1024x1024 float noise texture.
    pub texture: Option<PathBuf>,
    /// Number of distinct queries per query set.
    #[arg(long, default_value_t = 100_000)]
    pub queries: usize,
    /// Minimum measuring time per row for each of our sides (resident, cached), in seconds.
    #[arg(long, default_value_t = 1.0)]
    pub seconds: f64,
    /// Anisotropy limit.
    #[arg(long, default_value_t = 16.0)]
    pub max_aniso: f32,
    /// Only these filters (comma-separated); default: all.
    #[arg(long, value_delimiter = ',')]
    pub filters: Vec<FilterMode>,
    /// Only these query sets (comma-separated: coherent, random, aniso16); default: all.
    #[arg(long, value_delimiter = ',')]
    pub query_sets: Vec<QuerySet>,
    /// Cap of the texture cache, ours and OIIO's ImageCache (`max_memory_MB`), e.g. 256M.
    #[arg(long, value_name = "SIZE", default_value = "256M",
          value_parser = crate::render::memory::parse_memory_size)]
    pub cache: u64,
    /// A second, small cap whose rows add evictions (tiles read again from the file); the
    /// default holds 16 float tiles. Equal to `--cache` to skip those rows.
    #[arg(long, value_name = "SIZE", default_value = "1M",
          value_parser = crate::render::memory::parse_memory_size)]
    pub small_cache: Option<u64>,
    /// Skip the OpenImageIO side.
    #[arg(long)]
    pub no_oiio: bool,
    /// C++ compiler that builds the OpenImageIO side against libopenimageio-dev.
    #[arg(long, default_value = "c++")]
    pub cxx: PathBuf,
    /// C++ source of the OpenImageIO side [default: the copy of
    /// bench/oiio_texture_bench.cpp built into conetrace].
    #[arg(long)]
    pub oiio_source: Option<PathBuf>,
    /// Time by the wall clock instead of the thread's CPU time (both sides).
    #[arg(long)]
    pub wall_clock: bool,
    /// Queries per `Texture::sample_batch` call in the batched columns, as the shading
    /// lanes look up a texture once per material run of a wave (the default: a 16x16
    /// tile's camera hits at 1 spp). 0 skips the batched columns.
    #[arg(long, default_value_t = 256)]
    pub batch: usize,
}

/// How a timed pass makes its lookups.
#[derive(Clone, Copy, PartialEq)]
enum Calls {
    /// `Texture::sample` per query: the scalar shading path's and the C API's lookups.
    Single,
    /// `Texture::sample_batch` per this many queries: the shading lanes' lookups, the
    /// filter, storage kind and micro-cache found once per call.
    Batched(usize),
}

/// Every query of `queries` looked up once through `calls`; the sum of the results.
#[inline(never)]
fn look_up_all(
    tex: &Texture,
    queries: &[TextureQuery],
    opts: &FilterOptions,
    calls: Calls,
    out: &mut Vec<glam::Vec4>,
) -> glam::Vec4 {
    let mut acc = glam::Vec4::ZERO;
    match calls {
        Calls::Single => {
            for q in queries {
                acc += tex.sample(black_box(q), opts);
            }
        }
        Calls::Batched(size) => {
            for chunk in queries.chunks(size.max(1)) {
                out.resize(chunk.len(), glam::Vec4::ZERO);
                tex.sample_batch(black_box(chunk), opts, None, out);
                acc += out.iter().copied().sum::<glam::Vec4>();
            }
        }
    }
    acc
}

/// A stopwatch on the wall clock or on the calling thread's CPU time.
#[derive(Clone, Copy)]
enum Clock {
    Wall(Instant),
    ThreadCpu(Duration),
}

impl Clock {
    fn start(wall: bool) -> Clock {
        match thread_cpu_time() {
            Some(t) if !wall => Clock::ThreadCpu(t),
            _ => Clock::Wall(Instant::now()),
        }
    }

    fn elapsed(&self) -> Duration {
        match *self {
            Clock::Wall(start) => start.elapsed(),
            Clock::ThreadCpu(start) => thread_cpu_time()
                .map(|now| now.saturating_sub(start))
                .unwrap_or_default(),
        }
    }
}

/// CPU time consumed by the calling thread (Linux), or `None` where unavailable.
#[cfg(target_os = "linux")]
fn thread_cpu_time() -> Option<Duration> {
    use nix::time::{clock_gettime, ClockId};
    let now = clock_gettime(ClockId::CLOCK_THREAD_CPUTIME_ID).ok()?;
    let (seconds, nanos) = (now.tv_sec(), now.tv_nsec());
    (seconds >= 0 && (0..1_000_000_000).contains(&nanos))
        .then(|| Duration::new(seconds as u64, nanos as u32))
}

#[cfg(not(target_os = "linux"))]
fn thread_cpu_time() -> Option<Duration> {
    None
}

/// bench/oiio_texture_bench.cpp, compiled when `--oiio-source` is not given.
const OIIO_SOURCE: &str = include_str!("../../bench/oiio_texture_bench.cpp");

/// The line of a failed command's standard error that says what went wrong: the first
/// one naming an error (a compiler's first diagnostic), else the last one.
fn failure_line(stderr: &str) -> &str {
    let mut lines = stderr
        .lines()
        .map(str::trim)
        .filter(|line| !line.is_empty());
    lines
        .clone()
        .find(|line| line.contains("error"))
        .or_else(|| lines.next_back())
        .unwrap_or("no message")
}

/// The OpenImageIO side, compiled: the program and the source it was compiled from (which
/// its failures name, the program living in a temporary directory).
struct OiioProgram {
    program: PathBuf,
    source: PathBuf,
}

/// The OpenImageIO side's program: `--oiio-source` (which must be a file), else the
/// built-in copy written into `work`, compiled with `--cxx` into `work`.
fn oiio_program(args: &BenchTexturesArgs, work: &Path) -> Result<OiioProgram, String> {
    let source = match &args.oiio_source {
        Some(path) if path.is_file() => path.clone(),
        Some(path) => return Err(format!("{}: --oiio-source: no such file", path.display())),
        None => {
            let path = work.join("oiio_texture_bench.cpp");
            std::fs::write(&path, OIIO_SOURCE)
                .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
            path
        }
    };
    let program = work.join("oiio_texture_bench");
    let out = Command::new(&args.cxx)
        .args(["-O2", "-std=c++17"])
        .arg(&source)
        .arg("-o")
        .arg(&program)
        .args(["-lOpenImageIO", "-lOpenImageIO_Util"])
        .output()
        .map_err(|e| {
            format!(
                "{}: cannot run ({e}); run `bash scripts/setup.sh`",
                args.cxx.display()
            )
        })?;
    if !out.status.success() {
        return Err(format!(
            "{}: cannot compile with {}: {}",
            source.display(),
            args.cxx.display(),
            failure_line(&String::from_utf8_lossy(&out.stderr))
        ));
    }
    Ok(OiioProgram { program, source })
}

/// Queries of one set: how they are laid out, hence how often a lookup finds its tiles in
/// the thread's micro-cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum QuerySet {
    /// A rendered image's lookups in the order a render makes them: 16x16-pixel work
    /// tiles in raster order, each band of 16 pixel rows one plane with its own
    /// derivatives (random levels, anisotropy 1-4, random angles). Neighbouring lookups
    /// read the same texture tiles: the high hit rate.
    Coherent,
    /// The same derivatives, but every lookup at its own random place and scale: nearly
    /// every lookup misses the micro-cache, the low hit rate.
    Random,
    /// The coherent layout with anisotropy 20, clamped to the limit 16: 31 probes per
    /// level.
    Aniso16,
}

impl QuerySet {
    fn name(self) -> &'static str {
        match self {
            QuerySet::Coherent => "coherent",
            QuerySet::Random => "random",
            QuerySet::Aniso16 => "aniso16",
        }
    }
}

/// One row of the table: a filter on a query set under a cache cap.
struct Row {
    filter: FilterMode,
    set: QuerySet,
    cap: u64,
    cached: CachedRun,
    /// OpenImageIO's ns per lookup on the row's queries.
    oiio_ns: Option<f64>,
}

/// The demand-loaded side of a row: its rate, the resident rate timed beside it, and what
/// the cache did while it was timed.
struct CachedRun {
    per_sec: f64,
    resident_per_sec: f64,
    /// The two rates of lookups made in batches (`--batch`), timed after the single ones.
    batched: Option<(f64, f64)>,
    micro_hit_rate: f64,
    tiles_loaded: u64,
}

/// Deterministic queries of `set` over a texture whose smaller side is `size` texels. With
/// `level0` (for the filters that read level 0 alone, closest and bilinear) the minor axis
/// spans 0.5-2 texels of level 0 per pixel, as a render of a texture seen near its
/// resolution; otherwise 0.5-512, so the mip-mapped filters read every level.
fn query_set(set: QuerySet, level0: bool, n: usize, size: u32) -> Vec<TextureQuery> {
    const ROW: usize = 256;
    const WORK_TILE: usize = 16;
    let mut state = 0x9e37_79b9_7f4a_7c15u64 ^ set.name().len() as u64;
    let mut rnd = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let texel = 1.0 / size as f32;
    let plane_at = |rnd: &mut dyn FnMut() -> f32| {
        let angle = rnd() * std::f32::consts::PI;
        let (minor, ratio) = if set == QuerySet::Aniso16 {
            (texel * 2f32.powf(rnd() * 4.0), 20.0)
        } else {
            let octaves = if level0 { 2.0 } else { 10.0 };
            (texel * 2f32.powf(rnd() * octaves - 1.0), 1.0 + 3.0 * rnd())
        };
        let major = minor * ratio;
        let (sn, cs) = angle.sin_cos();
        TextureQuery {
            s: rnd(),
            t: rnd(),
            dsdx: major * cs,
            dtdx: major * sn,
            dsdy: -minor * sn,
            dtdy: minor * cs,
        }
    };
    let mut out = Vec::with_capacity(n);
    let mut plane = TextureQuery::default();
    let band = ROW * WORK_TILE;
    for k in 0..n {
        if set == QuerySet::Random {
            out.push(plane_at(&mut rnd));
            continue;
        }
        if k % band == 0 {
            plane = plane_at(&mut rnd);
        }
        // Pixel (px, py) of the band: work tile after work tile, each in raster order.
        let in_band = k % band;
        let (tile, in_tile) = (
            in_band / (WORK_TILE * WORK_TILE),
            in_band % (WORK_TILE * WORK_TILE),
        );
        let px = tile * WORK_TILE + in_tile % WORK_TILE;
        let py = in_tile / WORK_TILE;
        let (fx, fy) = (px as f32, py as f32);
        out.push(TextureQuery {
            s: plane.s + fx * plane.dsdx + fy * plane.dsdy,
            t: plane.t + fx * plane.dtdx + fy * plane.dtdy,
            ..plane
        });
    }
    out
}

fn noise_texture(size: u32) -> Vec<[f32; 4]> {
    let mut x = 0x1234_5678u32;
    (0..size * size)
        .map(|_| {
            std::array::from_fn(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                (x >> 8) as f32 / (1u32 << 24) as f32
            })
        })
        .collect()
}

/// Slices per side in [`measure_alternating`].
const ALTERNATIONS: u32 = 8;

/// One untimed pass over the query set (it opens the files and fills the caches, as OIIO's
/// side does).
fn warm(tex: &Texture, queries: &[TextureQuery], opts: &FilterOptions) {
    black_box(look_up_all(
        tex,
        queries,
        opts,
        Calls::Single,
        &mut Vec::new(),
    ));
}

/// Lookups made and time taken repeating the query set for at least `min_time` (at least
/// one pass).
fn time_lookups(
    tex: &Texture,
    queries: &[TextureQuery],
    opts: &FilterOptions,
    calls: Calls,
    min_time: Duration,
    wall: bool,
) -> (usize, Duration) {
    let mut acc = glam::Vec4::ZERO;
    let mut done = 0usize;
    let mut out = Vec::new();
    let start = Clock::start(wall);
    loop {
        acc += look_up_all(tex, queries, opts, calls, &mut out);
        done += queries.len();
        if start.elapsed() >= min_time {
            break;
        }
    }
    black_box(acc);
    (done, start.elapsed())
}

/// Lookups per second on one thread of `resident` and of `cached`, made through `calls`,
/// after one untimed pass each: the two are timed in alternating slices of `min_time / ALTERNATIONS` until each
/// has had `min_time`, so a change of load during the row weighs on both. A side whose
/// passes take longer than that (a cap that evicts) simply takes fewer slices.
fn measure_alternating(
    resident: &Texture,
    cached: &Texture,
    queries: &[TextureQuery],
    opts: &FilterOptions,
    calls: Calls,
    min_time: Duration,
    wall: bool,
) -> (f64, f64) {
    warm(resident, queries, opts);
    warm(cached, queries, opts);
    let slice = min_time / ALTERNATIONS;
    let mut totals = [(0usize, Duration::ZERO); 2];
    while totals.iter().any(|&(_, time)| time < min_time) {
        for (total, tex) in totals.iter_mut().zip([resident, cached]) {
            if total.1 < min_time {
                let (done, time) = time_lookups(tex, queries, opts, calls, slice, wall);
                total.0 += done;
                total.1 += time;
            }
        }
    }
    let [resident_rate, cached_rate] = totals.map(|(done, time)| done as f64 / time.as_secs_f64());
    (resident_rate, cached_rate)
}

/// [`measure_alternating`] of `resident` and of `tx` demand-loaded into a fresh cache of
/// `cap` bytes, single lookups and then, unless `batch` is 0, batches of `batch`; with the
/// micro-cache hit rate and the tiles read over the whole run.
#[allow(clippy::too_many_arguments)]
fn measure_cached(
    resident: &Texture,
    tx: &Path,
    cap: u64,
    queries: &[TextureQuery],
    opts: &FilterOptions,
    batch: usize,
    min_time: Duration,
    wall: bool,
) -> Result<CachedRun, String> {
    let cache = Arc::new(TileCache::new(cap));
    let tex = Texture::from_file_in(tx, ColorSpace::Linear, &cache).map_err(|e| e.to_string())?;
    if !tex.is_demand_loaded() {
        return Err(format!(
            "{}: not read tile by tile (a tiled, mip-mapped TIFF is needed)",
            tx.display()
        ));
    }
    let (resident_per_sec, per_sec) =
        measure_alternating(resident, &tex, queries, opts, Calls::Single, min_time, wall);
    let batched = (batch > 0).then(|| {
        let calls = Calls::Batched(batch);
        measure_alternating(resident, &tex, queries, opts, calls, min_time, wall)
    });
    crate::texture::flush_micro_caches();
    if let Some(failure) = tex.tile_failure() {
        return Err(failure.to_string());
    }
    let stats = tex.cache_stats().unwrap_or_default();
    Ok(CachedRun {
        per_sec,
        resident_per_sec,
        batched,
        micro_hit_rate: stats.micro_cache_hit_rate(),
        tiles_loaded: stats.tiles_loaded,
    })
}

fn write_queries(path: &Path, queries: &[TextureQuery]) -> Result<(), String> {
    let mut text = String::from("s,t,dsdx,dtdx,dsdy,dtdy\n");
    for q in queries {
        text.push_str(&format!(
            "{},{},{},{},{},{}\n",
            q.s, q.t, q.dsdx, q.dtdx, q.dsdy, q.dtdy
        ));
    }
    std::fs::write(path, text).map_err(|e| format!("{}: cannot write queries: {e}", path.display()))
}

/// OIIO timings from the C++ side, in ns per lookup.
struct OiioTimes {
    /// The ImageCache's `max_memory_MB` as OIIO reports it after the program set it.
    cache_mb: Option<f64>,
    /// Per filter.
    filters: Vec<(String, f64)>,
}

fn run_oiio(
    args: &BenchTexturesArgs,
    oiio: &OiioProgram,
    tx: &Path,
    queries: &Path,
    filters: &[FilterMode],
    cap: u64,
) -> Result<OiioTimes, String> {
    let names: Vec<String> = filters.iter().map(|f| f.to_string()).collect();
    let mut command = Command::new(&oiio.program);
    command
        .arg(tx)
        .arg(queries)
        .arg(names.join(","))
        .arg(args.max_aniso.to_string())
        .arg((cap as f64 / MIB).to_string())
        .arg(args.seconds.max(0.01).to_string());
    if args.wall_clock {
        command.arg("wall");
    }
    let out = command
        .output()
        .map_err(|e| format!("{} (compiled): cannot run: {e}", oiio.source.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{} (compiled): failed ({}): {}",
            oiio.source.display(),
            out.status,
            failure_line(&String::from_utf8_lossy(&out.stderr))
        ));
    }
    parse_oiio_output(&String::from_utf8_lossy(&out.stdout), &oiio.source)
}

/// Lines "cache_mb <MB>" and "<filter> <ns>".
fn parse_oiio_output(text: &str, source: &Path) -> Result<OiioTimes, String> {
    let mut cache_mb = None;
    let mut filters = Vec::new();
    for line in text.lines() {
        let mut parts = line.split_whitespace();
        if let (Some(k), Some(v)) = (parts.next(), parts.next()) {
            let v: f64 = v.parse().map_err(|_| {
                format!("{} (compiled): bad output line '{line}'", source.display())
            })?;
            match k {
                "cache_mb" => cache_mb = Some(v),
                _ => filters.push((k.to_string(), v)),
            }
        }
    }
    Ok(OiioTimes { cache_mb, filters })
}

const MIB: f64 = 1024.0 * 1024.0;

/// Runs the benchmark and prints the markdown table.
pub fn run(args: &BenchTexturesArgs) -> Result<(), String> {
    let work = std::env::temp_dir().join(format!("conetrace-bench-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let result = run_in(args, &work);
    let _ = std::fs::remove_dir_all(&work);
    result
}

/// The texture to benchmark: `--texture`, or a generated 1024x1024 float noise EXR.
fn source_texture(args: &BenchTexturesArgs, work: &Path) -> Result<PathBuf, String> {
    if let Some(p) = &args.texture {
        return Ok(p.clone());
    }
    let size = 1024;
    let texels = noise_texture(size);
    let path = work.join("noise.exr");
    exr::prelude::write_rgba_file(&path, size as usize, size as usize, |x, y| {
        let t = texels[y * size as usize + x];
        (t[0], t[1], t[2], t[3])
    })
    .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    Ok(path)
}

/// `source` made into the tiled, mip-mapped `tx` (64x64 tiles) that both sides read.
fn make_tx(source: &Path, tx: &Path) -> Result<(), String> {
    let out = Command::new("maketx")
        .arg(source)
        .arg("-o")
        .arg(tx)
        .args(["--filter", "box", "--tile", "64", "64"])
        .output()
        .map_err(|e| format!("maketx: cannot run ({e}); run `bash scripts/setup.sh`"))?;
    if !out.status.success() {
        return Err(format!(
            "maketx: {}",
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    Ok(())
}

fn run_in(args: &BenchTexturesArgs, work: &Path) -> Result<(), String> {
    // Built before anything is measured: a missing compiler or library costs no benchmark
    // time.
    let program = if args.no_oiio {
        None
    } else {
        Some(oiio_program(args, work)?)
    };
    let source = source_texture(args, work)?;
    let tx = work.join("bench.tx");
    make_tx(&source, &tx)?;
    let resident = Texture::from_file_whole(&tx, ColorSpace::Linear).map_err(|e| e.to_string())?;
    let size = resident.width().min(resident.height());
    let min_time = Duration::from_secs_f64(args.seconds.max(0.01));
    use FilterMode::{Aniso, Bilinear, Closest, Ewa, Trilinear};
    // (query set, level 0 alone, filters).
    let sets = [
        (QuerySet::Coherent, true, vec![Closest, Bilinear]),
        (QuerySet::Coherent, false, vec![Trilinear, Aniso, Ewa]),
        (QuerySet::Random, true, vec![Closest, Bilinear]),
        (QuerySet::Random, false, vec![Trilinear, Aniso, Ewa]),
        (QuerySet::Aniso16, false, vec![Aniso, Ewa]),
    ];
    let mut caps = vec![args.cache];
    caps.extend(args.small_cache.filter(|&small| small != args.cache));
    let mut oiio_caps = Vec::new();
    let mut rows = Vec::new();
    for (set, level0, filters) in &sets {
        if !args.query_sets.is_empty() && !args.query_sets.contains(set) {
            continue;
        }
        let filters: Vec<FilterMode> = filters
            .iter()
            .copied()
            .filter(|f| args.filters.is_empty() || args.filters.contains(f))
            .collect();
        if filters.is_empty() {
            continue;
        }
        let queries = query_set(*set, *level0, args.queries.max(1), size);
        for &cap in &caps {
            let mut oiio = Vec::new();
            if let Some(program) = &program {
                let qpath = work.join(format!("{}-{level0}.csv", set.name()));
                write_queries(&qpath, &queries)?;
                let oiio_filters: Vec<FilterMode> = filters
                    .iter()
                    .copied()
                    .filter(|f| *f != FilterMode::Ewa)
                    .collect();
                let times = run_oiio(args, program, &tx, &qpath, &oiio_filters, cap)?;
                oiio_caps.push((cap, times.cache_mb));
                oiio = times.filters;
            }
            for &filter in &filters {
                let opts = options(args, filter);
                let cached = measure_cached(
                    &resident,
                    &tx,
                    cap,
                    &queries,
                    &opts,
                    args.batch,
                    min_time,
                    args.wall_clock,
                )?;
                let oiio_ns = oiio
                    .iter()
                    .find(|(name, _)| *name == filter.to_string())
                    .map(|(_, ns)| *ns);
                rows.push(Row {
                    filter,
                    set: *set,
                    cap,
                    cached,
                    oiio_ns,
                });
            }
        }
    }
    print_header(args, &source, &resident, program.is_some(), &oiio_caps);
    print_table(&rows);
    Ok(())
}

fn options(args: &BenchTexturesArgs, filter: FilterMode) -> FilterOptions {
    FilterOptions {
        filter,
        wrap_s: WrapMode::Periodic,
        wrap_t: WrapMode::Periodic,
        max_aniso: args.max_aniso,
    }
}

fn print_header(
    args: &BenchTexturesArgs,
    source: &Path,
    tex: &Texture,
    oiio: bool,
    oiio_caps: &[(u64, Option<f64>)],
) {
    let clock = match Clock::start(args.wall_clock) {
        Clock::Wall(_) => "wall-clock time",
        Clock::ThreadCpu(_) => "thread CPU time",
    };
    println!(
        "Texture {} made into a 64x64-tiled .tx by maketx ({}x{}, {} levels), one thread, {} queries per set, \
         max aniso {}, rates per second of {clock}. \"resident\": the .tx decoded whole; \"cached\": the same \
         .tx read tile by tile into a fresh cache of the row's cap (micro-cache hits and tiles loaded over the \
         whole timed run); each row times the two in alternating slices. \"single\": one `Texture::sample` \
         call per lookup (the scalar shading path, the C API); \"batched\": one `Texture::sample_batch` call \
         per {} queries (the shading lanes, one call per material run of a wave{}).",
        source.display(),
        tex.width(),
        tex.height(),
        tex.level_count(),
        args.queries,
        args.max_aniso,
        args.batch,
        if args.batch == 0 { "; not measured: --batch 0" } else { "" },
    );
    if oiio {
        let mut seen: Vec<String> = Vec::new();
        for (cap, mb) in oiio_caps {
            let line = match mb {
                Some(mb) => format!(
                    "{:.2} MiB asked, max_memory_MB = {mb} reported",
                    *cap as f64 / MIB
                ),
                None => format!(
                    "{:.2} MiB asked, max_memory_MB not reported",
                    *cap as f64 / MIB
                ),
            };
            if !seen.contains(&line) {
                seen.push(line);
            }
        }
        println!(
            "OIIO: TextureSystem::texture() over the same .tx and queries, called from C++ \
             (bench/oiio_texture_bench.cpp, {} -O2) with a texture handle and the thread's Perthread info, \
             ImageCache {}, one thread, timed by the same clock; the fastest of three passes.",
            args.cxx.display(),
            seen.join("; ")
        );
    }
    println!();
}

fn print_table(rows: &[Row]) {
    println!(
        "| filter | queries | cap | single: resident (M/s) | cached (M/s) | cached / resident \
         | batched: resident (M/s) | cached (M/s) | cached / resident | micro-cache hits | tiles loaded \
         | OIIO (M/s) | single cached / OIIO |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let oiio = match r.oiio_ns {
            Some(ns) => format!("{:.2} | {:.2}x", 1e3 / ns, r.cached.per_sec * ns * 1e-9),
            None => "- | -".to_string(),
        };
        let batched = match r.cached.batched {
            Some((resident, cached)) => format!(
                "{:.2} | {:.2} | {:.2}",
                resident / 1e6,
                cached / 1e6,
                cached / resident
            ),
            None => "- | - | -".to_string(),
        };
        println!(
            "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {batched} | {:.1} % | {} | {} |",
            r.filter,
            r.set.name(),
            crate::render::memory::Bytes(r.cap),
            r.cached.resident_per_sec / 1e6,
            r.cached.per_sec / 1e6,
            r.cached.per_sec / r.cached.resident_per_sec,
            100.0 * r.cached.micro_hit_rate,
            r.cached.tiles_loaded,
            oiio
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_command_is_reported_by_its_first_error_else_its_last_line() {
        let compiler =
            "x.cpp: In function 'int main()':\nx.cpp:3:5: error: 'foo' was not declared\n\
                        x.cpp:4:5: error: 'bar' was not declared\n";
        assert_eq!(
            failure_line(compiler),
            "x.cpp:3:5: error: 'foo' was not declared"
        );
        assert_eq!(
            failure_line("warming up\nbench.tx: OpenImageIO cannot open it\n\n"),
            "bench.tx: OpenImageIO cannot open it"
        );
        assert_eq!(failure_line(""), "no message");
    }
}
