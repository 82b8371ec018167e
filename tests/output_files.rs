//! Output files a pipeline can trust: every output path is checked before any work, a failed
//! run writes nothing, the EXR, PNG and statistics of one run are never mixed with another
//! run's, links and permissions survive, the EXR header carries the standard camera matrices
//! in a fixed order, and the command line explains itself.

mod common;

use std::path::Path;

use common::*;
use conetrace::film::{read_exr as read_film, tonemap_to_srgb8, Layer};
use conetrace::scene::ToneMap;

const SMALL: [&str; 6] = ["--width", "48", "--height", "32", "--quiet", "--threads"];

fn render(dir: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["render"];
    args.extend_from_slice(&SMALL);
    args.push("2");
    args.extend_from_slice(extra);
    run_in(dir, &args)
}

fn stderr(out: &std::process::Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Every file in `dir`, sorted (hidden temporary files included).
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn bad_output_paths_are_refused_before_any_work_and_nothing_is_written() {
    let dir = temp_dir();
    std::fs::write(dir.path().join("blocker"), b"a file, not a directory").unwrap();
    let cases: [(&[&str], &str); 6] = [
        (&["-o", "out.png"], "out.png"),
        (&["-o", "out.jpg"], "out.jpg"),
        (&["-o", "same.exr", "--png", "same.exr"], "same.exr"),
        (&["-o", "a.exr", "--stats", "a.png"], "a.png"),
        (
            &["-o", "a.exr", "--stats", "blocker/stats.json"],
            "blocker/stats.json",
        ),
        (&["-o", "a.exr", "--png", "x.png", "--no-png"], "--no-png"),
    ];
    for (args, named) in cases {
        let out = render(dir.path(), args);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {message}");
        assert_eq!(message.lines().count(), 1, "{args:?}: {message}");
        assert!(message.contains(named), "{args:?}: {message}");
        assert!(!message.contains(".tmp-"), "{args:?}: {message}");
        assert_eq!(listing(dir.path()), ["blocker"], "{args:?} wrote something");
    }
}

#[test]
fn the_exr_png_and_stats_of_two_concurrent_runs_are_never_mixed() {
    let dir = temp_dir();
    for round in 0..3 {
        let runs: Vec<_> = ["1", "4"]
            .iter()
            .map(|spp| {
                let mut args = vec!["render".to_string()];
                args.extend(SMALL.iter().map(|s| s.to_string()));
                args.push("1".into());
                for a in ["-o", "shared.exr", "--stats", "shared.json", "--spp", spp] {
                    args.push(a.to_string());
                }
                conetrace()
                    .args(&args)
                    .current_dir(dir.path())
                    .stdout(std::process::Stdio::null())
                    .spawn()
                    .expect("start conetrace")
            })
            .collect();
        for run in runs {
            let out = run.wait_with_output().unwrap();
            assert!(out.status.success(), "{}", stderr(&out));
        }
        // The PNG is the EXR's colour, tone-mapped: both come from the same run.
        let (film, _) = read_film(&dir.path().join("shared.exr")).unwrap();
        let png = image::open(dir.path().join("shared.png"))
            .unwrap()
            .to_rgb8();
        let mut rgba = [0.0f32; 4];
        let mut mismatched = 0;
        for (x, y, pixel) in png.enumerate_pixels() {
            film.get(Layer::Color, x, y, &mut rgba);
            let expected = [0, 1, 2].map(|c| tonemap_to_srgb8(rgba[c], ToneMap::Clamp, 1.0));
            if pixel.0 != expected {
                mismatched += 1;
            }
        }
        assert_eq!(
            mismatched, 0,
            "round {round}: PNG pixels not from the EXR's run"
        );
        let stats: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join("shared.json")).unwrap())
                .unwrap();
        let spp = stats["spp"].as_u64().expect("stats give the spp");
        let header = std::fs::read(dir.path().join("shared.exr")).unwrap();
        let marker = "conetrace.option.spp\0string\0";
        let at = find(&header, marker.as_bytes()).expect("the EXR records its spp");
        let value_at = at + marker.len() + 4;
        let header_spp = (header[value_at] - b'0') as u64;
        assert_eq!(
            spp, header_spp,
            "round {round}: statistics and EXR from different runs"
        );
    }
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[test]
fn identical_renders_give_identical_bytes_with_standard_camera_matrices() {
    let dir = temp_dir();
    for name in ["a.exr", "b.exr"] {
        let out = render(dir.path(), &["-o", name, "--no-png"]);
        assert!(out.status.success(), "{}", stderr(&out));
    }
    let a = std::fs::read(dir.path().join("a.exr")).unwrap();
    let b = std::fs::read(dir.path().join("b.exr")).unwrap();
    assert!(a == b, "two identical renders wrote different bytes");
    // Standard OpenEXR camera attributes, as 4x4 float matrices ("m44f").
    for attribute in ["worldToCamera\0m44f\0", "worldToNDC\0m44f\0"] {
        assert!(
            find(&a, attribute.as_bytes()).is_some(),
            "{attribute:?} missing"
        );
    }
    assert!(
        find(&a, b"conetrace.settings").is_none(),
        "Debug-formatted settings remain"
    );
    assert!(find(&a, b"conetrace.option.filter\0string\0").is_some());
}

