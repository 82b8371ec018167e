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
