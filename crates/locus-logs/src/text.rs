//! Reading whitespace-separated text logs: plain or xz-compressed files,
//! comment and blank lines skipped, fields parsed with errors that name file,
//! line, column and field.

use core::str::{Split, SplitAsciiWhitespace};
use std::fs;
use std::io::Read;
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

/// The magic bytes that start a gzip stream.
const GZIP_MAGIC: [u8; 2] = [0x1f, 0x8b];

/// The text of a file, decompressed if it is an xz stream (by its `.xz`
/// extension or its magic bytes) or a gzip stream (by its `.gz` extension
/// or its magic bytes), read in chunks with every line bounded
/// by [`MAX_LINE`](crate::MAX_LINE): a file holding one huge line is
/// refused as soon as the line passes the bound, before it fills the
/// memory.
pub(crate) fn read_text(path: &Path) -> Result<String> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = fs::File::open(path).map_err(io)?;
    let mut head = [0u8; XZ_MAGIC.len()];
    let n = read_up_to(&mut file, &mut head).map_err(io)?;
    let is_xz = path.extension().is_some_and(|e| e == "xz") || head[..n] == XZ_MAGIC;
    let is_gz = path.extension().is_some_and(|e| e == "gz") || head[..n].starts_with(&GZIP_MAGIC);
    let size = file.metadata().map_or(0, |m| m.len());
    let head = std::io::Cursor::new(head[..n].to_vec());
    let decompress = |format, source| Error::Decompress {
        path: path.to_path_buf(),
        format,
        source,
    };
    let bytes = if is_gz && !is_xz {
        let input = std::io::BufReader::new(head.chain(file));
        let mut decoder = flate2::bufread::MultiGzDecoder::new(input);
        bounded(&mut decoder, path, size.saturating_mul(8)).map_err(|e| match e {
            Bounded::Line(e) => e,
            Bounded::Io(source) => decompress("gzip", source),
        })?
    } else if is_xz {
        let input = std::io::BufReader::new(head.chain(file));
        let mut decoder = xz::decoder(input);
        bounded(&mut decoder, path, size.saturating_mul(8)).map_err(|e| match e {
            Bounded::Line(e) => e,
            Bounded::Io(source) => decompress("xz", source),
        })?
    } else {
        bounded(&mut head.chain(file), path, size).map_err(|e| match e {
            Bounded::Line(e) => e,
            Bounded::Io(source) => io(source),
        })?
    };
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        Error::NotUtf8 {
            path: path.to_path_buf(),
            line: 1 + valid.iter().filter(|b| **b == b'\n').count(),
        }
    })
}

/// Reads into `buf` until it is full or the input ends; the bytes read.
fn read_up_to(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// Why [`bounded`] stopped.
enum Bounded {
    /// A line passed [`MAX_LINE`](crate::MAX_LINE).
    Line(Error),
    /// The input failed.
    Io(std::io::Error),
}

/// All of `r`, in chunks of 1 MiB, checking after each that the line being
/// read has not passed [`MAX_LINE`](crate::MAX_LINE); `hint` sizes the
/// first allocation (bytes, capped at 1 GiB).
fn bounded(r: &mut impl Read, path: &Path, hint: u64) -> core::result::Result<Vec<u8>, Bounded> {
    const CHUNK: usize = 1 << 20;
    let cap = usize::try_from(hint.min(1 << 30)).unwrap_or(CHUNK);
    let mut out: Vec<u8> = Vec::with_capacity(cap.max(CHUNK));
    // Bytes of the current line so far, and the complete lines before it.
    let (mut current, mut lines) = (0usize, 0usize);
    loop {
        let start = out.len();
        out.resize(start + CHUNK, 0);
        let n = match read_up_to(r, &mut out[start..]) {
            Ok(n) => n,
            Err(e) => return Err(Bounded::Io(e)),
        };
        out.truncate(start + n);
        let too_long = |line| {
            Bounded::Line(Error::LineTooLong {
                path: path.to_path_buf(),
                line,
                max: crate::MAX_LINE,
            })
        };
        // The chunk's first piece continues the current line; each newline
        // ends one; the piece after the last newline starts the next.
        let mut pieces = out[start..].split(|b| *b == b'\n').peekable();
        let mut first = true;
        while let Some(piece) = pieces.next() {
            let length = if first {
                current + piece.len()
            } else {
                piece.len()
            };
            first = false;
            if length > crate::MAX_LINE {
                return Err(too_long(lines + 1));
            }
            if pieces.peek().is_some() {
                lines += 1;
            } else {
                current = length;
            }
        }
        if n < CHUNK {
            return Ok(out);
        }
    }
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
    pub(crate) fn bounded(
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

    /// The next field as text, or `None` if the line ends before it (the
    /// column moves on either way).
    pub(crate) fn optional_text(&mut self) -> Option<&'a str> {
        self.column += 1;
        self.it.next()
    }

    /// The number of fields left on the line (consumed).
    pub(crate) fn count_rest(&mut self) -> usize {
        self.it.by_ref().count()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MAX_LINE;

    fn read(name: &str, content: &[u8]) -> Result<String> {
        let dir = std::env::temp_dir().join(format!("locus-logs-text-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        fs::write(&path, content).unwrap();
        let r = read_text(&path);
        let _ = fs::remove_file(&path);
        r
    }

    fn xz(data: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        liblzma::read::XzEncoder::new(data, 1)
            .read_to_end(&mut out)
            .unwrap();
        out
    }

    #[test]
    fn a_line_of_the_bound_reads_and_one_byte_more_is_refused_with_its_line() {
        // Lines straddle the 1 MiB chunks: the bound holds across them.
        let mut ok = b"a\nbb\n".to_vec();
        ok.extend(core::iter::repeat_n(b'#', MAX_LINE));
        ok.extend(b"\nc\n");
        assert_eq!(read("ok.csv", &ok).unwrap().len(), ok.len());
        assert_eq!(read("ok.csv.xz", &xz(&ok)).unwrap().len(), ok.len());
        let mut long = b"a\nbb\n".to_vec();
        long.extend(core::iter::repeat_n(b'#', MAX_LINE + 1));
        long.extend(b"\nc\n");
        for (name, content) in [("long.csv", long.clone()), ("long.csv.xz", xz(&long))] {
            let e = read(name, &content).unwrap_err();
            assert!(
                matches!(e, Error::LineTooLong { line: 3, .. }),
                "{name}: {e}"
            );
            assert!(
                e.to_string().contains(":3: line longer than 1048576 bytes"),
                "{e}"
            );
        }
        let gz = |data: &[u8]| {
            let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
            std::io::Write::write_all(&mut e, data).unwrap();
            e.finish().unwrap()
        };
        assert_eq!(read("ok.log.gz", &gz(&ok)).unwrap().len(), ok.len());
        assert_eq!(
            read("ok.log", &gz(b"a\n")).unwrap(),
            "a\n",
            "by its magic bytes"
        );
        let e = read("long.log.gz", &gz(&long)).unwrap_err();
        assert!(matches!(e, Error::LineTooLong { line: 3, .. }), "{e}");
        let e = read("bad.log", b"\x1f\x8b not gzip").unwrap_err();
        assert!(matches!(e, Error::Decompress { .. }), "{e}");
        assert!(
            e.to_string()
                .ends_with("bad.log: gzip decompression failed"),
            "{e}"
        );
        // A last line with no newline is bounded too.
        let e = read("tail.csv", &vec![b'x'; 3 * MAX_LINE]).unwrap_err();
        assert!(matches!(e, Error::LineTooLong { line: 1, .. }), "{e}");
    }
}
