//! A scene pays only for the effects it uses: for each effect, a scene without it reports
//! zero work of that kind and does not list it; a scene with it reports work and says why.

mod common;

use common::*;
use serde_json::Value;

const BASE: &str = r#"
[render]
width = 24
height = 16

[camera]
type = "pinhole"
eye = [0.0, 1.5, 5.0]
target = [0.0, 0.5, 0.0]
fov = 50

[environment]
color = [0.1, 0.1, 0.1]

[[texture]]
name = "checker"
file = "checker.exr"
color_space = "linear"

[[material]]
name = "matte"
base_color = [0.6, 0.6, 0.6]

[[material]]
name = "textured"
base_color = [1.0, 1.0, 1.0]
base_color_texture = "checker"

[[material]]
name = "mirror"
base_color = [0.0, 0.0, 0.0]
mirror = 1.0

[[material]]
name = "glass"
base_color = [0.0, 0.0, 0.0]
transmission = 1.0
ior = 1.5

[[material]]
name = "matched"
base_color = [0.0, 0.0, 0.0]
transmission = 1.0
ior = 1.0

[[material]]
name = "constant_cutout"
base_color = [0.6, 0.6, 0.6]
alpha_cutoff = 0.5

[[material]]
name = "tinted"
base_color = [0.0, 0.0, 0.0]
transmission = 1.0
ior = 1.5
attenuation_color = [0.5, 0.8, 0.6]
attenuation_distance = 1.0
"#;

const LIGHT: &str = r#"
[[light]]
type = "point"
position = [2.0, 5.0, 3.0]
intensity = 40.0
"#;

/// Render BASE + `extra` with a ground plane of material `ground`; return the stats JSON.
fn stats(ground: &str, extra: &str, args: &[&str]) -> Value {
    let dir = temp_dir();
    exr::prelude::write_rgba_file(dir.path().join("checker.exr"), 8, 8, |x, y| {
        let v = if (x + y) % 2 == 0 { 1.0 } else { 0.1 };
        (v, v, v, 1.0)
    })
    .unwrap();
    write(dir.path(), "ground.obj", &square_obj(10.0, 0.0));
    let text = format!("{BASE}{extra}\n[[mesh]]\nfile = \"ground.obj\"\nmaterial = \"{ground}\"\n");
    write(dir.path(), "s.toml", &text);
    let mut full = vec![
        "render", "s.toml", "-o", "o.exr", "--no-png", "--quiet", "--stats", "s.json",
    ];
    full.extend_from_slice(args);
    let out = run_in(dir.path(), &full);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap()
}

fn counter(stats: &Value, name: &str) -> u64 {
    stats["counters"][name]
        .as_u64()
        .unwrap_or_else(|| panic!("no counter {name}"))
}

