//! Where a scene's referenced files come from: the file system, or the bytes built into
//! the binary for the default scene.
//!
//! Loaders never touch `std::fs` directly; they ask a [`Files`] for a path relative to the
//! file being loaded. That lets the built-in default scene resolve `../models/box.obj` and
//! `../textures/checker.png` from `include_bytes!` data exactly as the asset files would.
//!
//! Every disk file a loader reads or references is recorded ([`Files::read_so_far`]), so
//! that a render can refuse an output that would overwrite any of them.

use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};

use glam::Vec3;

use super::error::SceneError;
use crate::scene::{Environment, SceneDescription, TextureSource};

/// Resolves and reads files relative to a base directory.
#[derive(Clone, Debug)]
pub(crate) struct Files {
    base_dir: PathBuf,
    /// `None` reads the file system; `Some` looks paths up in embedded (path, bytes) pairs.
    embedded: Option<&'static [(&'static str, &'static [u8])]>,
    /// The disk files read or referenced so far, shared by every `with_base` copy.
    touched: Arc<Mutex<Vec<PathBuf>>>,
}

impl Files {
    /// Files on disk, relative paths resolved against `base_dir`.
    pub(crate) fn disk(base_dir: &Path) -> Self {
        Files {
            base_dir: base_dir.to_path_buf(),
            embedded: None,
            touched: Arc::default(),
        }
    }

    /// Embedded files keyed by normalised relative paths such as `assets/models/box.obj`.
    pub(crate) fn embedded(
        base_dir: &str,
        table: &'static [(&'static str, &'static [u8])],
    ) -> Self {
        Files {
            base_dir: PathBuf::from(base_dir),
            embedded: Some(table),
            touched: Arc::default(),
        }
    }

    /// The same source with relative paths resolved against `dir` instead.
    pub(crate) fn with_base(&self, dir: &Path) -> Self {
        Files {
            base_dir: dir.to_path_buf(),
            embedded: self.embedded,
            touched: self.touched.clone(),
        }
    }

    /// The disk files read or referenced through this source and its `with_base` copies, in
    /// first-touch order, each once (embedded files are not on disk and are not listed).
    pub(crate) fn read_so_far(&self) -> Vec<PathBuf> {
        self.touched
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone()
    }

    fn record(&self, path: &Path) {
        let mut touched = self
            .touched
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        if !touched.iter().any(|p| p == path) {
            touched.push(path.to_path_buf());
        }
    }

    /// `relative` joined to the base directory and lexically normalised (absolute paths kept).
    pub(crate) fn resolve(&self, relative: &str) -> PathBuf {
        normalize(&self.base_dir.join(relative))
    }

    /// The bytes of the file at `path` (an already resolved path).
    pub(crate) fn read(&self, path: &Path) -> Result<Vec<u8>, SceneError> {
        match self.embedded {
            Some(table) => lookup(table, path).map(<[u8]>::to_vec).ok_or_else(|| {
                SceneError::unreadable(path.display(), "not among the built-in files")
            }),
            None => {
                self.record(path);
                if path.is_dir() {
                    return Err(SceneError::unreadable(path.display(), "is a directory"));
                }
                std::fs::read(path).map_err(|e| SceneError::unreadable(path.display(), e))
            }
        }
    }

    /// A texture source for the image at `path`, after checking it exists and can be opened.
    /// The image itself is decoded later by `crate::texture`.
    pub(crate) fn texture_source(&self, path: &Path) -> Result<TextureSource, SceneError> {
        match self.embedded {
            Some(table) => match lookup(table, path) {
                Some(bytes) => Ok(TextureSource::Encoded {
                    label: path.display().to_string(),
                    bytes: Arc::new(bytes.to_vec()),
                }),
                None => Err(SceneError::unreadable(
                    path.display(),
                    "not among the built-in files",
                )),
            },
            None => {
                self.record(path);
                if !path.is_file() {
                    let reason = if path.exists() {
                        "not a regular file"
                    } else {
                        "no such file"
                    };
                    return Err(SceneError::unreadable(path.display(), reason));
                }
                std::fs::File::open(path).map_err(|e| SceneError::unreadable(path.display(), e))?;
                Ok(TextureSource::File(path.to_path_buf()))
            }
        }
    }
}

/// The policy for a referenced file that cannot be read (missing, a directory, no
/// permission; docs/scene-format.md, "Missing and invalid referenced files"): an image or an
/// MTL library only changes how surfaces look, so the scene renders without it and a note
/// says so; geometry (mesh files, glTF buffers, patch files, fog bounds) is an error, as is a
/// file that is read but malformed.
///
/// Records the note `<place>: <what> not loaded (<reason>): <consequence>` once per `what`
/// (a file used by several materials is named once).
pub(crate) fn note_not_loaded(
    notes: &mut Vec<String>,
    place: &str,
    what: &str,
    error: &SceneError,
    consequence: &str,
) {
    let marker = format!("{what} not loaded");
    if notes.iter().any(|n| n.contains(&marker)) {
        return;
    }
    let reason = match error {
        SceneError::Unreadable { reason, .. } => reason.clone(),
        other => other.to_string(),
    };
    notes.push(format!("{place}: {marker} ({reason}): {consequence}"));
}

