//! A glTF camera framing a sphere from far away points at it (issue 33): a perspective camera
//! node at distances 1e2 to 1e6 from a mesh sphere, looking at it along an oblique direction
//! with a `yfov` that frames it exactly, shows the sphere centred and spanning the image
//! height, as the analytic projection gives. At 1e4 units the sphere's centroid was 3.7
//! pixels of 256 off centre (its top 4 rows down), at 1e6 units 160 pixels: the loader
//! pointed the camera at a target one unit in front of its f32 eye, so rounding the target
//! turned the view by up to half an ulp of the eye's coordinates.

mod common;

use glam::{DMat3, DQuat, DVec3};

use common::*;

const SIZE: usize = 256;
/// The sphere's angular radius seen from the camera (radians), at every distance: half the
/// field of view that frames it.
const ANGULAR_RADIUS: f64 = 0.005;

/// A UV sphere of `radius` at the origin as little-endian f32 positions and u32 indices.
fn sphere_buffer(radius: f64, segments: u32, rings: u32) -> (Vec<u8>, u32, u32) {
    let mut bytes = Vec::new();
    for ring in 0..=rings {
        let polar = std::f64::consts::PI * f64::from(ring) / f64::from(rings);
        for segment in 0..segments {
            let azimuth = std::f64::consts::TAU * f64::from(segment) / f64::from(segments);
            let p = DVec3::new(
                polar.sin() * azimuth.cos(),
                polar.cos(),
                polar.sin() * azimuth.sin(),
            ) * radius;
            for x in p.to_array() {
                bytes.extend((x as f32).to_le_bytes());
            }
        }
    }
    let vertex_count = (rings + 1) * segments;
    let mut index_count = 0;
    for ring in 0..rings {
        for segment in 0..segments {
            let next = (segment + 1) % segments;
            let corner = |r: u32, s: u32| r * segments + s;
            let (a, b) = (corner(ring, segment), corner(ring, next));
            let (c, d) = (corner(ring + 1, segment), corner(ring + 1, next));
            for i in [a, b, c, b, d, c] {
                bytes.extend(i.to_le_bytes());
            }
            index_count += 6;
        }
    }
    (bytes, vertex_count, index_count)
}

/// A glTF file with the sphere (framed exactly by `yfov`) at the origin and a camera node
/// `distance` away along an oblique direction, rotated to look at it with +Y up.
fn scene_json(distance: f64) -> String {
    let radius = distance * ANGULAR_RADIUS.sin();
    let (buffer, vertex_count, index_count) = sphere_buffer(radius, 96, 48);
    let positions_length = vertex_count * 12;
    let away = DVec3::new(0.3, 0.5, 0.8).normalize();
    let eye = away * distance;
    // glTF cameras look down their local -Z: local +Z points away from the sphere.
    let x_axis = DVec3::Y.cross(away).normalize();
    let rotation = DQuat::from_mat3(&DMat3::from_cols(x_axis, away.cross(x_axis), away));
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [
    {{"mesh": 0}},
    {{"camera": 0, "translation": [{}, {}, {}], "rotation": [{}, {}, {}, {}]}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": {}, "znear": 0.01}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": {positions_length}}},
    {{"buffer": 0, "byteOffset": {positions_length}, "byteLength": {}}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": {vertex_count}, "type": "VEC3"}},
    {{"bufferView": 1, "componentType": 5125, "count": {index_count}, "type": "SCALAR"}}
  ]
}}"#,
        eye.x,
        eye.y,
        eye.z,
        rotation.x,
        rotation.y,
        rotation.z,
        rotation.w,
        2.0 * ANGULAR_RADIUS,
        buffer.len(),
        base64(&buffer),
        index_count * 4,
    )
}

/// Which pixels of a `SIZE` x `SIZE` render of `gltf` the sphere covers (a depth in `Z`).
fn covered_pixels(gltf: &str) -> Vec<bool> {
    let dir = temp_dir();
    write(dir.path(), "sphere.gltf", gltf);
    let size = SIZE.to_string();
    let out = run_in(
        dir.path(),
        &[
            "render",
            "sphere.gltf",
            "-o",
            "out.exr",
            "--no-png",
            "--quiet",
            "--width",
            &size,
            "--height",
            &size,
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = read_exr(&dir.path().join("out.exr"));
    image.channel("Z").iter().map(|&z| z < f32::MAX).collect()
}

/// The covered pixels' centroid (x right, y down, pixel centres at +0.5) and the first and
/// last covered row and column.
fn centroid_and_extent(covered: &[bool]) -> ((f64, f64), [usize; 4]) {
    let (mut sum_x, mut sum_y, mut count) = (0.0, 0.0, 0.0);
    let mut extent = [usize::MAX, 0, usize::MAX, 0];
    for (i, _) in covered.iter().enumerate().filter(|(_, &c)| c) {
        let (x, y) = (i % SIZE, i / SIZE);
        sum_x += x as f64 + 0.5;
        sum_y += y as f64 + 0.5;
        count += 1.0;
        extent = [
            extent[0].min(x),
            extent[1].max(x),
            extent[2].min(y),
            extent[3].max(y),
        ];
    }
    assert!(count > 0.0, "the sphere is not in view");
    ((sum_x / count, sum_y / count), extent)
}

/// The sphere's silhouette is the circle inscribed in the square image (its tangent rays
/// make half the field of view with the view axis): centroid at the image centre, covered
/// from the first row and column to the last. Checked within a pixel at each distance.
#[test]
fn a_distant_gltf_camera_frames_its_sphere() {
    let mut failures = Vec::new();
    for distance in [1e2, 1e3, 1e4, 1e5, 1e6] {
        let covered = covered_pixels(&scene_json(distance));
        let ((x, y), [left, right, top, bottom]) = centroid_and_extent(&covered);
        eprintln!(
            "distance {distance:e}: centroid ({x:.2}, {y:.2}), columns {left}-{right}, rows {top}-{bottom}"
        );
        let centre = SIZE as f64 / 2.0;
        let last = SIZE - 1;
        if (x - centre).abs() > 1.0
            || (y - centre).abs() > 1.0
            || left > 1
            || top > 1
            || right + 1 < last
            || bottom + 1 < last
        {
            failures.push(format!(
                "distance {distance:e}: centroid ({x:.2}, {y:.2}), columns {left}-{right}, rows {top}-{bottom}"
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "expected centroid ({0}, {0}), columns and rows 0-{1}:\n{2}",
        SIZE / 2,
        SIZE - 1,
        failures.join("\n")
    );
}
