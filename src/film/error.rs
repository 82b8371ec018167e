//! Errors of writing and reading film files: one line naming the file and the problem.

use std::path::PathBuf;

/// Why a film could not be written or read. Every message names the file it concerns.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A file-system operation failed (`action` says which, e.g. "create directory").
    #[error("{}: cannot {action}: {source}", .path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The OpenEXR encoder or decoder failed.
    #[error("{}: OpenEXR {action} failed: {source}", .path.display())]
    Exr {
        path: PathBuf,
        action: &'static str,
        #[source]
        source: exr::error::Error,
    },
    /// The PNG encoder failed.
    #[error("{}: PNG encoding failed: {source}", .path.display())]
    Png {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    /// The film or the file's contents do not fit the request (missing layer, bad name ...).
    #[error("{}: {problem}", .path.display())]
    Invalid { path: PathBuf, problem: String },
}

impl OutputError {
    /// Shorthand for [`OutputError::Invalid`].
    pub fn invalid(path: impl Into<PathBuf>, problem: impl Into<String>) -> Self {
        OutputError::Invalid {
            path: path.into(),
            problem: problem.into(),
        }
    }

    /// Shorthand for [`OutputError::Io`].
    pub fn io(path: impl Into<PathBuf>, action: &'static str, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.into(),
            action,
            source,
        }
    }
}
