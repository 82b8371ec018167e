//! Measures how to trace incoherent secondary rays through Embree: 16-wide packets
//! (`rtcIntersect16`) against ray streams (`rtcIntersect1M`), with single rays as a baseline,
//! for closest-hit and shadow (occlusion) queries, all in one run.
//!
//! Scene: 100,000 random triangles and 1,000 spheres in a 100^3 box. Rays: 2^20 bounce rays
//! from random points on the triangles in uniformly random directions (what a diffuse bounce
//! produces after a few scattering events). Packets take the rays 16 at a time in generation
//! order, i.e. with no coherence at all.
//!
//! Run: `cargo run --release --example secondary_rays [ray_count] [passes]`.
//! The machines are shared and noisy: compare the ratios printed by one run.

use std::time::Instant;

use conetrace::embree::{
    enable_flush_denormals, CommittedScene, Device, EmbreeError, Ray, RayHit, RayPacket,
    SceneBuilder, TraceOptions,
};
use glam::Vec3;

/// xorshift64*: deterministic and dependency-free.
struct Rng(u64);

impl Rng {
    fn next_f32(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40) as f32 / (1u64 << 24) as f32
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        let mut c = || lo + (hi - lo) * self.next_f32();
        Vec3::new(c(), c(), c())
    }
    fn direction(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            let l2 = v.length_squared();
            if l2 > 1e-4 && l2 <= 1.0 {
                return v / l2.sqrt();
            }
        }
    }
}

const TRIANGLES: usize = 100_000;
const SPHERES: usize = 1_000;
const BOX: f32 = 50.0;

fn build_scene(device: &Device, rng: &mut Rng) -> Result<(CommittedScene, Vec<Vec3>), EmbreeError> {
    let mut vertices = Vec::with_capacity(3 * TRIANGLES);
    let mut triangles = Vec::with_capacity(TRIANGLES);
    for t in 0..TRIANGLES {
        let center = rng.vec(-BOX, BOX);
        for _ in 0..3 {
            vertices.push(center + rng.vec(-1.5, 1.5));
        }
        let b = 3 * t as u32;
        triangles.push([b, b + 1, b + 2]);
    }
    let spheres: Vec<(Vec3, f32)> = (0..SPHERES)
        .map(|_| (rng.vec(-BOX, BOX), 0.5 + 2.0 * rng.next_f32()))
        .collect();
    let mut builder = SceneBuilder::new(device)?;
    builder.add_triangle_mesh(&vertices, &triangles)?;
    builder.add_spheres(&spheres)?;
    Ok((builder.commit()?, vertices))
}

/// Bounce rays: a random point on a random triangle, pushed off the surface along the
/// direction, in a uniformly random direction.
fn bounce_rays(vertices: &[Vec3], count: usize, rng: &mut Rng) -> Vec<Ray> {
    (0..count)
        .map(|_| {
            let t = ((rng.next_f32() * TRIANGLES as f32) as usize).min(TRIANGLES - 1);
            let (mut a, mut b) = (rng.next_f32(), rng.next_f32());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let [p0, p1, p2] = [vertices[3 * t], vertices[3 * t + 1], vertices[3 * t + 2]];
            let p = p0 + a * (p1 - p0) + b * (p2 - p0);
            let d = rng.direction();
            Ray::segment(p, d, 1e-3, f32::INFINITY)
        })
        .collect()
}

