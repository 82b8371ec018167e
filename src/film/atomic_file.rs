//! Writing a file so that readers see either the old contents or the complete new ones.
//!
//! The data goes to a hidden temporary file in the target's directory
//! (`.<name>.tmp-<pid>-<n>`), is flushed and fsynced, and only then renamed over the
//! target (a rename within one directory is atomic on POSIX file systems). On any failure
//! the temporary file is removed and an existing target is left byte-identical. Output
//! files of long renders are rewritten periodically, and an interrupted write must never
//! destroy the last good image.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::error::OutputError;

/// Distinguishes temporary files of concurrent writes from one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Removes the temporary file when dropped, unless the write succeeded.
struct TempFileGuard {
    path: PathBuf,
    keep: bool,
}

impl Drop for TempFileGuard {
    fn drop(&mut self) {
        if !self.keep {
            let _ = fs::remove_file(&self.path);
        }
    }
}

/// Writes `path` atomically: `write` fills a buffered temporary file, which then replaces
/// `path`. The parent directory is created if missing. If `write` or any file operation
/// fails, the error is returned, the temporary file removed and `path` left untouched.
pub fn write_atomically<F>(path: &Path, write: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
{
    let file_name = path
        .file_name()
        .ok_or_else(|| OutputError::invalid(path, "output path has no file name"))?;
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&parent).map_err(|e| OutputError::io(&parent, "create directory", e))?;

    let mut temp_name = std::ffi::OsString::from(".");
    temp_name.push(file_name);
    temp_name.push(format!(
        ".tmp-{}-{}",
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let temp_path = parent.join(temp_name);
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&temp_path)
        .map_err(|e| OutputError::io(&temp_path, "create temporary file", e))?;
    let mut guard = TempFileGuard {
        path: temp_path.clone(),
        keep: false,
    };

    let mut writer = BufWriter::new(file);
    write(&mut writer)?;
    writer
        .flush()
        .map_err(|e| OutputError::io(&temp_path, "write temporary file", e))?;
    let file = writer
        .into_inner()
        .map_err(|e| OutputError::io(&temp_path, "write temporary file", e.into_error()))?;
    file.sync_all()
        .map_err(|e| OutputError::io(&temp_path, "sync temporary file", e))?;
    drop(file);

    fs::rename(&temp_path, path).map_err(|e| OutputError::io(path, "replace file", e))?;
    guard.keep = true;
    // Persist the rename itself; not every platform can open a directory, so best effort.
    if let Ok(dir) = File::open(&parent) {
        let _ = dir.sync_all();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn leftover_temp_files(dir: &Path) -> Vec<String> {
        fs::read_dir(dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp-"))
            .collect()
    }

    #[test]
    fn writes_and_replaces_creating_missing_directories() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a/b/out.bin");
        write_atomically(&path, |w| {
            w.write_all(b"first")
                .map_err(|e| OutputError::io("x", "write", e))
        })
        .unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"first");
        write_atomically(&path, |w| {
            w.write_all(b"second")
                .map_err(|e| OutputError::io("x", "write", e))
        })
        .unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"second");
        assert!(leftover_temp_files(&dir.path().join("a/b")).is_empty());
    }

    #[test]
    fn failed_write_leaves_the_old_file_and_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.bin");
        fs::write(&path, b"precious").unwrap();
        let result = write_atomically(&path, |w| {
            w.write_all(&[0u8; 100_000])
                .map_err(|e| OutputError::io("x", "write", e))?;
            Err(OutputError::invalid("x", "forced failure halfway"))
        });
        assert!(result.is_err());
        assert_eq!(fs::read(&path).unwrap(), b"precious");
        assert!(leftover_temp_files(dir.path()).is_empty());
    }

    #[test]
    fn failed_rename_leaves_no_temporary() {
        // The target is a non-empty directory: the final rename must fail.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("occupied");
        fs::create_dir(&path).unwrap();
        fs::write(path.join("inside"), b"x").unwrap();
        let err = write_atomically(&path, |_| Ok(())).unwrap_err();
        assert!(err.to_string().contains("occupied"), "{err}");
        assert!(leftover_temp_files(dir.path()).is_empty());
        assert_eq!(fs::read(path.join("inside")).unwrap(), b"x");
    }

    #[test]
    fn unusable_parent_is_reported_with_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let blocker = dir.path().join("file");
        fs::write(&blocker, b"not a directory").unwrap();
        let err = write_atomically(&blocker.join("out.png"), |_| Ok(())).unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains("file") && message.contains("create directory"),
            "{message}"
        );
        assert!(!message.contains('\n'));
    }
}
