//! Typed errors of the log readers.
//!
//! Every error names the file; errors in the content also name the line
//! (1-based, counting header lines) and, where one field is at fault, the
//! field's name and column (1-based), so a message reads like
//! `Robot3_Measurement.dat.xz:118: field "range" (column 3): "3.2x1" is not a number`.

use std::io;
use std::path::PathBuf;

/// What is wrong with one field of a record. The text of a field is quoted
/// by [`excerpt`]: at most [`EXCERPT_BYTES`] of it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FieldProblem {
    /// The line ends before this field.
    #[error("missing")]
    Missing,
    /// The text does not parse as a number.
    #[error("{0:?} is not a number")]
    NotANumber(String),
    /// The text does not parse as a non-negative integer.
    #[error("{0:?} is not a non-negative integer")]
    NotAnInteger(String),
    /// The text parses as NaN or an infinity.
    #[error("{0:?} is not finite")]
    NotFinite(String),
    /// The value is out of the field's valid range.
    #[error("{value} is out of range: {expected}")]
    OutOfRange {
        /// The value as read.
        value: String,
        /// What the field allows.
        expected: &'static str,
    },
    /// A scan's ranges do not number its beam sensor's beams (the column
    /// is that of the first range missing or too many).
    #[error("{found} ranges, beam sensor {sensor} has {expected} beams")]
    BeamCount {
        /// Ranges on the line.
        found: usize,
        /// Beams of the sensor.
        expected: u32,
        /// The sensor's id.
        sensor: u32,
    },
}

/// What is wrong with a record (a line) as a whole, or with its relation to
/// the lines before it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RecordProblem {
    /// The line has more fields than the format has columns.
    #[error("{found} fields, the format has {expected}")]
    TooManyFields {
        /// Columns of the format.
        expected: usize,
        /// Fields found on the line.
        found: usize,
    },
    /// The time stamp is earlier than the previous record's.
    #[error("time {time} s is earlier than the previous record's {previous} s")]
    TimeGoesBack {
        /// This record's time, s.
        time: f64,
        /// The previous record's time, s.
        previous: f64,
    },
    /// A key (subject or barcode) that must be unique appears again.
    #[error("{what} {value} already appeared on line {first_line}")]
    Duplicate {
        /// Which key ("subject", "barcode").
        what: &'static str,
        /// The repeated value.
        value: u32,
        /// The line of its first appearance.
        first_line: usize,
    },
    /// A record that may appear at most once (a `start` or `sensor` line, a
    /// `noise` record of one name) appears again.
    #[error("{what} already appeared on line {first_line}")]
    DuplicateRecord {
        /// Which record ("start line", "sensor line", "noise q_v", ...).
        what: &'static str,
        /// The line of its first appearance.
        first_line: usize,
    },
    /// Records that must agree with each other do not (truth lines with and
    /// without a heading in one file; a beacon at two positions).
    #[error("{what} line {first_line}")]
    Disagrees {
        /// What disagrees, ending in words that lead to the line, e.g.
        /// "truth lines give a heading or none, all alike: this one differs from".
        what: &'static str,
        /// The earlier line it disagrees with.
        first_line: usize,
    },
}

/// Bytes of a field's text quoted in an error at most: a field of
/// megabytes is quoted by its start and its length, not echoed whole.
pub const EXCERPT_BYTES: usize = 32;

/// `text` as an error quotes it: whole if at most [`EXCERPT_BYTES`] long,
/// else its first [`EXCERPT_BYTES`] bytes (cut at a character boundary),
/// an ellipsis and the length in bytes.
#[must_use]
pub fn excerpt(text: &str) -> String {
    if text.len() <= EXCERPT_BYTES {
        return text.to_owned();
    }
    let mut end = EXCERPT_BYTES;
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    format!("{}... ({} bytes)", &text[..end], text.len())
}

/// Errors of the log readers.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be read.
    #[error("{}: cannot read", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: io::Error,
    },
    /// The path exists but is not a regular file (a directory, a FIFO, a
    /// socket, a device): it is not read.
    #[error("{}: {what}, not a log file", path.display())]
    NotAFile {
        /// The path.
        path: PathBuf,
        /// What it is: "is a directory" or "is not a regular file (a FIFO)".
        what: &'static str,
    },
    /// Neither the file nor its `.xz`-compressed form exists.
    #[error("{}: not found (nor {}.xz)", path.display(), path.display())]
    NotFound {
        /// The file looked for (without `.xz`).
        path: PathBuf,
    },
    /// The file is not a valid xz or gzip stream.
    #[error("{}: {format} decompression failed", path.display())]
    Decompress {
        /// The file.
        path: PathBuf,
        /// The compression: "xz" or "gzip".
        format: &'static str,
        /// The decoder's error (corrupt data, failed integrity check,
        /// truncated stream).
        #[source]
        source: io::Error,
    },
    /// A line is longer than [`MAX_LINE`](crate::MAX_LINE) bytes: no
    /// record of a log is, and reading on would hold it all in memory.
    #[error(
        "{}:{line}: line longer than {max} bytes (no record of a log is; a damaged or \
         hostile file?)",
        path.display()
    )]
    LineTooLong {
        /// The file.
        path: PathBuf,
        /// The line (1-based).
        line: usize,
        /// The bound, bytes.
        max: usize,
    },
    /// The (decompressed) content is not UTF-8 text.
    #[error("{}:{line}: not valid UTF-8 text", path.display())]
    NotUtf8 {
        /// The file.
        path: PathBuf,
        /// Line of the first invalid byte (1-based).
        line: usize,
    },
    /// A field of a record is malformed.
    #[error("{}:{line}: field {field:?} (column {column}): {problem}", path.display())]
    Field {
        /// The file.
        path: PathBuf,
        /// Line (1-based, header lines counted).
        line: usize,
        /// Column (1-based, whitespace-separated fields).
        column: usize,
        /// The field's name in the format ("time", "range", ...).
        field: &'static str,
        /// What is wrong.
        problem: FieldProblem,
    },
    /// A record is malformed as a whole or inconsistent with earlier ones.
    #[error("{}:{line}: {problem}", path.display())]
    Record {
        /// The file.
        path: PathBuf,
        /// Line (1-based, header lines counted).
        line: usize,
        /// What is wrong.
        problem: RecordProblem,
    },
    /// A record the file must hold is absent (e.g. a dataset's header
    /// line, or any scan in a laser log).
    #[error("{}: no {what}", path.display())]
    Missing {
        /// The file.
        path: PathBuf,
        /// What is missing, e.g. "FLASER line".
        what: &'static str,
    },
    /// A robot number outside the dataset's robots.
    #[error("no robot {robot}: the dataset has robots {first}-{last}")]
    NoSuchRobot {
        /// The number asked for.
        robot: u32,
        /// The first robot's number.
        first: u32,
        /// The last robot's number.
        last: u32,
    },
}

/// `Result` with this crate's [`Error`].
pub type Result<T> = core::result::Result<T, Error>;
