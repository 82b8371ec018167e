//! Demand-loaded `.tx` textures: a tiled, mip-mapped TIFF in 64x64 tiles is read tile by
//! tile as lookups touch it. Its lookups and renders must equal those of the same levels
//! decoded whole, it must read fewer tiles than the file holds when seen from afar, and a
//! damaged tile must refuse the render with a line naming the file, the level and the
//! tile (exit status 2), never render black.
//!
//! `maketx` (OpenImageIO, installed by scripts/setup.sh) makes the files; without it the
//! tests fail.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use conetrace::texture::{
    ColorSpace, FilterMode, FilterOptions, Texture, TextureQuery, TextureTileSet, WrapMode,
};

/// A `size` x `size` RGB noise PNG in `dir`, made into `name` by `maketx` with `extra`.
fn maketx(dir: &Path, size: u32, name: &str, extra: &[&str]) -> PathBuf {
    let png = dir.join("noise.png");
    if !png.exists() {
        let mut rng = common::Rng(0x51a7_e5ee_d000_0001);
        let image = image::RgbImage::from_fn(size, size, |_, _| {
            image::Rgb(std::array::from_fn(|_| (rng.next_f32() * 255.0) as u8))
        });
        image.save(&png).expect("noise.png");
    }
    let tx = dir.join(name);
    let status = Command::new("maketx")
        .arg(&png)
        .arg("-o")
        .arg(&tx)
        .args(extra)
        .status()
        .expect("maketx must be installed (scripts/setup.sh)");
    assert!(status.success(), "maketx {name} failed");
    tx
}

fn bits(v: glam::Vec4) -> [u32; 4] {
    v.to_array().map(f32::to_bits)
}

#[test]
fn every_filter_reads_the_same_values_on_demand_as_decoded_whole() {
    let dir = common::temp_dir();
    for (name, extra) in [("bytes.tx", &[][..]), ("half.tx", &["-d", "half"][..])] {
        let tx = maketx(dir.path(), 300, name, extra);
        let demand = Texture::from_file(&tx, ColorSpace::Srgb).unwrap();
        let whole = Texture::from_file_whole(&tx, ColorSpace::Srgb).unwrap();
        assert!(demand.is_demand_loaded() && !whole.is_demand_loaded());
        assert_eq!(
            demand.tiles_read(),
            1,
            "only the 1x1 level is read on opening"
        );
        let mut rng = common::Rng(7);
        for filter in [
            FilterMode::Closest,
            FilterMode::Bilinear,
            FilterMode::Trilinear,
            FilterMode::Aniso,
            FilterMode::Ewa,
        ] {
            for wrap in [
                WrapMode::Periodic,
                WrapMode::Clamp,
                WrapMode::Black,
                WrapMode::Mirror,
            ] {
                let opts = FilterOptions {
                    filter,
                    wrap_s: wrap,
                    wrap_t: wrap,
                    max_aniso: 16.0,
                };
                for _ in 0..300 {
                    let scale = 10f32.powf(rng.range(-4.0, -0.5));
                    let q = TextureQuery {
                        s: rng.range(-0.5, 1.5),
                        t: rng.range(-0.5, 1.5),
                        dsdx: scale * rng.range(-1.0, 1.0),
                        dtdx: scale * rng.range(-1.0, 1.0),
                        dsdy: scale * rng.range(-0.3, 0.3),
                        dtdy: scale * rng.range(-0.3, 0.3),
                    };
                    assert_eq!(
                        bits(demand.sample(&q, &opts)),
                        bits(whole.sample(&q, &opts)),
                        "{name} {filter} {wrap} {q:?}"
                    );
                }
            }
        }
        assert!(demand.tile_failure().is_none());
        assert_eq!(demand.pyramid(), whole.pyramid(), "{name}: every texel");
        assert_eq!(demand.tiles_read(), demand.tiles_in_file());
    }
}

