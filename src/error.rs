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

/// The most characters of bad input an error message quotes
/// ([`excerpt`]).
pub const EXCERPT_CHARS: usize = 80;

/// `text` as an error message quotes it: whole when short, else its first
/// [`EXCERPT_CHARS`] characters and how long it was. A message about bad
/// input must stay readable (and small) whatever the input: a 200 MB line
/// is not printed whole.
pub fn excerpt(text: &str) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(EXCERPT_CHARS) {
        None => std::borrow::Cow::Borrowed(text),
        Some((end, _)) => {
            std::borrow::Cow::Owned(format!("{}... ({} bytes in all)", &text[..end], text.len()))
        }
    }
}

/// [`excerpt`] of bytes that may not be UTF-8 (invalid sequences shown as
/// U+FFFD); only the first bytes are looked at.
pub fn excerpt_bytes(bytes: &[u8]) -> String {
    let head = &bytes[..bytes.len().min(EXCERPT_CHARS * 4)];
    let text = String::from_utf8_lossy(head);
    match text.char_indices().nth(EXCERPT_CHARS) {
        None if head.len() == bytes.len() => text.into_owned(),
        None => format!("{text}... ({} bytes in all)", bytes.len()),
        Some((end, _)) => format!("{}... ({} bytes in all)", &text[..end], bytes.len()),
    }
}
