//! A glTF file whose index accessor cannot hold vertex indices (signed or float components,
//! or not scalars) is bad input: exit status 2, one line naming the file and the accessor,
//! and nothing written.

mod common;

use common::{base64, run_in, temp_dir, write};

/// A one-triangle glTF with its three indices stored as `component_type` / `kind`.
fn triangle_gltf(component_type: u32, kind: &str) -> String {
    let mut buffer = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|x| buffer.extend(x.to_le_bytes()));
    }
    // Room for three indices of any type (up to 4 bytes each, up to 2 components).
    buffer.extend([
        0u8, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
    ]);
    let data = base64(&buffer);
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
  "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1}}]}}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}],
  "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
                  {{"buffer": 0, "byteOffset": 36, "byteLength": 24}}],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
      "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": {component_type}, "count": 3, "type": "{kind}"}}]}}"#,
        len = buffer.len()
    )
}

#[test]
fn index_accessors_that_are_not_unsigned_scalars_are_rejected() {
    let dir = temp_dir();
    // The same file with proper indices renders, so the rejections below are about them.
    write(dir.path(), "good.gltf", &triangle_gltf(5125, "SCALAR"));
    let out = run_in(
        dir.path(),
        &[
            "render",
            "good.gltf",
            "-o",
            "good.exr",
            "--no-png",
            "--quiet",
            "--width",
            "8",
            "--height",
            "8",
        ],
    );
    assert!(
        out.status.success(),
        "the well-formed triangle fails: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (component_type, kind, what) in [
        (5120, "SCALAR", "Scalar of I8"),
        (5122, "SCALAR", "Scalar of I16"),
        (5126, "SCALAR", "Scalar of F32"),
        (5123, "VEC2", "Vec2 of U16"),
    ] {
        write(dir.path(), "bad.gltf", &triangle_gltf(component_type, kind));
        let out = run_in(
            dir.path(),
            &["render", "bad.gltf", "-o", "bad.exr", "--quiet"],
        );
        let stderr = String::from_utf8_lossy(&out.stderr);
        eprintln!(
            "componentType {component_type} {kind}: exit {:?}: {stderr}",
            out.status.code()
        );
        assert_eq!(out.status.code(), Some(2), "{what}: {stderr}");
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "{what}: expected one line, got {stderr:?}");
        assert!(
            lines[0].contains("bad.gltf")
                && lines[0].contains(&format!("index accessor 1 holds {what}"))
                && lines[0].contains("indices must be unsigned scalar integers"),
            "{what}: the message does not name the file and the problem: {}",
            lines[0]
        );
        assert!(
            !dir.path().join("bad.exr").exists(),
            "{what}: an output was written"
        );
        assert!(
            !dir.path().join("bad.png").exists(),
            "{what}: a PNG was written"
        );
    }
}
