//! The one error type every scene loader returns.
//!
//! Each message is a single line that starts with the file it concerns (with line and
//! column when the problem sits in a TOML scene) and then says what is wrong, so the
//! command line can print it as is.

use std::fmt;

/// Why a scene, mesh or texture reference could not be loaded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read (missing, unreadable, a directory).
    #[error("{file}: cannot read: {reason}")]
    Unreadable { file: String, reason: String },
    /// The file's extension names no format this loader knows.
    #[error("{file}: unknown scene format '{extension}' (known: toml, obj, gltf, glb)")]
    UnknownFormat { file: String, extension: String },
    /// A problem at a known place in a TOML scene (syntax, unknown key or name, bad value).
    #[error("{file}:{line}:{column}: {message}")]
    AtLocation {
        file: String,
        line: usize,
        column: usize,
        message: String,
    },
    /// A problem in a file as a whole (OBJ, glTF, or a value checked after parsing).
    #[error("{file}: {message}")]
    Invalid { file: String, message: String },
}

impl SceneError {
    /// A whole-file problem; newlines in `message` are folded so the message stays one line.
    pub fn invalid(file: impl fmt::Display, message: impl fmt::Display) -> Self {
        SceneError::Invalid {
            file: file.to_string(),
            message: one_line(&message.to_string()),
        }
    }

    /// A file that could not be read.
    pub fn unreadable(file: impl fmt::Display, reason: impl fmt::Display) -> Self {
        SceneError::Unreadable {
            file: file.to_string(),
            reason: one_line(&reason.to_string()),
        }
    }

    /// A problem at byte `offset` of `text`, reported as 1-based line and column.
    pub fn at_offset(
        file: impl fmt::Display,
        text: &str,
        offset: usize,
        message: impl fmt::Display,
    ) -> Self {
        let (line, column) = line_column(text, offset);
        SceneError::AtLocation {
            file: file.to_string(),
            line,
            column,
            message: one_line(&message.to_string()),
        }
    }
}

/// 1-based line and column (in characters) of byte `offset` in `text`.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    (line, column)
}

/// Joins the lines of a multi-line message with "; " and trims it (also for every error the
/// command line prints, `cli::run`).
pub fn one_line(message: &str) -> String {
    message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_and_column_are_one_based() {
        let text = "a = 1\nbb = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        assert_eq!(line_column(text, 9), (2, 4));
    }

    #[test]
    fn messages_are_one_line_and_name_the_file() {
        let e = SceneError::invalid("x.obj", "first\n  second\n");
        assert_eq!(e.to_string(), "x.obj: first; second");
        let e = SceneError::at_offset("s.toml", "a\nbc", 3, "bad");
        assert_eq!(e.to_string(), "s.toml:2:2: bad");
    }
}
