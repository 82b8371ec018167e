//! `conetrace bench scale-out`: predicts the wall time of a render split over 1 to 1,000
//! Slurm tasks from costs measured on this machine (docs/scale-out.md).
//!
//! Measured, with one worker thread:
//! - each work tile's render time (the tile rendered alone as a region: every sample, every
//!   AOV), after one warm-up render of the whole image;
//! - a task's fixed cost: loading the scene, decoding its textures, building the Embree scene
//!   and the `--part` probe estimate (`render::part`), which every task repeats;
//! - writing the whole image's EXR and reading it back, which bounds writing the parts and
//!   the merge (both touch every pixel once; the merge reads them and writes the image).
//!
//! Simulated, for each task count N: the parts `--part i/N` makes (the same probe estimate
//! and split as the real tasks), beyond one part per tile row combined with sample ranges;
//! each part costs its tiles' times (times its share of the samples) divided by the threads
//! per task (perfect scaling inside a node is assumed), plus the fixed cost and its share of
//! the EXR writing. Tasks go to `--slots` execution slots in array order, as Slurm fills
//! free CPUs, but only at the scheduler's passes (`--scheduler-tick` apart); the merge job
//! starts at the first pass after the last task ends and reads the parts and writes the
//! image. The passes' phase relative to the submission is unknown, so the prediction is the
//! mean over 16 evenly spread phases.

use std::sync::Arc;
use std::time::Instant;

use clap::Args;

use crate::cli::bench_scene::BenchSceneArgs;
use crate::cli::render_cmd::{self, RenderArgs};
use crate::cli::CommandError;
use crate::film::PixelRect;
use crate::integrator::Whitted;
use crate::render::part::{balanced_strip, estimate_tile_row_costs, RenderPart};
use crate::render::{self, RenderControl, WORK_TILE_SIZE};

#[derive(Args, Debug)]
pub struct BenchScaleOutArgs {
    #[command(flatten)]
    pub scene: BenchSceneArgs,
    /// Task counts to predict.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1,2,4,8,16,32,64,100,128,256,512,1000"
    )]
    pub tasks: Vec<u32>,
    /// Tasks that run at once (e.g. nodes x tasks per node); default: as many as tasks.
    #[arg(long)]
    pub slots: Option<u32>,
    /// Predict for this many samples per pixel, from the costs measured at `--spp`: every
    /// sample of a pixel costs the same on average (they differ only in position), so a
    /// tile's time scales with its samples. Default: `--spp`.
    #[arg(long)]
    pub predict_spp: Option<u32>,
    /// Worker threads of each task (its CPUs).
    #[arg(long, default_value_t = 1)]
    pub threads_per_task: u32,
    /// Seconds between the scheduler's passes: a task (and the merge job) starts at the
    /// first pass after its slot or dependency frees up; 0 starts it at once. The local
    /// cluster allocates every 3 s (docs/scale-out.md).
    #[arg(long, default_value_t = 3.0)]
    pub scheduler_tick: f64,
}

/// What one task costs, measured.
struct Measured {
    tiles: Vec<PixelRect>,
    /// Seconds per work tile, one thread.
    tile_seconds: Vec<f64>,
    /// Load, textures, Embree scene, probe estimate: repeated by every task.
    fixed_seconds: f64,
    /// Writing the whole image's EXR, and reading it back.
    write_seconds: f64,
    read_seconds: f64,
    row_costs: Vec<u64>,
}

