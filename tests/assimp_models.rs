//! Real files nobody here wrote (issue 6, part 3): every OBJ and glTF file of Debian's
//! `assimp-testmodels` is rendered by the conetrace binary at 16x16. Each either renders
//! (exit 0, a valid EXR with finite colour) or is rejected with exit status 2 and one line
//! naming the file — never a panic (status 101), an abort or a signal. The deliberately
//! malformed ones (NaN/infinite vertices, out-of-range indices, a missing buffer, recursive
//! nodes, wrong JSON types) must be among the rejected. Fails with a message naming
//! `bash scripts/setup.sh` when the package is not installed.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use common::*;

const MODELS: &str = "/usr/share/assimp/models";
const SETUP_HINT: &str = "run `bash scripts/setup.sh` (installs assimp-testmodels)";

fn model_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            model_files(&path, out);
        } else if let Some(ext) = path.extension().and_then(|e| e.to_str()) {
            if ["obj", "gltf", "glb"].contains(&ext.to_ascii_lowercase().as_str()) {
                out.push(path);
            }
        }
    }
}

/// How one file fared.
#[derive(Debug)]
enum Outcome {
    Rendered,
    Rejected(String),
}

/// Render `file` at 16x16 into a fresh directory and check the contract.
fn render_model(file: &Path) -> Result<Outcome, String> {
    let dir = temp_dir();
    let out = conetrace()
        .args([
            "render".as_ref(),
            file.as_os_str(),
            "-o".as_ref(),
            "out.exr".as_ref(),
            "--width".as_ref(),
            "16".as_ref(),
            "--height".as_ref(),
            "16".as_ref(),
            "--threads".as_ref(),
            "1".as_ref(),
            "--quiet".as_ref(),
        ])
        .current_dir(dir.path())
        .output()
        .map_err(|e| format!("cannot run conetrace: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let name = file.file_name().unwrap_or_default().to_string_lossy();
    match out.status.code() {
        Some(0) => {
            let image = read_exr(&dir.path().join("out.exr"));
            for channel in ["R", "G", "B", "A", "N.X", "N.Y", "N.Z", "albedo.R", "uv.U"] {
                if image.channel(channel).iter().any(|v| !v.is_finite()) {
                    return Err(format!("rendered with non-finite {channel}"));
                }
            }
            if !dir.path().join("out.png").exists() {
                return Err("rendered but wrote no PNG".into());
            }
            Ok(Outcome::Rendered)
        }
        Some(2) => {
            let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
            if lines.len() != 1 {
                return Err(format!("status 2 with {} lines: {stderr:?}", lines.len()));
            }
            if !lines[0].contains(&*name) {
                return Err(format!("message does not name the file: {}", lines[0]));
            }
            if dir.path().join("out.exr").exists() || dir.path().join("out.png").exists() {
                return Err("rejected but wrote an output".into());
            }
            Ok(Outcome::Rejected(lines[0].to_string()))
        }
        other => Err(format!(
            "status {other:?} ({}), stderr {stderr:?}",
            out.status
        )),
    }
}

#[test]
fn every_assimp_model_renders_or_is_rejected_with_one_line() {
    let mut files = Vec::new();
    model_files(Path::new(MODELS), &mut files);
    assert!(
        !files.is_empty(),
        "no OBJ or glTF files under {MODELS}: {SETUP_HINT}"
    );
    files.sort();
    let queue = Mutex::new(files.clone());
    let results = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let Some(file) = queue.lock().unwrap().pop() else {
                    break;
                };
                let outcome = render_model(&file);
                results.lock().unwrap().push((file, outcome));
            });
        }
    });
    let mut results = results.into_inner().unwrap();
    results.sort_by(|a, b| a.0.cmp(&b.0));
    let (mut rendered, mut rejected, mut broken) = (0, 0, Vec::new());
    for (file, outcome) in &results {
        match outcome {
            Ok(Outcome::Rendered) => rendered += 1,
            Ok(Outcome::Rejected(line)) => {
                rejected += 1;
                eprintln!("rejected: {line}");
            }
            Err(problem) => broken.push(format!("{}: {problem}", file.display())),
        }
    }
    eprintln!(
        "{} files: {rendered} rendered, {rejected} rejected",
        files.len()
    );
    assert!(broken.is_empty(), "contract broken:\n{}", broken.join("\n"));
    assert!(rendered >= 10, "only {rendered} files rendered");

    // The deliberately broken files are among the rejected.
    for malformed in [
        "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb",
        "glTF2/IndexOutOfRange/IndexOutOfRange.gltf",
        "glTF2/IndexOutOfRange/AllIndicesOutOfRange.gltf",
        "glTF2/MissingBin/BoxTextured.gltf",
        "glTF2/RecursiveNodes/RecursiveNodes.gltf",
        "glTF2/wrongTypes/badArray.gltf",
        "glTF2/wrongTypes/badNumber.gltf",
        "glTF2/wrongTypes/badObject.gltf",
        "glTF2/wrongTypes/badString.gltf",
        "glTF2/wrongTypes/badUint.gltf",
    ] {
        let path = Path::new(MODELS).join(malformed);
        let (_, outcome) = results
            .iter()
            .find(|(f, _)| *f == path)
            .unwrap_or_else(|| panic!("{} is not installed: {SETUP_HINT}", path.display()));
        assert!(
            matches!(outcome, Ok(Outcome::Rejected(_))),
            "{malformed}: {outcome:?}"
        );
    }

    // Outcomes the loaders' shared rules decide (docs/scene-format.md, "Rules every loader
    // follows"): zero normals are repaired, so BoxBadNormals renders; every glTF 1.0 file
    // and every file requiring an extension conetrace lacks is refused with its reason.
    let outcome_of = |relative: &str| {
        let path = Path::new(MODELS).join(relative);
        let (_, outcome) = results
            .iter()
            .find(|(f, _)| *f == path)
            .unwrap_or_else(|| panic!("{} is not installed: {SETUP_HINT}", path.display()));
        outcome
    };
    for repaired in [
        "glTF2/BoxBadNormals-glTF-Binary/BoxBadNormals.glb",
        "glTF2/ClearCoat-glTF/ClearCoatTest.gltf",
    ] {
        let outcome = outcome_of(repaired);
        assert!(
            matches!(outcome, Ok(Outcome::Rendered)),
            "{repaired}: {outcome:?}"
        );
    }
    for (refused, reason) in [
        (
            "glTF/CesiumMilkTruck/CesiumMilkTruck.gltf",
            "glTF 1.0 files are not supported (only glTF 2.0)",
        ),
        (
            "glTF/BoxTextured-glTF-Binary/BoxTextured.glb",
            "glTF 1.0 files are not supported (only glTF 2.0)",
        ),
        (
            "glTF2/draco/2CylinderEngine.gltf",
            "requires the glTF extension KHR_draco_mesh_compression, which conetrace does not support",
        ),
    ] {
        match outcome_of(refused) {
            Ok(Outcome::Rejected(line)) => assert!(line.ends_with(reason), "{line}"),
            other => panic!("{refused}: {other:?}"),
        }
    }
}

/// Inputs the fuzzers found crashing (tests/fuzz_regressions; the first byte is the
/// mesh_scene target's format selector: 0 OBJ, 1 glTF, 2 GLB) are rejected with one line.
#[test]
fn fuzz_regressions_are_rejected_with_one_line() {
    let dir = temp_dir();
    let regressions = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    let mut count = 0;
    for entry in std::fs::read_dir(&regressions).expect("tests/fuzz_regressions") {
        let path = entry.unwrap().path();
        let bytes = std::fs::read(&path).unwrap();
        let Some((&selector, body)) = bytes.split_first() else {
            continue;
        };
        let extension = ["obj", "gltf", "glb"][selector as usize % 3];
        let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
        let file = dir.path().join(format!("{stem}.{extension}"));
        std::fs::write(&file, body).unwrap();
        match render_model(&file) {
            Ok(Outcome::Rejected(_)) | Ok(Outcome::Rendered) => count += 1,
            Err(problem) => panic!("{}: {problem}", path.display()),
        }
    }
    assert!(count >= 1);
}
