//! OBJ and MTL files as real exporters write them (Debian's `assimp-testmodels`): Latin-1
//! material names, names with spaces, an MTL material without a name, a face with a hole
//! joined to its outer ring by a slit. Each renders with its materials (and its holes), and
//! malformed OBJ/MTL files are refused with the line that is wrong. The assimp models must be
//! installed (package `assimp-testmodels`): without them these tests fail.

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use common::*;
use conetrace::scene::load::load_scene;

const OBJ_MODELS: &str = "/usr/share/assimp/models/OBJ";

/// The path of an assimp OBJ model; panics (fails the test) when the package is missing.
fn assimp_model(name: &str) -> PathBuf {
    let path = Path::new(OBJ_MODELS).join(name);
    assert!(
        path.is_file(),
        "{} is missing: install the package assimp-testmodels",
        path.display()
    );
    path
}

/// Renders `file` at 48x48 in a fresh directory; asserts exit 0 and returns what it printed
/// (the summary with its notes) and the distinct albedo colours of the image (rounded to 1/1000).
fn render_albedos(file: &Path) -> (String, BTreeSet<[i32; 3]>) {
    let dir = temp_dir();
    let out = conetrace()
        .args([
            "render".as_ref(),
            file.as_os_str(),
            "-o".as_ref(),
            "out.exr".as_ref(),
            "--width".as_ref(),
            "48".as_ref(),
            "--height".as_ref(),
            "48".as_ref(),
        ])
        .current_dir(dir.path())
        .output()
        .expect("the conetrace binary runs");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(0), "{}: {stderr}", file.display());
    // The summary and its notes go to standard output.
    let summary = String::from_utf8_lossy(&out.stdout).into_owned() + &stderr;
    let image = read_exr(&dir.path().join("out.exr"));
    let (r, g, b) = (
        image.channel("albedo.R"),
        image.channel("albedo.G"),
        image.channel("albedo.B"),
    );
    let round = |x: f32| (x * 1000.0).round() as i32;
    let colours = (0..r.len())
        .map(|i| [round(r[i]), round(g[i]), round(b[i])])
        .collect();
    (summary, colours)
}

#[test]
fn latin1_material_names_keep_their_materials() {
    let path = assimp_model("regr01.obj");
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    // `usemtl Terraind\xE6k` (Latin-1 byte E6) finds `newmtl Terraind\xE6k` and its Kd.
    let terrain = scene
        .materials
        .iter()
        .position(|m| m.name == "Terraind\u{e6}k")
        .unwrap_or_else(|| {
            let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
            panic!("no material 'Terraind\u{e6}k' among {names:?}")
        });
    assert_eq!(
        scene.materials[terrain].base_color,
        glam::Vec3::new(0.4, 0.3, 0.3)
    );
    assert!(scene.meshes.iter().any(|m| m.material == terrain));
    assert!(
        scene.materials.iter().all(|m| m.name != "default"),
        "a face fell back to the default material"
    );
    let (summary, albedos) = render_albedos(&path);
    assert!(!summary.contains("not loaded"), "{summary}");
    // Several of the library's diffuse colours are seen, not the default grey.
    let library_colours = [
        [200, 200, 200], // Base, Sill
        [800, 600, 400], // Door
        [900, 900, 700], // Floor
        [500, 700, 400], // Site
        [500, 0, 0],     // Wall-out
        [800, 700, 500], // Wall-inner
        [400, 300, 300], // Ridging, Terraind\xE6k
        [900, 900, 600], // Roof
        [800, 500, 200], // Rafter
    ];
    let seen: Vec<_> = library_colours
        .iter()
        .filter(|c| albedos.contains(*c))
        .collect();
    assert!(
        seen.len() >= 2,
        "albedos {albedos:?} show only {seen:?} of the MTL colours"
    );
    assert!(!albedos.contains(&[800, 800, 800]), "default grey seen");
}

