//! The built-in default scene renders from any directory into out/, with every layer real.

mod common;

use common::*;

#[test]
fn default_scene_renders_into_out_with_all_layers() {
    let dir = temp_dir();
    let out = run_in(
        dir.path(),
        &[
            "render",
            "--width",
            "96",
            "--height",
            "54",
            "--stats",
            "stats.json",
            "--count-texture-tiles",
            "--aov",
            "all",
            "--quiet",
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("Mrays/s"), "summary line: {stdout}");
    assert!(dir.path().join("out/default.png").exists());
    let image = read_exr(&dir.path().join("out/default.exr"));
    assert_eq!((image.width, image.height), (96, 54));
    for name in [
        "R",
        "G",
        "B",
        "A",
        "Z",
        "N.X",
        "N.Y",
        "N.Z",
        "albedo.R",
        "albedo.G",
        "albedo.B",
        "uv.U",
        "uv.V",
        "tex.s",
        "tex.t",
        "tex.dsdx",
        "tex.dtdx",
        "tex.dsdy",
        "tex.dtdy",
        "texcolor.R",
        "texcolor.G",
        "texcolor.B",
        "lod",
        "footprint",
    ] {
        let values = image.channel(name);
        assert!(
            values.iter().all(|v| v.is_finite()),
            "{name} has a non-finite value"
        );
    }
    // Real data: the ground is textured (varying albedo), lit, and seen at many depths.
    let spread = |name: &str| {
        let v = image.channel(name);
        let lo = v.iter().cloned().fold(f32::INFINITY, f32::min);
        let hi = v.iter().cloned().fold(f32::NEG_INFINITY, f32::max);
        hi - lo
    };
    assert!(spread("R") > 0.1 && spread("albedo.G") > 0.1 && spread("N.Y") > 0.1);
    // The receding ground plane is minified: some pixels use coarse mip levels.
    assert!(
        image.channel("lod").iter().any(|&l| l > 2.0),
        "no minified lookups"
    );
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("stats.json")).unwrap())
            .unwrap();
    let counters = &stats["counters"];
    for kind in [
        "camera_rays",
        "shadow_rays",
        "reflection_rays",
        "refraction_rays",
        "texture_lookups",
    ] {
        assert!(
            counters[kind].as_u64().unwrap() > 0,
            "{kind} is zero: {counters}"
        );
    }
    assert_eq!(counters["camera_rays"].as_u64().unwrap(), 96 * 54);
    assert!(stats["texture_memory_bytes"].as_u64().unwrap() > 0);
    assert!(stats["texture_tiles"]["total"].as_u64().unwrap() > 0);
}

/// `--stats` measures the render as it runs without it: texture tiles, which need a record
/// of every texel block a filter reads, are counted only on `--count-texture-tiles`, and
/// counting them changes no pixel.
#[test]
fn stats_count_texture_tiles_only_on_request() {
    let dir = temp_dir();
    let render = |name: &str, extra: &[&str]| {
        let exr = format!("{name}.exr");
        let json = format!("{name}.json");
        let mut args = vec![
            "render", "--width", "64", "--height", "36", "--no-png", "-o", &exr, "--stats", &json,
        ];
        args.extend_from_slice(extra);
        let out = run_in(dir.path(), &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stats: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.path().join(&json)).unwrap()).unwrap();
        let summary = String::from_utf8_lossy(&out.stdout).into_owned();
        (read_exr(&dir.path().join(&exr)), stats, summary)
    };
    let (plain, plain_stats, plain_summary) = render("plain", &[]);
    let (counted, counted_stats, counted_summary) = render("counted", &["--count-texture-tiles"]);

    assert!(plain_stats["texture_tiles"].is_null(), "{plain_stats}");
    assert!(!plain_summary.contains("texture tiles"), "{plain_summary}");
    let tiles = counted_stats["texture_tiles"]["total"]
        .as_u64()
        .expect("tiles counted on request");
    assert!(tiles > 0);
    assert!(
        counted_summary.contains(&format!("{tiles} texture tiles")),
        "{counted_summary}"
    );
    assert!(plain_stats["counters"]["texture_lookups"].as_u64().unwrap() > 0);
    assert_eq!(
        plain_stats["counters"], counted_stats["counters"],
        "the same work either way"
    );
    for channel in ["R", "G", "B"] {
        let (a, b) = (plain.channel(channel), counted.channel(channel));
        assert!(
            a.iter()
                .zip(b.iter())
                .all(|(x, y)| x.to_bits() == y.to_bits()),
            "{channel} differs when tiles are counted"
        );
    }
}
