//! `conetrace render --time-limit SECONDS`: progressive rendering. Passes of samples are
//! rendered until the time is spent, and after each completed pass the outputs (the EXR with
//! all its layers, the PNG, the statistics) are replaced atomically, together
//! (`film::OutputSet`), so an image viewer watching the files sees the image converge and
//! never a half-written file.
//!
//! # Passes
//!
//! Pass `k` renders a range of sample indices of every pixel: `0..1`, `1..2`, `2..4`,
//! `4..8`, ... (each pass as many samples as all before it), so the first image appears
//! after one sample and writing the outputs costs at most one write per doubling of the
//! samples. After every pass but the first, the pass size is also cut to the samples that fit
//! in [`TIME_CAPPED_PASS_SHARE`] of the time left after a write as long as the last one, at
//! the speed measured on the previous pass ([`samples_that_fit`]): the share leaves room for
//! a pass that runs slower than the one before (a machine shared with other work), and the
//! time it leaves over goes to smaller passes after it. A pass that the deadline still
//! overtakes is abandoned within its current run of samples and the outputs keep the
//! previous pass; the summary line and `--stats` (`progressive.abandoned_samples`) say how
//! many samples were left out that way. The first pass always finishes (only Ctrl-C stops
//! it), so a time limit always gives an image.
//!
//! Samples are a pure function of (seed, pixel, sample index, dimension) (`crate::sampler`)
//! and every pass keeps the exact fixed-point sums of its samples (`film::sample_sum`), which
//! are added here across passes; the image after `M` samples is `mean_of_sum(sum, M)`, the
//! very value a single render of those `M` samples computes: a progressive render that
//! reaches `--spp N` equals `conetrace render --spp N` bit for bit. Alpha and the AOV layers
//! describe each pixel's first sample, so they come from the first pass.
//!
//! # Sample count and footprint scale
//!
//! `--spp N` with `--time-limit` is an upper bound: the render stops at `N` samples even with
//! time left. Without `--spp` (the scene's `spp` setting is not used either), the render goes
//! on until the time is up. The sampler's footprint scale depends on the render's sample
//! count (`max(1/8, 1/sqrt N)`, `camera::sample_footprint`), and must be the same for every
//! sample so that passes add up to one render. With `--spp N` it is that of `N`, from the
//! first pass on. Without `--spp` the render's sample count is the largest the sampler
//! indexes (`u32::MAX`, recorded as `conetrace.option.spp`), whose scale is the floor 1/8:
//! the scale of every render of 64 or more samples, so an unbounded progressive render that
//! reached `M >= 64` samples equals `conetrace render --spp M` bit for bit; one stopped
//! before 64 samples has textures filtered at the 64-sample footprint (sharper than an
//! `M`-sample render's, with the pixel samples doing the rest of the filtering).
//!
//! The EXR header records the samples reached (`conetrace.samples = 0..M`,
//! `conetrace.progressive.samples = M`) and the passes (`conetrace.progressive.passes`).
//!
//! # Interruption
//!
//! Ctrl-C or SIGTERM abandons the pass in flight within its current run of samples; the outputs keep the
//! last completed pass (already on disk) and the command exits with status 3
//! (`cli::EXIT_INTERRUPTED`), as an interrupted `conetrace render` does. Interrupted during
//! the first pass, nothing is written. There is no partial file to `--resume` from: every
//! output on disk is a complete image.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use serde::Serialize;

use crate::cli::outputs::OutputPlan;
use crate::cli::render_cmd::{self, RenderArgs, INTERRUPTED};
use crate::cli::resume::RenderSignature;
use crate::cli::{CommandError, EXIT_INTERRUPTED};
use crate::film::{self, sample_sum, ExrAttributes, Film, Layer, OutputSet, PixelRect};
use crate::integrator::selection;
use crate::render::part::RenderPart;
use crate::render::stats::PhaseSeconds;
use crate::render::{self, RenderControl, RenderStats, WorkCounters};

