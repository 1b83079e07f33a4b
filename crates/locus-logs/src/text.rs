//! Reading whitespace-separated text logs: plain or xz-compressed files,
//! comment and blank lines skipped, fields parsed with errors that name file,
//! line, column and field.

use core::str::{Split, SplitAsciiWhitespace};
use std::fs;
use std::path::{Path, PathBuf};

use crate::error::{Error, FieldProblem, RecordProblem, Result, excerpt};
use crate::xz::{self, XZ_MAGIC};

/// `dir/name` if it exists, else `dir/name.xz` if that exists.
///
/// # Errors
/// As [`existing`].
pub(crate) fn resolve(dir: &Path, name: &str) -> Result<PathBuf> {
    existing(&dir.join(name))
}

/// `path` if it exists, else `path.xz` if that exists; either must be a
/// regular file (symbolic links followed).
///
/// # Errors
/// [`Error::NotFound`] if neither exists; [`Error::NotAFile`] for a
/// directory, a FIFO, a socket or a device (a FIFO is never opened, so a
/// reader never waits on it); [`Error::Io`] with the system's reason for
/// a path that cannot be examined (a loop of symbolic links, no
/// permission).
pub(crate) fn existing(path: &Path) -> Result<PathBuf> {
    if regular_file(path)? {
        return Ok(path.to_path_buf());
    }
    let mut xz = path.as_os_str().to_owned();
    xz.push(".xz");
    let xz = PathBuf::from(xz);
    if regular_file(&xz)? {
        return Ok(xz);
    }
    Err(Error::NotFound {
        path: path.to_path_buf(),
    })
}

/// Whether `path` is a regular file (`false` if nothing is there).
fn regular_file(path: &Path) -> Result<bool> {
    match fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(true),
        Ok(m) => Err(Error::NotAFile {
            path: path.to_path_buf(),
            what: if m.is_dir() {
                "is a directory"
            } else {
                special_kind(&m.file_type())
            },
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(source) => Err(Error::Io {
            path: path.to_path_buf(),
            source,
        }),
    }
}

/// What a special file is, as [`Error::NotAFile`] says it.
#[cfg(unix)]
fn special_kind(t: &fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt as _;
    if t.is_fifo() {
        "is not a regular file (a FIFO)"
    } else if t.is_socket() {
        "is not a regular file (a socket)"
    } else if t.is_block_device() || t.is_char_device() {
        "is not a regular file (a device)"
    } else {
        "is not a regular file"
    }
}

#[cfg(not(unix))]
fn special_kind(_: &fs::FileType) -> &'static str {
    "is not a regular file"
}

/// The text of a file, decompressed if it is an xz stream (by its `.xz`
/// extension or its magic bytes).
pub(crate) fn read_text(path: &Path) -> Result<String> {
    let bytes = fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let is_xz = path.extension().is_some_and(|e| e == "xz") || bytes.starts_with(&XZ_MAGIC);
    let bytes = if is_xz {
        xz::decompress(&bytes).map_err(|source| Error::Decompress {
            path: path.to_path_buf(),
            source,
        })?
    } else {
        bytes
    };
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        Error::NotUtf8 {
            path: path.to_path_buf(),
            line: 1 + valid.iter().filter(|b| **b == b'\n').count(),
        }
    })
}

/// The data lines of a text: `(line number, fields)`, skipping blank lines
/// and lines whose first non-blank character is `#`. Fields are separated
/// by ASCII whitespace (spaces and tabs): the ASCII-only split is what
/// MRCLAM's files use, and takes about a third less time to parse them than
/// a Unicode-aware one.
pub(crate) fn records<'a>(text: &'a str, path: &'a Path) -> impl Iterator<Item = Fields<'a>> + 'a {
    text.lines().enumerate().filter_map(move |(i, line)| {
        let trimmed = line.trim_ascii_start();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            None
        } else {
            Some(Fields {
                path,
                line: i + 1,
                column: 0,
                it: Tokens::Whitespace(trimmed.split_ascii_whitespace()),
            })
        }
    })
}

/// The data lines of a comma-separated text: `(line number, fields)`,
/// skipping blank lines and lines whose first non-blank character is `#`.
/// Fields are trimmed of surrounding blanks; an empty field counts as a
/// field (and fails to parse as a number).
pub(crate) fn csv_records<'a>(
    text: &'a str,
    path: &'a Path,
) -> impl Iterator<Item = Fields<'a>> + 'a {
    text.lines().enumerate().filter_map(move |(i, line)| {
        let trimmed = line.trim();
        if trimmed.is_empty() || trimmed.starts_with('#') {
            None
        } else {
            Some(Fields {
                path,
                line: i + 1,
                column: 0,
                it: Tokens::Comma(trimmed.split(',')),
            })
        }
    })
}