fn measure(args: &RenderArgs) -> Result<(Measured, render::RenderOptions), CommandError> {
    let started = Instant::now();
    let scene = render_cmd::load(args)?;
    let mut options = render_cmd::options(args, &scene)?;
    options.count_texture_tiles = false;
    let pool = crate::cli::worker_pool(Some(1))?;
    let scene = Arc::new(scene);
    pool.install(|| {
        let context = render::prepare(scene.clone(), options.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        let row_costs = estimate_tile_row_costs(&context, &Whitted::default());
        let fixed_seconds = started.elapsed().as_secs_f64();
        let whole = render::render(&context, &Whitted::default(), &RenderControl::default())
            .map_err(crate::cli::render_failed)?;
        let tiles = render::work_tiles(options.width, options.height);
        let mut tile_seconds = Vec::with_capacity(tiles.len());
        for tile in &tiles {
            let part = RenderPart {
                region: *tile,
                samples: 0..options.spp.max(1),
            };
            let control = RenderControl {
                part: Some(&part),
                ..RenderControl::default()
            };
            let start = Instant::now();
            render::render(&context, &Whitted::default(), &control)
                .map_err(crate::cli::render_failed)?;
            tile_seconds.push(start.elapsed().as_secs_f64());
        }
        let path =
            std::env::temp_dir().join(format!("conetrace-scale-out-{}.exr", std::process::id()));
        let start = Instant::now();
        crate::film::write_exr(&whole.film, &path, &crate::film::ExrAttributes::default())
            .map_err(|e| CommandError::internal(e.to_string()))?;
        let write_seconds = start.elapsed().as_secs_f64();
        let start = Instant::now();
        let read_back = crate::film::read_exr(&path);
        let read_seconds = start.elapsed().as_secs_f64();
        let _ = std::fs::remove_file(&path);
        read_back.map_err(|e| CommandError::internal(e.to_string()))?;
        Ok((
            Measured {
                tiles,
                tile_seconds,
                fixed_seconds,
                write_seconds,
                read_seconds,
                row_costs,
            },
            options.clone(),
        ))
    })
}

/// The task times of `tasks` parts as `--part` (and sample ranges beyond one part per tile
/// row) would make them.
fn part_seconds(
    measured: &Measured,
    options: &render::RenderOptions,
    tasks: u32,
    threads: u32,
    spp: u32,
) -> Result<Vec<f64>, CommandError> {
    let rows = measured.row_costs.len() as u32;
    let spp = spp.max(1);
    let sample_scale = f64::from(spp) / f64::from(options.spp.max(1));
    // Beyond one strip per tile row, each strip's samples are split into groups too.
    let groups = tasks.div_ceil(rows).min(spp);
    let strips = tasks.div_ceil(groups).min(rows);
    let pixels = f64::from(options.width) * f64::from(options.height);
    let mut seconds = Vec::new();
    for index in 0..strips {
        let strip = balanced_strip(
            &measured.row_costs,
            index,
            strips,
            options.width,
            options.height,
        )
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
        let render: f64 = sample_scale
            * measured
                .tiles
                .iter()
                .zip(&measured.tile_seconds)
                .filter(|(t, _)| t.y0 >= strip.y0 && t.y0 < strip.y0 + strip.height)
                .map(|(_, s)| s)
                .sum::<f64>();
        let share = f64::from(strip.width) * f64::from(strip.height) / pixels;
        for group in 0..groups {
            let samples = spp * (group + 1) / groups - spp * group / groups;
            seconds.push(
                measured.fixed_seconds
                    + render * f64::from(samples) / f64::from(spp) / f64::from(threads)
                    + measured.write_seconds * share,
            );
        }
    }
    Ok(seconds)
}

/// When the merge job can start: `task_seconds` run in array order on `slots` slots, each
/// task starting at the first scheduler pass (every `tick` seconds from `phase`; `tick` 0:
/// at once) that finds a slot free, and the merge at the first pass after the last end.
pub fn merge_start(task_seconds: &[f64], slots: u32, tick: f64, phase: f64) -> f64 {
    let next_pass = |t: f64| {
        if tick <= 0.0 {
            t
        } else {
            phase + ((t - phase) / tick).ceil().max(0.0) * tick
        }
    };
    let mut free_at = vec![0.0f64; slots.max(1) as usize];
    let mut last_end = 0.0f64;
    for &seconds in task_seconds {
        let (slot, &free) = free_at
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .expect("at least one slot");
        let start = next_pass(free);
        free_at[slot] = start + seconds;
        last_end = last_end.max(start + seconds);
    }
    next_pass(last_end)
}

/// [`merge_start`] averaged over 16 phases of the scheduler's passes.
pub fn mean_merge_start(task_seconds: &[f64], slots: u32, tick: f64) -> f64 {
    const PHASES: u32 = 16;
    (0..PHASES)
        .map(|k| {
            merge_start(
                task_seconds,
                slots,
                tick,
                tick * f64::from(k) / f64::from(PHASES),
            )
        })
        .sum::<f64>()
        / f64::from(PHASES)
}

pub fn run(args: &BenchScaleOutArgs) -> Result<(), CommandError> {
    if args.threads_per_task == 0 || args.slots == Some(0) {
        return Err(CommandError::bad_input(
            "bench scale-out: --threads-per-task and --slots must be at least 1",
        ));
    }
    if !(args.scheduler_tick.is_finite() && args.scheduler_tick >= 0.0) {
        return Err(CommandError::bad_input(
            "bench scale-out: --scheduler-tick must be a number of seconds >= 0",
        ));
    }
    if args.predict_spp == Some(0) {
        return Err(CommandError::bad_input(
            "bench scale-out: --predict-spp must be at least 1",
        ));
    }
    // Each task is measured on one thread; --threads-per-task scales the prediction.
    let (measured, options) = measure(&args.scene.render_args(Some(1))?)?;
    let spp = args.predict_spp.unwrap_or(options.spp);
    let total: f64 = measured.tile_seconds.iter().sum();
    println!(
        "measured ({}x{}, {} spp, one thread): {} tiles in {} rows, {total:.3} s of tile rendering; \
         fixed cost per task {:.3} s; EXR write {:.3} s, read {:.3} s (whole image)",
        options.width,
        options.height,
        options.spp,
        measured.tiles.len(),
        options.height.div_ceil(WORK_TILE_SIZE),
        measured.fixed_seconds,
        measured.write_seconds,
        measured.read_seconds
    );
    println!(
        "| tasks | parts | slots | longest part s | predicted wall s | speed-up | efficiency |"
    );
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    let mut one_task = None;
    for &tasks in &args.tasks {
        if tasks == 0 {
            continue;
        }
        let parts = part_seconds(&measured, &options, tasks, args.threads_per_task, spp)?;
        let slots = args.slots.unwrap_or(tasks);
        // The merge reads every part's pixels (each pixel once per sample group) and writes
        // the image.
        let groups = (parts.len() as u32)
            .div_ceil(options.height.div_ceil(WORK_TILE_SIZE))
            .max(1);
        let merge = measured.read_seconds * f64::from(groups) + measured.write_seconds;
        let wall = mean_merge_start(&parts, slots, args.scheduler_tick) + merge;
        let reference = *one_task.get_or_insert(wall);
        let longest = parts.iter().copied().fold(0.0, f64::max);
        println!(
            "| {tasks} | {} | {slots} | {longest:.3} | {wall:.3} | {:.2} | {:.0}% |",
            parts.len(),
            reference / wall,
            100.0 * reference / wall / f64::from(slots.min(parts.len() as u32).max(1))
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tasks_fill_free_slots_in_order_at_scheduler_passes() {
        // No passes: list scheduling.
        assert_eq!(merge_start(&[1.0, 1.0, 1.0, 1.0], 2, 0.0, 0.0), 2.0);
        assert_eq!(merge_start(&[3.0, 1.0, 1.0, 1.0], 2, 0.0, 0.0), 3.0);
        assert_eq!(merge_start(&[1.0, 2.0, 3.0], 1, 0.0, 0.0), 6.0);
        assert_eq!(merge_start(&[1.0, 2.0, 3.0], 8, 0.0, 0.0), 3.0);
        // Passes every 3 s from 0: two waves of 1 s tasks start at 0 and 3, the merge at 6.
        assert_eq!(merge_start(&[1.0, 1.0, 1.0], 2, 3.0, 0.0), 6.0);
        // From phase 1: waves at 1 and 4, the merge at 7.
        assert_eq!(merge_start(&[1.0, 1.0, 1.0], 2, 3.0, 1.0), 7.0);
        assert_eq!(mean_merge_start(&[1.0], 1, 0.0), 1.0);
    }
}