/// Header attribute: the samples per pixel the image holds.
pub const PROGRESSIVE_SAMPLES_ATTRIBUTE: &str = "conetrace.progressive.samples";
/// Header attribute: the passes completed.
pub const PROGRESSIVE_PASSES_ATTRIBUTE: &str = "conetrace.progressive.passes";

/// The sample count of an unbounded progressive render (see the module doc).
pub const UNBOUNDED_SPP: u32 = u32::MAX;

/// What `--stats` adds for a progressive render.
#[derive(Clone, Debug, Serialize)]
pub struct ProgressiveStats {
    pub time_limit_seconds: f64,
    /// `--spp`, when given.
    pub sample_bound: Option<u32>,
    /// Passes completed (the outputs hold the last).
    pub passes: u32,
    /// Samples per pixel reached.
    pub samples: u32,
    /// Why the render stopped: "samples" (the bound was reached), "time" or "interrupted".
    pub stopped_by: String,
    /// Samples per pixel of the pass the deadline or Ctrl-C overtook and that was left out
    /// (0 when none was).
    pub abandoned_samples: u32,
}

/// The statistics file of a progressive render: the render's statistics (over all
/// completed passes; `spp` is the samples reached) and the passes.
#[derive(Serialize)]
struct ProgressiveStatsFile<'a> {
    #[serde(flatten)]
    render: &'a RenderStats,
    progressive: &'a ProgressiveStats,
}

/// The line printed after each completed pass, e.g. `progress: pass 3 done, 4 spp, 1.2 s of
/// 60 s; wrote out/x.exr`.
fn pass_line(
    passes: u32,
    samples: u32,
    elapsed: std::time::Duration,
    budget: std::time::Duration,
    exr: &std::path::Path,
) -> String {
    format!(
        "progress: pass {passes} done, {samples} spp, {:.1} s of {:.0} s; wrote {}",
        elapsed.as_secs_f64(),
        budget.as_secs_f64(),
        exr.display()
    )
}

/// The sample range of the pass after `done` samples: as many as were done (one for the
/// first pass), at most `bound - done` and at most `fits` (the samples the remaining time
/// holds, `None` before anything was measured). Empty when nothing more is to be rendered.
pub fn next_pass(done: u32, bound: u32, fits: Option<u64>) -> std::ops::Range<u32> {
    let mut size = u64::from(done.max(1)).min(u64::from(bound - done.min(bound)));
    if let Some(fits) = fits {
        size = size.min(fits);
    }
    done..done + size as u32
}

/// The share of the time left that a pass whose size the time caps is planned to fill.
pub const TIME_CAPPED_PASS_SHARE: f64 = 0.8;

/// The samples per pixel that fit in [`TIME_CAPPED_PASS_SHARE`] of `seconds_left` after a
/// write of `write_seconds`, at `seconds_per_sample`.
pub fn samples_that_fit(seconds_left: f64, write_seconds: f64, seconds_per_sample: f64) -> u64 {
    let usable = (seconds_left - write_seconds).max(0.0) * TIME_CAPPED_PASS_SHARE;
    (usable / seconds_per_sample.max(1e-12)).floor() as u64
}

/// Checks `--time-limit`: a number of seconds above zero and below 1e9 (about 31 years).
pub fn check_time_limit(seconds: f64) -> Result<Duration, CommandError> {
    if !(seconds.is_finite() && seconds > 0.0 && seconds < 1e9) {
        return Err(CommandError::bad_input(format!(
            "--time-limit must be a number of seconds above 0 and below 1e9, got {seconds}"
        )));
    }
    Ok(Duration::from_secs_f64(seconds))
}

/// The exact sample sums of every pixel over the passes so far, and the image they give.
struct Accumulated {
    sums: Vec<[i128; 3]>,
    samples: u32,
    /// The first pass's film without its sum channels: alpha and the AOV layers.
    image: Option<Film>,
}