fn effects(stats: &Value) -> Vec<String> {
    stats["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["effect"].as_str().unwrap().to_string())
        .collect()
}

fn sphere(material: &str) -> String {
    format!("\n[[sphere]]\ncenter = [0.0, 1.0, 0.0]\nradius = 1.0\nmaterial = \"{material}\"\n")
}

#[test]
fn shadows_only_with_lights() {
    let without = stats("matte", "", &[]);
    assert_eq!(counter(&without, "shadow_rays"), 0);
    assert!(!effects(&without).iter().any(|e| e == "shadows"));
    let with = stats("matte", LIGHT, &[]);
    assert!(counter(&with, "shadow_rays") > 0);
    assert!(effects(&with).iter().any(|e| e == "shadows"));
}

#[test]
fn secondary_rays_only_with_specular_materials() {
    let plain = stats("matte", &format!("{LIGHT}{}", sphere("matte")), &[]);
    assert_eq!(counter(&plain, "reflection_rays"), 0);
    assert_eq!(counter(&plain, "refraction_rays"), 0);
    let mirror = stats("matte", &format!("{LIGHT}{}", sphere("mirror")), &[]);
    assert!(counter(&mirror, "reflection_rays") > 0);
    assert_eq!(counter(&mirror, "refraction_rays"), 0);
    assert!(effects(&mirror).iter().any(|e| e == "mirror reflection"));
    let glass = stats("matte", &format!("{LIGHT}{}", sphere("glass")), &[]);
    assert!(counter(&glass, "refraction_rays") > 0);
    assert!(effects(&glass).iter().any(|e| e == "refraction"));
}

#[test]
fn fresnel_only_with_an_index_contrast() {
    // An index-matched medium (ior 1) refracts straight through and reflects nothing.
    let matched = stats("matte", &format!("{LIGHT}{}", sphere("matched")), &[]);
    let names = effects(&matched);
    assert!(names.iter().any(|e| e == "refraction"), "{names:?}");
    assert!(!names.iter().any(|e| e == "Fresnel"), "{names:?}");
    assert!(counter(&matched, "refraction_rays") > 0);
    assert_eq!(counter(&matched, "reflection_rays"), 0);
    let glass = stats("matte", &format!("{LIGHT}{}", sphere("glass")), &[]);
    assert!(effects(&glass).iter().any(|e| e == "Fresnel"));
    assert!(counter(&glass, "reflection_rays") > 0);
}

#[test]
fn cutout_filters_only_with_alpha_textures() {
    // A cut-off over a constant alpha is decided once for the whole mesh: no filter runs.
    let constant = stats("constant_cutout", LIGHT, &[]);
    assert!(!effects(&constant).iter().any(|e| e == "alpha cut-out"));
    assert_eq!(counter(&constant, "filter_callbacks"), 0);
}

#[test]
fn absorption_only_with_media() {
    let clear = stats("matte", &format!("{LIGHT}{}", sphere("glass")), &[]);
    assert_eq!(counter(&clear, "absorption_evaluations"), 0);
    assert!(!effects(&clear).iter().any(|e| e == "Beer's-law absorption"));
    let tinted = stats("matte", &format!("{LIGHT}{}", sphere("tinted")), &[]);
    assert!(counter(&tinted, "absorption_evaluations") > 0);
    assert!(effects(&tinted)
        .iter()
        .any(|e| e == "Beer's-law absorption"));
}

#[test]
fn footprints_only_with_filtered_textures() {
    let untextured = stats("matte", LIGHT, &[]);
    assert_eq!(counter(&untextured, "footprint_updates"), 0);
    assert_eq!(counter(&untextured, "texture_lookups"), 0);
    let textured = stats("textured", LIGHT, &[]);
    assert!(counter(&textured, "footprint_updates") > 0);
    assert!(counter(&textured, "texture_lookups") > 0);
    assert!(effects(&textured).iter().any(|e| e == "ray footprints"));
    // mip0 filtering needs no footprint: textures are looked up, footprints are not tracked.
    let mip0 = stats("textured", LIGHT, &["--lod", "mip0"]);
    assert!(counter(&mip0, "texture_lookups") > 0);
    assert_eq!(counter(&mip0, "footprint_updates"), 0);
    assert!(!effects(&mip0).iter().any(|e| e == "ray footprints"));
}

#[test]
fn all_effects_forces_the_general_path() {
    let general = stats("matte", LIGHT, &["--all-effects"]);
    let names = effects(&general);
    for effect in [
        "shadows",
        "mirror reflection",
        "refraction",
        "Fresnel",
        "ray footprints",
    ] {
        assert!(
            names.iter().any(|e| e == effect),
            "{effect} missing from {names:?}"
        );
    }
}

/// The shipped scenes (the default scene, the footprint figures and the benchmark scenes of
/// `conetrace bench effects`), each of which lacks some effects.
fn shipped_scenes() -> Vec<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes");
    let mut scenes = Vec::new();
    for dir in [root.clone(), root.join("bench")] {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|x| x == "toml") {
                scenes.push(path);
            }
        }
    }
    scenes.sort();
    scenes
}

/// Prepare `path` at 48x32 with the scene's own depth and the renderer's default filtering.
fn prepare_small(path: &std::path::Path) -> conetrace::render::RenderContext {
    use conetrace::film::AovSelection;
    use conetrace::render::RenderOptions;
    let scene = conetrace::scene::load::load_scene(path).unwrap();
    let options = RenderOptions {
        width: 48,
        height: 32,
        spp: 1,
        aovs: AovSelection::ALL,
        seed: 0,
        ..RenderOptions::from_settings(&scene.settings)
    };
    conetrace::render::prepare(std::sync::Arc::new(scene), options).unwrap()
}

fn render_with(
    context: &mut conetrace::render::RenderContext,
    effects: conetrace::render::EffectSet,
) -> conetrace::film::Film {
    render_forced(context, effects).film
}

