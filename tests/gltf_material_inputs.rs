//! glTF textured material inputs through the whole program: an emissive texture scaled by
//! `emissiveFactor` and `KHR_materials_emissive_strength` gives exactly its radiance, and a
//! normal texture bends the shading normal (the normal AOV) by the map's angle in the frame
//! of the texture coordinates and changes the lit image.
//!
//! The glTF files and their PNG textures are written here into a temporary directory; a TOML
//! scene places the camera (orthographic, looking down -z at the quad) and the lighting.

mod common;

use std::path::Path;

use common::*;

/// The quad [-1, 1]^2 at z = 0 facing +z, glTF uv (0, 0) at its top-left corner (-1, 1).
fn quad_buffer() -> Vec<u8> {
    let mut bytes = Vec::new();
    let positions = [
        [-1.0f32, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, -1.0, 0.0],
        [-1.0, -1.0, 0.0],
    ];
    let normals = [[0.0f32, 0.0, 1.0]; 4];
    let uvs = [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    for v in positions.iter().chain(&normals) {
        v.iter().for_each(|x| bytes.extend(x.to_le_bytes()));
    }
    for v in &uvs {
        v.iter().for_each(|x| bytes.extend(x.to_le_bytes()));
    }
    // Counter-clockwise seen from +z.
    for i in [0u16, 3, 2, 0, 2, 1] {
        bytes.extend(i.to_le_bytes());
    }
    bytes
}

/// Writes `quad.gltf` (with `quad.bin`) whose one material is `material`, textures
/// `images` (file names, texture i uses image i).
fn write_quad_gltf(dir: &Path, material: serde_json::Value, images: &[&str]) {
    let buffer = quad_buffer();
    std::fs::write(dir.join("quad.bin"), &buffer).unwrap();
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0}]}],
        "materials": [material],
        "textures": images.iter().enumerate().map(|(i, _)| serde_json::json!({"source": i, "sampler": 0})).collect::<Vec<_>>(),
        "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "images": images.iter().map(|f| serde_json::json!({"uri": f})).collect::<Vec<_>>(),
        "buffers": [{"byteLength": buffer.len(), "uri": "quad.bin"}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 128}, {"buffer": 0, "byteOffset": 128, "byteLength": 12}],
        "accessors": [
            {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-1, -1, 0], "max": [1, 1, 0]},
            {"bufferView": 0, "byteOffset": 48, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 0, "byteOffset": 96, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 1, "byteOffset": 0, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    std::fs::write(
        dir.join("quad.gltf"),
        serde_json::to_vec_pretty(&json).unwrap(),
    )
    .unwrap();
}

fn write_png(dir: &Path, name: &str, width: u32, texel: impl Fn(u32) -> [u8; 3]) {
    let image = image::RgbImage::from_fn(width, 1, |x, _| image::Rgb(texel(x)));
    image.save(dir.join(name)).unwrap();
}

/// Renders `scene.toml` in `dir` at 64x64 with every AOV and returns the EXR.
fn render(dir: &Path, scene: &str) -> ExrImage {
    render_with(dir, scene, &[])
}

