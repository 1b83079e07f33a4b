//! Relations between scan times (Kuemmerle et al., "On measuring the
//! accuracy of SLAM algorithms", 2009): manually verified relative poses,
//! one per line `t1 t2 dx dy dz roll pitch dyaw` (absolute UNIX times, s;
//! m; rad), plain or xz-compressed. The motion is that of the robot from
//! its pose at `t1` to its pose at `t2`, in the frame of the pose at `t1`.

use std::path::Path;

use crate::error::Result;
use crate::text::{existing, read_text, records};

/// The offset of the Intel lab's relations from the corrected CARMEN log's
/// time base, s: `t_log = t_abs - INTEL_OFFSET` (docs/log-format.md has the
/// check that matches it to the scans).
pub const INTEL_OFFSET: f64 = 976_052_857.337;

/// One relation, in the log's time base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Relation {
    /// Time of the first pose, s (log time base).
    pub t1: f64,
    /// Time of the second pose, s (log time base).
    pub t2: f64,
    /// Forward motion in the first pose's frame, m.
    pub dx: f64,
    /// Leftward motion in the first pose's frame, m.
    pub dy: f64,
    /// Heading change, rad.
    pub dyaw: f64,
    /// The line of the file it comes from (1-based).
    pub line: usize,
}

/// Reads a relations file, shifting its times by `-offset` (s) into a
/// log's time base (e.g. [`INTEL_OFFSET`]).
///
/// # Errors
/// As [`crate::locus_csv::read`] for the file; a malformed line
/// ([`crate::Error::Field`], [`crate::Error::Record`]) naming its line and
/// field. `dz`, `roll` and `pitch` must be numbers but are not kept.
pub fn read(path: &Path, offset: f64) -> Result<Vec<Relation>> {
    let file = existing(path)?;
    parse(&read_text(&file)?, &file, offset)
}

/// Parses the text of a relations file; `path` names it in errors.
///
/// # Errors
/// As [`read`].
pub fn parse(text: &str, path: &Path, offset: f64) -> Result<Vec<Relation>> {
    let mut out = Vec::new();
    for mut f in records(text, path) {
        let t1 = f.f64("t1")? - offset;
        let t2 = f.f64("t2")? - offset;
        let dx = f.f64("dx")?;
        let dy = f.f64("dy")?;
        for name in ["dz", "roll", "pitch"] {
            f.f64(name)?;
        }
        let dyaw = f.f64("dyaw")?;
        let line = f.line;
        f.end(8)?;
        out.push(Relation {
            t1,
            t2,
            dx,
            dy,
            dyaw,
            line,
        });
    }
    Ok(out)
}

/// For each relation, the indices of the scans its two times fall on: the
/// scan whose time (in `scan_times`, any order) is nearest each end, if
/// within `tolerance` (s) of it; `None` unless both ends fall on a scan.
#[must_use]
pub fn on_scans(
    relations: &[Relation],
    scan_times: &[f64],
    tolerance: f64,
) -> Vec<Option<(usize, usize)>> {
    let mut order: Vec<usize> = (0..scan_times.len()).collect();
    order.sort_by(|a, b| scan_times[*a].total_cmp(&scan_times[*b]));
    let nearest = |t: f64| -> Option<usize> {
        let k = order.partition_point(|i| scan_times[*i] < t);
        [k.checked_sub(1), Some(k)]
            .into_iter()
            .flatten()
            .filter_map(|k| order.get(k).copied())
            .min_by(|a, b| {
                (scan_times[*a] - t)
                    .abs()
                    .total_cmp(&(scan_times[*b] - t).abs())
            })
            .filter(|i| (scan_times[*i] - t).abs() <= tolerance)
    };
    relations
        .iter()
        .map(|r| Some((nearest(r.t1)?, nearest(r.t2)?)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relations_shift_and_fall_on_the_nearest_scans() {
        let text = "100.5 103.25 0.1 -0.2 0 0 0 0.3\n\n103.25 200 1 2 0 0 0 -1\n";
        let r = parse(text, Path::new("r"), 100.0).unwrap();
        assert_eq!(
            r[0],
            Relation {
                t1: 0.5,
                t2: 3.25,
                dx: 0.1,
                dy: -0.2,
                dyaw: 0.3,
                line: 1
            }
        );
        assert_eq!(r[1].line, 3);
        let scans = [3.2501, 0.0, 0.4995, 9.0];
        assert_eq!(on_scans(&r, &scans, 1e-3), [Some((2, 0)), None]);
        assert_eq!(on_scans(&r, &scans, 1e-4), [None, None]);
        let e = parse("1 2 3 4 5 6 7\n", Path::new("r"), 0.0).unwrap_err();
        assert_eq!(e.to_string(), "r:1: field \"dyaw\" (column 8): missing");
        let e = parse("1 2 3 4 5 6 7 8 9\n", Path::new("r"), 0.0).unwrap_err();
        assert_eq!(e.to_string(), "r:1: 9 fields, the format has 8");
    }
}
