//! The library's error type: every failure names what went wrong and, for
//! input, the file it came from.

use std::path::PathBuf;

/// Result alias used across the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The operating-system error.
        #[source]
        source: std::io::Error,
    },
    /// A file was read but its content is not what the format requires.
    #[error("{path}: {message}")]
    Format {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong, e.g. "line 17: field 3 ('z') is not a number: 'abc'".
        message: String,
    },
    /// The configuration is invalid (unknown method, bad threshold, ...).
    #[error("configuration: {0}")]
    Config(String),
    /// The input is well-formed but cannot be processed (no pose for a frame,
    /// empty frame, degenerate geometry, ...).
    #[error("{0}")]
    Input(String),
}

impl Error {
    /// A format error for `path` with a message.
    pub fn format(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Format {
            path: path.into(),
            message: message.into(),
        }
    }

    /// An I/O error for `path`.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.into(),
            source,
        }
    }
}
