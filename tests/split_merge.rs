//! A render split into parts (`--region`, `--samples`, `--part`) and put back together by
//! `conetrace merge` equals the single-machine render bit for bit, every channel (colour,
//! alpha and the AOVs); merge refuses parts that do not make up exactly one render, with one
//! line and exit status 2, writing nothing.
//!
//! The scene is the shipped default scene (mirror, glass with absorption, textures, sky) at
//! a small size and 4 samples per pixel, so samples fall at different positions and their
//! float sums depend on the grouping.

mod common;

use std::path::{Path, PathBuf};

use common::*;

const WIDTH: u32 = 80;
const HEIGHT: u32 = 64;
const SPP: u32 = 4;

fn scene() -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    assert!(
        path.exists(),
        "the shipped scene {} is missing",
        path.display()
    );
    path
}

/// Renders the shipped scene to `dir/name` with `extra` options; panics with stderr on failure.
fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    render_spp(dir, name, SPP, extra)
}

/// [`render`] at `spp` samples per pixel.
fn render_spp(dir: &Path, name: &str, spp: u32, extra: &[&str]) -> PathBuf {
    render_sized(
        dir,
        name,
        (WIDTH, HEIGHT),
        spp,
        &[&["--no-png"], extra].concat(),
    )
}

/// [`render`] of a `size.0` x `size.1` image at `spp` samples per pixel (a PNG too unless
/// `extra` says `--no-png`).
fn render_sized(dir: &Path, name: &str, size: (u32, u32), spp: u32, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let scene = scene();
    let (w, h, spp) = (size.0.to_string(), size.1.to_string(), spp.to_string());
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
        "--width",
        &w,
        "--height",
        &h,
        "--spp",
        &spp,
        "--aov",
        "all",
    ];
    args.extend_from_slice(extra);
    let output = run_in(dir, &args);
    assert!(
        output.status.success(),
        "render {extra:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    out
}

