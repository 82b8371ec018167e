//! Memory is bounded and failures are clean: a render that cannot fit is refused before
//! anything large is allocated, with the estimate; `--stats` gives the time of every phase
//! and the memory of every texture.

mod common;

use common::*;

#[test]
fn an_image_too_large_for_memory_is_refused_with_its_estimate() {
    let dir = temp_dir();
    let out = run_in(
        dir.path(),
        &[
            "render", "--width", "65536", "--height", "65536", "--quiet", "-o", "big.exr",
        ],
    );
    let message = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert_eq!(message.lines().count(), 1, "{message}");
    assert!(
        message.contains("needs about") && message.contains("GiB"),
        "{message}"
    );
    assert!(!dir.path().join("big.exr").exists());
    assert!(!dir.path().join("big.png").exists());
}

#[test]
fn max_memory_limits_the_render() {
    let dir = temp_dir();
    let small = [
        "render", "--width", "64", "--height", "36", "--quiet", "-o", "a.exr",
    ];
    let mut limited = small.to_vec();
    limited.extend(["--max-memory", "64K"]);
    let out = run_in(dir.path(), &limited);
    let message = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert!(
        message.contains("--max-memory") && message.contains("64.0 KiB"),
        "{message}"
    );
    assert!(!dir.path().join("a.exr").exists());

    let mut roomy = small.to_vec();
    roomy.extend(["--max-memory", "4G", "--stats", "s.json"]);
    let out = run_in(dir.path(), &roomy);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("s.json")).unwrap()).unwrap();
    let phases = &stats["phases"];
    for phase in ["load", "textures", "prepare", "render", "write", "total"] {
        let seconds = phases[phase].as_f64().unwrap_or(-1.0);
        assert!(seconds >= 0.0, "phase {phase}: {phases}");
    }
    let total = phases["total"].as_f64().unwrap();
    let parts: f64 = ["load", "textures", "prepare", "render", "write"]
        .iter()
        .map(|p| phases[p].as_f64().unwrap())
        .sum();
    assert!(
        parts <= total * 1.001 + 1e-6,
        "phases {parts} exceed the total {total}"
    );
    let textures = stats["texture_memory"]
        .as_array()
        .expect("texture_memory list");
    assert!(!textures.is_empty(), "the default scene has textures");
    let per_texture: u64 = textures.iter().map(|t| t["bytes"].as_u64().unwrap()).sum();
    assert_eq!(per_texture, stats["texture_memory_bytes"].as_u64().unwrap());
    let summary = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        summary.contains("textures") && summary.contains("write"),
        "{summary}"
    );
}

