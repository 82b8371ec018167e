//! The files a render writes, decided and checked before any work starts.
//!
//! A render writes up to three files: the EXR (`-o`), the PNG (`--png`, default beside the
//! EXR) and the statistics (`--stats`). An interrupted render writes none of them: its
//! finished part goes to a file of its own beside the EXR, `<name>.partial.exr` (and
//! `<stats>.partial.json` for its statistics, marked incomplete), which `--resume` reads. The
//! final files replace earlier ones together, only when the render completes
//! (`film::OutputSet`), and the partial files are removed then.
//!
//! Checked up front, so that a bad path costs no render time and exit 2 writes nothing: the
//! EXR must end in `.exr` and the PNG in `.png`; no two outputs may name the same file
//! (symbolic links followed); each output's directory must exist or be creatable, and be
//! writable; an output may not be an existing directory.

use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};

use crate::cli::render_cmd::RenderArgs;
use crate::cli::CommandError;
use crate::film::atomic_file::{parent_dir, resolve_symlinks};

/// Where one render's files go.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputPlan {
    pub exr: PathBuf,
    pub png: Option<PathBuf>,
    pub stats: Option<PathBuf>,
    /// The interrupted render's EXR, read by `--resume`.
    pub partial_exr: PathBuf,
    /// The interrupted render's statistics (when `--stats` is given).
    pub partial_stats: Option<PathBuf>,
    /// The PNG is the default one beside the EXR, not named by `--png`.
    pub png_is_default: bool,
}

/// `dir/name.ext` to `dir/name.partial.ext`.
pub fn partial_path(path: &Path) -> PathBuf {
    let stem = path.file_stem().unwrap_or_default();
    let mut name = OsString::from(stem);
    name.push(".partial");
    if let Some(extension) = path.extension() {
        name.push(".");
        name.push(extension);
    }
    path.with_file_name(name)
}

fn has_extension(path: &Path, wanted: &str) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(wanted))
}

/// The file `path` finally names, for comparing outputs: links followed, made absolute, the
/// existing part of its directory canonicalised and the rest (directories a render would
/// create, where no link can hide) normalised lexically.
fn identity(path: &Path) -> PathBuf {
    use std::path::Component;
    let resolved = resolve_symlinks(path);
    let absolute = std::path::absolute(&resolved).unwrap_or(resolved);
    let components: Vec<Component> = absolute.components().collect();
    // The longest prefix that exists and canonicalises.
    for split in (0..=components.len()).rev() {
        let prefix: PathBuf = components[..split].iter().collect();
        let Ok(mut out) = fs::canonicalize(&prefix) else {
            continue;
        };
        for component in &components[split..] {
            match component {
                Component::CurDir => {}
                Component::ParentDir => {
                    out.pop();
                }
                other => out.push(other.as_os_str()),
            }
        }
        return out;
    }
    absolute
}