#[test]
fn the_seed_decides_the_sample_positions() {
    // Four samples per pixel of the built-in scene: the same --seed gives the same pixels,
    // another seed (or the default, 0) other pixels.
    let dir = temp_dir();
    let runs: [(&str, &[&str]); 4] = [
        ("seed7.exr", &["--seed", "7"]),
        ("seed7_again.exr", &["--seed", "7"]),
        ("seed8.exr", &["--seed", "8"]),
        ("default.exr", &[]),
    ];
    for (name, seed) in runs {
        let mut args = vec!["-o", name, "--no-png", "--spp", "4"];
        args.extend_from_slice(seed);
        let out = render(dir.path(), &args);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
    }
    let pixels = |name: &str| read_exr(&dir.path().join(name)).channel("R").to_vec();
    let seven = pixels("seed7.exr");
    assert!(
        seven == pixels("seed7_again.exr"),
        "the same seed gave different pixels"
    );
    let differing = |other: &[f32]| seven.iter().zip(other).filter(|(a, b)| a != b).count();
    let eight = pixels("seed8.exr");
    assert!(
        differing(&eight) > seven.len() / 20,
        "seed 8 changed {} pixels",
        differing(&eight)
    );
    let default = pixels("default.exr");
    assert!(
        differing(&default) > seven.len() / 20,
        "seed 0 changed {} pixels",
        differing(&default)
    );
}

