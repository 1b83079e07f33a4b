//! The one error type of the crate: every variant that comes from a file
//! names the file, and the line (text formats) and the field where known.

use std::path::PathBuf;

/// What went wrong building, reading or writing a map.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum MapError {
    /// A file could not be read or written.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// A line of a plain text segment file is malformed.
    #[error("{}:{line}: {field}: {reason}", file.display())]
    Line {
        /// The file.
        file: PathBuf,
        /// The line, 1-based.
        line: usize,
        /// The field (`x1`, `y1`, `x2`, `y2`) or `line` for the whole line.
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A TOML or YAML file does not parse or does not have the expected shape
    /// (the parser's message names the field: a missing field, a wrong type).
    #[error("{}{}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Syntax {
        /// The file.
        file: PathBuf,
        /// The line, 1-based, where the parser tells it.
        line: Option<usize>,
        /// The parser's message.
        message: String,
    },
    /// A field of a map file parses but its value is not allowed.
    #[error("{}: {field}: {reason}", file.display())]
    Field {
        /// The file.
        file: PathBuf,
        /// The field (`resolution`, `origin`, `wall[2].to`, ...).
        field: String,
        /// What is wrong with it.
        reason: String,
    },
    /// An image (the PGM of a ROS map) cannot be decoded or written, or is
    /// not 8-bit.
    #[error("{}: {reason}", file.display())]
    Image {
        /// The image file.
        file: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A map, a grid or a mapping configuration built in code is invalid.
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// What was being built (`grid geometry`, `segment 3`, ...).
        what: String,
        /// What is wrong with it.
        reason: String,
    },
}

impl MapError {
    /// An [`MapError::Invalid`].
    pub(crate) fn invalid(what: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Invalid {
            what: what.into(),
            reason: reason.into(),
        }
    }
}
