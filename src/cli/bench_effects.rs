//! `conetrace bench effects`: the specialised path (the effects the scene analysis switched
//! on) against the general path (every effect on, as `render --all-effects`), and what each
//! unneeded effect costs when it is switched on anyway.
//!
//! For every scene, one prepared render context is rendered under several effect sets:
//! (a) the analysed set, (b) every effect, (c) for each effect the scene does not need, the
//! analysed set plus that one effect. The sets only ever add effects to the analysed one
//! ([`RenderContext::force_effects`] refuses anything else), so every configuration must give
//! the same image; the first film of each is compared with (a)'s. The configurations are
//! rendered round-robin (the starting one rotating each round), `--repeat` rounds, so drift
//! in the shared machine's load falls on all of them alike; each ratio is taken within a
//! round and the median and quartiles of those paired ratios are reported. The output is
//! markdown tables, printed and optionally written to `--markdown FILE`.

use std::ffi::OsString;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Args;

use crate::cli::render_cmd::{self, RenderArgs};
use crate::cli::summary::quantile;
use crate::cli::CommandError;
use crate::film::Film;
use crate::integrator::Whitted;
use crate::render::{self, EffectSet, RenderContext, RenderControl, WorkCounters};

#[derive(Args, Debug)]
pub struct BenchEffectsArgs {
    /// Scene files. Default: assets/scenes/default.toml, assets/scenes/fp_*.toml and
    /// assets/scenes/bench/*.toml, found from the current directory (the repository root).
    pub scenes: Vec<PathBuf>,
    /// Rounds over all configurations (medians and quartiles are over these).
    #[arg(long, default_value_t = 15)]
    pub repeat: usize,
    /// Image width (default: each scene's).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: each scene's).
    #[arg(long)]
    pub height: Option<u32>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Also write the markdown tables to this file.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// What one configuration switches on, relative to the scene's analysis.
#[derive(Clone, Debug)]
enum Variant {
    /// (a) exactly the analysed effects.
    Specialised,
    /// (b) every effect.
    General,
    /// (c) the analysed effects plus this one unneeded effect.
    PlusUnneeded(&'static str),
}

/// One configuration's measurements.
struct Measured {
    variant: Variant,
    effects: EffectSet,
    seconds: Vec<f64>,
    /// CPU time of all the process's threads per render (see [`cpu_seconds`]), when known.
    cpu_seconds: Vec<f64>,
    /// Work counters of the first render (rendering is deterministic).
    counters: WorkCounters,
    /// Largest absolute difference from the specialised film over every channel.
    max_difference: f32,
}

/// All configurations of one scene.
struct SceneResult {
    label: String,
    width: u32,
    height: u32,
    needed: Vec<&'static str>,
    configs: Vec<Measured>,
}

/// Median and quartiles of a sample (nearest-rank, sorted copy).
#[derive(Clone, Copy, Debug)]
struct Spread {
    q1: f64,
    median: f64,
    q3: f64,
    min: f64,
    max: f64,
}

impl Spread {
    fn of(values: &[f64]) -> Spread {
        let at = |q: f64| quantile(values, q);
        Spread {
            q1: at(0.25),
            median: at(0.5),
            q3: at(0.75),
            min: at(0.0),
            max: at(1.0),
        }
    }

    /// Where the interquartile range of a ratio lies relative to 1.
    fn verdict(&self) -> Verdict {
        if self.q3 < 1.0 {
            Verdict::Below
        } else if self.q1 > 1.0 {
            Verdict::Above
        } else {
            Verdict::WithinNoise
        }
    }
}

/// A ratio's interquartile range wholly below 1, wholly above 1, or containing 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Verdict {
    Below,
    Above,
    WithinNoise,
}

/// The scenes to run when none are named.
fn default_scenes() -> Result<Vec<PathBuf>, CommandError> {
    let root = Path::new("assets/scenes");
    let default = root.join("default.toml");
    if !default.is_file() {
        return Err(CommandError::bad_input(
            "assets/scenes/default.toml: not found; name the scenes or run from the repository root",
        ));
    }
    let mut scenes = vec![default];
    let mut listed = |dir: &Path, prefix: &str| -> Result<(), CommandError> {
        let entries = std::fs::read_dir(dir)
            .map_err(|e| CommandError::bad_input(format!("{}: {e}", dir.display())))?;
        let mut found: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension().is_some_and(|x| x == "toml")
                    && p.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with(prefix))
            })
            .collect();
        found.sort();
        scenes.extend(found);
        Ok(())
    };
    listed(root, "fp_")?;
    let bench = root.join("bench");
    if bench.is_dir() {
        listed(&bench, "")?;
    }
    Ok(scenes)
}

