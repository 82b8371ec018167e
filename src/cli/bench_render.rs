//! `conetrace bench render`: raw packet traversal vs full shading, side by side in one run.
//!
//! Every pass uses the same scene, tiles, threads and camera rays: the render's own, every
//! sample of every pixel in the packets the integrator builds (a pixel's samples together
//! for Whitted, one sample of 4x4 pixel blocks at a time for the path tracer), so the
//! traversal floor is measured at the render's sample count. The raw pass only traces
//! camera rays; the traversal pass adds one occlusion ray
//! per hit and light but shades nothing (the Embree work of camera-plus-shadow rendering);
//! the full pass renders the rays with shading, shadow rays and secondary rays, and the
//! direct pass with shading and shadow rays only. Each pass runs several times and the
//! median is kept.
//!
//! The same passes also run on a second Embree scene built without robust mode (Embree's
//! faster, non-watertight triangle test), interleaved with the robust ones, to state what
//! watertight traversal costs: the "robust / fast" ratios of the last table. Each
//! `--against` variant (another sphere test, wave layout or build quality) is paired with
//! the default the same way, its Embree scene build timed too.

use std::sync::Arc;
use std::time::Instant;

use clap::Args;
use glam::Vec3;
use rayon::prelude::*;

use crate::cli::bench_scene::BenchSceneArgs;
use crate::cli::render_cmd;
use crate::cli::summary::median;
use crate::cli::CommandError;
use crate::render::stats::WorkCounters;
use crate::render::tracer::{
    IncoherentLayout, SphereTraversal, TraceHit, TraceRay, TracerSettings,
};
use crate::render::{self, RenderContext, RenderControl, RenderOptions};
use crate::shading::{self, SpawnPoint};
use conetrace::integrator::for_each_camera_run;
use conetrace::integrator::selection::{IntegratorKind, SelectedIntegrator};

#[derive(Args, Debug)]
pub struct BenchRenderArgs {
    #[command(flatten)]
    pub scene: BenchSceneArgs,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(long, allow_negative_numbers = true, value_parser = render_cmd::thread_count_parser())]
    pub threads: Option<usize>,
    /// Repetitions of each pass (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub repeat: usize,
    /// The integrator of the full-render passes.
    #[arg(long, default_value = "whitted", value_parser = ["whitted", "path"])]
    pub integrator: String,
    /// Also time each pass with this traversal variant, paired per round with the default,
    /// and the Embree scene build of both (repeatable).
    #[arg(long, value_enum)]
    pub against: Vec<TraversalVariant>,
}

/// A traversal setting `--against` pairs with the default ([`TracerSettings`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum TraversalVariant {
    /// Spheres through Embree's point geometry.
    EmbreeSpheres,
    /// Spheres as a user geometry with our own exact test.
    UserSpheres,
    /// Incoherent waves as AoS ray streams.
    Streams,
    /// Incoherent waves as 16-wide SoA packets.
    Packets,
    /// Embree's high build quality (spatial splits) whatever the triangle count.
    HighQuality,
    /// Embree's medium build quality whatever the triangle count.
    MediumQuality,
}

impl TraversalVariant {
    /// `settings` changed as this variant says.
    fn apply(self, settings: TracerSettings) -> TracerSettings {
        match self {
            TraversalVariant::EmbreeSpheres => TracerSettings {
                spheres: SphereTraversal::EmbreePoints,
                ..settings
            },
            TraversalVariant::UserSpheres => TracerSettings {
                spheres: SphereTraversal::UserGeometry,
                ..settings
            },
            TraversalVariant::Streams => TracerSettings {
                incoherent: IncoherentLayout::Streams,
                ..settings
            },
            TraversalVariant::Packets => TracerSettings {
                incoherent: IncoherentLayout::Packets,
                ..settings
            },
            TraversalVariant::HighQuality => TracerSettings {
                high_quality_min_triangles: 0,
                ..settings
            },
            TraversalVariant::MediumQuality => TracerSettings {
                high_quality_min_triangles: usize::MAX,
                ..settings
            },
        }
    }