#[test]
fn a_far_lookup_reads_only_the_tiles_it_touches() {
    let dir = common::temp_dir();
    let tx = maketx(dir.path(), 1024, "big.tx", &[]);
    let texture = Texture::from_file(&tx, ColorSpace::Srgb).unwrap();
    // 16x16 + 8x8 + 4x4 + 2x2 + 1 + 1 + ... tiles over levels 1024 to 1.
    assert_eq!(texture.tiles_in_file(), 256 + 64 + 16 + 4 + 7);
    let q = TextureQuery {
        s: 0.3,
        t: 0.6,
        dsdx: 1.0 / 40.0,
        dtdx: 0.0,
        dsdy: 0.0,
        dtdy: 1.0 / 40.0,
    };
    let opts = FilterOptions {
        filter: FilterMode::Trilinear,
        ..FilterOptions::default()
    };
    let mut touched = TextureTileSet::new();
    texture.sample_recording(&q, &opts, &mut touched);
    // A footprint of 1/40 of the texture blends two levels near 64x64: a tile or two
    // each, and the 1x1 level read on opening.
    assert!((2..=8).contains(&touched.count()), "{}", touched.count());
    assert_eq!(texture.tiles_read(), 1 + touched.count());
}

fn scene(dir: &Path, texture: &str) {
    common::write(dir, "quad.obj", &common::square_obj(1.0, 0.0));
    common::write(
        dir,
        "s.toml",
        &format!(
            r#"
[render]
width = 48
height = 32
[camera]
eye = [0.3, 1.5, 0.9]
target = [0.0, 0.0, 0.0]
fov = 40.0
[environment]
color = [0.2, 0.2, 0.2]
[[light]]
type = "directional"
direction = [0.2, -1.0, -0.3]
[[texture]]
name = "t"
file = "{texture}"
[[material]]
name = "m"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "t"
[[mesh]]
file = "quad.obj"
material = "m"
"#
        ),
    );
}

fn render(dir: &Path, output: &str) -> std::process::Output {
    common::run_in(
        dir,
        &[
            "render",
            "s.toml",
            "-o",
            output,
            "--quiet",
            "--no-png",
            "--integrator",
            "whitted",
        ],
    )
}