#[test]
fn material_names_with_spaces_and_latin1_libraries_load() {
    // box_spaces.mtl holds a Latin-1 name too: before, the whole library was dropped.
    let path = assimp_model("box_mat_with_spaces.obj");
    let scene = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
    assert!(names.contains(&"Terraind\u{e6}k"), "{names:?}");
    let used: BTreeSet<&str> = scene
        .meshes
        .iter()
        .map(|m| scene.materials[m.material].name.as_str())
        .collect();
    assert_eq!(
        used,
        BTreeSet::from(["Material name with many, many spaces"]),
        "{names:?}"
    );
    let (summary, albedos) = render_albedos(&path);
    assert!(!summary.contains("not loaded"), "{summary}");
    assert!(albedos.contains(&[200, 200, 200]), "{albedos:?}");
    assert!(!albedos.contains(&[800, 800, 800]), "{albedos:?}");
}

#[test]
fn an_empty_material_name_gets_the_default_material_and_a_note() {
    let path = assimp_model("empty_mat.obj");
    let (summary, albedos) = render_albedos(&path);
    assert!(
        summary.contains("empty_mat.mtl: line 3: material without a name"),
        "{summary}"
    );
    assert!(
        summary.contains("empty_mat.obj: line 233: usemtl without a material name"),
        "{summary}"
    );
    assert!(albedos.contains(&[800, 800, 800]), "{albedos:?}");
}