    fn name(self) -> &'static str {
        match self {
            TraversalVariant::EmbreeSpheres => "embree-spheres",
            TraversalVariant::UserSpheres => "user-spheres",
            TraversalVariant::Streams => "streams",
            TraversalVariant::Packets => "packets",
            TraversalVariant::HighQuality => "high-quality",
            TraversalVariant::MediumQuality => "medium-quality",
        }
    }
}

/// The render's camera rays (every sample of every pixel, in the integrator's packets)
/// traced through Embree with no shading; returns rays traced.
pub fn trace_camera_rays_only(context: &RenderContext, kind: IntegratorKind) -> u64 {
    let options = &context.options;
    let tiles = render::work_tiles(options.width, options.height);
    tiles
        .par_iter()
        .map_init(
            || {
                crate::embree::enable_flush_denormals();
                (
                    Vec::<TraceRay>::new(),
                    Vec::<TraceHit>::new(),
                    WorkCounters::default(),
                )
            },
            |(rays, hits, counters), tile| {
                let mut traced = 0;
                let in_flight = kind.samples_in_flight();
                for_each_camera_run(context, *tile, in_flight, rays, |rays| {
                    context.tracer.intersect(rays, hits, true, counters);
                    traced += rays.len() as u64;
                });
                traced
            },
        )
        .sum()
}