/// [`render`] with `extra` options.
fn render_with(dir: &Path, scene: &str, extra: &[&str]) -> ExrImage {
    write(dir, "scene.toml", scene);
    let mut args = vec![
        "render",
        "scene.toml",
        "--width",
        "64",
        "--height",
        "64",
        "--spp",
        "1",
        "--aov",
        "all",
        "--no-png",
        "--quiet",
        "--output",
        "out.exr",
    ];
    args.extend_from_slice(extra);
    let out = run_in(dir, &args);
    assert!(
        out.status.success(),
        "render failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    read_exr(&dir.join("out.exr"))
}

const CAMERA: &str =
    "[camera]\ntype = \"orthographic\"\neye = [0, 0, 3]\ntarget = [0, 0, 0]\nheight = 2\n\
                      [[mesh]]\nfile = \"quad.gltf\"\n";

/// The sRGB transfer function's inverse (IEC 61966-2-1).
fn srgb_to_linear(byte: u8) -> f32 {
    let c = f32::from(byte) / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[test]
fn emissive_texture_gives_factor_times_strength_times_texel() {
    let dir = temp_dir();
    let (left, right) = ([255u8, 128, 0], [0u8, 64, 255]);
    // Eight texels: the left four one colour, the right four another; pixels well inside
    // each half read one colour only.
    write_png(
        dir.path(),
        "glow.png",
        8,
        |x| if x < 4 { left } else { right },
    );
    let factor = [1.0f32, 0.5, 1.0];
    let strength = 3.0f32;
    write_quad_gltf(
        dir.path(),
        serde_json::json!({
            "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
            "emissiveFactor": factor,
            "emissiveTexture": {"index": 0},
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}
        }),
        &["glow.png"],
    );
    let image = render(dir.path(), CAMERA);
    for (texel, columns) in [(left, 6..26), (right, 38..58)] {
        let expected: Vec<f32> = (0..3)
            .map(|c| factor[c] * strength * srgb_to_linear(texel[c]))
            .collect();
        for y in [8, 32, 56] {
            for x in columns.clone().step_by(5) {
                for (c, name) in ["R", "G", "B"].iter().enumerate() {
                    let got = image.at(name, x, y);
                    assert!(
                        (got - expected[c]).abs() <= 2e-3 * expected[c].max(1.0),
                        "pixel ({x}, {y}) {name}: {got}, expected {}",
                        expected[c]
                    );
                }
            }
        }
    }
}

#[test]
fn normal_texture_tilts_the_shading_normal() {
    let dir = temp_dir();
    // A constant tangent-space normal tilted 30 degrees towards +X (the texture's s, world
    // +x here) on the right half, the flat normal (128, 128, 255) on the left half.
    let angle = 30f32.to_radians();
    let encode = |v: f32| ((v * 0.5 + 0.5) * 255.0).round() as u8;
    let tilted = [encode(angle.sin()), 128, encode(angle.cos())];
    write_png(dir.path(), "normals.png", 8, |x| {
        if x < 4 {
            [128, 128, 255]
        } else {
            tilted
        }
    });
    write_quad_gltf(
        dir.path(),
        serde_json::json!({
            "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0},
            "normalTexture": {"index": 0, "scale": 1.0}
        }),
        &["normals.png"],
    );
    // Light from the upper right: the tilted half faces it more directly.
    let scene = format!(
        "{CAMERA}[[light]]\ntype = \"directional\"\ndirection = [-0.5, 0, -0.866]\nintensity = 1\n"
    );
    // Also without footprints (mip level 0, bilinear), where hits of materials without a
    // normal map skip dP/ds and dP/dt: the normal map's tangent frame still needs them.
    for extra in [&[][..], &["--lod", "mip0", "--filter", "bilinear"]] {
        check_tilted_normals(&render_with(dir.path(), &scene, extra), tilted);
    }
}

fn check_tilted_normals(image: &ExrImage, tilted: [u8; 3]) {
    let decode = |b: u8| 2.0 * f32::from(b) / 255.0 - 1.0;
    let expected =
        glam::Vec3::new(decode(tilted[0]), decode(tilted[1]), decode(tilted[2])).normalize();
    let flat = glam::Vec3::new(decode(128), decode(128), decode(255)).normalize();
    let normal_at = |x: usize, y: usize| {
        glam::Vec3::new(
            image.at("N.X", x, y),
            image.at("N.Y", x, y),
            image.at("N.Z", x, y),
        )
    };
    for y in [10, 32, 54] {
        let (left, right) = (normal_at(16, y), normal_at(48, y));
        assert!(
            (right - expected).length() < 2e-3,
            "tilted half: {right}, expected {expected}"
        );
        assert!(
            (left - flat).length() < 2e-3,
            "flat half: {left}, expected {flat}"
        );
        let tilt = right.dot(glam::Vec3::Z).acos().to_degrees();
        assert!((tilt - 30.0).abs() < 0.5, "tilt {tilt} degrees");
        // The lit colour follows the bent normal: brighter where it faces the light.
        let (lit_left, lit_right) = (image.at("R", 16, y), image.at("R", 48, y));
        assert!(
            lit_right > 1.05 * lit_left,
            "left {lit_left}, right {lit_right}"
        );
    }
}

/// `doubleSided` makes an emissive quad glow from both sides; without it, only its front
/// (the side its counter-clockwise winding faces, +z here) emits. Seen from behind (-z),
/// in the path tracer and in Whitted alike.
#[test]
fn double_sided_emitters_glow_from_behind_and_one_sided_ones_do_not() {
    let dir = temp_dir();
    for double_sided in [true, false] {
        write_quad_gltf(
            dir.path(),
            serde_json::json!({
                "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
                "emissiveFactor": [1.0, 0.5, 0.25],
                "doubleSided": double_sided
            }),
            &[],
        );
        let behind = CAMERA.replace("eye = [0, 0, 3]", "eye = [0, 0, -3]");
        for integrator in ["path", "whitted"] {
            let image = render_with(dir.path(), &behind, &["--integrator", integrator]);
            let got = image.at("R", 32, 32);
            let want = if double_sided { 1.0 } else { 0.0 };
            assert!(
                (got - want).abs() < 1e-6,
                "{integrator}, doubleSided {double_sided}: {got} seen from behind, expected {want}"
            );
        }
    }
}