/// Removes the textures at `missing` (indices into `scene.textures`, files that could not be
/// read) from the scene: material slots bound to them are emptied, so the material renders
/// with its factors alone; an environment map among them leaves a black environment. Other
/// bindings are re-indexed.
pub(crate) fn leave_out_textures(scene: &mut SceneDescription, missing: &[usize]) {
    if missing.is_empty() {
        return;
    }
    // New index of each texture, `None` for a removed one.
    let mut kept = 0;
    let new_index: Vec<Option<usize>> = (0..scene.textures.len())
        .map(|i| {
            if missing.contains(&i) {
                None
            } else {
                kept += 1;
                Some(kept - 1)
            }
        })
        .collect();
    let mut index = 0;
    scene.textures.retain(|_| {
        index += 1;
        new_index[index - 1].is_some()
    });
    for material in &mut scene.materials {
        for slot in material.texture_slots_mut() {
            if let Some(binding) = slot {
                match new_index.get(binding.texture).copied().flatten() {
                    Some(i) => binding.texture = i,
                    None => *slot = None,
                }
            }
        }
    }
    if let Environment::LatLong { texture, .. } = &mut scene.environment {
        match new_index.get(*texture).copied().flatten() {
            Some(i) => *texture = i,
            None => scene.environment = Environment::Color(Vec3::ZERO),
        }
    }
}

fn lookup(table: &'static [(&'static str, &'static [u8])], path: &Path) -> Option<&'static [u8]> {
    let wanted = normalize(path);
    table
        .iter()
        .find(|(name, _)| Path::new(name) == wanted)
        .map(|(_, bytes)| *bytes)
}

/// Removes `.` components and folds `dir/..` pairs without touching the file system.
pub(crate) fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for component in path.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => {
                let last_is_normal =
                    matches!(out.components().next_back(), Some(Component::Normal(_)));
                if last_is_normal {
                    out.pop();
                } else {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    static TABLE: &[(&str, &[u8])] = &[("assets/models/box.obj", b"v 0 0 0\n")];

    #[test]
    fn normalize_folds_parent_components() {
        assert_eq!(
            normalize(Path::new("assets/scenes/../models/./box.obj")),
            PathBuf::from("assets/models/box.obj")
        );
        assert_eq!(normalize(Path::new("../a/b")), PathBuf::from("../a/b"));
        assert_eq!(normalize(Path::new("/x/../y")), PathBuf::from("/y"));
    }

    #[test]
    fn embedded_files_resolve_relative_to_the_base() {
        let files = Files::embedded("assets/scenes", TABLE);
        let path = files.resolve("../models/box.obj");
        assert_eq!(files.read(&path).unwrap(), b"v 0 0 0\n");
        assert!(files.read(&files.resolve("missing.obj")).is_err());
        assert!(matches!(
            files.texture_source(&path),
            Ok(TextureSource::Encoded { .. })
        ));
    }

    #[test]
    fn missing_disk_files_are_errors_naming_the_file() {
        let files = Files::disk(Path::new("/nonexistent-dir"));
        let err = files.read(&files.resolve("x.obj")).unwrap_err().to_string();
        assert!(
            err.starts_with("/nonexistent-dir/x.obj: cannot read"),
            "{err}"
        );
        let err = files
            .texture_source(&files.resolve("t.png"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("t.png") && err.contains("no such file"),
            "{err}"
        );
    }

    #[test]
    fn every_disk_file_read_or_referenced_is_recorded_once() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.obj"), b"v 0 0 0\n").unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        std::fs::write(dir.path().join("sub/t.png"), b"png").unwrap();
        let files = Files::disk(dir.path());
        files.read(&files.resolve("a.obj")).unwrap();
        files.read(&files.resolve("a.obj")).unwrap();
        let nested = files.with_base(&dir.path().join("sub"));
        nested.texture_source(&nested.resolve("t.png")).unwrap();
        // A file that could not be read is recorded too: an output there would change what
        // the next render reads.
        assert!(nested.read(&nested.resolve("missing.mtl")).is_err());
        assert_eq!(
            files.read_so_far(),
            [
                dir.path().join("a.obj"),
                dir.path().join("sub/t.png"),
                dir.path().join("sub/missing.mtl")
            ]
        );
        // Built-in files are not on disk.
        let embedded = Files::embedded("assets/scenes", TABLE);
        embedded
            .read(&embedded.resolve("../models/box.obj"))
            .unwrap();
        assert!(embedded.read_so_far().is_empty());
    }
}
