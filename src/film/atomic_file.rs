//! Writing output files so that readers see either the old contents or the complete new ones,
//! and so that the files of one run are replaced together.
//!
//! Each file's data goes to a hidden temporary file in the target's directory
//! (`.<name>.tmp-<pid>-<n>`), is flushed and fsynced, and only then renamed over the target
//! (a rename within one directory is atomic on POSIX file systems). An [`OutputSet`] stages
//! several files (a render's EXR, PNG and statistics) and renames them all only when every
//! one was written: a failure leaves none of them behind and every earlier file untouched
//! (a rename that fails midway puts back the files already replaced, from hard-link backups).
//!
//! Committing holds an exclusive `flock` on each target directory while it renames, so two
//! processes writing the same outputs replace them one set after the other: the EXR, PNG and
//! statistics on disk always come from the same run.
//!
//! A target that is a symbolic link stays one: the link is followed and the file it points
//! to is replaced. An existing target keeps its permission bits.
//!
//! Error messages name the path the user gave, never the hidden temporary file.

use std::fs::{self, File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::error::OutputError;

/// Distinguishes temporary files of concurrent writes from one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// One file written to its temporary name, waiting for [`OutputSet::commit`].
struct StagedFile {
    /// The path as the user gave it (for messages).
    user_path: PathBuf,
    /// Where the data finally goes: `user_path` with symbolic links followed.
    target: PathBuf,
    temp: PathBuf,
}

/// Files staged for replacement together. Dropping a set that was not committed removes its
/// temporary files and leaves every target untouched.
#[derive(Default)]
pub struct OutputSet {
    staged: Vec<StagedFile>,
    /// Files removed when the set commits.
    superseded: Vec<PathBuf>,
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        for file in &self.staged {
            let _ = fs::remove_file(&file.temp);
        }
    }
}

/// The file `path` finally names: symbolic links are followed (also dangling ones, whose
/// target is created), at most 40 levels deep as the kernel allows.
pub fn resolve_symlinks(path: &Path) -> PathBuf {
    let mut current = path.to_path_buf();
    for _ in 0..40 {
        match fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => match fs::read_link(&current) {
                Ok(link) => {
                    current = match current.parent() {
                        Some(parent) if link.is_relative() => parent.join(link),
                        _ => link,
                    };
                }
                Err(_) => return current,
            },
            _ => return current,
        }
    }
    current
}