/// The tokens of one line: whitespace- or comma-separated.
enum Tokens<'a> {
    Whitespace(SplitAsciiWhitespace<'a>),
    Comma(Split<'a, char>),
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a str;

    fn next(&mut self) -> Option<&'a str> {
        match self {
            Tokens::Whitespace(it) => it.next(),
            Tokens::Comma(it) => it.next().map(str::trim),
        }
    }
}

/// The fields of one data line, read left to right.
pub(crate) struct Fields<'a> {
    path: &'a Path,
    /// Line number, 1-based.
    pub(crate) line: usize,
    column: usize,
    it: Tokens<'a>,
}

impl<'a> Fields<'a> {
    /// The next field as text.
    pub(crate) fn next_text(&mut self, field: &'static str) -> Result<&'a str> {
        self.column += 1;
        self.it
            .next()
            .ok_or_else(|| self.field_error(field, FieldProblem::Missing))
    }

    /// An error about the field just read (or missing).
    pub(crate) fn field_error(&self, field: &'static str, problem: FieldProblem) -> Error {
        Error::Field {
            path: self.path.to_path_buf(),
            line: self.line,
            column: self.column,
            field,
            problem,
        }
    }

    /// An error about the record as a whole.
    pub(crate) fn record_error(&self, problem: RecordProblem) -> Error {
        Error::Record {
            path: self.path.to_path_buf(),
            line: self.line,
            problem,
        }
    }

    /// The next field as a finite number.
    pub(crate) fn f64(&mut self, field: &'static str) -> Result<f64> {
        let text = self.next_text(field)?;
        self.number(field, text)
    }

    /// `text` (the field just read) as a finite number.
    fn number(&self, field: &'static str, text: &str) -> Result<f64> {
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(self.field_error(field, FieldProblem::NotFinite(excerpt(text)))),
            Err(_) => Err(self.field_error(field, FieldProblem::NotANumber(excerpt(text)))),
        }
    }

    /// The next field as a finite number, or `None` if the line ends
    /// before it (an optional last field).
    pub(crate) fn optional_f64(&mut self, field: &'static str) -> Result<Option<f64>> {
        self.column += 1;
        match self.it.next() {
            Some(text) => self.number(field, text).map(Some),
            None => Ok(None),
        }
    }

    /// The next field as a finite number that is `>= 0`.
    pub(crate) fn non_negative(&mut self, field: &'static str) -> Result<f64> {
        self.bounded(field, |v| v >= 0.0, ">= 0")
    }

    /// The next field as a finite number that is `> 0`.
    pub(crate) fn positive(&mut self, field: &'static str) -> Result<f64> {
        self.bounded(field, |v| v > 0.0, "> 0")
    }

    /// The next field as a finite number for which `ok` holds; else an
    /// out-of-range error quoting `expected`.
    fn bounded(
        &mut self,
        field: &'static str,
        ok: impl Fn(f64) -> bool,
        expected: &'static str,
    ) -> Result<f64> {
        let v = self.f64(field)?;
        if ok(v) {
            Ok(v)
        } else {
            Err(self.field_error(
                field,
                FieldProblem::OutOfRange {
                    value: v.to_string(),
                    expected,
                },
            ))
        }
    }

    /// The next field as a non-negative integer.
    pub(crate) fn u32(&mut self, field: &'static str) -> Result<u32> {
        let text = self.next_text(field)?;
        text.parse::<u32>()
            .map_err(|_| self.field_error(field, FieldProblem::NotAnInteger(excerpt(text))))
    }

    /// Checks that no field is left (the format has `columns` columns).
    pub(crate) fn end(mut self, columns: usize) -> Result<()> {
        let extra = self.it.by_ref().count();
        if extra == 0 {
            Ok(())
        } else {
            Err(self.record_error(RecordProblem::TooManyFields {
                expected: columns,
                found: columns + extra,
            }))
        }
    }
}

/// Tracks that time stamps never decrease (repeats are allowed).
pub(crate) struct TimeOrder {
    previous: f64,
}

impl TimeOrder {
    pub(crate) fn new() -> Self {
        Self {
            previous: f64::NEG_INFINITY,
        }
    }

    pub(crate) fn check(&mut self, fields: &Fields<'_>, time: f64) -> Result<()> {
        if time < self.previous {
            return Err(fields.record_error(RecordProblem::TimeGoesBack {
                time,
                previous: self.previous,
            }));
        }
        self.previous = time;
        Ok(())
    }
}
