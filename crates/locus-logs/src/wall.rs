//! The map a log carries: wall segments inline, or a reference to a map
//! file (loading a map file is not this crate's job).

use std::path::{Path, PathBuf};

/// A wall of the log's map: the segment from `(x1, y1)` to `(x2, y2)` in
/// the world frame, m. A reader refuses a wall of zero length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    /// x of the first end, m.
    pub x1: f64,
    /// y of the first end, m.
    pub y1: f64,
    /// x of the second end, m.
    pub x2: f64,
    /// y of the second end, m.
    pub y2: f64,
}

impl Wall {
    /// Length of the segment, m (0 for a degenerate wall).
    #[must_use]
    pub fn length(&self) -> f64 {
        (self.x2 - self.x1).hypot(self.y2 - self.y1)
    }
}

/// The path of a map file as a `map` record writes it: relative to the
/// directory of the log file (or absolute), non-empty, without a comma, a
/// line break or surrounding blanks, so that it can be written back in a
/// comma-separated record unchanged.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MapPath(String);

impl MapPath {
    /// `path` if it can be written in a `map` record (see [`MapPath`]),
    /// else `None`.
    #[must_use]
    pub fn new(path: &str) -> Option<Self> {
        let ok = !path.is_empty()
            && path.trim() == path
            && !path.contains([',', '\n', '\r'])
            && path.len() <= crate::MAX_LINE / 2;
        ok.then(|| Self(path.to_owned()))
    }

    /// The path as written in the record.
    #[must_use]
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// The map file's path for the log file `log_file`: the recorded path
    /// joined to the log file's directory (an absolute recorded path is
    /// returned as it is). Nothing is read.
    #[must_use]
    pub fn resolve(&self, log_file: &Path) -> PathBuf {
        log_file
            .parent()
            .unwrap_or_else(|| Path::new(""))
            .join(&self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn map_paths_that_cannot_be_written_back_are_refused() {
        assert!(MapPath::new("maps/lab.yaml").is_some());
        for bad in ["", " a.yaml", "a.yaml ", "a,b.yaml", "a\nb", "a\rb"] {
            assert!(MapPath::new(bad).is_none(), "{bad:?}");
        }
    }

    #[test]
    fn a_map_path_resolves_beside_the_log() {
        let m = MapPath::new("maps/lab.yaml").unwrap();
        assert_eq!(
            m.resolve(Path::new("/data/run1/log.csv")),
            Path::new("/data/run1/maps/lab.yaml")
        );
        assert_eq!(m.resolve(Path::new("log.csv")), Path::new("maps/lab.yaml"));
        let abs = MapPath::new("/maps/lab.yaml").unwrap();
        assert_eq!(
            abs.resolve(Path::new("/data/log.csv")),
            Path::new("/maps/lab.yaml")
        );
        assert_eq!(
            Wall {
                x1: 0.0,
                y1: 0.0,
                x2: 3.0,
                y2: 4.0
            }
            .length(),
            5.0
        );
    }
}
