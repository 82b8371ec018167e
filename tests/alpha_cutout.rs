//! Alpha cut-outs (Embree filter callbacks in Rust, `render::tracer::alpha_filter`) seen at a
//! distance and up close: 16-wide packets and single rays agree, distant coverage equals the
//! texture's mean alpha, a magnified view is a crisp cut at the cutoff, and the renderer's
//! output (pixels with a depth in `Z`) shows the same coverage.
//!
//! The mask is assets/textures/leaf_alpha.png (scripts/make_footprint_assets.py): leaves
//! with alpha exactly 0 or 1, so the fraction of texels at or above the cutoff equals the
//! mean alpha.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use conetrace::film::AovSelection;
use conetrace::footprint::LodStrategy;
use conetrace::render::tracer::{TraceHit, TraceRay};
use conetrace::render::{RenderContext, RenderOptions, WorkCounters};
use conetrace::texture::{FilterMode, FilterOptions};
use glam::{Vec2, Vec3};

use common::*;

fn leaf_texture_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/leaf_alpha.png")
}

/// A 2x2 quad in the plane z = 0 facing +z; st = ((x + 1) / 2, (1 - y) / 2).
const QUAD_OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n\
f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";

/// A scene with the leaf-masked quad repeated `repeat` times across, seen head-on by a
/// pinhole camera at `distance` whose view (vertical fov `fov` degrees) stays inside the quad.
/// With `textured`, the leaf image is also the base-colour texture.
fn write_scene(dir: &Path, repeat: f32, distance: f32, fov: f32, textured: bool) -> PathBuf {
    write(dir, "quad.obj", QUAD_OBJ);
    let texture = leaf_texture_path();
    write(
        dir,
        "leaves.toml",
        &format!(
            r#"
[camera]
type = "pinhole"
eye = [0.0, 0.0, {distance}]
target = [0.0, 0.0, 0.0]
fov = {fov}

[environment]
color = [0.0, 0.0, 0.0]

[[light]]
type = "directional"
direction = [0.0, 0.0, -1.0]

[[texture]]
name = "leaf"
file = "{texture}"
color_space = "linear"

[[material]]
name = "leaves"
base_color = [0.2, 0.6, 0.2]
{base_color_texture}
alpha_texture = "leaf"
alpha_cutoff = 0.5
texture_scale = [{repeat}, {repeat}]

[[mesh]]
file = "quad.obj"
material = "leaves"
"#,
            texture = texture.display(),
            base_color_texture = if textured {
                "base_color_texture = \"leaf\""
            } else {
                ""
            }
        ),
    )
}

fn prepare(scene: &Path, size: u32) -> RenderContext {
    let description = conetrace::scene::load::load_scene(scene).expect("test scene loads");
    let options = RenderOptions {
        width: size,
        height: size,
        spp: 1,
        max_depth: 1,
        min_throughput: 0.001,
        lod: LodStrategy::Cone,
        filter: FilterOptions {
            filter: FilterMode::Trilinear,
            ..FilterOptions::default()
        },
        fresnel: Default::default(),
        aovs: AovSelection::default(),
        count_texture_tiles: false,
        all_effects: false,
        seed: 0,
        sample_clamp: None,
    };
    conetrace::render::prepare(Arc::new(description), options).expect("scene prepares")
}

/// One camera ray through each pixel centre, with its cone, in 4x4-block order (as the
/// renderer packs them, so each packet of 16 is one block).
fn camera_rays(context: &RenderContext, size: u32) -> Vec<TraceRay> {
    let mut rays = Vec::with_capacity((size * size) as usize);
    for by in (0..size).step_by(4) {
        for bx in (0..size).step_by(4) {
            for y in by..by + 4 {
                for x in bx..bx + 4 {
                    let (fx, fy) = (x as f32 + 0.5, y as f32 + 0.5);
                    let (origin, direction) = context.camera.generate_ray(fx, fy, Vec2::splat(0.5));
                    let footprint = context.camera.initial_footprint(
                        LodStrategy::Cone,
                        fx,
                        fy,
                        origin,
                        direction,
                    );
                    let (cone_width, cone_spread) = footprint.cone_at_origin();
                    rays.push(TraceRay {
                        origin,
                        direction,
                        tfar: f32::INFINITY,
                        cone_width,
                        cone_spread,
                    });
                }
            }
        }
    }
    rays
}