impl Accumulated {
    /// Adds a pass's film, which covers the whole image and the sample range `samples`.
    fn add_pass(
        &mut self,
        pass: &Film,
        samples: &std::ops::Range<u32>,
        layers: &[Layer],
    ) -> Result<(), CommandError> {
        let width = pass.width();
        let mut digits = [0.0f32; 3 * sample_sum::DIGITS];
        let mut color = [0.0f32; 4];
        for (index, sum) in self.sums.iter_mut().enumerate() {
            let (x, y) = (index as u32 % width, index as u32 / width);
            if pass.has(Layer::SampleSum) {
                pass.get(Layer::SampleSum, x, y, &mut digits);
                for (channel, chunk) in sum.iter_mut().zip(digits.chunks_exact(sample_sum::DIGITS))
                {
                    let chunk: &[f32; sample_sum::DIGITS] = chunk.try_into().map_err(|_| {
                        CommandError::internal("progressive: a sum has the wrong digit count")
                    })?;
                    *channel += sample_sum::decode(chunk).ok_or_else(|| {
                        CommandError::internal("progressive: a pass wrote a malformed sum")
                    })?;
                }
            } else {
                // A pass holding all the render's samples (a one-pass render) has only
                // final colours; one sample's value is its own exact sum.
                pass.get(Layer::Color, x, y, &mut color);
                for (channel, value) in sum.iter_mut().zip(color) {
                    *channel += sample_sum::to_fixed(value);
                }
            }
        }
        self.samples += samples.len() as u32;
        if self.image.is_none() {
            let mut image = Film::try_new(pass.width(), pass.height(), layers)
                .map_err(CommandError::internal)?;
            image.copy_region_from(
                pass,
                PixelRect {
                    x0: 0,
                    y0: 0,
                    width: pass.width(),
                    height: pass.height(),
                },
            );
            self.image = Some(image);
        }
        if let Some(image) = &mut self.image {
            for (index, sum) in self.sums.iter().enumerate() {
                let (x, y) = (index as u32 % width, index as u32 / width);
                image.get(Layer::Color, x, y, &mut color);
                for (c, s) in color.iter_mut().zip(sum) {
                    *c = sample_sum::mean_of_sum(*s, self.samples);
                }
                image.set(Layer::Color, x, y, &color);
            }
        }
        Ok(())
    }
}