fn render_forced(
    context: &mut conetrace::render::RenderContext,
    effects: conetrace::render::EffectSet,
) -> conetrace::render::RenderResult {
    context.force_effects(effects).unwrap();
    let result = conetrace::render::render(
        context,
        &conetrace::integrator::Whitted::default(),
        &conetrace::render::RenderControl::default(),
    )
    .expect("traversal succeeds");
    assert!(result.stats.complete);
    result
}

/// Switching on effects a scene does not need never changes a pixel: the specialised path
/// (analysed set), the general path (every effect, `--all-effects`) and the analysed set
/// plus any one unneeded effect give bit-identical colour and AOVs on every shipped scene.
#[test]
fn specialised_and_general_paths_give_the_same_image() {
    use conetrace::render::EffectSet;
    let scenes = shipped_scenes();
    assert!(scenes.len() >= 5, "{scenes:?}");
    for path in scenes {
        let mut context = prepare_small(&path);
        let analysed = context.effects;
        let specialised = render_with(&mut context, analysed);
        let mut variants = vec![("all effects", EffectSet::all())];
        for (name, single) in EffectSet::singles() {
            if !analysed.includes(&single) {
                variants.push((name, analysed.union(single)));
            }
        }
        for (name, effects) in variants {
            let film = render_with(&mut context, effects);
            for channel in specialised.channel_names() {
                let a = specialised.channel(&channel).unwrap();
                let b = film.channel(&channel).unwrap();
                let differing = a
                    .iter()
                    .zip(b)
                    .filter(|(x, y)| x.to_bits() != y.to_bits())
                    .count();
                assert_eq!(
                    differing,
                    0,
                    "{}: switching on {name} changed {differing} values of {channel}",
                    path.display()
                );
            }
        }
    }
}

/// A forced effect set must include every effect the scene needs; a smaller one is refused
/// and leaves the render's set as it was.
#[test]
fn forcing_effects_cannot_drop_a_needed_one() {
    use conetrace::render::{EffectSet, ForceEffectsError};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let mut context = prepare_small(&path);
    let analysed = context.effects;
    assert!(
        analysed.shadows && analysed.footprints,
        "{:?}",
        analysed.names()
    );
    let missing = |result: Result<(), ForceEffectsError>| match result {
        Err(ForceEffectsError::MissingNeeded(missing)) => missing,
        other => panic!("expected a refusal, got {other:?}"),
    };
    assert_eq!(
        missing(context.force_effects(EffectSet::default())),
        analysed
    );
    assert_eq!(context.effects, analysed);
    let without_shadows = EffectSet {
        shadows: false,
        ..EffectSet::all()
    };
    assert_eq!(
        missing(context.force_effects(without_shadows)).names(),
        vec!["shadows"]
    );
    assert_eq!(context.effects, analysed);
    context.force_effects(EffectSet::all()).unwrap();
    assert_eq!(context.effects, EffectSet::all());
}

/// `conetrace bench effects` on the matte benchmark scene: every unneeded effect gets a row,
/// the footprint row shows the footprint work the general path adds, and every image matches
/// the specialised one.
#[test]
fn bench_effects_reports_unneeded_work_and_identical_images() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = run_in(
        root,
        &[
            "bench",
            "effects",
            "assets/scenes/bench/matte_lit.toml",
            "--repeat",
            "1",
            "--width",
            "32",
            "--height",
            "18",
        ],
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("### Specialised path vs general path"),
        "{text}"
    );
    let rows: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("| assets/scenes/bench/matte_lit.toml |"))
        .collect();
    // One comparison row plus one row per unneeded effect (all but shadows).
    let unneeded = conetrace::render::EffectSet::singles().len() - 1;
    assert_eq!(rows.len(), 1 + unneeded, "{text}");
    let footprints = rows
        .iter()
        .find(|r| r.contains("| ray footprints |"))
        .unwrap_or_else(|| panic!("no footprint row in {text}"));
    assert!(footprints.contains("footprint_updates 0 →"), "{footprints}");
    // A forced alpha cut-out runs alpha tests on every mesh: its cost is real work.
    let cutout = rows
        .iter()
        .find(|r| r.contains("| alpha cut-out |"))
        .unwrap_or_else(|| panic!("no alpha cut-out row in {text}"));
    assert!(cutout.contains("filter_callbacks 0 →"), "{cutout}");
    assert!(
        rows.iter().all(|r| r.trim_end().ends_with("| identical |")),
        "{text}"
    );
    // A scene that does not exist is bad input.
    let missing = run_in(root, &["bench", "effects", "no/such/scene.toml"]);
    assert_eq!(missing.status.code(), Some(2));
}