#[test]
fn a_symlinked_output_stays_a_link_and_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let dir = temp_dir();
    std::fs::create_dir(dir.path().join("store")).unwrap();
    std::fs::write(dir.path().join("store/real.exr"), b"old").unwrap();
    std::fs::set_permissions(
        dir.path().join("store/real.exr"),
        std::fs::Permissions::from_mode(0o604),
    )
    .unwrap();
    std::os::unix::fs::symlink("store/real.exr", dir.path().join("link.exr")).unwrap();
    let out = render(dir.path(), &["-o", "link.exr", "--no-png"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let link = std::fs::symlink_metadata(dir.path().join("link.exr")).unwrap();
    assert!(link.file_type().is_symlink());
    let real = std::fs::metadata(dir.path().join("store/real.exr")).unwrap();
    assert_eq!(real.permissions().mode() & 0o777, 0o604);
    assert!(
        real.len() > 100,
        "the link's target was not replaced by the render"
    );
}

#[test]
fn the_command_line_explains_itself() {
    let dir = temp_dir();
    let help = run_in(dir.path(), &["render", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout).into_owned();
    for expected in [
        "else 640",
        "else 360",
        "mip0, distance, cone1, cone, differential",
        "closest, bilinear, trilinear, aniso, ewa",
        "clamp, reinhard",
        "--resume",
    ] {
        assert!(
            help.contains(expected),
            "render --help lacks {expected:?}:\n{help}"
        );
    }
    let texture_help = run_in(dir.path(), &["sample-texture", "--help"]);
    let texture_help = String::from_utf8_lossy(&texture_help.stdout).into_owned();
    assert!(
        texture_help.contains("periodic, clamp, black, mirror"),
        "{texture_help}"
    );

    let negative = render(dir.path(), &["--max-depth", "-1"]);
    let message = stderr(&negative);
    assert_eq!(negative.status.code(), Some(2), "{message}");
    assert!(!message.contains("-- -1"), "misleading tip: {message}");
    assert!(message.contains("--max-depth"), "{message}");

    let bench = run_in(dir.path(), &["bench", "render", "-o", "x.exr"]);
    assert_eq!(bench.status.code(), Some(2), "{}", stderr(&bench));
    assert!(stderr(&bench).contains("-o"), "{}", stderr(&bench));

    write(
        dir.path(),
        "q.csv",
        "s,t,dsdx,dtdx,dsdy,dtdy\n0.5,0.5,0,0,0,0\n",
    );
    let texture = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/checker.png");
    let zero = run_in(
        dir.path(),
        &[
            "sample-texture",
            texture.to_str().unwrap(),
            "--queries",
            "q.csv",
            "--max-aniso",
            "0",
        ],
    );
    assert_eq!(zero.status.code(), Some(2), "{}", stderr(&zero));
    assert!(stderr(&zero).contains("--max-aniso"), "{}", stderr(&zero));
}

#[test]
fn aov_none_writes_only_colour_and_alpha_with_the_same_pixels() {
    // `--aov none` leaves out Z, N, albedo and uv (they are not computed); the colour of
    // every pixel is the default render's, bit for bit, for both integrators and for one
    // and several samples per pixel. Combining `none` with another layer is refused.
    let dir = temp_dir();
    let scene = write(
        dir.path(),
        "lamp.toml",
        "[render]\nwidth = 40\nheight = 24\n\n[camera]\neye = [0.0, 1.0, 3.0]\n\
         target = [0.0, 0.0, 0.0]\nfov = 50.0\n\n[[material]]\nname = \"lamp\"\n\
         emission = [4.0, 4.0, 4.0]\n\n[[sphere]]\ncenter = [0.0, 1.5, 0.0]\nradius = 0.4\n\
         material = \"lamp\"\n\n[[sphere]]\ncenter = [0.0, -100.0, 0.0]\nradius = 100.0\n",
    );
    let scene = scene.to_str().unwrap();
    let cases: [(&str, &[&str]); 3] = [
        ("built-in scene, whitted, 1 spp", &[]),
        ("built-in scene, whitted, 4 spp", &["--spp", "4"]),
        (
            "area light, path, 4 spp",
            &[scene, "--spp", "4", "--integrator", "path"],
        ),
    ];
    for (case, extra) in cases {
        let mut default_args = vec!["-o", "default.exr", "--no-png"];
        default_args.extend_from_slice(extra);
        let out = render(dir.path(), &default_args);
        assert!(out.status.success(), "{case}: {}", stderr(&out));
        let mut none_args = vec!["-o", "none.exr", "--no-png", "--aov", "none"];
        none_args.extend_from_slice(extra);
        let out = render(dir.path(), &none_args);
        assert!(out.status.success(), "{case}: {}", stderr(&out));
        let default = read_exr(&dir.path().join("default.exr"));
        let none = read_exr(&dir.path().join("none.exr"));
        assert!(default.names().contains(&"albedo.R".to_string()), "{case}");
        let mut names = none.names();
        names.sort();
        assert_eq!(names, ["A", "B", "G", "R"], "{case}");
        for channel in ["R", "G", "B", "A"] {
            let (a, b) = (default.channel(channel), none.channel(channel));
            assert!(a.iter().any(|&v| v > 0.0), "{case}: {channel} is black");
            let same = a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
            assert!(same, "{case}: {channel} differs without the surface AOVs");
        }
    }
    let out = render(
        dir.path(),
        &["-o", "both.exr", "--aov", "none", "--aov", "lod"],
    );
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("--aov none"), "{}", stderr(&out));
    assert!(!dir.path().join("both.exr").exists());
}

/// `bench render` and `bench scale-out` write no image: their `--help` lists none of
/// `render`'s options about outputs, interruption, progress or splitting (they used to list
/// `-o` and `--png`, which then failed), and those options are unknown to them.
#[test]
fn bench_commands_list_only_the_options_that_apply() {
    let dir = temp_dir();
    for bench in ["render", "scale-out"] {
        let out = run_in(dir.path(), &["bench", bench, "--help"]);
        assert!(
            out.status.success(),
            "bench {bench} --help: {}",
            stderr(&out)
        );
        let help = String::from_utf8_lossy(&out.stdout);
        for option in [
            "-o,",
            "--output",
            "--png",
            "--no-png",
            "--stats",
            "--resume",
            "--max-memory",
            "--quiet",
            "--region",
            "--samples",
            "--part",
            "--time-limit",
            "--tonemap",
        ] {
            assert!(
                !help.contains(option),
                "bench {bench} --help lists {option}:\n{help}"
            );
        }
        for option in ["--width", "--spp", "--lod", "--filter", "--patch-mode"] {
            assert!(
                help.contains(option),
                "bench {bench} --help lacks {option}:\n{help}"
            );
        }
        let png = run_in(dir.path(), &["bench", bench, "--png", "x.png"]);
        assert_eq!(png.status.code(), Some(2), "{}", stderr(&png));
        assert!(stderr(&png).contains("'--png'"), "{}", stderr(&png));
        assert!(!dir.path().join("x.png").exists());
    }
}

/// Numeric options out of range name the documented range (`--width -3` used to say "not in
/// 0..=4294967295"), in `render` and in the benchmarks that share its options.
#[test]
fn out_of_range_numbers_name_the_documented_range() {
    let dir = temp_dir();
    let cases: [(&[&str], &str); 7] = [
        (&["render", "--width", "-3"], "1..=65536"),
        (&["render", "--height", "65537"], "1..=65536"),
        (&["render", "--spp", "0"], "1..=4294967295"),
        (&["render", "--threads", "0"], "1..=1024"),
        (&["render", "--vct-resolution", "1"], "2..=1024"),
        (&["bench", "render", "--width", "-3"], "1..=65536"),
        (&["bench", "scale-out", "--height", "0"], "1..=65536"),
    ];
    for (args, range) in cases {
        let out = run_in(dir.path(), args);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {message}");
        assert_eq!(message.lines().count(), 1, "{args:?}: {message}");
        assert!(
            message.contains(range) && message.contains(args[args.len() - 2]),
            "{args:?}: {message}"
        );
    }
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
}

/// `bench textures` builds its OpenImageIO side wherever it runs (the C++ source is built
/// into the program), times OpenImageIO on the same queries, and reports a side that fails
/// to compile or to run by the one line that says why.
#[test]
fn bench_textures_runs_outside_the_repository() {
    let dir = temp_dir();
    let quick = [
        "bench",
        "textures",
        "--queries",
        "2000",
        "--seconds",
        "0.01",
        "--filters",
        "bilinear",
    ];
    let out = run_in(dir.path(), &quick);
    assert!(out.status.success(), "{}", stderr(&out));
    let table = String::from_utf8_lossy(&out.stdout);
    let row = table
        .lines()
        .find(|line| line.starts_with("| bilinear | coherent |"))
        .unwrap_or_else(|| panic!("no bilinear row:\n{table}"));
    // Every column filled: the batched lookups were timed and OIIO's rate came back.
    assert!(!row.contains(" - "), "{row}");
    assert_eq!(row.matches('|').count(), 14, "thirteen columns: {row}");
    let columns: Vec<&str> = row.split('|').map(str::trim).collect();
    let oiio_rate: f64 = columns[12].parse().unwrap_or_else(|_| panic!("{row}"));
    assert!(oiio_rate > 0.0 && oiio_rate.is_finite(), "{row}");

    write(
        dir.path(),
        "broken.cpp",
        "int main() { return undeclared_name; }\n",
    );
    let mut args = quick.to_vec();
    args.extend(["--oiio-source", "broken.cpp"]);
    let out = run_in(dir.path(), &args);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert_eq!(message.lines().count(), 1, "{message}");
    assert!(
        message.contains("broken.cpp: cannot compile") && message.contains("undeclared_name"),
        "{message}"
    );

    write(
        dir.path(),
        "failing.cpp",
        "#include <cstdio>\nint main() { std::fprintf(stderr, \"the benchmark broke\\n\"); return 1; }\n",
    );
    let mut args = quick.to_vec();
    args.extend(["--oiio-source", "failing.cpp"]);
    let out = run_in(dir.path(), &args);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert_eq!(message.lines().count(), 1, "{message}");
    assert!(
        message.contains("failing.cpp (compiled): failed")
            && message.contains("the benchmark broke"),
        "{message}"
    );

    let mut args = quick.to_vec();
    args.extend(["--oiio-source", "missing.cpp"]);
    let out = run_in(dir.path(), &args);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert!(
        message.contains("missing.cpp: --oiio-source: no such file"),
        "{message}"
    );
}

/// Without a terminal (a farm's log), a render that takes longer than the progress interval
/// prints plain lines: fraction done, rate and time left, and a last line at the end.
#[test]
fn without_a_terminal_a_long_render_prints_plain_progress_lines() {
    let dir = temp_dir();
    let out = conetrace()
        .args([
            "render",
            "-o",
            "p.exr",
            "--no-png",
            "--threads",
            "1",
            "--width",
            "160",
            "--height",
            "96",
            "--spp",
            "16",
        ])
        .env("CONETRACE_PROGRESS_INTERVAL", "0.02")
        .current_dir(dir.path())
        .output()
        .expect("conetrace runs");
    let text = stderr(&out);
    assert!(out.status.success(), "{text}");
    // 10 x 6 tiles of 16 pixels.
    let total = 60;
    let mut last_done = 0;
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines.len() >= 2, "{text}");
    for (index, line) in lines.iter().enumerate() {
        let rest = line
            .strip_prefix("progress: ")
            .unwrap_or_else(|| panic!("not a progress line: {line}"));
        let (percent, rest) = rest.split_once("% (").expect(line);
        let (done, rest) = rest.split_once('/').expect(line);
        let (count, rest) = rest.split_once(" tiles), ").expect(line);
        let (rate, rest) = rest.split_once(" tiles/s, ").expect(line);
        let (percent, done): (usize, usize) = (percent.parse().unwrap(), done.parse().unwrap());
        assert_eq!(count, total.to_string(), "{line}");
        assert!(done >= last_done && done <= total, "{line}");
        assert_eq!(percent, 100 * done / total, "{line}");
        assert!(rate.parse::<f64>().unwrap() > 0.0, "{line}");
        if index + 1 < lines.len() {
            let eta = rest.strip_prefix("ETA ").expect(line);
            assert!(eta.ends_with(" s"), "{line}");
        } else {
            assert_eq!(done, total, "the last line is the end: {line}");
        }
        last_done = done;
    }

    // --quiet prints none, and neither does a bad interval setting: it is refused.
    let out = conetrace()
        .args([
            "render", "-o", "q.exr", "--no-png", "--quiet", "--width", "32",
        ])
        .env("CONETRACE_PROGRESS_INTERVAL", "0.02")
        .current_dir(dir.path())
        .output()
        .expect("conetrace runs");
    assert!(
        out.status.success() && out.stderr.is_empty(),
        "{}",
        stderr(&out)
    );
    let out = conetrace()
        .args(["render", "-o", "r.exr", "--no-png", "--width", "32"])
        .env("CONETRACE_PROGRESS_INTERVAL", "soon")
        .current_dir(dir.path())
        .output()
        .expect("conetrace runs");
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("CONETRACE_PROGRESS_INTERVAL=soon"));
    assert!(!dir.path().join("r.exr").exists());
}