fn merge(dir: &Path, parts: &[PathBuf], out: &str) -> std::process::Output {
    let out = dir.join(out);
    let mut args: Vec<&str> = vec!["merge"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", out.to_str().unwrap()]);
    run_in(dir, &args)
}

fn merged(dir: &Path, parts: &[PathBuf], out: &str) -> PathBuf {
    let output = merge(dir, parts, out);
    assert!(
        output.status.success(),
        "merge failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    dir.join(out)
}

/// Every channel of `a` and `b` has the same bits; the data and display windows agree.
fn assert_same_image(a: &Path, b: &Path) {
    let (fa, attributes_a) = conetrace::film::read_exr(a).unwrap();
    let (fb, attributes_b) = conetrace::film::read_exr(b).unwrap();
    assert_eq!(attributes_a.window, attributes_b.window);
    assert_eq!((fa.width(), fa.height()), (fb.width(), fb.height()));
    assert_eq!(fa.channel_names(), fb.channel_names());
    assert!(!fa.has(conetrace::film::Layer::SampleSum));
    for name in fa.channel_names() {
        let (va, vb) = (fa.channel(&name).unwrap(), fb.channel(&name).unwrap());
        let differing = va
            .iter()
            .zip(vb)
            .filter(|(x, y)| x.to_bits() != y.to_bits())
            .count();
        assert_eq!(
            differing,
            0,
            "channel {name}: {differing} pixels differ between {} and {}",
            a.display(),
            b.display()
        );
    }
    // The files themselves are identical: same header, same compressed pixels.
    assert_eq!(
        std::fs::read(a).unwrap(),
        std::fs::read(b).unwrap(),
        "{} and {} differ as files",
        a.display(),
        b.display()
    );
}

#[test]
fn region_parts_merge_into_the_single_render() {
    let dir = temp_dir();
    let whole = render(dir.path(), "whole.exr", &[]);
    for count in [1u32, 2, 4] {
        let parts: Vec<PathBuf> = (0..count)
            .map(|i| {
                let spec = format!("{i}/{count}");
                render(
                    dir.path(),
                    &format!("part{i}of{count}.exr"),
                    &["--part", &spec],
                )
            })
            .collect();
        // A part's data window is its strip, its display window the whole image.
        if count > 1 {
            let (film, attributes) = conetrace::film::read_exr(&parts[1]).unwrap();
            let window = attributes.window.expect("a strip has a data window");
            assert_eq!((window.full_width, window.full_height), (WIDTH, HEIGHT));
            assert_eq!(film.width(), WIDTH);
            assert!(window.y0 > 0 && film.height() < HEIGHT);
            assert!(film.has(conetrace::film::Layer::Lod), "AOVs come along");
        }
        let out = merged(dir.path(), &parts, &format!("merged{count}.exr"));
        assert_same_image(&whole, &out);
    }
    // Explicit regions, including a column split, in any order.
    let parts = [
        render(dir.path(), "right.exr", &["--region", "48,0,80,64"]),
        render(dir.path(), "left_top.exr", &["--region", "0,0,48,32"]),
        render(dir.path(), "left_bottom.exr", &["--region", "0,32,48,64"]),
    ];
    assert_same_image(&whole, &merged(dir.path(), &parts, "regions.exr"));
}

/// `--region` takes any rectangle inside the image: the render traces the work tiles that
/// cover it and keeps its pixels, so every channel equals the whole render's there, bit for
/// bit. The region's EXR has the region as its data window and the whole image as its
/// display window; `--png` writes the region alone, sized to it, with the whole render's
/// PNG pixels.
#[test]
fn a_region_off_the_tile_grid_holds_the_whole_render_s_pixels() {
    let dir = temp_dir();
    let d = dir.path();
    let size = (120, 104);
    let whole = render_sized(d, "whole.exr", size, SPP, &[]);
    let png = d.join("region.png");
    let region = render_sized(
        d,
        "region.exr",
        size,
        SPP,
        &["--region", "10,10,100,100", "--png", png.to_str().unwrap()],
    );
    let (whole_film, _) = conetrace::film::read_exr(&whole).unwrap();
    let (region_film, attributes) = conetrace::film::read_exr(&region).unwrap();
    let window = attributes.window.expect("a region has a data window");
    assert_eq!(
        (window.x0, window.y0, window.full_width, window.full_height),
        (10, 10, size.0, size.1)
    );
    assert_eq!((region_film.width(), region_film.height()), (90, 90));
    assert_eq!(region_film.channel_names(), whole_film.channel_names());
    for name in whole_film.channel_names() {
        let (all, part) = (
            whole_film.channel(&name).unwrap(),
            region_film.channel(&name).unwrap(),
        );
        let differing = (0..90usize * 90)
            .filter(|&i| {
                let (x, y) = (10 + i % 90, 10 + i / 90);
                part[i].to_bits() != all[y * size.0 as usize + x].to_bits()
            })
            .count();
        assert_eq!(differing, 0, "channel {name}: {differing} pixels differ");
    }

    let whole_png = image::open(d.join("whole.png")).unwrap().to_rgba8();
    let region_png = image::open(&png)
        .unwrap_or_else(|e| panic!("--region --png wrote no readable {}: {e}", png.display()))
        .to_rgba8();
    assert_eq!(region_png.dimensions(), (90, 90));
    for (x, y, pixel) in region_png.enumerate_pixels() {
        assert_eq!(
            pixel,
            whole_png.get_pixel(x + 10, y + 10),
            "PNG pixel {x},{y}"
        );
    }
}

/// Regions with edges off the tile grid that tile the frame merge into the single render,
/// byte for byte (here three, cutting tiles both ways).
#[test]
fn odd_edged_regions_merge_into_the_single_render() {
    let dir = temp_dir();
    let d = dir.path();
    let whole = render(d, "whole.exr", &[]);
    let parts = [
        render(d, "top_left.exr", &["--region", "0,0,37,23"]),
        render(d, "top_right.exr", &["--region", "37,0,80,23"]),
        render(d, "bottom.exr", &["--region", "0,23,80,64"]),
    ];
    assert_same_image(&whole, &merged(d, &parts, "odd.exr"));
}

#[test]
fn sample_ranges_that_cut_a_packet_block_merge_into_the_single_render() {
    // Whitted traces up to 16 samples of a pixel together (blocks 0, 1, 2-3, 4-7, 8-15 and
    // 16-23 here); parts
    // that begin or end inside a block trace that block's packets as the whole render does.
    let dir = temp_dir();
    let whole = render_spp(dir.path(), "whole24.exr", 24, &[]);
    let splits: [&[&str]; 2] = [
        &["0..5", "5..17", "17..24"],
        &["0..1", "1..16", "16..23", "23..24"],
    ];
    for (k, ranges) in splits.iter().enumerate() {
        let parts: Vec<PathBuf> = ranges
            .iter()
            .enumerate()
            .map(|(i, range)| {
                render_spp(
                    dir.path(),
                    &format!("b{k}_{i}.exr"),
                    24,
                    &["--samples", range],
                )
            })
            .collect();
        let out = merged(dir.path(), &parts, &format!("blocks{k}.exr"));
        assert_same_image(&whole, &out);
    }
}

#[test]
fn sample_range_parts_merge_into_the_single_render() {
    let dir = temp_dir();
    let whole = render(dir.path(), "whole.exr", &[]);
    let splits: [&[&str]; 3] = [
        &["0..4"],
        &["0..2", "2..4"],
        &["3..4", "0..1", "2..3", "1..2"],
    ];
    for (k, ranges) in splits.iter().enumerate() {
        let parts: Vec<PathBuf> = ranges
            .iter()
            .enumerate()
            .map(|(i, range)| render(dir.path(), &format!("s{k}_{i}.exr"), &["--samples", range]))
            .collect();
        if ranges.len() > 1 {
            let (film, attributes) = conetrace::film::read_exr(&parts[0]).unwrap();
            assert!(film.has(conetrace::film::Layer::SampleSum));
            let range = &attributes.strings["conetrace.samples"];
            assert_eq!(attributes.strings["conetrace.sample_weight_sum"], {
                let (a, b) = range.split_once("..").unwrap();
                (b.parse::<u32>().unwrap() - a.parse::<u32>().unwrap()).to_string()
            });
        }
        let out = merged(dir.path(), &parts, &format!("merged{k}.exr"));
        assert_same_image(&whole, &out);
    }
    // Both kinds at once: the top strip whole, the bottom strip in two sample ranges.
    let parts = [
        render(dir.path(), "top.exr", &["--part", "0/2"]),
        render(
            dir.path(),
            "bottom_a.exr",
            &["--part", "1/2", "--samples", "0..3"],
        ),
        render(
            dir.path(),
            "bottom_b.exr",
            &["--part", "1/2", "--samples", "3..4"],
        ),
    ];
    assert_same_image(&whole, &merged(dir.path(), &parts, "mixed.exr"));
}

/// Merge fails with exit 2, one line naming `expect`, and writes nothing.
fn assert_refused(dir: &Path, parts: &[PathBuf], expect: &str) {
    let output = merge(dir, parts, "refused.exr");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{parts:?}: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains(expect), "expected {expect:?} in: {stderr}");
    assert!(
        !dir.join("refused.exr").exists(),
        "a refused merge wrote its output"
    );
}

#[test]
fn merge_refuses_parts_that_are_not_one_render() {
    let dir = temp_dir();
    let d = dir.path();
    let top = render(d, "top.exr", &["--region", "0,0,80,32"]);
    let bottom = render(d, "bottom.exr", &["--region", "0,32,80,64"]);
    let low = render(d, "low.exr", &["--samples", "0..2"]);
    let high = render(d, "high.exr", &["--samples", "2..4"]);
    // Sanity: the good sets merge.
    merged(d, &[top.clone(), bottom.clone()], "ok1.exr");
    merged(d, &[low.clone(), high.clone()], "ok2.exr");

    let other_depth = render(
        d,
        "other.exr",
        &["--region", "0,32,80,64", "--max-depth", "2"],
    );
    assert_refused(d, &[top.clone(), other_depth], "conetrace.option.max-depth");
    let overlapping = render(d, "overlap.exr", &["--region", "0,16,80,64"]);
    assert_refused(d, &[top.clone(), overlapping], "overlaps");
    assert_refused(
        d,
        std::slice::from_ref(&top),
        "pixel 0,32 has 0 of its 4 samples",
    );
    assert_refused(d, &[low.clone(), low.clone(), high.clone()], "overlaps");
    assert_refused(d, std::slice::from_ref(&low), "has 2 of its 4 samples");
    let mid = render(d, "mid.exr", &["--samples", "1..3"]);
    assert_refused(d, &[low.clone(), mid], "overlaps");
    // A truncated file.
    let bytes = std::fs::read(&bottom).unwrap();
    let truncated = d.join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() * 2 / 3]).unwrap();
    assert_refused(d, &[top.clone(), truncated], "truncated.exr");
    // A missing file.
    assert_refused(d, &[top, d.join("absent.exr")], "absent.exr");
}