/// `conetrace render`'s options for `scene` with this benchmark's size overrides.
fn render_args(scene: &Path, args: &BenchEffectsArgs) -> Result<RenderArgs, CommandError> {
    let mut argv: Vec<OsString> = vec!["conetrace".into(), "--quiet".into(), "--no-png".into()];
    if let Some(width) = args.width {
        argv.extend(["--width".into(), width.to_string().into()]);
    }
    if let Some(height) = args.height {
        argv.extend(["--height".into(), height.to_string().into()]);
    }
    argv.extend(["--".into(), scene.as_os_str().to_owned()]);
    RenderArgs::from_argv(argv).map_err(|e| CommandError::internal(format!("bench effects: {e}")))
}

/// CPU time used so far by all threads of this process, from Linux's per-thread
/// `/proc/self/task/*/schedstat` (nanoseconds on a CPU). Unlike the wall-clock time it does
/// not grow while the shared machine runs someone else's work; `None` where unavailable.
fn cpu_seconds() -> Option<f64> {
    let mut total_ns = 0u64;
    for task in std::fs::read_dir("/proc/self/task").ok()? {
        let path = task.ok()?.path().join("schedstat");
        // A thread may exit between listing and reading: skip it.
        let Ok(text) = std::fs::read_to_string(path) else {
            continue;
        };
        total_ns += text.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(total_ns as f64 * 1e-9)
}

/// Largest absolute difference between two films of the same layout, over every channel.
fn max_difference(a: &Film, b: &Film) -> f32 {
    let mut max = 0.0f32;
    for name in a.channel_names() {
        let (Some(x), Some(y)) = (a.channel(&name), b.channel(&name)) else {
            return f32::INFINITY;
        };
        for (p, q) in x.iter().zip(y) {
            if p != q {
                let d = (p - q).abs();
                max = max.max(if d.is_nan() { f32::INFINITY } else { d });
            }
        }
    }
    max
}

/// Counters as (name, value) pairs, in declaration order.
fn counter_list(counters: &WorkCounters) -> Vec<(String, u64)> {
    match serde_json::to_value(counters) {
        Ok(serde_json::Value::Object(map)) => map
            .into_iter()
            .map(|(k, v)| (k, v.as_u64().unwrap_or(0)))
            .collect(),
        _ => Vec::new(),
    }
}

/// The counters that differ from the specialised path's, as "name a -> b".
fn counter_changes(base: &WorkCounters, other: &WorkCounters) -> String {
    let changes: Vec<String> = counter_list(base)
        .into_iter()
        .zip(counter_list(other))
        .filter(|((_, a), (_, b))| a != b)
        .map(|((name, a), (_, b))| format!("{name} {a} → {b}"))
        .collect();
    if changes.is_empty() {
        "none".to_string()
    } else {
        changes.join(", ")
    }
}

/// Switches `context` to `effects` (rebuilding the Embree scene when the alpha tests change:
/// outside the timed render).
fn use_effects(context: &mut RenderContext, effects: EffectSet) -> Result<(), CommandError> {
    // Configurations are built from the analysed set, so a refusal is a bug.
    context
        .force_effects(effects)
        .map_err(|e| CommandError::internal(format!("bench effects: {e}")))
}

fn render_once(context: &RenderContext) -> Result<render::RenderResult, CommandError> {
    render::render(context, &Whitted::default(), &RenderControl::default())
        .map_err(crate::cli::render_failed)
}

/// Measure every configuration of one scene.
fn bench_scene(
    path: &Path,
    args: &BenchEffectsArgs,
    repeat: usize,
) -> Result<SceneResult, CommandError> {
    let render_args = render_args(path, args)?;
    let scene = render_cmd::load(&render_args)?;
    let mut options = render_cmd::options(&render_args, &scene)?;
    options.count_texture_tiles = false;
    options.all_effects = false;
    let label = path.display().to_string();
    let mut context = render::prepare(Arc::new(scene), options.clone())
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let analysed = context.effects;

    let mut variants = vec![
        (Variant::Specialised, analysed),
        (Variant::General, EffectSet::all()),
    ];
    for (name, single) in EffectSet::singles() {
        if !analysed.includes(&single) {
            variants.push((Variant::PlusUnneeded(name), analysed.union(single)));
        }
    }

    // Warm-up round: one render of each configuration, whose film and counters are kept.
    let mut reference: Option<Film> = None;
    let mut configs = Vec::new();
    for (variant, effects) in variants {
        use_effects(&mut context, effects)?;
        let result = render_once(&context)?;
        let max_difference = match &reference {
            Some(film) => max_difference(film, &result.film),
            None => 0.0,
        };
        if reference.is_none() {
            reference = Some(result.film);
        }
        configs.push(Measured {
            variant,
            effects,
            seconds: Vec::with_capacity(repeat),
            cpu_seconds: Vec::with_capacity(repeat),
            counters: result.stats.counters,
            max_difference,
        });
    }
    let n = configs.len();
    for round in 0..repeat {
        for j in 0..n {
            let i = (j + round) % n;
            use_effects(&mut context, configs[i].effects)?;
            let cpu_before = cpu_seconds();
            let result = render_once(&context)?;
            if let (Some(before), Some(after)) = (cpu_before, cpu_seconds()) {
                configs[i].cpu_seconds.push(after - before);
            }
            configs[i].seconds.push(result.stats.seconds);
        }
    }
    Ok(SceneResult {
        label,
        width: options.width,
        height: options.height,
        needed: analysed.names(),
        configs,
    })
}

/// Paired per-round ratios `a[r] / b[r]`.
fn ratios(a: &[f64], b: &[f64]) -> Spread {
    let r: Vec<f64> = a.iter().zip(b).map(|(x, y)| x / y.max(1e-12)).collect();
    Spread::of(&r)
}

fn ms(spread: &Spread) -> String {
    format!(
        "{:.2} ({:.2}–{:.2})",
        spread.median * 1e3,
        spread.min * 1e3,
        spread.max * 1e3
    )
}

fn ratio(spread: &Spread) -> String {
    format!("{:.3} [{:.3}–{:.3}]", spread.median, spread.q1, spread.q3)
}

/// The paired ratio of two configurations' CPU times; `None` where unknown. The kernel
/// updates a running thread's CPU time at scheduler ticks (a few ms), so renders that short
/// can read zero: then the ratio is unknown too.
fn cpu_ratio(a: &Measured, b: &Measured) -> Option<Spread> {
    let known = |m: &Measured| {
        m.cpu_seconds.len() == m.seconds.len() && m.cpu_seconds.iter().all(|&t| t > 0.0)
    };
    (known(a) && known(b)).then(|| ratios(&a.cpu_seconds, &b.cpu_seconds))
}

fn optional_ratio(spread: Option<Spread>) -> String {
    spread
        .as_ref()
        .map(ratio)
        .unwrap_or_else(|| "n/a".to_string())
}

fn difference(d: f32) -> String {
    if d == 0.0 {
        "identical".to_string()
    } else {
        format!("{d:.3e}")
    }
}

/// One scene's measurement of one unneeded effect, for the per-effect summary.
struct UnneededCost {
    /// Median of the paired ratios time / specialised time.
    median: f64,
    verdict: Verdict,
    /// The same ratio in CPU time, when known.
    cpu: Option<Spread>,
}

/// The markdown report of all scenes.
fn report(results: &[SceneResult], repeat: usize, threads: usize, command: &str) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Command: `{command}` — {threads} worker threads, {repeat} interleaved rounds per scene \
         (plus one warm-up round whose images and counters are compared). Times are render \
         times (tiles only, scene preparation excluded): median (min–max) in ms. Ratios are \
         paired within a round: median [first–third quartile]; \"within noise\" when that \
         range contains 1.\n"
    );
    let _ = writeln!(
        out,
        "### Specialised path vs general path (`--all-effects`)\n"
    );
    let _ = writeln!(
        out,
        "| scene | size | effects the scene needs | specialised ms | general ms | specialised / general | verdict | CPU time specialised / general | work the general path adds | image difference |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|");
    for scene in results {
        let (Some(spec), Some(general)) = (scene.configs.first(), scene.configs.get(1)) else {
            continue;
        };
        let r = ratios(&spec.seconds, &general.seconds);
        let _ = writeln!(
            out,
            "| {} | {}x{} | {} | {} | {} | {} | {} | {} | {} | {} |",
            scene.label,
            scene.width,
            scene.height,
            scene.needed.join(", "),
            ms(&Spread::of(&spec.seconds)),
            ms(&Spread::of(&general.seconds)),
            ratio(&r),
            match r.verdict() {
                Verdict::Below => "specialised faster",
                Verdict::Above => "specialised SLOWER",
                Verdict::WithinNoise => "within noise",
            },
            optional_ratio(cpu_ratio(spec, general)),
            counter_changes(&spec.counters, &general.counters),
            difference(general.max_difference),
        );
    }

    let _ = writeln!(
        out,
        "\n### Each unneeded effect switched on alone (analysed set + that effect)\n"
    );
    let _ = writeln!(
        out,
        "| scene | effect switched on | time / specialised | verdict | CPU time / specialised | work it adds | image difference |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|");
    let mut per_effect: Vec<(&'static str, Vec<UnneededCost>)> = EffectSet::singles()
        .into_iter()
        .map(|(name, _)| (name, Vec::new()))
        .collect();
    for scene in results {
        let Some(spec) = scene.configs.first() else {
            continue;
        };
        for config in &scene.configs {
            let Variant::PlusUnneeded(name) = config.variant else {
                continue;
            };
            let r = ratios(&config.seconds, &spec.seconds);
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {} | {} |",
                scene.label,
                name,
                ratio(&r),
                match r.verdict() {
                    Verdict::Above => "costs time",
                    Verdict::Below => "faster (noise)",
                    Verdict::WithinNoise => "within noise",
                },
                optional_ratio(cpu_ratio(config, spec)),
                counter_changes(&spec.counters, &config.counters),
                difference(config.max_difference),
            );
            if let Some((_, list)) = per_effect.iter_mut().find(|(n, _)| *n == name) {
                list.push(UnneededCost {
                    median: r.median,
                    verdict: r.verdict(),
                    cpu: cpu_ratio(config, spec),
                });
            }
        }
    }

    let _ = writeln!(
        out,
        "\n### Per effect: cost when switched on but not needed (medians over the scenes above)\n"
    );
    let _ = writeln!(
        out,
        "| effect | scenes where unneeded | time / specialised: median of the per-scene medians | lowest – highest | scenes where it costs time (IQR above 1) | CPU time / specialised: median of medians | scenes where it costs CPU time (IQR above 1) |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|");
    for (name, list) in &per_effect {
        if list.is_empty() {
            let _ = writeln!(out, "| {name} | 0 | — | — | — | — | — |");
            continue;
        }
        let medians: Vec<f64> = list.iter().map(|c| c.median).collect();
        let s = Spread::of(&medians);
        let costly = list.iter().filter(|c| c.verdict == Verdict::Above).count();
        let cpu: Option<Vec<Spread>> = list.iter().map(|c| c.cpu).collect();
        let (cpu_median, cpu_costly) = match cpu {
            Some(cpu) => {
                let medians: Vec<f64> = cpu.iter().map(|c| c.median).collect();
                let costly = cpu.iter().filter(|c| c.verdict() == Verdict::Above).count();
                (
                    format!("{:.3}", Spread::of(&medians).median),
                    costly.to_string(),
                )
            }
            None => ("n/a".to_string(), "n/a".to_string()),
        };
        let _ = writeln!(
            out,
            "| {name} | {} | {:.3} | {:.3} – {:.3} | {costly} | {cpu_median} | {cpu_costly} |",
            list.len(),
            s.median,
            s.min,
            s.max,
        );
    }
    out
}

pub fn run(args: &BenchEffectsArgs) -> Result<(), CommandError> {
    let scenes = if args.scenes.is_empty() {
        default_scenes()?
    } else {
        args.scenes.clone()
    };
    let repeat = args.repeat.max(1);
    let pool = crate::cli::worker_pool(args.threads)?;
    let command = std::iter::once("conetrace".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    pool.install(|| {
        let mut results = Vec::new();
        for path in &scenes {
            eprintln!("bench effects: {}", path.display());
            results.push(bench_scene(path, args, repeat)?);
        }
        let text = report(&results, repeat, rayon::current_num_threads(), &command);
        print!("{text}");
        if let Some(file) = &args.markdown {
            std::fs::write(file, &text)
                .map_err(|e| CommandError::bad_input(format!("{}: {e}", file.display())))?;
        }
        Ok(())
    })
}
