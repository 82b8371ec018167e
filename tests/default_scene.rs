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
