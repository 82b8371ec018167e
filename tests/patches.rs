//! Curved surfaces from the command line: patch scenes load and render, and bad control
//! data is refused with one line naming the file and exit status 2, writing nothing.

mod common;

use std::path::Path;

use common::*;

/// A small scene around one `[[patch]]`/`[[patch_file]]` table given as `surface`.
fn scene(surface: &str) -> String {
    format!(
        "[render]\nwidth = 16\nheight = 16\n\n[camera]\neye = [0, 0, 6]\ntarget = [0, 0, 0]\n\n\
         [[light]]\ntype = \"directional\"\ndirection = [0, 0, -1]\n\n{surface}\n"
    )
}

fn assert_refused(dir: &Path, file: &str, expected: &[&str]) {
    let out = run_in(dir, &["render", file, "-o", "out.exr", "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{file}: stderr {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{file}: expected one line, got {stderr:?}");
    for part in expected {
        assert!(lines[0].contains(part), "'{}' lacks '{part}'", lines[0]);
    }
    assert!(!dir.join("out.exr").exists(), "{file}: an EXR was written");
}

fn flat_grid(replace_first: Option<&str>) -> String {
    let mut points: Vec<String> = (0..16)
        .map(|k| format!("[{}, {}, 0]", k % 4, k / 4))
        .collect();
    if let Some(first) = replace_first {
        points[0] = first.to_string();
    }
    format!("[{}]", points.join(", "))
}

#[test]
fn bad_control_data_is_refused() {
    let dir = temp_dir();
    let cases: [(&str, String, Vec<&str>); 4] = [
        (
            "count.toml",
            "[[patch]]\ncontrol_points = [[0,0,0],[1,0,0],[0,1,0]]\n".into(),
            vec!["count.toml:", "needs 16 control points, not 3"],
        ),
        (
            "nan.toml",
            format!(
                "[[patch]]\ncontrol_points = {}\n",
                flat_grid(Some("[nan, 0, 0]"))
            ),
            vec!["nan.toml:", "not finite"],
        ),
        (
            "degenerate.toml",
            format!(
                "[[patch]]\nkind = \"lagrange\"\ncontrol_points = [{}]\n",
                vec!["[1, 2, 3]"; 16].join(", ")
            ),
            vec!["degenerate.toml:", "fully degenerate"],
        ),
        (
            "triangle.toml",
            "[[bezier_triangle]]\ncontrol_points = [[0,0,0],[1,0,0]]\n".into(),
            vec!["triangle.toml:", "needs 10 control points, not 2"],
        ),
    ];
    for (file, surface, expected) in cases {
        write(dir.path(), file, &scene(&surface));
        assert_refused(dir.path(), file, &expected);
    }
}

#[test]
fn bad_patch_files_are_refused_naming_the_patch_file() {
    let dir = temp_dir();
    let mut bpt = String::from("1\n3 3\n");
    for k in 0..16 {
        bpt += &format!("{} {} 0\n", k % 4, k / 4);
    }
    write(dir.path(), "nan.bpt", &bpt.replace("2 1 0", "2 nan 0"));
    write(dir.path(), "short.bpt", &bpt.replace("1\n3 3", "2\n3 3"));
    write(
        dir.path(),
        "a.toml",
        &scene("[[patch_file]]\nfile = \"nan.bpt\"\n"),
    );
    write(
        dir.path(),
        "b.toml",
        &scene("[[patch_file]]\nfile = \"short.bpt\"\n"),
    );
    assert_refused(dir.path(), "a.toml", &["nan.bpt: line 9:", "not finite"]);
    assert_refused(dir.path(), "b.toml", &["short.bpt:", "ends where"]);
}

/// A mirror patch is a reason for reflection rays: materials used only by patches count in
/// the effect analysis, and the teapot renders with its patches hit.
#[test]
fn a_mirror_patch_turns_reflections_on_and_renders() {
    let dir = temp_dir();
    let surface = "[[material]]\nname = \"chrome\"\nmirror = 0.9\n\n\
                   [[patch]]\nkind = \"hermite\"\nmaterial = \"chrome\"\ncontrol_points = [\
                   [-3,-3,0],[-1,-3,0],[1,-3,0],[3,-3,0],[-3,-1,0],[-1,-1,1],[1,-1,1],[3,-1,0],\
                   [-3,1,0],[-1,1,1],[1,1,1],[3,1,0],[-3,3,0],[-1,3,0],[1,3,0],[3,3,0]]\n";
    write(dir.path(), "m.toml", &scene(surface));
    let out = run_in(
        dir.path(),
        &[
            "render", "m.toml", "-o", "o.exr", "--no-png", "--quiet", "--stats", "s.json",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap()).unwrap();
    let reflection = stats["counters"]["reflection_rays"]
        .as_u64()
        .expect("a counter");
    assert!(reflection > 0, "no reflection rays: {}", stats["counters"]);
    let effects = stats["effects"].to_string();
    assert!(effects.contains("mirror reflection"), "{effects}");
}

/// `--patch-mode tessellate` renders the teapot as triangles and says how many, and how
/// long they took, in the statistics; a finer bound makes more of them.
#[test]
fn tessellation_is_reported_and_follows_the_error_bound() {
    let dir = temp_dir();
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/models/teapot.bpt");
    let surface = format!(
        "[[patch_file]]\nfile = \"{}\"\nrotate = [-90, 0, 0]\nscale = 0.5\n",
        assets.display()
    );
    write(dir.path(), "t.toml", &scene(&surface));
    let triangles = |error: &str| -> u64 {
        let out = run_in(
            dir.path(),
            &[
                "render",
                "t.toml",
                "-o",
                "o.exr",
                "--no-png",
                "--quiet",
                "--stats",
                "s.json",
                "--patch-mode",
                "tessellate",
                "--tessellation-error",
                error,
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stats: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join("s.json")).unwrap())
                .unwrap();
        let notes = stats["notes"].to_string();
        let note = notes
            .split('"')
            .find(|n| n.contains("tessellated"))
            .unwrap_or_else(|| panic!("no tessellation note in {notes}"));
        assert!(
            note.contains(" s") && note.contains("32 curved patches"),
            "{note}"
        );
        let count = note
            .split(": ")
            .nth(1)
            .and_then(|r| r.split(' ').next())
            .unwrap();
        count
            .parse()
            .unwrap_or_else(|_| panic!("no triangle count in {note}"))
    };
    let coarse = triangles("0.01");
    let fine = triangles("0.0001");
    eprintln!("teapot: {coarse} triangles within 0.01, {fine} within 0.0001");
    assert!(coarse > 32 * 2 && fine > 4 * coarse, "{coarse} vs {fine}");
    let out = run_in(
        dir.path(),
        &[
            "render",
            "t.toml",
            "-o",
            "o.exr",
            "--quiet",
            "--tessellation-error",
            "0",
        ],
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--tessellation-error 0"));
}