#[test]
fn shadow_walks_only_through_transmissive_occluders() {
    let opaque = stats("matte", &format!("{LIGHT}{}", sphere("mirror")), &[]);
    assert!(counter(&opaque, "shadow_rays") > 0);
    assert_eq!(counter(&opaque, "shadow_walk_queries"), 0);
    assert!(!effects(&opaque).iter().any(|e| e == "transmissive shadows"));
    let glass = stats("matte", &format!("{LIGHT}{}", sphere("glass")), &[]);
    assert!(counter(&glass, "shadow_walk_queries") > 0);
    assert!(effects(&glass).iter().any(|e| e == "transmissive shadows"));
}

/// The statistics of a render with a forced effect set report that set (each forced effect
/// marked as forced), not a fresh analysis of the scene.
#[test]
fn statistics_report_the_forced_effects() {
    use conetrace::render::EffectSet;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let mut context = prepare_small(&path);
    let analysed = context.effects;
    assert_ne!(analysed, EffectSet::all());
    let result = render_forced(&mut context, EffectSet::all());
    let mut reported: Vec<&str> = result
        .stats
        .effects
        .iter()
        .map(|e| e.effect.as_str())
        .collect();
    reported.sort();
    let mut all = EffectSet::all().names();
    all.sort();
    assert_eq!(reported, all, "the statistics after forcing every effect");
    for reason in &result.stats.effects {
        let needed = analysed.names().contains(&reason.effect.as_str());
        assert_eq!(
            !needed,
            reason.because.contains("forced"),
            "{}: {}",
            reason.effect,
            reason.because
        );
    }
    // Back to the analysed set: the statistics follow.
    let result = render_forced(&mut context, analysed);
    let mut reported: Vec<&str> = result
        .stats
        .effects
        .iter()
        .map(|e| e.effect.as_str())
        .collect();
    reported.sort();
    let mut needed = analysed.names();
    needed.sort();
    assert_eq!(reported, needed);
}

/// `render --all-effects` writes the forced (complete) set into the statistics.
#[test]
fn all_effects_statistics_list_every_effect() {
    let general = stats("matte", LIGHT, &["--all-effects"]);
    let mut names = effects(&general);
    names.sort();
    let mut all: Vec<String> = conetrace::render::EffectSet::all()
        .names()
        .into_iter()
        .map(String::from)
        .collect();
    all.sort();
    assert_eq!(names, all);
}

/// The tracer obeys the effect analysis: a scene without alpha cut-outs installs no filter
/// (no callback runs), and forcing the cut-out effect on installs alpha tests on every mesh,
/// whose callbacks then run (the general path's real cost) without changing the image.
#[test]
fn alpha_tests_follow_the_effect_set() {
    use conetrace::render::tracer::AlphaTests;
    use conetrace::render::EffectSet;
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/default.toml");
    let mut context = prepare_small(&path);
    let analysed = context.effects;
    assert!(!analysed.alpha_cutout, "{:?}", analysed.names());
    assert_eq!(context.tracer.settings().alpha_tests, AlphaTests::Off);
    let specialised = render_forced(&mut context, analysed);
    assert_eq!(specialised.stats.counters.filter_callbacks, 0);
    let forced = EffectSet {
        alpha_cutout: true,
        ..analysed
    };
    let general = render_forced(&mut context, forced);
    assert_eq!(context.tracer.settings().alpha_tests, AlphaTests::EveryMesh);
    assert!(
        general.stats.counters.filter_callbacks > 0,
        "forced alpha cut-out ran no filter callback"
    );
    for channel in specialised.film.channel_names() {
        assert_eq!(
            specialised.film.channel(&channel),
            general.film.channel(&channel),
            "{channel}"
        );
    }
    // And back: no filter again.
    let again = render_forced(&mut context, analysed);
    assert_eq!(context.tracer.settings().alpha_tests, AlphaTests::Off);
    assert_eq!(again.stats.counters.filter_callbacks, 0);
}
