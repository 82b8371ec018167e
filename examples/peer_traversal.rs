//! Traversal alone, conetrace's Embree against Mitsuba 3's, on the same scene and the same
//! rays: bench/peers/mitsuba/traversal.py writes the rays (camera rays and diffuse bounce
//! rays of the path-tracing peer scene) and times Mitsuba's `ray_intersect_preliminary` and
//! `ray_test` on them; this program traces the same file through conetrace's tracer the way
//! the path tracer does (incoherent `rtcIntersect1M` / `rtcOccluded1M` streams of one wave,
//! 256 rays, at a time) on one thread and prints the rates.
//!
//! Run: `cargo run --release --example peer_traversal SCENE.toml RAYS.bin [passes]`; the ray
//! file holds little-endian f32 `ox oy oz dx dy dz` per ray.

use std::sync::Arc;
use std::time::Instant;

use conetrace::render::stats::WorkCounters;
use conetrace::render::tracer::{
    IncoherentLayout, SphereTraversal, TraceHit, TraceRay, Tracer, TracerSettings,
};
use conetrace::render::RenderOptions;
use glam::Vec3;

/// Rays per stream call: one 16 x 16 tile's wave of one sample.
const WAVE: usize = 256;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        return Err("usage: peer_traversal SCENE.toml RAYS.bin [passes]".into());
    }
    // As on every tracing thread of a render (`embree::enable_flush_denormals`).
    conetrace::embree::enable_flush_denormals();
    let passes: usize = args.get(3).map_or(Ok(5), |p| p.parse())?;
    let scene = Arc::new(conetrace::scene::load::load_scene(std::path::Path::new(
        &args[1],
    ))?);
    let options = RenderOptions::from_settings(&scene.settings);
    let mut settings = TracerSettings::for_render(&scene, &options);
    // `CONETRACE_NOT_ROBUST=1`: Embree's faster, non-watertight default instead of robust
    // mode, to see what watertightness costs on these rays.
    settings.robust = std::env::var_os("CONETRACE_NOT_ROBUST").is_none();
    // The other traversal choices, to measure each against the default on these rays:
    // `CONETRACE_SPHERES=user|embree`, `CONETRACE_INCOHERENT=packets|streams`,
    // `CONETRACE_BUILD_QUALITY=high|medium`.
    let var = |name: &str| std::env::var(name).ok();
    match var("CONETRACE_SPHERES").as_deref() {
        Some("user") => settings.spheres = SphereTraversal::UserGeometry,
        Some("embree") => settings.spheres = SphereTraversal::EmbreePoints,
        _ => {}
    }
    match var("CONETRACE_INCOHERENT").as_deref() {
        Some("packets") => settings.incoherent = IncoherentLayout::Packets,
        Some("streams") => settings.incoherent = IncoherentLayout::Streams,
        _ => {}
    }
    match var("CONETRACE_BUILD_QUALITY").as_deref() {
        Some("high") => settings.high_quality_min_triangles = 0,
        Some("medium") => settings.high_quality_min_triangles = usize::MAX,
        _ => {}
    }
    let build_start = Instant::now();
    let (tracer, _) = Tracer::build_with(&scene, &[], &options, settings)?;
    let build_seconds = build_start.elapsed().as_secs_f64();
    let bytes = std::fs::read(&args[2])?;
    let floats: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let rays: Vec<TraceRay> = floats
        .chunks_exact(6)
        .map(|r| TraceRay {
            origin: Vec3::new(r[0], r[1], r[2]),
            direction: Vec3::new(r[3], r[4], r[5]),
            tfar: f32::INFINITY,
            cone_width: 0.0,
            cone_spread: 0.0,
        })
        .collect();
    let mut counters = WorkCounters::default();
    let mut hits: Vec<TraceHit> = Vec::new();
    let mut blocked: Vec<bool> = Vec::new();
    let (mut best_hit, mut best_occluded) = (f64::INFINITY, f64::INFINITY);
    let mut hit_count = 0usize;
    for _ in 0..passes {
        let start = Instant::now();
        hit_count = 0;
        for wave in rays.chunks(WAVE) {
            tracer.intersect_stream(wave.iter().copied(), &mut hits, &mut counters);
            hit_count += hits.iter().filter(|h| h.is_hit()).count();
        }
        best_hit = best_hit.min(start.elapsed().as_secs_f64());
        let start = Instant::now();
        for wave in rays.chunks(WAVE) {
            tracer.occluded_stream(wave.iter().copied(), &mut blocked, &mut counters);
        }
        best_occluded = best_occluded.min(start.elapsed().as_secs_f64());
    }
    let mrays = |seconds: f64| rays.len() as f64 / seconds / 1e6;
    println!(
        "{} rays, {hit_count} hits, robust {}, spheres {:?}, waves {:?}, high build quality from {} triangles; \
         scene build {build_seconds:.3} s; closest hit {best_hit:.4} s ({:.2} Mrays/s), occlusion \
         {best_occluded:.4} s ({:.2} Mrays/s); fastest of {passes}, 1 thread",
        rays.len(),
        settings.robust,
        settings.spheres,
        settings.incoherent,
        settings.high_quality_min_triangles,
        mrays(best_hit),
        mrays(best_occluded)
    );
    Ok(())
}