#[test]
fn partial_render_options_are_checked() {
    let dir = temp_dir();
    let scene = scene();
    for (args, expect) in [
        (vec!["--region", "1,0,81,16"], "--region"),
        (vec!["--region", "5,9,5,12"], "--region"),
        (vec!["--samples", "2..9"], "--samples"),
        (vec!["--part", "4/4"], "--part"),
        (vec!["--part", "0/9"], "tile"),
    ] {
        let mut all = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            "x.exr",
            "--no-png",
            "--quiet",
            "--width",
            "80",
            "--height",
            "64",
            "--spp",
            "4",
        ];
        all.extend(args.iter());
        let output = run_in(dir.path(), &all);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expect), "{args:?}: {stderr}");
        assert!(!dir.path().join("x.exr").exists());
    }
    // A sample range's colour is not the image: no PNG of it.
    let output = run_in(
        dir.path(),
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            "x.exr",
            "--png",
            "x.png",
            "--quiet",
            "--width",
            "80",
            "--height",
            "64",
            "--spp",
            "4",
            "--samples",
            "0..2",
        ],
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--png") && stderr.contains("--samples"),
        "{stderr}"
    );
    assert!(!dir.path().join("x.exr").exists() && !dir.path().join("x.png").exists());
}

/// The merge reads its parts one at a time: eight sample-range parts of a 1024x512 image
/// (46 MB of channels each) merge under a 200 MB data limit (`prlimit --data`), as two do.
/// It used to hold every part at once and abort for want of memory. Worker threads are
/// limited to 2 so that the stacks of a many-core machine do not count against the limit.
#[test]
fn merging_many_sample_parts_holds_one_part_at_a_time() {
    let dir = temp_dir();
    let scene = scene();
    let mut parts = Vec::new();
    for i in 0..8 {
        let name = format!("g{i}.exr");
        let samples = format!("{i}..{}", i + 1);
        let out = run_in(
            dir.path(),
            &[
                "render",
                scene.to_str().unwrap(),
                "--width",
                "1024",
                "--height",
                "512",
                "--spp",
                "8",
                "--aov",
                "none",
                "--threads",
                "2",
                "--no-png",
                "--quiet",
                "--samples",
                &samples,
                "-o",
                &name,
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        parts.push(name);
    }
    let out = std::process::Command::new("prlimit")
        .arg("--data=200000000")
        .arg(env!("CARGO_BIN_EXE_conetrace"))
        .arg("merge")
        .args(&parts)
        .args(["-o", "merged.exr"])
        .env("RAYON_NUM_THREADS", "2")
        .current_dir(dir.path())
        .output()
        .expect("prlimit (util-linux) runs");
    assert!(
        out.status.success(),
        "{}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.path().join("merged.exr").exists());
}
