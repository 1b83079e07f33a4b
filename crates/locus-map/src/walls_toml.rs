//! Walls in TOML: an array of `[[wall]]` tables, each with its two ends in
//! metres. No other keys are allowed; a file with no wall is an empty map.
//!
//! ```toml
//! # the arena, metres
//! [[wall]]
//! from = [0.0, 0.0]
//! to = [4.0, 0.0]
//!
//! [[wall]]
//! from = [4, 0]
//! to = [4, 3]
//! ```

use core::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use crate::{MapError, Segment, SegmentMap};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    #[serde(default)]
    wall: Vec<Wall>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Wall {
    from: [f64; 2],
    to: [f64; 2],
}

/// Reads a TOML wall file.
///
/// # Errors
/// [`MapError::Io`] if it cannot be read; else as [`parse`].
pub fn load(path: &Path) -> Result<SegmentMap, MapError> {
    let src = std::fs::read_to_string(path).map_err(|source| MapError::Io {
        file: path.into(),
        source,
    })?;
    SegmentMap::new(parse(&src, path)?)
}

/// The walls of the TOML text `src`; `file` names it in errors.
///
/// # Errors
/// [`MapError::Syntax`] with the line and the parser's message (which names
/// a missing, unknown or mistyped field); [`MapError::Field`]
/// (`wall[i].from`, `wall[i].to`, `i` from 0) for a coordinate that is not
/// finite.
pub fn parse(src: &str, file: &Path) -> Result<Vec<Segment>, MapError> {
    let parsed: File = toml::from_str(src).map_err(|e| MapError::Syntax {
        file: file.into(),
        line: e
            .span()
            .map(|s| src[..s.start.min(src.len())].matches('\n').count() + 1),
        message: e.message().trim().to_string(),
    })?;
    parsed
        .wall
        .iter()
        .enumerate()
        .map(|(i, w)| {
            for (name, p) in [("from", w.from), ("to", w.to)] {
                if !p.iter().all(|x| x.is_finite()) {
                    return Err(MapError::Field {
                        file: file.into(),
                        field: format!("wall[{i}].{name}"),
                        reason: format!("{p:?}: coordinates must be finite"),
                    });
                }
            }
            Ok(Segment::new(w.from, w.to))
        })
        .collect()
}

/// The TOML text of `segments` under a comment header; the numbers are
/// written so that they read back bit for bit.
pub fn format(segments: &[Segment]) -> String {
    let mut s = String::from("# Locus walls: each [[wall]] from one end to the other (m)\n");
    for seg in segments {
        let _ = write!(
            s,
            "\n[[wall]]\nfrom = [{:?}, {:?}]\nto = [{:?}, {:?}]\n",
            seg.a[0], seg.a[1], seg.b[0], seg.b[1]
        );
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