/// Whether `a` and `b` name one file: the same [`identity`], or, for files that exist, the
/// same device and inode (a hard link, or a path through a bind mount).
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    if identity(a) == identity(b) {
        return true;
    }
    match (fs::metadata(a), fs::metadata(b)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Checks that a file can be created at `path` (what `what` calls it in messages): its
/// nearest existing ancestor directory accepts a new file, and `path` is not a directory.
fn check_writable(path: &Path, what: &str) -> Result<(), CommandError> {
    let fail =
        |problem: String| CommandError::bad_input(format!("{}: {what}: {problem}", path.display()));
    let target = resolve_symlinks(path);
    if target.file_name().is_none() {
        return Err(fail("not a file name".into()));
    }
    if target.is_dir() {
        return Err(fail("is a directory".into()));
    }
    let mut dir = parent_dir(&target);
    loop {
        match fs::metadata(&dir) {
            Ok(meta) if meta.is_dir() => break,
            Ok(_) => {
                return Err(fail(format!(
                    "cannot create a file there: {} is not a directory",
                    dir.display()
                )))
            }
            Err(_) => match dir.parent() {
                Some(up) if !up.as_os_str().is_empty() => dir = up.to_path_buf(),
                _ => {
                    dir = PathBuf::from(".");
                    break;
                }
            },
        }
    }
    // Permission bits do not tell (root, ACLs, read-only mounts): try it.
    let probe = dir.join(format!(".conetrace-probe-{}", std::process::id()));
    match fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(_) => {
            let _ = fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(fail(format!("cannot write in {}: {e}", dir.display()))),
    }
}

impl OutputPlan {
    /// The outputs `args` ask for (defaults filled in), checked as the module doc says.
    pub fn from_args(args: &RenderArgs) -> Result<OutputPlan, CommandError> {
        if args.no_png && args.png.is_some() {
            return Err(CommandError::bad_input(
                "--png and --no-png contradict each other; give one",
            ));
        }
        let stem = args
            .scene
            .as_deref()
            .and_then(Path::file_stem)
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "default".to_string());
        let exr = args
            .output
            .clone()
            .unwrap_or_else(|| PathBuf::from("out").join(format!("{stem}.exr")));
        if !has_extension(&exr, "exr") {
            let hint = if has_extension(&exr, "png") {
                " (a PNG is written beside the EXR, or where --png says)"
            } else {
                ""
            };
            return Err(CommandError::bad_input(format!(
                "{}: -o must name an OpenEXR file ending in .exr{hint}",
                exr.display()
            )));
        }
        let png = if args.no_png {
            None
        } else {
            Some(
                args.png
                    .clone()
                    .unwrap_or_else(|| exr.with_extension("png")),
            )
        };
        if let Some(png) = &png {
            if !has_extension(png, "png") {
                return Err(CommandError::bad_input(format!(
                    "{}: --png must name a file ending in .png",
                    png.display()
                )));
            }
        }
        let plan = OutputPlan {
            partial_exr: partial_path(&exr),
            partial_stats: args.stats.as_deref().map(partial_path),
            exr,
            png,
            stats: args.stats.clone(),
            png_is_default: args.png.is_none(),
        };
        plan.check()?;
        Ok(plan)
    }

    /// Refuses outputs that would overwrite one of the render's inputs (every file the
    /// scene's loaders read: `SceneDescription::input_files`): the render would destroy what
    /// it reads.
    pub fn check_inputs<'a>(
        &self,
        inputs: impl IntoIterator<Item = &'a Path>,
    ) -> Result<(), CommandError> {
        let outputs = self.named();
        for input in inputs {
            if let Some((option, path)) = outputs.iter().find(|(_, out)| same_file(out, input)) {
                return Err(CommandError::bad_input(format!(
                    "{}: {option} would overwrite {}, an input of the render",
                    path.display(),
                    input.display()
                )));
            }
        }
        Ok(())
    }

    /// Leaves out the default PNG, which a render of part of the image or of its samples
    /// does not write (an explicit `--png` stays).
    pub fn without_default_png(&mut self) {
        if self.png_is_default {
            self.png = None;
        }
    }

    /// Every output the render may write, with the option (or default) that names it.
    fn named(&self) -> Vec<(&'static str, &Path)> {
        let mut all = vec![("-o", self.exr.as_path())];
        if let Some(png) = &self.png {
            let option = if self.png_is_default {
                "the PNG beside the EXR"
            } else {
                "--png"
            };
            all.push((option, png.as_path()));
        }
        if let Some(stats) = &self.stats {
            all.push(("--stats", stats.as_path()));
        }
        // Written by an interrupted render, and removed by a completed one (a progressive
        // render's too): either would destroy an input of the same name.
        all.push(("the partial render", self.partial_exr.as_path()));
        if let Some(partial) = &self.partial_stats {
            all.push(("the partial statistics", partial.as_path()));
        }
        all
    }

    fn check(&self) -> Result<(), CommandError> {
        let named = self.named();
        for (i, (first_option, first)) in named.iter().enumerate() {
            for (second_option, second) in &named[i + 1..] {
                if same_file(first, second) {
                    return Err(CommandError::bad_input(format!(
                        "{}: {first_option} and {second_option} name the same file ({})",
                        first.display(),
                        second.display()
                    )));
                }
            }
        }
        for (option, path) in &named {
            check_writable(path, option)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    fn plan(args: &[&str]) -> Result<OutputPlan, CommandError> {
        let mut all = vec!["conetrace", "render"];
        all.extend_from_slice(args);
        let cli = crate::cli::Cli::try_parse_from(all).unwrap();
        let crate::cli::Command::Render(args) = cli.command else {
            unreachable!("parsed a render command")
        };
        OutputPlan::from_args(&args)
    }

    #[test]
    fn partial_files_sit_beside_their_outputs() {
        assert_eq!(
            partial_path(Path::new("a/keep.exr")),
            PathBuf::from("a/keep.partial.exr")
        );
        assert_eq!(
            partial_path(Path::new("s.json")),
            PathBuf::from("s.partial.json")
        );
    }

    #[test]
    fn wrong_extensions_collisions_and_unwritable_paths_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let at = |name: &str| dir.path().join(name).display().to_string();
        let message = |args: &[&str]| plan(args).unwrap_err().message;
        assert!(message(&["-o", &at("out.png")]).contains(".exr"));
        assert!(message(&["-o", &at("out.jpg")]).contains(".exr"));
        assert!(message(&["-o", &at("a.exr"), "--png", &at("a.jpg")]).contains(".png"));
        let same = message(&[
            "-o",
            &at("a.exr"),
            "--png",
            &at("b.png"),
            "--stats",
            &at("b.png"),
        ]);
        assert!(same.contains("same file"), "{same}");
        // The same file reached through another spelling of its directory.
        let other_spelling = format!("{}/./sub/../a.png", dir.path().display());
        let same = message(&[
            "-o",
            &at("a.exr"),
            "--png",
            &other_spelling,
            "--stats",
            &at("a.png"),
        ]);
        assert!(same.contains("same file"), "{same}");
        std::fs::write(dir.path().join("blocker"), b"x").unwrap();
        let blocked = message(&["-o", &at("blocker/out.exr")]);
        assert!(blocked.contains("not a directory"), "{blocked}");
        std::fs::create_dir(dir.path().join("taken.png")).unwrap();
        assert!(message(&["-o", &at("taken.exr")]).contains("is a directory"));
        assert!(
            message(&["-o", &at("a.exr"), "--png", &at("a.png"), "--no-png"]).contains("--no-png")
        );
        // Nothing was created by any of the checks.
        let mut names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["blocker", "taken.png"]);
    }

    #[test]
    fn outputs_may_not_overwrite_inputs() {
        let dir = tempfile::tempdir().unwrap();
        let texture = dir.path().join("wood.png");
        std::fs::write(&texture, b"texture bytes").unwrap();
        let exr = dir.path().join("out.exr");
        let plan = plan(&[
            "-o",
            exr.to_str().unwrap(),
            "--png",
            texture.to_str().unwrap(),
        ])
        .unwrap();
        let message = plan.check_inputs([texture.as_path()]).unwrap_err().message;
        assert!(
            message.contains("--png") && message.contains("wood.png"),
            "{message}"
        );
        assert!(plan
            .check_inputs([dir.path().join("other.png").as_path()])
            .is_ok());
        // The same file through a hard link.
        let linked = dir.path().join("linked.png");
        std::fs::hard_link(&texture, &linked).unwrap();
        let message = plan.check_inputs([linked.as_path()]).unwrap_err().message;
        assert!(message.contains("linked.png"), "{message}");
    }

    #[test]
    fn ordinary_outputs_are_accepted() {
        let dir = tempfile::tempdir().unwrap();
        let exr = dir.path().join("new/dir/keep.EXR");
        let plan = plan(&["-o", exr.to_str().unwrap(), "--stats", "s.json"]).unwrap();
        assert_eq!(plan.png, Some(exr.with_extension("png")));
        assert_eq!(
            plan.partial_exr,
            dir.path().join("new/dir/keep.partial.EXR")
        );
        assert_eq!(plan.partial_stats, Some(PathBuf::from("s.partial.json")));
    }
}