/// Outputs in one directory named once relatively and once absolutely are committed under
/// one directory lock: the second lock of the same directory used to wait forever.
#[test]
fn one_directory_spelt_two_ways_does_not_hang_the_commit() {
    let dir = temp_dir();
    let png = dir.path().join("same.png");
    let mut child = conetrace()
        .args(["render", "--width", "32", "--height", "16", "--quiet"])
        .args(["-o", "same.exr", "--png", png.to_str().unwrap()])
        .current_dir(dir.path())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("conetrace runs");
    let started = std::time::Instant::now();
    while child.try_wait().expect("poll conetrace").is_none() {
        if started.elapsed() > std::time::Duration::from_secs(120) {
            child.kill().ok();
            panic!("the render did not finish in 120 s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let out = child.wait_with_output().expect("conetrace output");
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(dir.path().join("same.exr").exists() && png.exists());
}

/// A one-triangle glTF whose buffer is the external file `bin_name`, and its bytes.
fn triangle_gltf_with_bin(bin_name: &str) -> (String, Vec<u8>) {
    let mut buffer = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|x| buffer.extend(x.to_le_bytes()));
    }
    let gltf = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "buffers": [{{"byteLength": {len}, "uri": "{bin_name}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": {len}}}],
  "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}}]}}"#,
        len = buffer.len()
    );
    (gltf, buffer)
}

