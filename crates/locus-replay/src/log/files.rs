//! The [`Log`] of a recorded file: a Locus CSV log, a ROS 2 bag with its
//! topic mapping, a libRSF log, and the map file a log's beams are
//! corrected against.

use alloc::sync::Arc;
use std::path::{Path, PathBuf};

use locus_logs::Lines;
use locus_logs::locus_csv::{self, LocusLog};
use locus_map::Map;

use super::{Log, SharedMap};
use crate::Error;

impl Log {
    /// Reads a Locus CSV log file (`.xz` read directly; `FILE.xz` tried if
    /// `FILE` does not exist).
    ///
    /// # Errors
    /// Missing file (named), a path that is not a regular file (what it
    /// is), malformed line (file and line), an implausible record
    /// ([`Log::from_locus`]).
    pub fn locus_csv(path: &Path) -> Result<Self, Error> {
        let (log, lines, file) = locus_csv::read_with_lines(path)?;
        let map_file = log.map.as_ref().map(|m| m.resolve(&file));
        Self::from_locus_with_map(&file_name(path), log, lines, map_file)
    }

    /// Reads a ROS 2 bag (MCAP) by the mapping in the TOML file
    /// `mapping_file` ([`locus_bag::read_log`], docs/bags.md), with the map
    /// file the mapping names.
    ///
    /// # Errors
    /// The bag or the mapping cannot be read ([`Error::Bag`]: the file,
    /// record, topic and field named); the map file cannot be loaded
    /// ([`Error::Map`]); an implausible record ([`Log::from_locus`]).
    pub fn bag(bag: &Path, mapping_file: &Path) -> Result<Self, Error> {
        let log = locus_bag::read_log(bag, mapping_file)?;
        // `read_log` resolved the map path against the mapping file.
        let map_file = log.map.as_ref().map(|m| m.as_str().into());
        Self::from_locus_with_map(&file_name(bag), log, Lines::default(), map_file)
    }

    /// Loads the map file at `path` (a ROS map_server YAML, or walls as
    /// text or TOML: `locus_map::Map::load`) as the log's map, the one its
    /// beams are corrected against (`locus replay carmen --map`).
    ///
    /// # Errors
    /// [`Error::Map`]: the map reader's error, which names the file (and
    /// the line and field of a malformed one).
    pub fn load_map(&mut self, path: &Path) -> Result<(), Error> {
        let map = Map::load(path).map_err(|e| Error::Map {
            file: self.name.clone(),
            line: None,
            reason: e.to_string(),
        })?;
        self.map = Some(SharedMap(Arc::new(map)));
        Ok(())
    }

    /// [`Log::from_locus_lines`] with the map loaded from `map_file` (the
    /// log's `map` record resolved), which a log with walls must not have.
    fn from_locus_with_map(
        name: &str,
        log: LocusLog,
        lines: Lines,
        map_file: Option<PathBuf>,
    ) -> Result<Self, Error> {
        let map_line = lines.map;
        let map_error = |reason: String| Error::Map {
            file: name.to_string(),
            line: map_line,
            reason,
        };
        if map_file.is_some() && !log.walls.is_empty() {
            return Err(map_error(
                "the log gives both walls and a map file: give one".to_string(),
            ));
        }
        let mut out = Self::from_locus_lines(name, log, lines)?;
        if let Some(p) = map_file {
            let map = Map::load(&p).map_err(|e| map_error(e.to_string()))?;
            out.map = Some(SharedMap(Arc::new(map)));
        }
        Ok(out)
    }

    /// Reads a log in libRSF's text format (`range2` and `odom2diff` lines:
    /// UWB ranges as range-only sightings, differential-drive odometry),
    /// with the ground truth's `point2` lines from `truth` if given
    /// (positions only). The ranges' declared variance is not used as the
    /// noise.
    ///
    /// # Errors
    /// Missing file (named), malformed line (file and line), an
    /// implausible record ([`Log::from_locus`]).
    pub fn librsf(input: &Path, truth: Option<&Path>) -> Result<Self, Error> {
        let read = locus_logs::librsf::read(input, truth)?;
        Self::from_locus_lines(&file_name(input), read.log, read.lines)
    }
}

/// A log's name: its file's name (empty for a path that has none).
fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}