#[test]
fn a_render_through_demand_loaded_tiles_equals_the_render_of_the_levels_decoded_whole() {
    let dir = common::temp_dir();
    maketx(dir.path(), 512, "tiles64.tx", &[]);
    // The same levels in 32x32 tiles: decoded whole.
    let resident = maketx(dir.path(), 512, "tiles32.tx", &["--tile", "32", "32"]);
    assert!(!Texture::from_file(&resident, ColorSpace::Srgb)
        .unwrap()
        .is_demand_loaded());
    let mut images = Vec::new();
    for file in ["tiles64.tx", "tiles32.tx"] {
        scene(dir.path(), file);
        let out = render(dir.path(), "out.exr");
        assert!(
            out.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        images.push(common::read_exr(&dir.path().join("out.exr")));
    }
    // Pixels, bit for bit (the files' headers name the texture files, which differ).
    for (name, pixels) in &images[0].channels {
        let other = images[1].channel(name);
        assert!(
            pixels
                .iter()
                .zip(other)
                .all(|(a, b)| a.to_bits() == b.to_bits()),
            "channel {name} differs"
        );
    }
}

#[test]
fn the_stats_count_the_tiles_a_render_read_of_those_the_file_holds() {
    let dir = common::temp_dir();
    maketx(dir.path(), 2048, "big.tx", &[]);
    scene(dir.path(), "big.tx");
    let out = common::run_in(
        dir.path(),
        &[
            "render",
            "s.toml",
            "-o",
            "out.exr",
            "--quiet",
            "--no-png",
            "--integrator",
            "whitted",
            "--stats",
            "s.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("s.json")).unwrap()).unwrap();
    let entry = &stats["texture_memory"][0];
    let read = entry["tiles_read"].as_u64().expect("tiles_read");
    let in_file = entry["tiles_in_file"].as_u64().expect("tiles_in_file");
    // 32x32 + 16x16 + 8x8 + 4x4 + 2x2 tiles, then one for each level from 64x64 to 1x1.
    assert_eq!(in_file, 1024 + 256 + 64 + 16 + 4 + 7);
    // A 48x32 image of the quad needs a few coarse levels' tiles, not level 0.
    assert!((2..100).contains(&read), "{read} of {in_file} tiles read");
    let bytes = entry["bytes"].as_u64().unwrap();
    assert_eq!(bytes % 4, 0);
    assert!(
        bytes <= read * 64 * 64 * 4,
        "{bytes} bytes for {read} tiles"
    );
}

#[test]
fn a_damaged_tile_refuses_the_render_naming_file_level_and_tile() {
    let dir = common::temp_dir();
    let tx = maketx(dir.path(), 512, "damaged.tx", &[]);
    // Every tile of every level but the 1x1 one (read on opening) is overwritten.
    let mut bytes = std::fs::read(&tx).unwrap();
    let mut decoder = tiff::decoder::Decoder::new(std::io::Cursor::new(bytes.clone())).unwrap();
    let mut chunks = Vec::new();
    loop {
        let (w, h) = decoder.dimensions().unwrap();
        if (w, h) != (1, 1) {
            let offsets = decoder
                .get_tag_u64_vec(tiff::tags::Tag::TileOffsets)
                .unwrap();
            let counts = decoder
                .get_tag_u64_vec(tiff::tags::Tag::TileByteCounts)
                .unwrap();
            chunks.extend(offsets.into_iter().zip(counts));
        }
        if !decoder.more_images() {
            break;
        }
        decoder.next_image().unwrap();
    }
    assert!(chunks.len() > 80);
    for (offset, count) in chunks {
        bytes[offset as usize..(offset + count) as usize].fill(0xff);
    }
    std::fs::write(&tx, &bytes).unwrap();
    scene(dir.path(), "damaged.tx");
    let out = render(dir.path(), "out.exr");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    let line = stderr.trim();
    assert_eq!(line.lines().count(), 1, "{stderr}");
    assert!(line.contains("damaged.tx: level "), "{stderr}");
    assert!(line.contains(", tile ("), "{stderr}");
    assert!(!dir.path().join("out.exr").exists(), "no image is written");
}

/// Renders `s.toml` in `dir` into `output` with `extra` arguments; fails the test on a
/// non-zero exit.
fn render_with(dir: &Path, output: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["render", "s.toml", "-o", output, "--quiet", "--no-png"];
    args.extend_from_slice(extra);
    let out = common::run_in(dir, &args);
    assert!(
        out.status.success(),
        "{extra:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The bits of every pixel of every channel of `path`, channels by name.
fn pixel_bits(path: &Path) -> Vec<(String, Vec<u32>)> {
    let image = common::read_exr(path);
    let mut channels: Vec<(String, Vec<u32>)> = image
        .channels
        .iter()
        .map(|(name, pixels)| (name.clone(), pixels.iter().map(|v| v.to_bits()).collect()))
        .collect();
    channels.sort();
    channels
}

#[test]
fn a_cache_of_four_tiles_renders_the_images_of_the_default_cache_and_of_resident_levels() {
    let dir = common::temp_dir();
    maketx(dir.path(), 1024, "cached.tx", &[]);
    // The same levels in 32x32 tiles: decoded whole, fully resident.
    maketx(dir.path(), 1024, "resident.tx", &["--tile", "32", "32"]);
    for integrator in ["whitted", "path"] {
        for (lod, filter) in [("mip0", "bilinear"), ("cone", "aniso"), ("distance", "ewa")] {
            let common_args = [
                "--integrator",
                integrator,
                "--lod",
                lod,
                "--filter",
                filter,
                "--spp",
                "2",
                "--seed",
                "11",
            ];
            let mut images = Vec::new();
            for (file, cache) in [
                ("resident.tx", None),
                ("cached.tx", None),
                ("cached.tx", Some("64K")),
            ] {
                scene(dir.path(), file);
                let mut args = common_args.to_vec();
                if let Some(size) = cache {
                    args.extend(["--texture-cache", size]);
                }
                render_with(dir.path(), "out.exr", &args);
                images.push(pixel_bits(&dir.path().join("out.exr")));
            }
            let case = format!("{integrator} --lod {lod} --filter {filter}");
            assert_eq!(
                images[1], images[0],
                "{case}: default cache against resident"
            );
            assert_eq!(images[2], images[0], "{case}: 64K cache against resident");
        }
    }
}

/// The `texture_cache` totals, the distinct tiles touched and the summary line of a
/// mip-0, bilinear render of `cached.tx` with `extra` arguments.
fn cache_stats(dir: &Path, extra: &[&str]) -> (serde_json::Value, u64, String) {
    let mut args = vec![
        "--integrator",
        "whitted",
        "--lod",
        "mip0",
        "--filter",
        "bilinear",
        "--stats",
        "s.json",
        "--count-texture-tiles",
    ];
    args.extend_from_slice(extra);
    let out = render_with(dir, "out.exr", &args);
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("s.json")).unwrap()).unwrap();
    let touched = stats["texture_tiles"]["total"]
        .as_u64()
        .expect("tiles touched");
    let cache = stats["texture_cache"].clone();
    assert!(cache.is_object(), "{stats}");
    let per_texture = &stats["texture_memory"][0]["cache"];
    for counter in ["tiles_loaded", "tiles_evicted", "bytes_read", "cache_hits"] {
        assert_eq!(
            per_texture[counter], cache[counter],
            "{counter}: one texture"
        );
    }
    (
        cache,
        touched,
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

#[test]
fn the_stats_count_loads_evictions_and_hits_of_the_texture_cache() {
    let dir = common::temp_dir();
    maketx(dir.path(), 1024, "cached.tx", &[]);
    scene(dir.path(), "cached.tx");
    let counter = |cache: &serde_json::Value, name: &str| {
        cache[name]
            .as_u64()
            .unwrap_or_else(|| panic!("{name} in {cache}"))
    };
    let rate = |cache: &serde_json::Value, name: &str| cache[name].as_f64().unwrap();

    // Without a cap that binds: every tile touched is read once (and the 1x1 level on
    // opening, which a mip-0 render never touches), none evicted.
    let (cache, touched, summary) = cache_stats(dir.path(), &[]);
    assert!(touched > 16, "{touched} tiles touched");
    assert_eq!(counter(&cache, "tiles_loaded"), touched + 1, "{cache}");
    assert_eq!(counter(&cache, "tiles_evicted"), 0, "{cache}");
    assert_eq!(counter(&cache, "capacity_bytes"), 256 << 20);
    let loads = counter(&cache, "tiles_loaded");
    assert_eq!(
        counter(&cache, "micro_cache_misses") - counter(&cache, "cache_hits"),
        loads - 1,
        "every shared-cache miss reads a tile: {cache}"
    );
    assert!(counter(&cache, "bytes_read") > 0);
    // 8-bit RGBA tiles of at most 64x64 texels.
    assert!(counter(&cache, "peak_resident_bytes") <= loads * 64 * 64 * 4);
    assert!(rate(&cache, "micro_cache_hit_rate") > 0.5, "{cache}");
    assert!(summary.contains("texture cache: "), "{summary}");
    assert!(summary.contains(" 0 evicted"), "{summary}");

    // A cap of 4 tiles: tiles are evicted and read again, the peak stays under the cap.
    let (cache, touched_capped, summary) = cache_stats(dir.path(), &["--texture-cache", "64K"]);
    assert_eq!(touched_capped, touched);
    assert!(counter(&cache, "tiles_evicted") > 0, "{cache}");
    assert!(counter(&cache, "tiles_loaded") > touched + 1, "{cache}");
    assert!(
        counter(&cache, "peak_resident_bytes") <= 64 * 1024,
        "{cache}"
    );
    assert_eq!(counter(&cache, "capacity_bytes"), 64 * 1024);
    assert!(rate(&cache, "cache_hit_rate") < 1.0, "{cache}");
    assert!(summary.contains("of 0.1 MiB"), "{summary}");
}

#[test]
fn a_bad_texture_cache_size_is_one_line_and_exit_status_2() {
    let dir = common::temp_dir();
    maketx(dir.path(), 64, "small.tx", &[]);
    scene(dir.path(), "small.tx");
    for bad in ["12Q", "-5M", "0", "lots"] {
        let out = common::run_in(
            dir.path(),
            &[
                "render",
                "s.toml",
                "-o",
                "out.exr",
                "--quiet",
                &format!("--texture-cache={bad}"),
            ],
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{bad}: {stderr}");
        assert!(stderr.contains("--texture-cache"), "{bad}: {stderr}");
        assert!(!dir.path().join("out.exr").exists());
    }
}