/// One measured way of tracing all rays; returns a checksum of the hits.
fn run(
    scene: &CommittedScene,
    rays: &[Ray],
    method: &str,
    shadow: bool,
) -> Result<u64, EmbreeError> {
    let opts = TraceOptions::incoherent();
    let mut checksum = 0u64;
    match method {
        "single" => {
            for r in rays {
                if shadow {
                    checksum += scene.occluded1(r, opts)? as u64;
                } else if let Some(h) = scene.intersect1(r, opts)? {
                    checksum += h.prim_id as u64;
                }
            }
        }
        "packet16" | "packet8" => {
            let wide = method == "packet16";
            let width = if wide { 16 } else { 8 };
            let mut p16 = RayPacket::<16>::new();
            let mut p8 = RayPacket::<8>::new();
            for chunk in rays.chunks(width) {
                if wide {
                    p16 = RayPacket::new();
                    chunk
                        .iter()
                        .enumerate()
                        .for_each(|(l, r)| p16.set_ray(l, r));
                    if shadow {
                        scene.occluded16(&mut p16, opts)?;
                    } else {
                        scene.intersect16(&mut p16, opts)?;
                    }
                } else {
                    p8 = RayPacket::new();
                    chunk.iter().enumerate().for_each(|(l, r)| p8.set_ray(l, r));
                    if shadow {
                        scene.occluded8(&mut p8, opts)?;
                    } else {
                        scene.intersect8(&mut p8, opts)?;
                    }
                }
                for lane in 0..chunk.len() {
                    checksum += match (wide, shadow) {
                        (true, true) => p16.is_occluded(lane) as u64,
                        (true, false) => p16.hit(lane).map_or(0, |h| h.prim_id as u64),
                        (false, true) => p8.is_occluded(lane) as u64,
                        (false, false) => p8.hit(lane).map_or(0, |h| h.prim_id as u64),
                    };
                }
            }
        }
        "stream" | "stream_coherent" => {
            let opts = if method == "stream" {
                opts
            } else {
                TraceOptions::coherent()
            };
            // Streams of 1024 rays: what a renderer would batch per bounce and tile.
            let mut batch: Vec<RayHit> = Vec::with_capacity(1024);
            for chunk in rays.chunks(1024) {
                batch.clear();
                batch.extend(chunk.iter().map(RayHit::new));
                if shadow {
                    scene.occluded_stream(&mut batch, opts)?;
                    checksum += batch.iter().filter(|r| r.is_occluded()).count() as u64;
                } else {
                    scene.intersect_stream(&mut batch, opts)?;
                    checksum += batch
                        .iter()
                        .map(|r| r.hit().map_or(0, |h| h.prim_id as u64))
                        .sum::<u64>();
                }
            }
        }
        _ => {}
    }
    Ok(checksum)
}

fn main() -> Result<(), EmbreeError> {
    let args: Vec<String> = std::env::args().collect();
    let ray_count: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1 << 20);
    let repeats: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    enable_flush_denormals();
    let device = Device::with_config("threads=1")?;
    let mut rng = Rng(0x005E_ED0F_C0DE);
    let (scene, vertices) = build_scene(&device, &mut rng)?;
    let rays = bounce_rays(&vertices, ray_count, &mut rng);
    println!(
        "scene: {TRIANGLES} triangles + {SPHERES} spheres, native packet width {}, {} rays, \
         1 thread, {repeats} passes",
        scene.packet_width(),
        rays.len()
    );
    let methods = ["single", "packet8", "packet16", "stream", "stream_coherent"];
    // Blocks of rays are traced by every method in turn (rotating which goes first), so
    // drifting load from other processes on the shared machine hits all methods alike.
    const BLOCK: usize = 16 * 1024;
    for shadow in [false, true] {
        let mut seconds = vec![0.0f64; methods.len()];
        let mut sums = vec![0u64; methods.len()];
        for repeat in 0..repeats {
            for (b, block) in rays.chunks(BLOCK).enumerate() {
                for k in 0..methods.len() {
                    let m = (k + b + repeat) % methods.len();
                    let start = Instant::now();
                    let sum = run(&scene, block, methods[m], shadow)?;
                    seconds[m] += start.elapsed().as_secs_f64();
                    if repeat == 0 {
                        sums[m] += sum;
                    }
                }
            }
        }
        println!(
            "{}:",
            if shadow {
                "occlusion (shadow rays)"
            } else {
                "closest hit"
            }
        );
        let traced = (rays.len() * repeats) as f64;
        for (m, method) in methods.iter().enumerate() {
            println!(
                "  {method:<16} {:7.3} Mrays/s  ({:5.2}x single)  checksum {}",
                traced / seconds[m] / 1e6,
                seconds[0] / seconds[m],
                sums[m]
            );
        }
    }
    Ok(())
}