struct Traced {
    rays: Vec<TraceRay>,
    packets: Vec<TraceHit>,
    singles: Vec<TraceHit>,
    callbacks: u64,
}

fn trace_both(context: &RenderContext, size: u32) -> Traced {
    let rays = camera_rays(context, size);
    let (mut packets, mut singles) = (Vec::new(), Vec::new());
    let mut counters = WorkCounters::default();
    context
        .tracer
        .intersect(&rays, &mut packets, true, &mut counters);
    let callbacks = counters.filter_callbacks;
    context
        .tracer
        .intersect_one_by_one(&rays, &mut singles, &mut counters);
    Traced {
        rays,
        packets,
        singles,
        callbacks,
    }
}

fn coverage(hits: &[TraceHit]) -> f64 {
    hits.iter().filter(|h| h.is_hit()).count() as f64 / hits.len() as f64
}

/// Far away (about 30 texels across each pixel footprint): 16-wide packets and single rays
/// take the same decisions (the callback's per-ray threshold is a function of the ray's
/// origin and direction only), and the fraction of rays that hit is the mean alpha.
#[test]
fn distant_leaves_cover_the_mean_alpha_with_packets_and_single_rays() {
    let dir = temp_dir();
    // 64 repeats of 256 texels over 2 units; the camera sees 1.6 units at 256 pixels:
    // 8192 * 0.8 / 256 = 25.6 texels per pixel.
    let distance = 40.0f32;
    let fov = 2.0 * (0.8f32 / distance).atan().to_degrees();
    let scene = write_scene(dir.path(), 64.0, distance, fov, false);
    let size = 256;
    let context = prepare(&scene, size);
    let traced = trace_both(&context, size);
    assert!(
        traced.callbacks >= traced.rays.len() as u64,
        "the alpha filter ran only {} times for {} rays",
        traced.callbacks,
        traced.rays.len()
    );

    let differing = traced
        .packets
        .iter()
        .zip(&traced.singles)
        .filter(|(p, s)| p.is_hit() != s.is_hit())
        .count();
    let (packet_coverage, single_coverage) = (coverage(&traced.packets), coverage(&traced.singles));
    let mean_alpha = context.textures[0].mean_alpha() as f64;
    eprintln!(
        "distant leaves: mean alpha {mean_alpha:.4}, packet coverage {packet_coverage:.4} ({}-wide device packets), single-ray coverage {single_coverage:.4}, {differing} of {} rays differ",
        context.tracer.packet_width(),
        traced.rays.len()
    );
    // Identical up to rare rays whose filtered alpha sits exactly at their threshold, where
    // the packet and single-ray triangle tests may round u, v or t differently.
    assert!(
        differing * 1000 <= traced.rays.len(),
        "{differing} rays differ between packets and single rays"
    );
    for c in [packet_coverage, single_coverage] {
        assert!(
            (c - mean_alpha).abs() <= 0.05 * mean_alpha,
            "coverage {c:.4} vs mean alpha {mean_alpha:.4}"
        );
    }
}

