//! Whitted's hits shaded in lanes (`Whitted::shade_in_lanes`) against its scalar path:
//! shipped scenes give the same image and AOVs, bit for bit, and the lanes take the hits
//! they cover (mirrors, glass, emitters and absorbing media included), fog on the way
//! included.

mod common;

use common::{assert_same_bits, render_small, temp_dir, uv_sphere_obj, write};
use conetrace::film::{AovSelection, Film};
use conetrace::footprint::LodStrategy;
use conetrace::integrator::Whitted;
use conetrace::render::RenderOptions;

/// Textured and untextured opaque materials on meshes and spheres, mirrors and glass (a
/// tinted one, whose inside absorbs), an emitter, point and environment light, and fog over
/// a ground, in front of spheres, and bounded by a mesh.
const SCENES: [&str; 11] = [
    "assets/scenes/default.toml",
    "assets/scenes/teapot_textured.toml",
    "assets/scenes/teapot_mirror.toml",
    "assets/scenes/fp_magnifier.toml",
    "assets/scenes/fp_convex.toml",
    "assets/scenes/fp_concave.toml",
    "assets/scenes/cornell.toml",
    "assets/scenes/bench/env_lit_textured.toml",
    "assets/scenes/bench/matte_lit.toml",
    "assets/scenes/fog.toml",
    "assets/scenes/fog_mesh.toml",
];

/// Scenes of triangle meshes and analytic spheres alone, without fog, with mirrors
/// (`default`, `fp_convex`, `fp_concave`), glass on spheres and meshes (`default`,
/// `cornell`, `fp_magnifier`), an absorbing medium (`default`'s tinted glass) and an emitter
/// (`cornell`'s lamp): every hit takes the lanes.
const DELTA_SCENES: [&str; 5] = [
    "assets/scenes/default.toml",
    "assets/scenes/fp_convex.toml",
    "assets/scenes/fp_concave.toml",
    "assets/scenes/fp_magnifier.toml",
    "assets/scenes/cornell.toml",
];

/// Spheres, analytic and tessellated (with vertex normals, so cones see their curvature),
/// whose materials mix the lobes: an opaque lobe beside a mirror and a Fresnel-weighted
/// dielectric boundary with an absorbing inside, a perfect mirror and clear glass (an opaque
/// weight of zero), a two-sided emitter that also reflects, and a metallic-roughness
/// boundary with an emission texture's factor. Written to `dir`.
fn mixed_lobes_scene(dir: &std::path::Path) -> String {
    write(
        dir,
        "sphere.obj",
        &uv_sphere_obj([0.0, 0.0, 0.0], 1.0, 24, 12),
    );
    let ground = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/ground.obj");
    let checker =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/textures/checker.png");
    let scene = format!(
        r#"
[render]
max_depth = 6

[camera]
type = "pinhole"
eye = [0.0, 1.5, 7.0]
target = [0.0, 0.8, 0.0]
up = [0.0, 1.0, 0.0]
fov = 50

[[light]]
type = "point"
position = [3.0, 6.0, 4.0]
color = [1.0, 1.0, 1.0]
intensity = 200.0

[environment]
color = [0.4, 0.5, 0.7]

[[texture]]
name = "checker"
file = "{checker}"

[[material]]
name = "ground"
base_color = [0.8, 0.8, 0.8]
base_color_texture = "checker"
texture_scale = [8.0, 8.0]

[[material]]
name = "mixed"
base_color = [0.7, 0.3, 0.2]
mirror = 0.3
transmission = 0.5
ior = 1.4
attenuation_color = [0.5, 0.8, 0.6]
attenuation_distance = 1.0

[[material]]
name = "perfect_mirror"
base_color = [0.5, 0.5, 0.5]
mirror = 1.0

[[material]]
name = "clear_glass"
base_color = [1.0, 1.0, 1.0]
transmission = 1.0
ior = 1.5
attenuation_color = [0.9, 0.6, 0.5]
attenuation_distance = 0.8

[[material]]
name = "shiny_lamp"
base_color = [0.2, 0.2, 0.2]
mirror = 0.4
emission = [3.0, 2.0, 1.0]
two_sided = true

[[material]]
name = "rough_glass"
base_color = [0.9, 0.9, 0.9]
base_color_texture = "checker"
roughness = 0.2
metallic = 0.0
transmission = 0.6
ior = 1.3
emission = [0.5, 0.5, 0.2]

[[mesh]]
file = "{ground}"
material = "ground"
scale = [20.0, 1.0, 20.0]

[[mesh]]
file = "sphere.obj"
material = "mixed"
translate = [-1.2, 1.0, 0.5]

[[mesh]]
file = "sphere.obj"
material = "clear_glass"
translate = [1.2, 0.7, 1.5]
scale = 0.7

[[sphere]]
center = [1.6, 1.0, -1.0]
radius = 1.0
material = "perfect_mirror"

[[sphere]]
center = [-0.2, 0.5, 2.2]
radius = 0.5
material = "shiny_lamp"

[[sphere]]
center = [0.0, 2.6, -1.5]
radius = 0.8
material = "rough_glass"
"#,
        checker = checker.display(),
        ground = ground.display(),
    );
    write(dir, "mixed_lobes.toml", &scene)
        .to_string_lossy()
        .into_owned()
}