#[test]
fn no_output_may_overwrite_any_file_the_render_reads() {
    let dir = temp_dir();
    let at = |name: &str| dir.path().join(name);
    let (gltf, bin) = triangle_gltf_with_bin("tri.bin");
    write(dir.path(), "tri.gltf", &gltf);
    std::fs::write(at("tri.bin"), &bin).unwrap();
    write(
        dir.path(),
        "m.mtl",
        "newmtl red\nKd 0.8 0.1 0.1\nmap_Kd wood.png\n",
    );
    std::fs::write(at("wood.png"), b"texture bytes, refused before decoding").unwrap();
    let obj = format!("mtllib m.mtl\nusemtl red\n{}", square_obj(1.0, 0.0));
    write(dir.path(), "m.obj", &obj);
    write(dir.path(), "plain.obj", &square_obj(1.0, 0.0));
    write(
        dir.path(),
        "s.toml",
        "[[mesh]]\nfile = \"plain.obj\"\n[[texture]]\nname = \"t\"\nfile = \"t.partial.exr\"\n",
    );
    std::fs::write(
        at("t.partial.exr"),
        b"a texture named like a partial render",
    )
    .unwrap();
    std::os::unix::fs::symlink("tri.bin", at("link.json")).unwrap();
    std::fs::hard_link(at("tri.bin"), at("hard.json")).unwrap();
    let before: Vec<(String, Vec<u8>)> = listing(dir.path())
        .into_iter()
        .map(|name| (name.clone(), std::fs::read(at(&name)).unwrap()))
        .collect();
    let cases: [(&[&str], &str); 7] = [
        (&["tri.gltf", "--stats", "tri.bin"], "tri.bin"),
        (&["tri.gltf", "--stats", "./sub/../tri.bin"], "tri.bin"),
        (&["tri.gltf", "--stats", "link.json"], "tri.bin"),
        (&["tri.gltf", "--stats", "hard.json"], "tri.bin"),
        (&["m.obj", "--stats", "m.mtl"], "m.mtl"),
        (&["m.obj", "--stats", "wood.png"], "wood.png"),
        (&["s.toml", "--stats", "plain.obj"], "plain.obj"),
    ];
    for (args, input) in cases {
        let mut all = args.to_vec();
        all.extend(["-o", "out.exr"]);
        let out = render(dir.path(), &all);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {message}");
        assert_eq!(message.lines().count(), 1, "{args:?}: {message}");
        assert!(
            message.contains("would overwrite") && message.contains(input),
            "{args:?}: {message}"
        );
    }
    // The partial file of `-o t.exr` is t.partial.exr, a texture of s.toml.
    let out = render(dir.path(), &["s.toml", "-o", "t.exr"]);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert!(message.contains("t.partial.exr"), "{message}");
    let after: Vec<(String, Vec<u8>)> = listing(dir.path())
        .into_iter()
        .map(|name| (name.clone(), std::fs::read(at(&name)).unwrap()))
        .collect();
    assert_eq!(before, after, "a refused render changed or created a file");
    // The model still renders.
    let out = render(
        dir.path(),
        &["tri.gltf", "-o", "ok.exr", "--stats", "ok.json"],
    );
    assert!(out.status.success(), "{}", stderr(&out));
}