/// The directory a file at `path` lives in (`.` for a bare file name).
pub fn parent_dir(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

impl OutputSet {
    /// Writes one file of the set to a temporary file beside its target; `write` fills it.
    /// The target's directory is created if missing. On failure nothing of this file
    /// remains (files staged earlier stay staged until the set is dropped or committed).
    pub fn stage<F>(&mut self, path: &Path, write: F) -> Result<(), OutputError>
    where
        F: FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
    {
        let target = resolve_symlinks(path);
        let file_name = target
            .file_name()
            .ok_or_else(|| OutputError::invalid(path, "output path has no file name"))?;
        let parent = parent_dir(&target);
        fs::create_dir_all(&parent).map_err(|e| OutputError::io(&parent, "create directory", e))?;

        let mut temp_name = std::ffi::OsString::from(".");
        temp_name.push(file_name);
        temp_name.push(format!(
            ".tmp-{}-{}",
            std::process::id(),
            TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        let temp = parent.join(temp_name);
        // Readable too: writers may patch what they wrote (see `exr_header_order`).
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(&temp)
            .map_err(|e| OutputError::io(path, "create file", e))?;
        // From here on the set owns the temporary file and removes it on failure.
        self.staged.push(StagedFile {
            user_path: path.to_path_buf(),
            target: target.clone(),
            temp: temp.clone(),
        });
        let result = (|| {
            let mut writer = BufWriter::new(file);
            write(&mut writer)?;
            writer
                .flush()
                .map_err(|e| OutputError::io(path, "write", e))?;
            let file = writer
                .into_inner()
                .map_err(|e| OutputError::io(path, "write", e.into_error()))?;
            // An existing file keeps its permissions.
            if let Ok(meta) = fs::metadata(&target) {
                if meta.is_file() {
                    file.set_permissions(meta.permissions())
                        .map_err(|e| OutputError::io(path, "set permissions of", e))?;
                }
            }
            file.sync_all()
                .map_err(|e| OutputError::io(path, "sync", e))
        })();
        if result.is_err() {
            if let Some(file) = self.staged.pop() {
                let _ = fs::remove_file(&file.temp);
            }
        }
        result
    }

    /// Removes `path` (if it exists) when the set commits successfully, under the same lock
    /// as the replacements: e.g. a partial render the committed outputs supersede.
    pub fn remove_on_commit(&mut self, path: &Path) {
        self.superseded.push(path.to_path_buf());
    }

    /// Replaces every target with its staged file, under an exclusive lock of each target
    /// directory so that concurrent sets do not interleave. Each existing target is first
    /// hard-linked to a backup name; if a rename fails, the targets already replaced get
    /// their old contents back (or are removed if they did not exist), so the set is
    /// replaced whole or not at all, and the error names the user's path.
    pub fn commit(mut self) -> Result<(), OutputError> {
        // One lock per directory however its paths are spelt (`.` and its absolute path are
        // one directory): flock through a second handle would wait for the first forever.
        let mut dirs: Vec<PathBuf> = self
            .staged
            .iter()
            .map(|f| parent_dir(&f.target))
            .chain(self.superseded.iter().map(|p| parent_dir(p)))
            .map(|dir| fs::canonicalize(&dir).unwrap_or(dir))
            .collect();
        dirs.sort();
        dirs.dedup();
        // Locks are taken in sorted order, so two sets never wait for each other in a cycle.
        // A directory that cannot be opened or locked (an unusual file system) is renamed
        // into without a lock: each file is still replaced atomically.
        let locks: Vec<File> = dirs
            .iter()
            .filter_map(|dir| {
                let handle = File::open(dir).ok()?;
                handle.lock().ok()?;
                Some(handle)
            })
            .collect();
        let staged = std::mem::take(&mut self.staged);
        // Backups of the targets that exist (hard links: no data is copied). A file system
        // without hard links gets no backup, and a failed rename then cannot be undone.
        let backups: Vec<Option<PathBuf>> = staged
            .iter()
            .map(|file| {
                let backup = PathBuf::from(format!("{}.bak", file.temp.display()));
                fs::hard_link(&file.target, &backup).ok().map(|_| backup)
            })
            .collect();
        let mut result = Ok(());
        for (index, file) in staged.iter().enumerate() {
            if let Err(e) = fs::rename(&file.temp, &file.target) {
                result = Err(OutputError::io(&file.user_path, "replace file", e));
                for rest in &staged[index..] {
                    let _ = fs::remove_file(&rest.temp);
                }
                // Undo the replacements already made.
                for (done, backup) in staged[..index].iter().zip(&backups) {
                    match backup {
                        Some(backup) => {
                            let _ = fs::rename(backup, &done.target);
                        }
                        None => {
                            let _ = fs::remove_file(&done.target);
                        }
                    }
                }
                break;
            }
        }
        for backup in backups.iter().flatten() {
            let _ = fs::remove_file(backup);
        }
        if result.is_ok() {
            for path in &self.superseded {
                let _ = fs::remove_file(path);
            }
        }
        // Persist the renames; not every platform can sync a directory, so best effort.
        for dir in &locks {
            let _ = dir.sync_all();
        }
        drop(locks);
        result
    }
}

/// Writes `path` atomically: `write` fills a buffered temporary file, which then replaces
/// `path`. The parent directory is created if missing. If `write` or any file operation
/// fails, the error is returned, the temporary file removed and `path` left untouched.
pub fn write_atomically<F>(path: &Path, write: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), OutputError>,
{
    let mut set = OutputSet::default();
    set.stage(path, write)?;
    set.commit()
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

    fn bytes(data: &'static [u8]) -> impl FnOnce(&mut BufWriter<File>) -> Result<(), OutputError> {
        move |w| {
            w.write_all(data)
                .map_err(|e| OutputError::io("x", "write", e))
        }
    }

    #[test]
    fn one_directory_spelt_two_ways_is_locked_once() {
        let dir = tempfile::tempdir().unwrap();
        fs::create_dir(dir.path().join("sub")).unwrap();
        let a = dir.path().join("a.bin");
        let b = dir.path().join("sub/../b.bin");
        let (sender, receiver) = std::sync::mpsc::channel();
        // On a thread: a commit that locks the directory twice never returns.
        std::thread::spawn(move || {
            let mut set = OutputSet::default();
            let staged = set
                .stage(&a, bytes(b"a"))
                .and_then(|_| set.stage(&b, bytes(b"b")));
            let _ = sender.send(staged.and_then(|_| set.commit()));
        });
        let committed = receiver
            .recv_timeout(std::time::Duration::from_secs(20))
            .expect("the commit returns");
        assert!(committed.is_ok(), "{committed:?}");
        assert_eq!(fs::read(dir.path().join("b.bin")).unwrap(), b"b");
    }

    #[test]
    fn writes_and_replaces_creating_missing_directories() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a/b/out.bin");
        write_atomically(&path, bytes(b"first")).unwrap();
        assert_eq!(fs::read(&path).unwrap(), b"first");
        write_atomically(&path, bytes(b"second")).unwrap();
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
    fn failed_rename_leaves_no_temporary_and_names_the_users_path() {
        // The target is a non-empty directory: the final rename must fail.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("occupied");
        fs::create_dir(&path).unwrap();
        fs::write(path.join("inside"), b"x").unwrap();
        let err = write_atomically(&path, |_| Ok(())).unwrap_err();
        assert!(err.to_string().contains("occupied"), "{err}");
        assert!(!err.to_string().contains(".tmp-"), "{err}");
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

    #[test]
    fn a_failing_member_leaves_every_file_of_the_set_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.exr"), dir.path().join("a.png"));
        fs::write(&a, b"old a").unwrap();
        fs::write(&b, b"old b").unwrap();
        let mut set = OutputSet::default();
        set.stage(&a, bytes(b"new a")).unwrap();
        let failed = set.stage(&b, |_| Err(OutputError::invalid(&b, "encoder failed")));
        assert!(failed.is_err());
        drop(set);
        assert_eq!(fs::read(&a).unwrap(), b"old a");
        assert_eq!(fs::read(&b).unwrap(), b"old b");
        assert!(leftover_temp_files(dir.path()).is_empty());
    }

    #[test]
    fn a_committed_set_replaces_all_its_files() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.exr"), dir.path().join("sub/a.png"));
        fs::write(&a, b"old a").unwrap();
        let mut set = OutputSet::default();
        set.stage(&a, bytes(b"new a")).unwrap();
        set.stage(&b, bytes(b"new b")).unwrap();
        // Nothing is visible before the commit.
        assert_eq!(fs::read(&a).unwrap(), b"old a");
        assert!(!b.exists());
        set.commit().unwrap();
        assert_eq!(fs::read(&a).unwrap(), b"new a");
        assert_eq!(fs::read(&b).unwrap(), b"new b");
    }

    #[test]
    fn a_failed_rename_restores_the_files_already_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.png"));
        fs::write(&a, b"old a").unwrap();
        let mut set = OutputSet::default();
        set.stage(&a, bytes(b"new a")).unwrap();
        set.stage(&b, bytes(b"new b")).unwrap();
        // The second target becomes a non-empty directory after staging: its rename fails.
        fs::create_dir(&b).unwrap();
        fs::write(b.join("inside"), b"x").unwrap();
        let superseded = dir.path().join("a.partial.exr");
        fs::write(&superseded, b"partial").unwrap();
        set.remove_on_commit(&superseded);
        assert!(set.commit().is_err());
        assert_eq!(fs::read(&a).unwrap(), b"old a");
        assert!(
            superseded.exists(),
            "a failed commit removed the partial file"
        );
        let mut names: Vec<String> = fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["a.exr", "a.partial.exr", "b.png"]);
    }

    #[test]
    fn a_symlinked_output_stays_a_link_and_its_target_is_replaced() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real/out.exr");
        fs::create_dir_all(real.parent().unwrap()).unwrap();
        fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.exr");
        std::os::unix::fs::symlink("real/out.exr", &link).unwrap();
        write_atomically(&link, bytes(b"new")).unwrap();
        assert!(fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(fs::read(&real).unwrap(), b"new");
    }

    #[test]
    fn an_existing_file_keeps_its_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("shared.exr");
        fs::write(&path, b"old").unwrap();
        fs::set_permissions(&path, fs::Permissions::from_mode(0o640)).unwrap();
        write_atomically(&path, bytes(b"new")).unwrap();
        let mode = fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o640);
    }
}
