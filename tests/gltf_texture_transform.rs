//! Khronos' `TextureTransformTest.gltf` (package `assimp-testmodels`) rendered the way a
//! user would (`conetrace render TextureTransformTest.gltf`, camera placed to frame it),
//! each of its six tiles judged from the rendered albedo.
//!
//! The model is built so that a correct `KHR_texture_transform` shows: in the top row, the
//! green "U", blue "V" and cyan "UV" quadrants of its UV texture (yellow means the offset was
//! not applied); in the bottom row, an arrow pointing at a green mark on each of the
//! "Rotation", "Scale" and "All" tiles (a yellow mark means the transform was not applied,
//! a red one that the rotation turned the wrong way).
//!
//! The model lies in the plane z = 0 (the marks 0.01 in front). Every pixel's camera ray is
//! intersected with that plane, so the arrows are measured in the model's own units, free of
//! the framing camera's perspective; tiles and marks are located by their meshes' materials.

mod common;

use common::{read_exr, temp_dir};
use conetrace::camera::Camera;
use conetrace::scene::load::{frame_camera, load_scene};
use conetrace::scene::SceneDescription;
use glam::{Vec2, Vec3};
use std::path::Path;

const MODEL: &str = "/usr/share/assimp/models/glTF2/textureTransform/TextureTransformTest.gltf";
const WIDTH: usize = 1200;
const HEIGHT: usize = 800;

/// The albedo classes the test tells apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Hue {
    Yellow,
    Green,
    Blue,
    Cyan,
    Red,
    /// The arrow.
    Black,
    /// White, grey and edge blends: not counted.
    Other,
}

fn hue(albedo: [f32; 3]) -> Hue {
    let on = |v: f32| v > 0.25;
    let off = |v: f32| v < 0.06;
    let [r, g, b] = albedo;
    if r.max(g).max(b) < 0.1 {
        return Hue::Black;
    }
    match (on(r), on(g), on(b), off(r), off(g), off(b)) {
        (true, true, _, _, _, true) => Hue::Yellow,
        (_, true, false, true, _, true) => Hue::Green,
        (_, _, true, true, true, _) => Hue::Blue,
        (_, true, true, true, _, _) => Hue::Cyan,
        (true, _, _, _, true, true) => Hue::Red,
        _ => Hue::Other,
    }
}

/// An axis-aligned rectangle of the model's plane (world x, y).
#[derive(Clone, Copy, Debug)]
struct Rect {
    center: Vec2,
    half: Vec2,
}

impl Rect {
    fn contains(&self, p: Vec2, margin: f32) -> bool {
        let d = (p - self.center).abs();
        d.x <= self.half.x + margin && d.y <= self.half.y + margin
    }
}

/// The world rectangles of the meshes drawn with the material called `material`.
fn rects(scene: &SceneDescription, material: &str) -> Vec<Rect> {
    scene
        .meshes
        .iter()
        .filter(|m| scene.materials[m.material].name == material)
        .map(|m| {
            let lo = m.positions.iter().fold(Vec3::MAX, |a, &b| a.min(b));
            let hi = m.positions.iter().fold(Vec3::MIN, |a, &b| a.max(b));
            assert!(hi.z - lo.z < 0.02, "{material}: not in a z plane");
            Rect {
                center: ((lo + hi) * 0.5).truncate(),
                half: ((hi - lo) * 0.5).truncate(),
            }
        })
        .collect()
}

/// One rendered pixel: where its ray meets the plane z = 0, and its albedo class.
#[derive(Clone, Copy)]
struct Sample {
    at: Vec2,
    hue: Hue,
}

/// The colour most of a top-row tile shows (white lettering and edges not counted).
fn dominant_hue(tile: Rect, samples: &[Sample]) -> (Hue, String) {
    let candidates = [Hue::Yellow, Hue::Green, Hue::Blue, Hue::Cyan];
    let counts: Vec<usize> = candidates
        .iter()
        .map(|&h| {
            samples
                .iter()
                .filter(|s| s.hue == h && tile.contains(s.at, -0.03))
                .count()
        })
        .collect();
    let best = (0..candidates.len())
        .max_by_key(|&i| counts[i])
        .expect("four candidates");
    let summary = candidates
        .iter()
        .zip(&counts)
        .map(|(h, n)| format!("{h:?} {n}"))
        .collect::<Vec<_>>()
        .join(", ");
    (candidates[best], summary)
}