/// The film of `scene` rendered small by Whitted, in lanes or not, and how many hits the
/// lanes shaded.
fn render_film(scene: &str, in_lanes: bool, options: impl Fn(&mut RenderOptions)) -> (Film, u64) {
    let whitted = Whitted {
        shade_in_lanes: in_lanes,
    };
    let (film, counters) = render_small(scene, &whitted, options);
    (film, counters.lane_hits)
}

/// Renders `scene` both ways, compares them and returns how many hits the lanes shaded.
fn check(scene: &str, variant: &str, options: impl Fn(&mut RenderOptions)) -> u64 {
    let (lanes, hits) = render_film(scene, true, &options);
    let (scalar, scalar_hits) = render_film(scene, false, &options);
    assert_eq!(scalar_hits, 0, "{scene}: the scalar render used the lanes");
    assert_same_bits(&format!("{scene} ({variant})"), &lanes, &scalar);
    hits
}

#[test]
fn lanes_give_the_scalar_path_s_image_bit_for_bit() {
    for scene in SCENES {
        let hits = check(scene, "default", |_| {});
        assert!(hits > 0, "{scene}: no hit took the lanes");
    }
}

#[test]
fn lanes_give_the_scalar_path_s_aovs_bit_for_bit() {
    for scene in SCENES {
        check(scene, "every AOV", |options| {
            options.aovs = AovSelection::ALL
        });
    }
}

#[test]
fn lanes_give_the_scalar_path_s_image_without_footprints() {
    for scene in SCENES {
        check(scene, "mip0", |options| options.lod = LodStrategy::Mip0);
    }
}

#[test]
fn lanes_give_the_scalar_path_s_image_with_ray_differentials() {
    for scene in SCENES {
        check(scene, "differential", |options| {
            options.lod = LodStrategy::Differential
        });
    }
}

/// Every traced ray that hits takes the lanes on scenes of meshes and spheres without fog,
/// mirrors, glass, emitters and absorbing media included: the lanes' hits and misses are
/// all the camera, reflection and refraction rays.
#[test]
fn lanes_take_every_hit_of_mirrors_glass_emitters_and_media() {
    for scene in DELTA_SCENES {
        let whitted = Whitted::default();
        let (_, counters) = render_small(scene, &whitted, |_| {});
        let traced = counters.camera_rays + counters.reflection_rays + counters.refraction_rays;
        assert!(
            counters.reflection_rays + counters.refraction_rays > 0,
            "{scene}: no mirror or glass ray"
        );
        assert_eq!(
            counters.lane_hits + counters.lane_misses,
            traced,
            "{scene}: hits left the lanes"
        );
    }
}

/// Materials that mix an opaque lobe with a mirror and a Fresnel-weighted boundary, weight-0
/// opaque lobes, emitters that reflect, and absorbing insides, under every footprint
/// strategy: the same bits both ways, and every hit in the lanes.
#[test]
fn lanes_give_the_scalar_path_s_image_for_mixed_lobes() {
    let dir = temp_dir();
    let scene = mixed_lobes_scene(dir.path());
    for lod in [
        LodStrategy::Mip0,
        LodStrategy::Distance,
        LodStrategy::Cone1,
        LodStrategy::Cone,
        LodStrategy::Differential,
    ] {
        let hits = check(&scene, &format!("{lod:?}"), |options| options.lod = lod);
        let (_, counters) = render_small(&scene, &Whitted::default(), |options| options.lod = lod);
        let traced = counters.camera_rays + counters.reflection_rays + counters.refraction_rays;
        assert_eq!(
            hits + counters.lane_misses,
            traced,
            "{lod:?}: hits left the lanes"
        );
        assert!(
            counters.absorption_evaluations > 0,
            "{lod:?}: nothing absorbed"
        );
    }
    check(&scene, "every AOV", |options| {
        options.aovs = AovSelection::ALL
    });
}