/// The voxel cone tracer's pyramid counts towards `--max-memory` before it is built: a
/// limit the film and textures fit in refuses a 256-voxel grid (exit 2, the pyramid named,
/// nothing written), while Whitted renders the same scene under the same limit. Before, the
/// estimate left the pyramid out and the render went ahead.
#[test]
fn the_voxel_pyramid_counts_towards_max_memory() {
    let dir = temp_dir();
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/vct_cornell.toml");
    let scene = scene.to_str().unwrap();
    let args = |integrator: &'static str| {
        vec![
            "render",
            scene,
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "1",
            "--quiet",
            "--integrator",
            integrator,
            "--vct-resolution",
            "256",
            "--max-memory",
            "64M",
            "-o",
            "v.exr",
        ]
    };
    let out = run_in(dir.path(), &args("vct"));
    let message = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert_eq!(message.trim().lines().count(), 1, "{message}");
    assert!(
        message.contains("voxel pyramid") && message.contains("--max-memory"),
        "{message}"
    );
    assert!(!dir.path().join("v.exr").exists());
    let out = run_in(dir.path(), &args("whitted"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Three textures of the same size, 64x32 (2731 texels over its levels 64x32 ... 1x1):
/// an 8-bit PNG, a half-float and a float OpenEXR, each on a sphere.
fn three_precision_scene(dir: &std::path::Path) -> String {
    let (w, h) = (64usize, 32usize);
    let value = |x: usize, y: usize| ((x * 7 + y * 13) % 256) as f32 / 255.0;
    let bytes: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            let v = (value(i % w, i / w) * 255.0) as u8;
            [v, 255 - v, v / 2, 255]
        })
        .collect();
    image::RgbaImage::from_raw(w as u32, h as u32, bytes)
        .unwrap()
        .save(dir.join("bytes.png"))
        .unwrap();
    exr::prelude::write_rgba_file(dir.join("half.exr"), w, h, |x, y| {
        let v = half::f16::from_f32(value(x, y));
        (v, v, v, half::f16::ONE)
    })
    .unwrap();
    exr::prelude::write_rgba_file(dir.join("float.exr"), w, h, |x, y| {
        let v = value(x, y);
        (v, v, v, 1.0f32)
    })
    .unwrap();
    let mut scene = String::from(
        "[render]\nwidth = 32\nheight = 24\n\n[camera]\ntype = \"pinhole\"\n\
         eye = [0.0, 0.0, 9.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 50\n\n\
         [[light]]\ntype = \"point\"\nposition = [0.0, 4.0, 6.0]\nintensity = 40.0\n",
    );
    for (i, name) in ["bytes.png", "half.exr", "float.exr"].iter().enumerate() {
        scene.push_str(&format!(
            "\n[[texture]]\nname = \"t{i}\"\nfile = \"{name}\"\ncolor_space = \"linear\"\n\
             \n[[material]]\nname = \"m{i}\"\nbase_color = [1.0, 1.0, 1.0]\n\
             base_color_texture = \"t{i}\"\n\
             \n[[sphere]]\ncenter = [{}.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m{i}\"\n",
            2 * i as i32 - 2
        ));
    }
    scene
}