/// Renders `file` in `dir` and asserts the failure contract: exit 2, one line containing
/// every part of `expected`, no output.
fn assert_refused(dir: &Path, file: &str, expected: &[&str]) {
    let out = run_in(dir, &["render", file, "-o", "out.exr", "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{file}: {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{file}: {stderr:?}");
    for part in expected {
        assert!(
            lines[0].contains(part),
            "{file}: '{}' lacks '{part}'",
            lines[0]
        );
    }
    assert!(!dir.join("out.exr").exists() && !dir.join("out.png").exists());
}

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn malformed_obj_lines_are_named() {
    let cases = [
        // (OBJ text, what the message must contain)
        (
            format!("{TRIANGLE}v 1 x 0\nf 1 2 3\n"),
            "m.obj: line 4: position parse error",
        ),
        (
            format!("{TRIANGLE}vn 0 1\nf 1 2 3\n"),
            "m.obj: line 4: normal parse error",
        ),
        (
            format!("{TRIANGLE}f 1 2 a\n"),
            "m.obj: line 4: face parse error",
        ),
        (
            format!("{TRIANGLE}f 1 2 3\n\nf 1 2 7\n"),
            "m.obj: line 6: face refers to vertex 7, but the file has 3 vertices",
        ),
        (
            format!("{TRIANGLE}f 1 2 -4\n"),
            "m.obj: line 4: face refers to vertex -4",
        ),
        (
            format!("{TRIANGLE}vt 0 0\nf 1/2 2/1 3/1\n"),
            "m.obj: line 5: face refers to texture coordinate 2",
        ),
        (
            format!("{TRIANGLE}f\nf 1 2 3\n"),
            "m.obj: line 4: face without vertices",
        ),
        (
            format!("{TRIANGLE}f 1 0 2\n"),
            "m.obj: line 4: face refers to vertex 0",
        ),
    ];
    for (text, expected) in cases {
        let dir = temp_dir();
        write(dir.path(), "m.obj", &text);
        assert_refused(dir.path(), "m.obj", &[expected]);
    }
}

#[test]
fn malformed_mtl_lines_are_named() {
    let obj = format!("mtllib m.mtl\n{TRIANGLE}usemtl a\nf 1 2 3\n");
    let cases = [
        (
            "newmtl a\nKd 1 0\n",
            "m.mtl: line 2: 'Kd 1 0' needs 1 or 3 numbers",
        ),
        (
            "newmtl a\n\nKd 1 x 0\n",
            "m.mtl: line 3: material parse error",
        ),
        ("newmtl a\nNs many\n", "m.mtl: line 2: material parse error"),
        (
            "newmtl a\nillum high\n",
            "m.mtl: line 2: material parse error",
        ),
        (
            "newmtl a\nKe 1 -1 1\n",
            "m.mtl: line 2: 'Ke 1 -1 1': a colour component is negative",
        ),
        (
            "newmtl a\nKs 2 2 2\n",
            "m.mtl: line 2: 'Ks 2 2 2': Ks is a reflectance, its components must lie in [0, 1]",
        ),
        (
            "newmtl a\nKd 2 0 0\n",
            "m.mtl: line 2: 'Kd 2 0 0': Kd is a reflectance, its components must lie in [0, 1]",
        ),
        (
            "newmtl a\nTr half\n",
            "m.mtl: line 2: 'Tr half': Tr must be a number in [0, 1]",
        ),
        (
            "newmtl a\nd -1\n",
            "m.mtl: line 2: 'd -1': d must be a number in [0, 1]",
        ),
        (
            "newmtl a\nd -halo 2\n",
            "m.mtl: line 2: 'd -halo 2': d must be a number in [0, 1]",
        ),
        (
            "newmtl a\nTr 3\n",
            "m.mtl: line 2: 'Tr 3': Tr must be a number in [0, 1]",
        ),
    ];
    for (mtl, expected) in cases {
        let dir = temp_dir();
        write(dir.path(), "m.obj", &obj);
        write(dir.path(), "m.mtl", mtl);
        assert_refused(dir.path(), "m.obj", &[expected]);
    }
}

/// A map file that cannot be read is not a malformed line: the render goes on without it
/// (exit 0, the material's own `Kd` seen) and the summary names the file and its MTL line.
#[test]
fn a_missing_map_file_renders_without_it_and_says_so() {
    let dir = temp_dir();
    write(
        dir.path(),
        "m.obj",
        "mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 0 1 0\nusemtl a\nf 1 2 3\n",
    );
    write(
        dir.path(),
        "m.mtl",
        "# textures\nnewmtl a\nKd 0.5 0.25 1\nmap_Kd missing.png\n",
    );
    let (summary, albedos) = render_albedos(&dir.path().join("m.obj"));
    assert!(
        summary.contains(
            "m.mtl: line 4: texture 'missing.png' not loaded (no such file): rendered without it"
        ),
        "{summary}"
    );
    assert!(albedos.contains(&[500, 250, 1000]), "{albedos:?}");
}

#[test]
fn one_number_colours_mean_grey() {
    // The MTL format lets `Kd r` stand for `Kd r r r`; `tobj` alone panics on it.
    let dir = temp_dir();
    write(
        dir.path(),
        "m.obj",
        &format!("mtllib m.mtl\n{TRIANGLE}usemtl a\nf 1 2 3\n"),
    );
    write(dir.path(), "m.mtl", "newmtl a\nKd 0.25\nKs 0\n");
    let scene = load_scene(&dir.path().join("m.obj")).unwrap_or_else(|e| panic!("{e}"));
    let a = scene.materials.iter().find(|m| m.name == "a").unwrap();
    assert_eq!(a.base_color, glam::Vec3::splat(0.25));
    let classic = a.model.classic().expect("the classic model");
    assert_eq!(classic.specular, 0.0);
}

/// Renders `scene` (with `files` beside it) orthographically in a fresh directory at `size` x
/// `size` pixels and returns which pixels a camera ray hit (a depth in the EXR's `Z`), row by
/// row from the top.
fn covered_pixels(scene: &str, files: &[(&str, &str)], size: usize) -> Vec<bool> {
    let dir = temp_dir();
    for (name, text) in files {
        write(dir.path(), name, text);
    }
    write(dir.path(), "scene.toml", scene);
    let size_text = size.to_string();
    let out = run_in(
        dir.path(),
        &[
            "render",
            "scene.toml",
            "-o",
            "out.exr",
            "--no-png",
            "--quiet",
            "--width",
            &size_text,
            "--height",
            &size_text,
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let image = read_exr(&dir.path().join("out.exr"));
    assert_eq!((image.width, image.height), (size, size));
    image.channel("Z").iter().map(|&z| z < f32::MAX).collect()
}

/// A TOML scene viewing `mesh` with an orthographic camera from `eye` towards `target`, the
/// view `height` units tall, the mesh grey.
fn orthographic_scene(mesh: &str, eye: [f64; 3], target: [f64; 3], height: f64) -> String {
    format!(
        "[camera]\ntype = \"orthographic\"\neye = {eye:?}\ntarget = {target:?}\nheight = {height}\n\n\
         [[material]]\nname = \"grey\"\nbase_color = [0.5, 0.5, 0.5]\n\n\
         [[mesh]]\nfile = {mesh:?}\nmaterial = \"grey\"\n"
    )
}

/// Issue 33: a 4x4 square with a 2x2 hole, written as one face whose boundary runs round the
/// square, along a slit to the hole, round the hole and back, covers 12 units^2 seen
/// orthographically; it covered all 16.
#[test]
fn a_face_with_a_bridged_hole_renders_its_hole() {
    let obj = "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 1 1 0\nv 3 1 0\nv 3 3 0\nv 1 3 0\n\
               f 1 2 3 4 1 5 8 7 6 5\n";
    // 8 units across 128 pixels: a pixel is 1/16 unit, the square's and the hole's edges
    // lie between pixel centres.
    let scene = orthographic_scene("square.obj", [2.0, 2.0, 5.0], [2.0, 2.0, 0.0], 8.0);
    let covered = covered_pixels(&scene, &[("square.obj", obj)], 128);
    let area = covered.iter().filter(|&&c| c).count() as f64 / 256.0;
    eprintln!("bridged square: {area} units^2 covered");
    assert!((area - 12.0).abs() < 0.05, "covered {area} units^2, not 12");
    // The middle of the hole (the image's centre) and the middle of the ring below it.
    assert!(!covered[64 * 128 + 64], "the hole's middle is covered");
    assert!(
        covered[(64 + 24) * 128 + 64],
        "the ring below the hole is not covered"
    );
}

/// The (y, z) corners of the first face of an OBJ file, in order.
fn first_face_corners(obj: &str) -> Vec<(f64, f64)> {
    let vertices: Vec<(f64, f64)> = obj
        .lines()
        .filter_map(|line| line.strip_prefix("v "))
        .map(|rest| {
            let xyz: Vec<f64> = rest
                .split_whitespace()
                .map(|w| w.parse().expect("number"))
                .collect();
            (xyz[1], xyz[2])
        })
        .collect();
    let face = obj
        .lines()
        .find_map(|line| line.strip_prefix("f "))
        .expect("a face");
    face.split_whitespace()
        .map(|corner| {
            let index: usize = corner.split('/').next().unwrap().parse().expect("index");
            vertices[index - 1]
        })
        .collect()
}

/// assimp's `concave_polygon.obj` is one face at x = -1.146: a thin ring (radii about 0.69
/// and 0.74 around y = 2.4, z = 2.35) walked as an outer circle, a slit, the inner circle
/// and the slit back. Seen orthographically along -x it covers the ring's area (the
/// shoelace area of its boundary, where the slit cancels) with its middle open; it was
/// rendered as a filled disk, seven times that area.
#[test]
fn assimp_concave_polygon_renders_as_a_ring() {
    let path = assimp_model("concave_polygon.obj");
    let obj = std::fs::read_to_string(&path).expect("readable model");
    let corners = first_face_corners(&obj);
    let ring_area = 0.5
        * (0..corners.len())
            .map(|k| {
                let ((y0, z0), (y1, z1)) = (corners[k], corners[(k + 1) % corners.len()]);
                y0 * z1 - y1 * z0
            })
            .sum::<f64>()
            .abs();
    // 1.6 units across 160 pixels: a pixel is 0.01 unit, the ring about 5 pixels wide.
    let scene = orthographic_scene(
        path.to_str().expect("utf-8 path"),
        [0.0, 2.4, 2.35],
        [-1.146, 2.4, 2.35],
        1.6,
    );
    let covered = covered_pixels(&scene, &[], 160);
    let area = covered.iter().filter(|&&c| c).count() as f64 * 1e-4;
    eprintln!("concave_polygon.obj: {area} units^2 covered, the ring {ring_area}");
    assert!(
        (area - ring_area).abs() < 0.05 * ring_area,
        "covered {area} units^2, the ring {ring_area}"
    );
    assert!(!covered[80 * 160 + 80], "the ring's middle is covered");
}