/// The arrow on `tile`: its tip and unit direction in the model's plane, with a summary.
fn arrow(tile: Rect, samples: &[Sample]) -> Result<(Vec2, Vec2, String), String> {
    let points: Vec<Vec2> = samples
        .iter()
        .filter(|s| s.hue == Hue::Black && tile.contains(s.at, 0.0))
        .map(|s| s.at)
        .collect();
    if points.len() < 200 {
        return Err(format!("no arrow ({} dark pixels)", points.len()));
    }
    let mean = |p: &[Vec2]| p.iter().copied().sum::<Vec2>() / p.len() as f32;
    let c = mean(&points);
    // The arrow's axis: the principal direction of its pixels.
    let (mut sxx, mut sxy, mut syy) = (0.0f32, 0.0f32, 0.0f32);
    for p in &points {
        let d = *p - c;
        sxx += d.x * d.x;
        sxy += d.x * d.y;
        syy += d.y * d.y;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let mut axis = Vec2::new(angle.cos(), angle.sin());
    let along = |p: Vec2, axis: Vec2| (p - c).dot(axis);
    // The head is the end whose half holds the widest cross-section (the arrowhead's base);
    // the shaft is equally narrow all along.
    let (lo, hi) = points.iter().fold((f32::MAX, f32::MIN), |(lo, hi), &p| {
        (lo.min(along(p, axis)), hi.max(along(p, axis)))
    });
    let middle = 0.5 * (lo + hi);
    let widest = |upper: bool| -> f32 {
        let mut slices: std::collections::HashMap<i64, (f32, f32)> = Default::default();
        for &p in &points {
            let a = along(p, axis);
            if (a > middle) == upper {
                let across = (p - c).perp_dot(axis);
                let slot = slices
                    .entry((a / 0.01).floor() as i64)
                    .or_insert((f32::MAX, f32::MIN));
                *slot = (slot.0.min(across), slot.1.max(across));
            }
        }
        slices.values().map(|(a, b)| b - a).fold(0.0, f32::max)
    };
    let (upper, lower) = (widest(true), widest(false));
    if lower > upper {
        axis = -axis;
    }
    let reach = points
        .iter()
        .map(|&p| along(p, axis))
        .fold(f32::MIN, f32::max);
    let near_tip: Vec<Vec2> = points
        .iter()
        .copied()
        .filter(|&p| along(p, axis) > reach - 0.01)
        .collect();
    let tip = mean(&near_tip);
    let summary = format!(
        "arrow of {} px, tip at ({:.3}, {:.3}) pointing ({:.3}, {:.3}), head {:.3} wide, \
         shaft {:.3}",
        points.len(),
        tip.x - tile.center.x,
        tip.y - tile.center.y,
        axis.x,
        axis.y,
        upper.max(lower),
        upper.min(lower)
    );
    Ok((tip, axis, summary))
}

/// Where the arrow (tip, unit direction) lands among `marks` (rectangle, colour): the mark
/// nearest the tip among those the arrow's line runs through and that do not lie behind
/// the tip.
fn landing(tip: Vec2, axis: Vec2, marks: &[(Rect, Hue)]) -> (Option<Hue>, String) {
    let mut best: Option<(f32, Hue)> = None;
    let mut summary = Vec::new();
    for &(mark, hue) in marks {
        let v = mark.center - tip;
        let ahead = v.dot(axis);
        let off_line = v.perp_dot(axis).abs();
        let radius = mark.half.min_element();
        let on_line = ahead > -radius && off_line < radius;
        summary.push(format!(
            "{hue:?} mark {ahead:.3} ahead, {off_line:.3} off the line (half-size {radius:.3})"
        ));
        if on_line && best.is_none_or(|(nearest, _)| ahead < nearest) {
            best = Some((ahead, hue));
        }
    }
    (best.map(|(_, hue)| hue), summary.join("; "))
}

#[test]
fn every_tile_of_the_texture_transform_test_shows_its_correct_mark() {
    assert!(
        Path::new(MODEL).is_file(),
        "{MODEL} is missing: install the package assimp-testmodels (scripts/setup.sh)"
    );
    let dir = temp_dir();
    let exr = dir.path().join("transform.exr");
    let png = dir.path().join("transform.png");
    let output = common::conetrace()
        .args(["render", MODEL, "--quiet", "--spp", "1"])
        .args([
            "--width",
            &WIDTH.to_string(),
            "--height",
            &HEIGHT.to_string(),
        ])
        .arg("-o")
        .arg(&exr)
        .arg("--png")
        .arg(&png)
        .output()
        .expect("the conetrace binary runs");
    assert!(
        output.status.success(),
        "render failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    if let Ok(keep) = std::env::var("CONETRACE_KEEP_RENDER") {
        std::fs::copy(&png, &keep).expect("copy the PNG where CONETRACE_KEEP_RENDER says");
    }
    let image = read_exr(&exr);
    assert_eq!((image.width, image.height), (WIDTH, HEIGHT));

    // The camera the command placed: the one that frames the model's bounds at 3:2.
    let scene = load_scene(Path::new(MODEL)).unwrap_or_else(|e| panic!("{e}"));
    let camera = Camera::new(
        &frame_camera(&scene, WIDTH as f32 / HEIGHT as f32),
        WIDTH as u32,
        HEIGHT as u32,
    );
    let (r, g, b) = (
        image.channel("albedo.R"),
        image.channel("albedo.G"),
        image.channel("albedo.B"),
    );
    let depth = image.channel("Z");
    let mut samples = Vec::new();
    let mut depth_mismatches = 0;
    for y in 0..HEIGHT {
        for x in 0..WIDTH {
            let i = y * WIDTH + x;
            if depth[i] >= 1.0e30 {
                continue;
            }
            let (origin, dir) = camera.generate_ray(x as f32 + 0.5, y as f32 + 0.5, Vec2::ZERO);
            let t = -origin.z / dir.z;
            // The depth AOV is camera-space depth; the plane's must agree up to the marks'
            // 0.01 offset, or this is not the camera that rendered the image.
            if (t * dir.dot(camera.forward()) - depth[i]).abs() > 0.05 {
                depth_mismatches += 1;
            }
            samples.push(Sample {
                at: (origin + dir * t).truncate(),
                hue: hue([r[i], g[i], b[i]]),
            });
        }
    }
    assert!(
        depth_mismatches * 1000 < samples.len(),
        "{depth_mismatches} of {} pixels do not lie on the model's plane: the test's camera \
         is not the one the render used",
        samples.len()
    );

    let one = |material: &str| -> Rect {
        match rects(&scene, material)[..] {
            [rect] => rect,
            ref other => panic!("{} meshes use material {material}", other.len()),
        }
    };
    let mut marks: Vec<(Rect, Hue)> = Vec::new();
    for (material, colour) in [
        ("Correct", Hue::Green),
        ("NotSupported", Hue::Yellow),
        ("Error", Hue::Red),
    ] {
        for rect in rects(&scene, material) {
            // The mark must render in its colour, or "green" would mean nothing.
            let inside: Vec<&Sample> = samples
                .iter()
                .filter(|s| rect.contains(s.at, -0.01))
                .collect();
            let coloured = inside.iter().filter(|s| s.hue == colour).count();
            assert!(
                coloured * 2 > inside.len() && !inside.is_empty(),
                "the {material} mark at {:?} is not mostly {colour:?}",
                rect.center
            );
            marks.push((rect, colour));
        }
    }

    let mut failures = Vec::new();
    for (name, expected) in [
        ("Offset U", Hue::Green),
        ("Offset V", Hue::Blue),
        ("Offset UV", Hue::Cyan),
    ] {
        let (shown, counts) = dominant_hue(one(name), &samples);
        eprintln!("{name}: shows {shown:?} (expected {expected:?}; pixels: {counts})");
        if shown != expected {
            failures.push(format!("{name} shows {shown:?}, not {expected:?}"));
        }
    }
    let arrow_tiles = ["Rotation", "Scale", "All"].map(|name| (name, one(name)));
    for (name, tile) in arrow_tiles {
        // A tile's marks are those nearer its centre than any other arrow tile's.
        let distance = |a: Vec2, b: Vec2| (a - b).abs().max_element();
        let own_marks: Vec<(Rect, Hue)> = marks
            .iter()
            .copied()
            .filter(|(mark, _)| {
                arrow_tiles.iter().all(|(_, other)| {
                    distance(mark.center, tile.center) <= distance(mark.center, other.center)
                })
            })
            .collect();
        let (target, description) = match arrow(tile, &samples) {
            Ok((tip, axis, shape)) => {
                let (target, geometry) = landing(tip, axis, &own_marks);
                (target, format!("{shape}; {geometry}"))
            }
            Err(why) => (None, why),
        };
        let verdict = match target {
            Some(Hue::Green) => "the green (correct) mark".to_string(),
            Some(Hue::Yellow) => "the yellow (not applied) mark".to_string(),
            Some(Hue::Red) => "the red (error) mark".to_string(),
            Some(other) => format!("{other:?}"),
            None => "no mark".to_string(),
        };
        eprintln!("{name}: the arrow points at {verdict}: {description}");
        if target != Some(Hue::Green) {
            failures.push(format!("{name}'s arrow points at {verdict}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("; "));
}
