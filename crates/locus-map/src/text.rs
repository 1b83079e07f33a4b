//! Walls as plain text: one wall per line, `x1 y1 x2 y2` in metres separated
//! by spaces or tabs; `#` starts a comment (a whole line or the rest of
//! one); blank lines are skipped.
//!
//! ```text
//! # the arena, metres
//! 0 0 4 0
//! 4 0 4 3   # east wall
//! ```

use core::fmt::Write as _;
use std::path::Path;

use crate::{MapError, Segment, SegmentMap};

/// The fields of a line, in order.
const FIELDS: [&str; 4] = ["x1", "y1", "x2", "y2"];

/// Reads a wall file.
///
/// # Errors
/// [`MapError::Io`] if it cannot be read; else as [`parse`].
pub fn load(path: &Path) -> Result<SegmentMap, MapError> {
    let src = std::fs::read_to_string(path).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })?;
    let segments = parse(&src, path)?;
    SegmentMap::new(segments)
}

/// The walls of the text `src`; `file` names it in errors.
///
/// # Errors
/// [`MapError::Line`] naming the line and the field: a number that does not
/// parse or is not finite (`x1` to `y2`), a missing field, or more than four
/// (`line`).
pub fn parse(src: &str, file: &Path) -> Result<Vec<Segment>, MapError> {
    let mut out = Vec::new();
    for (i, raw) in src.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("");
        let err = |field: &str, reason: String| MapError::Line {
            file: file.into(),
            line: i + 1,
            field: field.to_string(),
            reason,
        };
        let mut words = line.split_whitespace();
        let Some(first) = words.next() else {
            continue;
        };
        let mut v = [0.0; 4];
        for (k, field) in FIELDS.iter().enumerate() {
            let word = if k == 0 { Some(first) } else { words.next() };
            let word =
                word.ok_or_else(|| err(field, "missing: a wall is `x1 y1 x2 y2` (m)".into()))?;
            let x: f64 = word
                .parse()
                .map_err(|_| err(field, format!("{word:?} is not a number")))?;
            if !x.is_finite() {
                return Err(err(field, format!("{word:?} is not finite")));
            }
            v[k] = x;
        }
        if let Some(extra) = words.next() {
            return Err(err(
                "line",
                format!("{extra:?} after y2: a wall is `x1 y1 x2 y2` (m)"),
            ));
        }
        out.push(Segment::from(v));
    }
    Ok(out)
}

/// The text of `segments`, one per line under a comment header; the numbers
/// are written so that they read back bit for bit.
pub fn format(segments: &[Segment]) -> String {
    let mut s = String::from("# Locus walls: x1 y1 x2 y2 (m), one per line\n");
    for seg in segments {
        let [a, b, c, d] = seg.to_array();
        let _ = writeln!(s, "{a:?} {b:?} {c:?} {d:?}");
    }
    s
}

/// Writes `segments` to `path` ([`format()`]).
///
/// # Errors
/// [`MapError::Io`].
pub fn save(segments: &[Segment], path: &Path) -> Result<(), MapError> {
    std::fs::write(path, format(segments)).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })
}
