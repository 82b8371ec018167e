//! `conetrace bench textures`: single-thread lookups per second for every filter,
//! ours and OpenImageIO's TextureSystem (through /usr/bin/python3 and
//! bench/oiio_texture_bench.py, whose text is built into the program so that it runs from
//! any directory) on the same queries, printed as a markdown table.
//!
//! OIIO is timed from Python, so the script also times the same loop calling an
//! empty Python function; the table shows OIIO's rate both raw and with that
//! per-call overhead subtracted. This is a measurement tool, never a test.
//!
//! Both sides are timed by the CPU time of the measuring thread (Linux
//! `CLOCK_THREAD_CPUTIME_ID`; Python's `time.thread_time`), not by the wall clock:
//! on a shared machine with more runnable jobs than cores, wall time mostly measures
//! the other jobs. `--wall-clock` restores wall-clock timing on both sides.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::texture::{ColorSpace, FilterMode, FilterOptions, Texture, TextureQuery, WrapMode};

/// Arguments of `bench-textures`.
#[derive(clap::Args, Debug)]
pub struct BenchTexturesArgs {
    /// Texture to benchmark; default: a generated 1024x1024 float noise texture.
    pub texture: Option<PathBuf>,
    /// Number of distinct queries per query set.
    #[arg(long, default_value_t = 100_000)]
    pub queries: usize,
    /// Minimum measuring time per row for our side, in seconds.
    #[arg(long, default_value_t = 1.0)]
    pub seconds: f64,
    /// Anisotropy limit.
    #[arg(long, default_value_t = 16.0)]
    pub max_aniso: f32,
    /// Only these filters (comma-separated); default: all.
    #[arg(long, value_delimiter = ',')]
    pub filters: Vec<FilterMode>,
    /// Skip the OpenImageIO side.
    #[arg(long)]
    pub no_oiio: bool,
    /// Queries given to OIIO per row (Python is slow).
    #[arg(long, default_value_t = 20_000)]
    pub oiio_queries: usize,
    /// Python interpreter that has the OpenImageIO module.
    #[arg(long, default_value = "/usr/bin/python3")]
    pub python: PathBuf,
    /// The OIIO benchmark script [default: the copy of bench/oiio_texture_bench.py built
    /// into conetrace].
    #[arg(long)]
    pub oiio_script: Option<PathBuf>,
    /// Time by the wall clock instead of the thread's CPU time (both sides).
    #[arg(long)]
    pub wall_clock: bool,
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

/// Runs the OIIO script with Python's `time.perf_counter` replaced by
/// `time.thread_time` (CPU time of the calling thread), so it is timed like our side.
const PYTHON_THREAD_TIME_SHIM: &str = "import runpy, sys, time\n\
time.perf_counter = time.thread_time\n\
sys.argv = sys.argv[1:]\n\
runpy.run_path(sys.argv[0], run_name='__main__')\n";

/// bench/oiio_texture_bench.py, run when `--oiio-script` is not given.
const OIIO_SCRIPT: &str = include_str!("../../bench/oiio_texture_bench.py");

/// The line of a failed Python run's standard error that says what went wrong: the last
/// one, which a traceback ends with (`ModuleNotFoundError: ...`) and `sys.exit(message)`
/// prints alone.
fn python_failure_line(stderr: &str) -> &str {
    stderr
        .lines()
        .map(str::trim)
        .rfind(|line| !line.is_empty())
        .unwrap_or("no message")
}

/// The script to run: `--oiio-script` (which must be a file), else the built-in copy written
/// into `work`.
fn oiio_script(args: &BenchTexturesArgs, work: &Path) -> Result<PathBuf, String> {
    match &args.oiio_script {
        Some(path) if path.is_file() => Ok(path.clone()),
        Some(path) => Err(format!("{}: --oiio-script: no such file", path.display())),
        None => {
            let path = work.join("oiio_texture_bench.py");
            std::fs::write(&path, OIIO_SCRIPT)
                .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
            Ok(path)
        }
    }
}

/// One row of the table: a filter on a query set.
struct Row {
    filter: FilterMode,
    set: &'static str,
    ours_per_sec: f64,
    oiio_raw_ns: Option<f64>,
}

/// Deterministic query sets laid out like a rendered image (raster order, 256-pixel
/// rows, each band of 8 rows one plane with its own derivatives), so lookups are as
/// coherent as a renderer's: "mixed" (random levels, anisotropy 1-4, random angles)
/// and "aniso16" (anisotropy 20 clamped to the limit 16: 31 probes per level).
fn query_set(name: &str, n: usize, size: u32) -> Vec<TextureQuery> {
    const ROW: usize = 256;
    const BAND: usize = 8;
    let mut state = 0x9e37_79b9_7f4a_7c15u64 ^ name.len() as u64;
    let mut rnd = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let texel = 1.0 / size as f32;
    let mut out = Vec::with_capacity(n);
    let mut plane = TextureQuery::default();
    for k in 0..n {
        let (px, py) = (k % ROW, k / ROW);
        if k % (ROW * BAND) == 0 {
            let angle = rnd() * std::f32::consts::PI;
            let (minor, ratio) = if name == "aniso16" {
                (texel * 2f32.powf(rnd() * 4.0), 20.0)
            } else {
                (texel * 2f32.powf(rnd() * 10.0 - 1.0), 1.0 + 3.0 * rnd())
            };
            let major = minor * ratio;
            let (sn, cs) = angle.sin_cos();
            plane = TextureQuery {
                s: rnd(),
                t: rnd(),
                dsdx: major * cs,
                dtdx: major * sn,
                dsdy: -minor * sn,
                dtdy: minor * cs,
            };
        }
        let (fx, fy) = (px as f32, (py % BAND) as f32);
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

/// Lookups per second on one thread, repeating the query set for `min_time`.
fn measure(
    tex: &Texture,
    queries: &[TextureQuery],
    opts: &FilterOptions,
    min_time: Duration,
    wall: bool,
) -> f64 {
    let mut done = 0usize;
    let start = Clock::start(wall);
    let mut acc = glam::Vec4::ZERO;
    loop {
        for q in queries {
            acc += tex.sample(black_box(q), opts);
        }
        done += queries.len();
        if start.elapsed() >= min_time {
            break;
        }
    }
    black_box(acc);
    done as f64 / start.elapsed().as_secs_f64()
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

/// OIIO timings from the Python script, in ns per call.
struct OiioTimes {
    /// An empty Python function with the same arguments.
    empty: f64,
    /// texture() on a 1x1 texture (binding overhead plus a trivial lookup).
    binding: f64,
    /// Per filter.
    filters: Vec<(String, f64)>,
}

fn run_oiio(
    args: &BenchTexturesArgs,
    script: &Path,
    tx: &Path,
    queries: &Path,
    filters: &[FilterMode],
) -> Result<OiioTimes, String> {
    let names: Vec<String> = filters.iter().map(|f| f.to_string()).collect();
    let mut command = Command::new(&args.python);
    if !args.wall_clock {
        command.args(["-c", PYTHON_THREAD_TIME_SHIM]);
    }
    let out = command
        .arg(script)
        .arg(tx)
        .arg(queries)
        .args(["--filters", &names.join(",")])
        .args(["--max-aniso", &args.max_aniso.to_string()])
        .output()
        .map_err(|e| format!("{}: cannot run: {e}", args.python.display()))?;
    if !out.status.success() {
        return Err(format!(
            "{}: failed ({}): {}",
            script.display(),
            out.status,
            python_failure_line(&String::from_utf8_lossy(&out.stderr))
        ));
    }
    // Lines "empty <ns>", "binding <ns>" and "<filter> <ns>".
    let text = String::from_utf8_lossy(&out.stdout);
    let mut empty = None;
    let mut binding = None;
    let mut rates = Vec::new();
    for line in text.lines() {
        let mut parts = line.split_whitespace();
        if let (Some(k), Some(v)) = (parts.next(), parts.next()) {
            let v: f64 = v
                .parse()
                .map_err(|_| format!("{}: bad output line '{line}'", script.display()))?;
            if k == "empty" {
                empty = Some(v);
            } else if k == "binding" {
                binding = Some(v);
            } else {
                rates.push((k.to_string(), v));
            }
        }
    }
    let missing = |what: &str| format!("{}: no {what} timing", script.display());
    Ok(OiioTimes {
        empty: empty.ok_or_else(|| missing("empty-call"))?,
        binding: binding.ok_or_else(|| missing("binding"))?,
        filters: rates,
    })
}

/// Runs the benchmark and prints the markdown table.
pub fn run(args: &BenchTexturesArgs) -> Result<(), String> {
    let work = std::env::temp_dir().join(format!("conetrace-bench-{}", std::process::id()));
    std::fs::create_dir_all(&work).map_err(|e| format!("{}: {e}", work.display()))?;
    let result = run_in(args, &work);
    let _ = std::fs::remove_dir_all(&work);
    result
}

fn run_in(args: &BenchTexturesArgs, work: &Path) -> Result<(), String> {
    // Found before anything is measured: a missing script costs no benchmark time.
    let script = if args.no_oiio {
        None
    } else {
        Some(oiio_script(args, work)?)
    };
    let source = match &args.texture {
        Some(p) => p.clone(),
        None => {
            let size = 1024;
            let texels = noise_texture(size);
            let path = work.join("noise.exr");
            exr::prelude::write_rgba_file(&path, size as usize, size as usize, |x, y| {
                let t = texels[y * size as usize + x];
                (t[0], t[1], t[2], t[3])
            })
            .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
            path
        }
    };
    let tex = Texture::from_file(&source, ColorSpace::Linear).map_err(|e| e.to_string())?;
    let size = tex.width().min(tex.height());
    let min_time = Duration::from_secs_f64(args.seconds.max(0.01));
    let sets: [(&'static str, Vec<FilterMode>); 2] = [
        (
            "mixed",
            vec![
                FilterMode::Closest,
                FilterMode::Bilinear,
                FilterMode::Trilinear,
                FilterMode::Aniso,
                FilterMode::Ewa,
            ],
        ),
        ("aniso16", vec![FilterMode::Aniso, FilterMode::Ewa]),
    ];
    let tx = work.join("bench.tx");
    let mut oiio_note = String::new();
    let mut overhead: Option<(f64, f64)> = None;
    if !args.no_oiio {
        let out = Command::new("maketx")
            .arg(&source)
            .arg("-o")
            .arg(&tx)
            .args(["--filter", "box"])
            .output()
            .map_err(|e| {
                format!("maketx: cannot run ({e}); run `bash scripts/setup.sh` or pass --no-oiio")
            })?;
        if !out.status.success() {
            return Err(format!(
                "maketx: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
    }
    let mut rows = Vec::new();
    for (set, filters) in &sets {
        let filters: Vec<FilterMode> = filters
            .iter()
            .copied()
            .filter(|f| args.filters.is_empty() || args.filters.contains(f))
            .collect();
        if filters.is_empty() {
            continue;
        }
        let queries = query_set(set, args.queries.max(1), size);
        let mut oiio = Vec::new();
        if let Some(script) = &script {
            let qpath = work.join(format!("{set}.csv"));
            write_queries(
                &qpath,
                &queries[..args.oiio_queries.clamp(1, queries.len())],
            )?;
            let oiio_filters: Vec<FilterMode> = filters
                .iter()
                .copied()
                .filter(|f| *f != FilterMode::Ewa)
                .collect();
            let times = run_oiio(args, script, &tx, &qpath, &oiio_filters)?;
            overhead = Some((times.empty, times.binding));
            oiio = times.filters;
        }
        for &filter in &filters {
            let opts = FilterOptions {
                filter,
                wrap_s: WrapMode::Periodic,
                wrap_t: WrapMode::Periodic,
                max_aniso: args.max_aniso,
            };
            let ours = measure(&tex, &queries, &opts, min_time, args.wall_clock);
            let oiio_raw_ns = oiio
                .iter()
                .find(|(name, _)| *name == filter.to_string())
                .map(|(_, ns)| *ns);
            rows.push(Row {
                filter,
                set,
                ours_per_sec: ours,
                oiio_raw_ns,
            });
        }
    }
    if let Some((e, b)) = overhead {
        oiio_note = format!(
            "OIIO via Python: an empty Python call with the same arguments costs {e:.0} ns (subtracted in \"OIIO net\"); \
             texture() on a 1x1 texture (binding overhead + trivial lookup) costs {b:.0} ns (subtracted in \"OIIO C++ est.\").\n"
        );
    }
    let clock = match Clock::start(args.wall_clock) {
        Clock::Wall(_) => "wall-clock time",
        Clock::ThreadCpu(_) => "thread CPU time",
    };
    println!(
        "Texture {} ({}x{}, {} levels), one thread, {} queries per set, max aniso {}, rates per second of {clock}.\n{}",
        source.display(),
        tex.width(),
        tex.height(),
        tex.level_count(),
        args.queries,
        args.max_aniso,
        oiio_note
    );
    println!("| filter | queries | conetrace (M lookups/s) | OIIO raw (M/s) | OIIO net (M/s) | conetrace / OIIO net | OIIO C++ est. (M/s) | conetrace / C++ est. |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let cols = match (r.oiio_raw_ns, overhead) {
            (Some(ns), Some((e, b))) => {
                let net_ns = (ns - e).max(1e-3);
                let cpp_ns = (ns - b).max(1e-3);
                format!(
                    "{:.3} | {:.3} | {:.1}x | {:.3} | {:.1}x",
                    1e3 / ns,
                    1e3 / net_ns,
                    r.ours_per_sec * net_ns * 1e-9,
                    1e3 / cpp_ns,
                    r.ours_per_sec * cpp_ns * 1e-9
                )
            }
            _ => "- | - | - | - | -".to_string(),
        };
        println!(
            "| {} | {} | {:.2} | {} |",
            r.filter,
            r.set,
            r.ours_per_sec / 1e6,
            cols
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_python_failure_is_reported_by_its_last_line() {
        let traceback = "Traceback (most recent call last):\n  File \"x.py\", line 3, in <module>\n    \
                         import OpenImageIO\nModuleNotFoundError: No module named 'OpenImageIO'\n\n";
        assert_eq!(
            python_failure_line(traceback),
            "ModuleNotFoundError: No module named 'OpenImageIO'"
        );
        assert_eq!(
            python_failure_line("OpenImageIO Python module missing\n"),
            "OpenImageIO Python module missing"
        );
        assert_eq!(python_failure_line(""), "no message");
    }
}