/// Up close (about 0.4 texels per pixel) the cut-out is crisp: each ray hits exactly where
/// the texel under it is at or above the cutoff, so the coverage is the fraction of such
/// texels in view, not a dithered mean.
#[test]
fn magnified_leaves_are_a_crisp_cutout() {
    let dir = temp_dir();
    // One repeat of 256 texels over 2 units; the camera sees 0.4 units (51 texels) at 128
    // pixels.
    let distance = 2.0f32;
    let fov = 2.0 * (0.2f32 / distance).atan().to_degrees();
    let scene = write_scene(dir.path(), 1.0, distance, fov, false);
    let size = 128;
    let context = prepare(&scene, size);
    let traced = trace_both(&context, size);
    let level = &context.textures[0].pyramid().levels[0];
    let mut agree = 0usize;
    let mut expected_hits = 0usize;
    for (ray, hit) in traced.rays.iter().zip(&traced.packets) {
        // Where the ray meets the plane z = 0, and the texel there.
        let t = -ray.origin.z / ray.direction.z;
        let p: Vec3 = ray.origin + t * ray.direction;
        let (s, tt) = ((p.x + 1.0) / 2.0, (1.0 - p.y) / 2.0);
        let x = ((s * level.width as f32) as usize).min(level.width as usize - 1);
        let y = ((tt * level.height as f32) as usize).min(level.height as usize - 1);
        let opaque = level.texel(x, y)[3] >= 0.5;
        expected_hits += opaque as usize;
        agree += (opaque == hit.is_hit()) as usize;
    }
    let n = traced.rays.len();
    let expected = expected_hits as f64 / n as f64;
    let got = coverage(&traced.packets);
    eprintln!(
        "magnified leaves: texels in view >= cutoff {expected:.4}, coverage {got:.4}, {agree} of {n} rays agree with the texel under them"
    );
    assert!(
        expected > 0.1 && expected < 0.9,
        "the view should show leaf edges (opaque fraction {expected})"
    );
    // Disagreement only along edges, where bilinear interpolation moves the cut by under a
    // texel (about two pixels here).
    assert!(agree * 100 >= n * 95, "only {agree} of {n} rays agree");
    assert!(
        (got - expected).abs() < 0.02,
        "coverage {got} vs {expected}"
    );
    let differing = traced
        .packets
        .iter()
        .zip(&traced.singles)
        .filter(|(p, s)| p.is_hit() != s.is_hit())
        .count();
    assert!(
        differing * 1000 <= n,
        "{differing} rays differ between packets and single rays"
    );
}

/// Render the distant view with `--lod cone` and return the fraction of pixels covered
/// (where the EXR's `Z` channel holds a depth) and the mask's mean alpha.
fn rendered_distant_coverage(textured: bool) -> (f64, f64) {
    let dir = temp_dir();
    let distance = 40.0f32;
    let fov = 2.0 * (0.8f32 / distance).atan().to_degrees();
    let scene = write_scene(dir.path(), 64.0, distance, fov, textured);
    let out = run_in(
        dir.path(),
        &[
            "render",
            scene.to_str().expect("utf-8 path"),
            "-o",
            "leaves.exr",
            "--no-png",
            "--quiet",
            "--width",
            "256",
            "--height",
            "256",
            "--lod",
            "cone",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = read_exr(&dir.path().join("leaves.exr"));
    // `Z` is the first hit's depth, f32::MAX where the camera ray missed (`A` is 1 for every
    // finished pixel, background included).
    let depth = image.channel("Z");
    let covered = depth.iter().filter(|&&z| z < f32::MAX).count() as f64 / depth.len() as f64;
    let texture = conetrace::texture::Texture::from_file(
        &leaf_texture_path(),
        conetrace::texture::ColorSpace::Linear,
    )
    .expect("leaf texture loads");
    (covered, texture.mean_alpha() as f64)
}

/// The whole program: the fraction of pixels whose camera ray hit (a depth in `Z`) in the
/// distant view of leaves that also use the leaf image as base colour matches the mean alpha within
/// 5%.
#[test]
fn rendered_distant_textured_leaves_cover_the_mean_alpha() {
    let (covered, mean_alpha) = rendered_distant_coverage(true);
    eprintln!("rendered coverage {covered:.4}, mean alpha {mean_alpha:.4}");
    assert!(
        (covered - mean_alpha).abs() <= 0.05 * mean_alpha,
        "rendered coverage {covered:.4} vs mean alpha {mean_alpha:.4}"
    );
}

/// The same with a material whose only texture is the alpha mask: the effect analysis
/// (src/render/effects.rs) must still turn ray footprints on, or camera rays would carry no
/// cone and the alpha filter would test single texels at the cutoff (coverage 0.32 was
/// measured that way) instead of the mean alpha.
#[test]
fn rendered_distant_alpha_only_leaves_cover_the_mean_alpha() {
    let (covered, mean_alpha) = rendered_distant_coverage(false);
    eprintln!("rendered coverage {covered:.4}, mean alpha {mean_alpha:.4}");
    assert!(
        (covered - mean_alpha).abs() <= 0.05 * mean_alpha,
        "rendered coverage {covered:.4} vs mean alpha {mean_alpha:.4}"
    );
}