/// Only outputs the render will write are checked against its inputs: a region or a sample
/// range writes no PNG unless --png names one; the default PNG is named as such when it
/// would overwrite an input. The partial files are always checked: a completed render,
/// progressive too, removes them.
#[test]
fn outputs_the_render_will_not_write_do_not_block_it() {
    let dir = temp_dir();
    let at = |name: &str| dir.path().join(name);
    image::RgbImage::from_pixel(4, 4, image::Rgb([200, 100, 50]))
        .save(at("tex.png"))
        .unwrap();
    // An EXR texture named like the partial file of `-o t.exr`.
    let out = render(dir.path(), &["-o", "t.partial.exr", "--no-png"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let scene = "[[texture]]\nname = \"t\"\nfile = \"tex.png\"\n\
         [[texture]]\nname = \"p\"\nfile = \"t.partial.exr\"\n\
         [[material]]\nname = \"m\"\nbase_color_texture = \"t\"\n\
         [[material]]\nname = \"n\"\nbase_color_texture = \"p\"\n\
         [[sphere]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n\
         [[sphere]]\ncenter = [3, 0, 0]\nradius = 1\nmaterial = \"n\"\n";
    write(dir.path(), "s.toml", scene);
    let texture = std::fs::read(at("tex.png")).unwrap();
    let partial = std::fs::read(at("t.partial.exr")).unwrap();

    // The whole image writes tex.png beside tex.exr: refused, naming the default PNG.
    let out = render(dir.path(), &["s.toml", "-o", "tex.exr"]);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert!(
        message.contains("the PNG beside the EXR would overwrite"),
        "{message}"
    );
    // A region or a sample range writes no PNG: it renders.
    for part in [
        &["--region", "0,0,16,16"][..],
        &["--samples", "0..1", "--spp", "2"],
    ] {
        let mut args = vec!["s.toml", "-o", "tex.exr"];
        args.extend_from_slice(part);
        let out = render(dir.path(), &args);
        assert!(out.status.success(), "{part:?}: {}", stderr(&out));
    }
    // A progressive render removes the partial file of its EXR when it completes.
    let out = render(
        dir.path(),
        &[
            "s.toml",
            "-o",
            "t.exr",
            "--no-png",
            "--time-limit",
            "30",
            "--spp",
            "1",
        ],
    );
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{message}");
    assert!(
        message.contains("the partial render would overwrite"),
        "{message}"
    );
    assert_eq!(std::fs::read(at("tex.png")).unwrap(), texture);
    assert_eq!(std::fs::read(at("t.partial.exr")).unwrap(), partial);

    // --quiet shows no progress, so a bad progress interval setting does not matter.
    let out = conetrace()
        .args(["render", "s.toml", "-o", "q.exr", "--no-png", "--quiet"])
        .args(["--width", "16", "--height", "16"])
        .env("CONETRACE_PROGRESS_INTERVAL", "abc")
        .current_dir(dir.path())
        .output()
        .expect("conetrace runs");
    assert!(out.status.success(), "{}", stderr(&out));
}
