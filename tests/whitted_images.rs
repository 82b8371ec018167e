//! Whitted's images of every shipped scene stay exactly what they were: each scene under
//! assets/scenes/ and the built-in default scene is rendered small (64x36, 1 spp, every AOV),
//! with its own effects and with every effect forced on, and every channel is compared bit
//! for bit with the reference EXRs in tests/data/whitted_images/ (rendered by
//! `regenerate.sh` there, with the same options, from the code the references stand for;
//! one set per width of Embree's native packets, see [`reference_dir`]).
//!
//! A second set renders every scene with 4 samples per pixel and only the default AOVs (Z, N,
//! albedo, uv), the scene's own effects: there the hits of later samples, and the first
//! samples' (which write no texture-lookup AOV), are shaded in lanes
//! (`integrator::lanes`), which the set above, all first samples writing every AOV, leaves
//! to the scalar path.
//!
//! Restructuring the integrator must not move a single bit; a change that is meant to alter
//! the images regenerates the references and says why in its commit.

mod common;

use std::path::{Path, PathBuf};

use common::*;

/// The options `regenerate.sh` renders the references with.
const OPTIONS: [&str; 14] = [
    "--width",
    "64",
    "--height",
    "36",
    "--spp",
    "1",
    "--aov",
    "all",
    "--no-png",
    "--quiet",
    "--threads",
    "2",
    "--integrator",
    "whitted",
];

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The references for this machine's Embree. Its kernels for 16-lane packets (AVX-512) and
/// for 8-lane ones (AVX2) can place a hit differently in the last bits of its distance and
/// barycentrics, so each width has its own set, rendered on a machine of that width:
/// tests/data/whitted_images/ for 16 lanes, its width8/ for 8.
fn reference_dir() -> PathBuf {
    let width = conetrace::embree::Device::new()
        .expect("Embree device")
        .packet_width();
    let root = manifest_dir().join("tests/data/whitted_images");
    match width {
        16 => root,
        8 => root.join("width8"),
        _ => panic!(
            "no reference images for an Embree device of {width}-lane packets: render a set \
             with tests/data/whitted_images/regenerate.sh"
        ),
    }
}

/// Every scene file under assets/scenes/, as (reference name, path), sorted.
fn shipped_scenes() -> Vec<(String, PathBuf)> {
    fn walk(dir: &Path, found: &mut Vec<PathBuf>) {
        let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
        for entry in entries {
            let path = entry.expect("directory entry").path();
            if path.is_dir() {
                walk(&path, found);
            } else if path.extension().is_some_and(|e| e == "toml") {
                found.push(path);
            }
        }
    }
    let root = manifest_dir().join("assets/scenes");
    let mut paths = Vec::new();
    walk(&root, &mut paths);
    paths.sort();
    paths
        .into_iter()
        .map(|path| {
            let relative = path.strip_prefix(&root).expect("under assets/scenes");
            let name = relative
                .with_extension("")
                .to_string_lossy()
                .replace(['/', '\\'], "_");
            (name, path)
        })
        .collect()
}

/// The options of the second set: 4 samples per pixel, the default AOVs.
const SAMPLE_WAVE_OPTIONS: [&str; 11] = [
    "--width",
    "64",
    "--height",
    "36",
    "--spp",
    "4",
    "--no-png",
    "--quiet",
    "--threads",
    "2",
    "--integrator",
];

/// Renders `scene` (the built-in one for `None`) into `dir` and returns the EXR's path.
fn render(dir: &Path, name: &str, scene: Option<&Path>, all_effects: bool) -> PathBuf {
    render_with(dir, name, scene, all_effects, &OPTIONS)
}

/// [`render`] with `options`.
fn render_with(
    dir: &Path,
    name: &str,
    scene: Option<&Path>,
    all_effects: bool,
    options: &[&str],
) -> PathBuf {
    let output = dir.join(format!("{name}.exr"));
    let mut command = conetrace();
    command.current_dir(manifest_dir()).arg("render");
    if let Some(scene) = scene {
        command.arg(scene);
    }
    command.args(options).arg("--output").arg(&output);
    if all_effects {
        command.arg("--all-effects");
    }
    let out = command.output().expect("run conetrace");
    assert!(
        out.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    output
}

/// Differences between two images, channel by channel: empty when every value has the
/// same bits.
fn differences(reference: &ExrImage, rendered: &ExrImage) -> Vec<String> {
    let mut found = Vec::new();
    if (reference.width, reference.height) != (rendered.width, rendered.height) {
        found.push(format!(
            "size {}x{} != reference {}x{}",
            rendered.width, rendered.height, reference.width, reference.height
        ));
        return found;
    }
    if reference.names() != rendered.names() {
        found.push(format!(
            "channels {:?} != reference {:?}",
            rendered.names(),
            reference.names()
        ));
        return found;
    }
    for (name, expected) in &reference.channels {
        let actual = rendered.channel(name);
        let (mut count, mut largest) = (0usize, 0f32);
        for (a, e) in actual.iter().zip(expected) {
            if a.to_bits() != e.to_bits() {
                count += 1;
                largest = largest.max((a - e).abs());
            }
        }
        if count > 0 {
            found.push(format!(
                "{name}: {count} values differ, largest difference {largest:e}"
            ));
        }
    }
    found
}

#[test]
fn every_shipped_scene_renders_bit_for_bit_as_its_reference() {
    let dir = temp_dir();
    let references = reference_dir();
    let mut cases: Vec<(String, Option<PathBuf>)> = vec![("builtin_default".to_string(), None)];
    cases.extend(shipped_scenes().into_iter().map(|(n, p)| (n, Some(p))));
    assert!(cases.len() > 10, "found only {} scenes", cases.len());
    let mut failures = Vec::new();
    let mut compared = 0;
    for (name, scene) in &cases {
        for all_effects in [false, true] {
            let label = if all_effects {
                format!("{name}.all_effects")
            } else {
                name.clone()
            };
            let reference_path = references.join(format!("{label}.exr"));
            assert!(
                reference_path.is_file(),
                "no reference image {} for a shipped scene: render it with regenerate.sh",
                reference_path.display()
            );
            let rendered = render(dir.path(), &label, scene.as_deref(), all_effects);
            let reference = read_exr(&reference_path);
            let rendered = read_exr(&rendered);
            compared += reference.channels.len();
            for difference in differences(&reference, &rendered) {
                failures.push(format!("{label}: {difference}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "images differ from their references:\n{}",
        failures.join("\n")
    );
    eprintln!(
        "{} renders, {compared} channels identical to their references",
        cases.len() * 2
    );
}

#[test]
fn every_shipped_scene_renders_its_sample_waves_bit_for_bit() {
    let dir = temp_dir();
    let references = reference_dir();
    let mut options = SAMPLE_WAVE_OPTIONS.to_vec();
    options.push("whitted");
    let mut failures = Vec::new();
    let scenes = shipped_scenes();
    assert!(scenes.len() > 10, "found only {} scenes", scenes.len());
    for (name, scene) in &scenes {
        let label = format!("{name}.spp4");
        let reference_path = references.join(format!("{label}.exr"));
        assert!(
            reference_path.is_file(),
            "no reference image {} for a shipped scene: render it with regenerate.sh",
            reference_path.display()
        );
        let rendered = render_with(dir.path(), &label, Some(scene), false, &options);
        let reference = read_exr(&reference_path);
        let rendered = read_exr(&rendered);
        for difference in differences(&reference, &rendered) {
            failures.push(format!("{label}: {difference}"));
        }
    }
    assert!(
        failures.is_empty(),
        "images differ from their references:\n{}",
        failures.join("\n")
    );
}