#[test]
fn texture_memory_is_the_storage_of_the_source_precision() {
    let dir = temp_dir();
    write(dir.path(), "scene.toml", &three_precision_scene(dir.path()));
    let out = run_in(
        dir.path(),
        &[
            "render",
            "scene.toml",
            "--quiet",
            "-o",
            "p.exr",
            "--no-png",
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
    let reported: Vec<(String, u64)> = stats["texture_memory"]
        .as_array()
        .expect("texture_memory list")
        .iter()
        .map(|t| {
            (
                t["texture"].as_str().unwrap().to_string(),
                t["bytes"].as_u64().unwrap(),
            )
        })
        .collect();
    println!("texture memory: {reported:?}");
    let bytes_of = |file: &str| {
        reported
            .iter()
            .find(|(name, _)| name.ends_with(file))
            .unwrap_or_else(|| panic!("{file} missing from {reported:?}"))
            .1
    };
    // 64x32 + 32x16 + 16x8 + 8x4 + 4x2 + 2x1 + 1x1 texels.
    let texels = 2048 + 512 + 128 + 32 + 8 + 2 + 1;
    assert_eq!(texels, 2731);
    let float = bytes_of("float.exr");
    assert_eq!(float, texels * 16, "float: four f32 a texel");
    assert_eq!(
        bytes_of("bytes.png"),
        texels * 4,
        "8-bit: a quarter of float"
    );
    assert_eq!(bytes_of("half.exr"), texels * 8, "half: half of float");
    // The estimate made before decoding, from each file's header, is the same storage.
    for file in ["bytes.png", "half.exr", "float.exr"] {
        let header = conetrace::texture::file_texture_header(&dir.path().join(file)).unwrap();
        assert_eq!(header.decoded_bytes(), bytes_of(file), "{file}: {header:?}");
    }
}

#[test]
fn a_texture_too_large_to_allocate_is_an_error_naming_it() {
    // A PNG whose header claims 60000x60000 texels: 13.4 GiB as bytes, 17.9 GiB with its
    // levels. `--max-memory` lets it past the estimate; decoding it must fail with one
    // line naming the file, exit 2 and no output, not abort.
    let dir = temp_dir();
    let mut png = Vec::new();
    png.extend_from_slice(b"\x89PNG\r\n\x1a\n");
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(b"IHDR");
    ihdr.extend_from_slice(&60000u32.to_be_bytes());
    ihdr.extend_from_slice(&60000u32.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    png.extend_from_slice(&13u32.to_be_bytes());
    png.extend_from_slice(&ihdr);
    png.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    // Some image data (a zlib stream of one stored block of 1000 zero bytes), so the
    // header is read as a whole and the failure is the texels' size.
    let zeros = [0u8; 1000];
    let mut idat = b"IDAT\x78\x01\x01".to_vec();
    idat.extend_from_slice(&1000u16.to_le_bytes());
    idat.extend_from_slice(&(!1000u16).to_le_bytes());
    idat.extend_from_slice(&zeros);
    idat.extend_from_slice(&((1000u32 << 16) | 1).to_be_bytes()); // Adler-32 of the zeros
    png.extend_from_slice(&(idat.len() as u32 - 4).to_be_bytes());
    png.extend_from_slice(&idat);
    png.extend_from_slice(&crc32(&idat).to_be_bytes());
    png.extend_from_slice(&0u32.to_be_bytes());
    png.extend_from_slice(b"IEND");
    png.extend_from_slice(&crc32(b"IEND").to_be_bytes());
    std::fs::write(dir.path().join("huge.png"), png).unwrap();
    let scene = three_precision_scene(dir.path()).replace("bytes.png", "huge.png");
    write(dir.path(), "scene.toml", &scene);
    let out = run_in(
        dir.path(),
        &[
            "render",
            "scene.toml",
            "--quiet",
            "-o",
            "h.exr",
            "--max-memory",
            "1000T",
        ],
    );
    let message = String::from_utf8_lossy(&out.stderr).into_owned();
    println!("{message}");
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert_eq!(message.lines().count(), 1, "{message}");
    assert!(message.contains("huge.png"), "{message}");
    assert!(
        !message.contains("IDAT"),
        "the header was not read whole: {message}"
    );
    assert!(!dir.path().join("h.exr").exists());
}

/// CRC-32 of a PNG chunk's type and data (ISO 3309, as PNG specifies).
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// The estimate in MiB from a refusal ("the render needs about 15.4 MiB (...").
fn estimated_mib(message: &str) -> f64 {
    let rest = message
        .split("needs about ")
        .nth(1)
        .unwrap_or_else(|| panic!("no estimate in {message}"));
    let (number, unit) = rest.split_once(' ').unwrap();
    assert!(unit.starts_with("MiB"), "{message}");
    number.parse().unwrap()
}

/// A part holding a sample range carries 18 channels of exact sums beside its image (and the
/// EXR encoder copies them): the estimate counts them, 144 bytes a pixel more than the whole
/// render's. It used to count the whole render's alone, so a part under `--max-memory` could
/// take five times the limit.
#[test]
fn a_sample_range_part_counts_its_exact_sums() {
    let dir = temp_dir();
    let refused = |extra: &[&str]| {
        let mut args = vec![
            "render",
            "--width",
            "512",
            "--height",
            "512",
            "--aov",
            "none",
            "--spp",
            "2",
            "--quiet",
            "-o",
            "p.exr",
            "--max-memory",
            "1K",
        ];
        args.extend_from_slice(extra);
        let out = run_in(dir.path(), &args);
        let message = String::from_utf8_lossy(&out.stderr).into_owned();
        assert_eq!(out.status.code(), Some(2), "{message}");
        estimated_mib(&message)
    };
    let whole = refused(&[]);
    let part = refused(&["--samples", "0..1"]);
    let sums_mib = 512.0 * 512.0 * 144.0 / (1024.0 * 1024.0);
    assert!(
        (part - whole - sums_mib).abs() < 0.2,
        "whole {whole} MiB, part {part} MiB: expected {sums_mib} MiB more"
    );
    assert!(!dir.path().join("p.exr").exists());
}