/// The render's camera rays traced as in [`trace_camera_rays_only`], then, from every hit,
/// one occlusion ray towards each light traced as a stream: the Embree work of camera-plus-shadow rendering with no
/// shading at all (no hit reconstruction, footprints, texture lookups or light evaluation).
/// The shadow origin steps back along the camera ray, past the error bound of
/// `origin + t * direction` (`shading::SpawnPoint::along_ray`), instead of along the surface
/// normal from a recomputed point, which needs no surface reconstruction. Returns (camera rays, shadow rays).
pub fn trace_camera_and_shadow_rays_only(
    context: &RenderContext,
    kind: IntegratorKind,
) -> (u64, u64) {
    let options = &context.options;
    let tiles = render::work_tiles(options.width, options.height);
    let lights = &context.scene.lights;
    tiles
        .par_iter()
        .map_init(
            || {
                crate::embree::enable_flush_denormals();
                (
                    Vec::<TraceRay>::new(),
                    Vec::<TraceHit>::new(),
                    Vec::<TraceRay>::new(),
                    Vec::<bool>::new(),
                    WorkCounters::default(),
                )
            },
            |(rays, hits, shadow_rays, blocked, counters), tile| {
                let mut traced = (0, 0);
                let in_flight = kind.samples_in_flight();
                for_each_camera_run(context, *tile, in_flight, rays, |rays| {
                    context.tracer.intersect(rays, hits, true, counters);
                    shadow_rays.clear();
                    for (ray, hit) in rays.iter().zip(hits.iter()) {
                        if !hit.is_hit() {
                            continue;
                        }
                        let origin = SpawnPoint::along_ray(ray.origin, ray.direction, hit.t)
                            .offset_origin(-ray.direction);
                        for light in lights {
                            let sample = shading::sample_li(light, origin);
                            let tfar = shading::shadow_ray_end(
                                sample.distance,
                                shading::light_position(light).unwrap_or(Vec3::ZERO),
                                0.0,
                            );
                            shadow_rays.push(TraceRay {
                                origin,
                                direction: sample.direction_to_light,
                                tfar,
                                cone_width: 0.0,
                                cone_spread: 0.0,
                            });
                        }
                    }
                    if !shadow_rays.is_empty() {
                        context.tracer.occluded(shadow_rays, blocked, counters);
                    }
                    traced.0 += rays.len() as u64;
                    traced.1 += shadow_rays.len() as u64;
                });
                traced
            },
        )
        .reduce(|| (0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
}

/// Paired times of two Embree scenes of the same render, per pass: the default ("a") and a
/// variant ("b"), such as the robust (watertight) scene and the fast one.
struct PairedCost {
    /// Column names of the two scenes.
    a: String,
    b: String,
    /// (pass name, a's seconds, b's seconds) per round.
    rounds: Vec<(&'static str, f64, f64)>,
}

impl PairedCost {
    fn new(a: &str, b: &str) -> PairedCost {
        PairedCost {
            a: a.to_owned(),
            b: b.to_owned(),
            rounds: Vec::new(),
        }
    }

    /// One round: each pass on both scenes, `a` first in even rounds and `b` first in odd
    /// rounds, so neither profits from running second.
    fn measure(
        &mut self,
        round: usize,
        (a, b): (&RenderContext, &RenderContext),
        kind: IntegratorKind,
        render_timed: &dyn Fn(&RenderContext) -> Result<render::RenderResult, CommandError>,
    ) -> Result<(), CommandError> {
        let time = |f: &dyn Fn()| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        };
        let even = round.is_multiple_of(2);
        let order = if even { [a, b] } else { [b, a] };
        // (a, b) seconds of one pass, run in `order`.
        let pair = |seconds: [f64; 2]| {
            if even {
                (seconds[0], seconds[1])
            } else {
                (seconds[1], seconds[0])
            }
        };
        let (x, y) = pair(order.map(|c| {
            time(&|| {
                trace_camera_rays_only(c, kind);
            })
        }));
        self.rounds.push(("camera rays, no shading", x, y));
        let (x, y) = pair(order.map(|c| {
            time(&|| {
                trace_camera_and_shadow_rays_only(c, kind);
            })
        }));
        self.rounds.push(("camera + shadow rays, no shading", x, y));
        let first = render_timed(order[0])?.stats.seconds;
        let second = render_timed(order[1])?.stats.seconds;
        let (x, y) = pair([first, second]);
        self.rounds.push(("full render", x, y));
        Ok(())
    }

    /// Adds one round's scene build times (in the table's "Embree scene build" row).
    fn record_build(&mut self, a_seconds: f64, b_seconds: f64) {
        self.rounds
            .push(("Embree scene build", a_seconds, b_seconds));
    }

    fn print(&self, title: &str, repeat: usize) {
        println!("{title}, paired per round, median of {repeat}:");
        let (a, b) = (&self.a, &self.b);
        println!("| pass | {a} seconds | {b} seconds | {a} / {b} |");
        println!("|---|---|---|---|");
        for pass in [
            "camera rays, no shading",
            "camera + shadow rays, no shading",
            "full render",
            "Embree scene build",
        ] {
            let rows: Vec<&(&str, f64, f64)> =
                self.rounds.iter().filter(|(p, _, _)| *p == pass).collect();
            if rows.is_empty() {
                continue;
            }
            let x = median(&rows.iter().map(|r| r.1).collect::<Vec<_>>());
            let y = median(&rows.iter().map(|r| r.2).collect::<Vec<_>>());
            let ratio = median(
                &rows
                    .iter()
                    .map(|r| r.1 / r.2.max(1e-12))
                    .collect::<Vec<_>>(),
            );
            println!("| {pass} | {x:.4} | {y:.4} | {ratio:.3} |");
        }
    }
}

/// The context of each `--against` variant, with its paired times.
struct VariantRun {
    variant: TraversalVariant,
    context: RenderContext,
    cost: PairedCost,
}

impl VariantRun {
    fn new(
        variant: TraversalVariant,
        scene: &Arc<crate::scene::SceneDescription>,
        options: &RenderOptions,
    ) -> Result<VariantRun, CommandError> {
        let bad = |e: render::PrepareError| CommandError::bad_input(e.to_string());
        let mut context = render::prepare(scene.clone(), options.clone()).map_err(bad)?;
        let settings = variant.apply(context.tracer.settings());
        context.set_tracer_settings(settings).map_err(bad)?;
        Ok(VariantRun {
            variant,
            context,
            cost: PairedCost::new("default", variant.name()),
        })
    }

    /// Times one build of the default's Embree scene and one of the variant's, on this
    /// run's context (left with the variant's); nothing when the variant is the default.
    fn time_builds(&mut self, default: TracerSettings) -> Result<Option<(f64, f64)>, CommandError> {
        let bad = |e: render::PrepareError| CommandError::bad_input(e.to_string());
        let variant = self.context.tracer.settings();
        if variant == default {
            return Ok(None);
        }
        let start = Instant::now();
        self.context.set_tracer_settings(default).map_err(bad)?;
        let a = start.elapsed().as_secs_f64();
        let start = Instant::now();
        self.context.set_tracer_settings(variant).map_err(bad)?;
        Ok(Some((a, start.elapsed().as_secs_f64())))
    }
}

pub fn run(args: &BenchRenderArgs) -> Result<(), CommandError> {
    let render_args = args.scene.render_args(args.threads)?;
    let scene = render_cmd::load(&render_args)?;
    let mut options = render_cmd::options(&render_args, &scene)?;
    options.count_texture_tiles = false;
    let repeat = args.repeat.max(1);
    let pool = crate::cli::worker_pool(args.threads)?;
    let scene = Arc::new(scene);
    pool.install(|| {
        let context = render::prepare(scene.clone(), options.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        // The same rays shaded with direct light and shadow rays only (no reflection or
        // refraction rays): the camera-plus-shadow rendering the target speaks of.
        let direct_options = RenderOptions {
            max_depth: 0,
            ..options.clone()
        };
        let direct_context = render::prepare(scene.clone(), direct_options)
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        // The same scene without Embree's robust mode: what watertight traversal costs.
        let mut fast_context = render::prepare(scene.clone(), options.clone())
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        fast_context
            .set_robust_traversal(false)
            .map_err(|e| CommandError::bad_input(e.to_string()))?;
        let kind = match args.integrator.as_str() {
            "path" => IntegratorKind::Path,
            _ => IntegratorKind::Whitted,
        };
        let integrator: SelectedIntegrator = render_cmd::select_integrator(&context, kind)?;
        let mut variants = args
            .against
            .iter()
            .map(|&variant| VariantRun::new(variant, &scene, &options))
            .collect::<Result<Vec<_>, _>>()?;
        let render_timed = |context: &RenderContext| {
            render::render(context, &integrator, &RenderControl::default())
                .map_err(crate::cli::render_failed)
        };
        // Traversal-only passes record failures in the tracer instead of returning them.
        let check_traversal = |context: &RenderContext| match context.tracer.take_failure() {
            Some(error) => Err(crate::cli::render_failed(render::RenderError::Traversal {
                scene: context.scene.source.clone(),
                source: error,
            })),
            None => Ok(()),
        };
        // Warm up every path once (page faults, lazy BVH parts).
        let warm_up = [&context, &fast_context]
            .into_iter()
            .chain(variants.iter().map(|v| &v.context));
        for c in warm_up {
            trace_camera_rays_only(c, kind);
            trace_camera_and_shadow_rays_only(c, kind);
            check_traversal(c)?;
            render_timed(c)?;
        }
        render_timed(&direct_context)?;
        let mut robust_cost = PairedCost::new("robust", "fast");

        let mut raw_times = Vec::new();
        let mut full_times = Vec::new();
        let mut direct_times = Vec::new();
        let mut direct_counters = WorkCounters::default();
        let mut raw_rays = 0;
        let mut traversal_times = Vec::new();
        let mut traversal_rays = (0, 0);
        let mut full_counters = WorkCounters::default();
        for round in 0..repeat {
            let start = Instant::now();
            raw_rays = trace_camera_rays_only(&context, kind);
            raw_times.push(start.elapsed().as_secs_f64());
            let start = Instant::now();
            traversal_rays = trace_camera_and_shadow_rays_only(&context, kind);
            traversal_times.push(start.elapsed().as_secs_f64());
            check_traversal(&context)?;
            let result = render_timed(&context)?;
            full_times.push(result.stats.seconds);
            full_counters = result.stats.counters;
            let result = render_timed(&direct_context)?;
            direct_times.push(result.stats.seconds);
            direct_counters = result.stats.counters;
            // Robust vs fast, paired within the round.
            robust_cost.measure(round, (&context, &fast_context), kind, &render_timed)?;
            check_traversal(&context)?;
            check_traversal(&fast_context)?;
            for run in &mut variants {
                run.cost
                    .measure(round, (&context, &run.context), kind, &render_timed)?;
                check_traversal(&run.context)?;
                if let Some((a, b)) = run.time_builds(context.tracer.settings())? {
                    run.cost.record_build(a, b);
                }
            }
        }
        let raw = median(&raw_times);
        let full = median(&full_times);
        let raw_rate = raw_rays as f64 / raw / 1e6;
        let full_camera_rate = full_counters.camera_rays as f64 / full / 1e6;
        let full_ray_rate = full_counters.total_rays() as f64 / full / 1e6;
        let direct = median(&direct_times);
        let direct_camera_rate = direct_counters.camera_rays as f64 / direct / 1e6;
        let direct_ray_rate = direct_counters.total_rays() as f64 / direct / 1e6;
        println!(
            "scene {} at {}x{}, {} spp, {} threads, {} integrator, median of {repeat}",
            scene.source,
            options.width,
            options.height,
            options.spp,
            rayon::current_num_threads(),
            kind.name()
        );
        println!("| pass | seconds | camera Mrays/s | all Mrays/s |");
        println!("|---|---|---|---|");
        println!("| raw packet traversal ({raw_rays} camera rays, no shading) | {raw:.4} | {raw_rate:.2} | {raw_rate:.2} |");
        let traversal = median(&traversal_times);
        let traversal_rate = (traversal_rays.0 + traversal_rays.1) as f64 / traversal / 1e6;
        println!(
            "| camera + shadow rays traced, nothing shaded ({} camera, {} shadow rays) | {traversal:.4} | {:.2} | {traversal_rate:.2} |",
            traversal_rays.0,
            traversal_rays.1,
            traversal_rays.0 as f64 / traversal / 1e6
        );
        println!(
            "| full shading ({} camera, {} shadow, {} reflection, {} refraction rays) | {full:.4} | {full_camera_rate:.2} | {full_ray_rate:.2} |",
            full_counters.camera_rays,
            full_counters.shadow_rays,
            full_counters.reflection_rays,
            full_counters.refraction_rays
        );
        println!(
            "| camera + shadow rays, shaded, no bounces ({} camera, {} shadow rays) | {direct:.4} | {direct_camera_rate:.2} | {direct_ray_rate:.2} |",
            direct_counters.camera_rays, direct_counters.shadow_rays
        );
        println!(
            "ratio camera+shadow/raw: {:.3} in all rays per second, {:.3} in camera rays per second (pixels)",
            direct_ray_rate / raw_rate,
            direct_camera_rate / raw_rate
        );
        println!(
            "ratio camera+shadow traversal without shading/raw: {:.3} in all rays per second (the ceiling shading can approach)",
            traversal_rate / raw_rate
        );
        println!(
            "ratio full/raw: {:.3} in all rays per second, {:.3} in camera rays per second (pixels)",
            full_ray_rate / raw_rate,
            full_camera_rate / raw_rate
        );
        robust_cost.print(
            "watertight traversal (Embree robust mode) vs Embree's default",
            repeat,
        );
        for run in &variants {
            run.cost.print(
                &format!("default traversal vs {}", run.variant.name()),
                repeat,
            );
        }
        Ok(())
    })
}