/// Sets `flag` once Ctrl-C was pressed or, when `deadline` is given, the deadline passed;
/// returns when `done` is set.
fn watch(flag: &AtomicBool, done: &AtomicBool, deadline: Option<Instant>) {
    while !done.load(Ordering::SeqCst) {
        if INTERRUPTED.load(Ordering::SeqCst) || deadline.is_some_and(|d| Instant::now() >= d) {
            flag.store(true, Ordering::SeqCst);
            return;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

pub fn run(args: &RenderArgs, time_limit: f64) -> Result<(), CommandError> {
    let budget = check_time_limit(time_limit)?;
    let outputs = OutputPlan::from_args(args)?;
    render_cmd::catch_interrupts(&outputs.exr);
    let started = Instant::now();
    let deadline = started + budget;
    let mut scene = render_cmd::load(args)?;
    // The integrator options join the scene's settings, as in a one-shot render.
    render_cmd::apply_integrator_options(args, &mut scene)?;
    let mut phases = PhaseSeconds {
        load: started.elapsed().as_secs_f64(),
        ..PhaseSeconds::default()
    };
    outputs.check_inputs(scene.input_files.iter().map(std::path::PathBuf::as_path))?;
    let mut options = render_cmd::options(args, &scene)?;
    options.spp = args.spp.unwrap_or(UNBOUNDED_SPP);
    let bound = options.spp;
    let tonemap = render_cmd::tonemap(args, &scene)?;
    let exposure = scene.settings.exposure;
    let estimate =
        render_cmd::memory_estimate(&scene, &options, render_cmd::texture_cache(args).capacity())?;
    render::memory::check(&estimate, args.max_memory, &scene.source)
        .map_err(CommandError::bad_input)?;
    let pool = crate::cli::worker_pool(args.threads)?;

    let decoding = Instant::now();
    let (textures, texture_digests) =
        render_cmd::decode_textures(&scene, &render_cmd::texture_cache(args), args.quiet)?;
    phases.textures = decoding.elapsed().as_secs_f64();
    let signature =
        RenderSignature::new(&scene, args.scene.as_deref(), &options, &texture_digests)?;

    let scene = Arc::new(scene);
    render_cmd::loading_done();
    let preparing = Instant::now();
    let context = pool
        .install(|| render::prepare_with_textures(scene.clone(), options.clone(), textures))
        .map_err(|e| CommandError::bad_input(e.to_string()))?;
    let resolution = selection::resolve(context.scene.settings.integrator, &context.scene);
    // Built once (the voxel scene, for vct) and used by every pass.
    let integrator = render_cmd::select_integrator(&context, resolution.kind)?;
    phases.prepare = preparing.elapsed().as_secs_f64();
    let layers = render::film_layers(options.aovs);
    let pixel_count = options.width as usize * options.height as usize;
    let mut accumulated = Accumulated {
        sums: vec![[0i128; 3]; pixel_count],
        samples: 0,
        image: None,
    };
    let mut counters = WorkCounters::default();
    let mut render_seconds = 0.0;
    let mut write_seconds = 0.0;
    let mut passes = 0u32;
    let mut last_stats: Option<RenderStats> = None;
    let mut seconds_per_sample: Option<f64> = None;
    let mut last_write_seconds = 0.0;
    let mut abandoned_samples = 0u32;
    let stopped_by = loop {
        if accumulated.samples >= bound {
            break "samples";
        }
        if INTERRUPTED.load(Ordering::SeqCst) {
            break "interrupted";
        }
        let fits = seconds_per_sample.map(|per_sample| {
            let left = deadline
                .saturating_duration_since(Instant::now())
                .as_secs_f64();
            samples_that_fit(left, last_write_seconds, per_sample)
        });
        let samples = next_pass(accumulated.samples, bound, fits);
        if samples.is_empty() {
            break "time";
        }
        let part = RenderPart {
            samples: samples.clone(),
            ..RenderPart::whole(&options)
        };
        let cancel = AtomicBool::new(false);
        let pass_done = AtomicBool::new(false);
        // The first pass ignores the deadline (see the module doc).
        let pass_deadline = (passes > 0).then_some(deadline);
        let result = std::thread::scope(|scope| {
            scope.spawn(|| watch(&cancel, &pass_done, pass_deadline));
            let result = pool.install(|| {
                let control = RenderControl {
                    cancel: Some(&cancel),
                    part: Some(&part),
                    ..RenderControl::default()
                };
                render::render(&context, &integrator, &control)
            });
            pass_done.store(true, Ordering::SeqCst);
            result
        });
        let result = result.map_err(crate::cli::render_failed)?;
        if phases.first_ray == 0.0 {
            phases.first_ray = crate::cli::seconds_since_start(result.first_ray_at);
        }
        if !result.finished_tiles.iter().all(|&f| f) {
            abandoned_samples = samples.len() as u32;
            break if INTERRUPTED.load(Ordering::SeqCst) {
                "interrupted"
            } else {
                "time"
            };
        }
        render_seconds += result.stats.seconds;
        counters.add(&result.stats.counters);
        seconds_per_sample = Some(result.stats.seconds / samples.len() as f64);
        accumulated.add_pass(&result.film, &samples, &layers)?;
        passes += 1;

        let mut stats = result.stats;
        stats.integrator = Some(resolution.to_string());
        stats.notes.extend(selection::unsupported_effects(
            resolution.kind,
            &context.scene,
        ));
        stats.counters = counters.clone();
        stats.seconds = render_seconds;
        stats.spp = accumulated.samples;
        stats.mrays_per_second = counters.total_rays() as f64 / render_seconds.max(1e-9) / 1e6;
        phases.render = render_seconds;
        phases.write = write_seconds;
        phases.total = started.elapsed().as_secs_f64();
        stats.phases = Some(phases);
        let writing = Instant::now();
        let progress = ProgressiveStats {
            time_limit_seconds: time_limit,
            sample_bound: args.spp,
            passes,
            samples: accumulated.samples,
            stopped_by: "running".to_string(),
            abandoned_samples: 0,
        };
        write_outputs(
            &outputs,
            &accumulated,
            &stats,
            &progress,
            &signature,
            &context.camera,
            tonemap,
            exposure,
        )?;
        last_write_seconds = writing.elapsed().as_secs_f64();
        write_seconds += last_write_seconds;
        last_stats = Some(stats);
        if !args.quiet {
            // One plain line a pass: a farm's log shows how far the render has come.
            eprintln!(
                "{}",
                pass_line(
                    passes,
                    accumulated.samples,
                    started.elapsed(),
                    budget,
                    &outputs.exr
                )
            );
        }
    };

    let Some(mut stats) = last_stats else {
        return Err(render_cmd::nothing_written(
            "the first pass finished",
            &outputs.exr,
        ));
    };
    phases.write = write_seconds;
    phases.total = started.elapsed().as_secs_f64();
    stats.phases = Some(phases);
    let progress = ProgressiveStats {
        time_limit_seconds: time_limit,
        sample_bound: args.spp,
        passes,
        samples: accumulated.samples,
        stopped_by: stopped_by.to_string(),
        abandoned_samples,
    };
    // The statistics get their final word (why the render stopped, the total time); the
    // images on disk are the last pass's already.
    if let Some(stats_path) = &outputs.stats {
        let mut set = OutputSet::default();
        stage_stats(&mut set, stats_path, &stats, &progress)?;
        set.commit()
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
    }
    let mut line = stats.summary_line();
    let stopper = if stopped_by == "interrupted" {
        "an interrupt"
    } else {
        stopped_by
    };
    line.push_str(&format!(
        "; progressive: {}, {} spp reached, stopped by {stopper} (time limit {time_limit} s)",
        pass_count(passes),
        accumulated.samples
    ));
    if abandoned_samples > 0 {
        let by = if stopped_by == "interrupted" {
            "cut short by the interrupt"
        } else {
            "overtaken by the deadline"
        };
        line.push_str(&format!(
            "; a pass of {abandoned_samples} spp was {by} and left out"
        ));
    }
    line.push_str(&format!("; wrote {}", outputs.exr.display()));
    if let Some(png_path) = &outputs.png {
        line.push_str(&format!(" and {}", png_path.display()));
    }
    println!("{line}");
    if stopped_by == "interrupted" {
        return Err(CommandError {
            message: format!(
                "interrupted: the outputs hold pass {passes} ({} samples per pixel)",
                accumulated.samples
            ),
            status: EXIT_INTERRUPTED,
        });
    }
    Ok(())
}

/// "1 pass", "N passes".
fn pass_count(passes: u32) -> String {
    if passes == 1 {
        "1 pass".to_string()
    } else {
        format!("{passes} passes")
    }
}

fn stage_stats(
    set: &mut OutputSet,
    path: &std::path::Path,
    stats: &RenderStats,
    progress: &ProgressiveStats,
) -> Result<(), CommandError> {
    let text = serde_json::to_string_pretty(&ProgressiveStatsFile {
        render: stats,
        progressive: progress,
    })
    .map_err(|e| CommandError::internal(format!("statistics: {e}")))?;
    render_cmd::stage_text(set, path, &text).map_err(|e| CommandError::bad_input(e.to_string()))
}

/// Replaces the EXR, PNG and statistics with the image of the passes so far, together.
#[allow(clippy::too_many_arguments)]
fn write_outputs(
    outputs: &OutputPlan,
    accumulated: &Accumulated,
    stats: &RenderStats,
    progress: &ProgressiveStats,
    signature: &RenderSignature,
    camera: &conetrace::camera::Camera,
    tonemap: crate::scene::ToneMap,
    exposure: f32,
) -> Result<(), CommandError> {
    let Some(image) = &accumulated.image else {
        return Err(CommandError::internal("progressive: no pass to write"));
    };
    let mut attributes = ExrAttributes {
        software: Some(format!("conetrace {}", env!("CARGO_PKG_VERSION"))),
        world_to_camera: Some(camera.world_to_camera_matrix()),
        world_to_ndc: Some(camera.world_to_ndc_matrix()),
        ..ExrAttributes::default()
    };
    let samples = 0..accumulated.samples;
    let strings = &mut attributes.strings;
    strings.insert(
        film::partial::SAMPLES_ATTRIBUTE.to_string(),
        film::partial::format_sample_range(&samples),
    );
    strings.insert(
        film::partial::SAMPLE_WEIGHT_ATTRIBUTE.to_string(),
        samples.len().to_string(),
    );
    strings.insert(
        PROGRESSIVE_SAMPLES_ATTRIBUTE.to_string(),
        accumulated.samples.to_string(),
    );
    strings.insert(
        PROGRESSIVE_PASSES_ATTRIBUTE.to_string(),
        progress.passes.to_string(),
    );
    for (name, value) in signature.attributes() {
        strings.insert(name.to_string(), value.to_string());
    }
    let written = |e: film::OutputError| CommandError::bad_input(e.to_string());
    let mut set = OutputSet::default();
    film::stage_exr(&mut set, image, &outputs.exr, &attributes).map_err(written)?;
    if let Some(png_path) = &outputs.png {
        film::stage_png(&mut set, image, png_path, tonemap, exposure).map_err(written)?;
    }
    if let Some(stats_path) = &outputs.stats {
        stage_stats(&mut set, stats_path, stats, progress)?;
    }
    // Every output is a complete image: an earlier interrupted render's partial files are
    // superseded, as a complete render's commit removes them.
    set.remove_on_commit(&outputs.partial_exr);
    if let Some(partial_stats) = &outputs.partial_stats {
        set.remove_on_commit(partial_stats);
    }
    set.commit().map_err(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_pass_is_one_plain_line() {
        assert_eq!(
            pass_line(
                3,
                4,
                std::time::Duration::from_millis(1234),
                std::time::Duration::from_secs(60),
                std::path::Path::new("out/x.exr")
            ),
            "progress: pass 3 done, 4 spp, 1.2 s of 60 s; wrote out/x.exr"
        );
    }

    #[test]
    fn passes_double_and_respect_the_bound_and_the_time() {
        let mut done = 0;
        let mut sizes = Vec::new();
        loop {
            let pass = next_pass(done, 20, None);
            if pass.is_empty() {
                break;
            }
            assert_eq!(pass.start, done);
            sizes.push(pass.len());
            done = pass.end;
        }
        assert_eq!(sizes, vec![1, 1, 2, 4, 8, 4]);
        assert_eq!(next_pass(8, 100, Some(3)), 8..11);
        assert!(next_pass(8, 100, Some(0)).is_empty());
        assert!(next_pass(5, 5, None).is_empty());
        assert_eq!(next_pass(0, UNBOUNDED_SPP, None), 0..1);
        assert_eq!(
            next_pass(1 << 31, UNBOUNDED_SPP, None),
            (1 << 31)..UNBOUNDED_SPP
        );
    }

    #[test]
    fn a_pass_the_time_caps_leaves_a_fifth_of_the_time_spare() {
        // 10 s left, a 1 s write, 0.1 s a sample: 9 s usable, 7.2 s planned, 72 samples.
        assert_eq!(samples_that_fit(10.0, 1.0, 0.1), 72);
        assert_eq!(samples_that_fit(0.5, 1.0, 0.1), 0);
        assert_eq!(samples_that_fit(1.0, 0.0, 0.0), 800_000_000_000);
    }

    #[test]
    fn time_limits_must_be_positive_seconds() {
        assert!(check_time_limit(0.5).is_ok());
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(check_time_limit(bad).is_err(), "{bad}");
        }
    }
}
