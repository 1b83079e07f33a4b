//! Locus's own log format: one comma-separated text file (plain or
//! xz-compressed) holding a robot's odometry, landmark measurements, an
//! optional ground truth and the landmark map. The format is specified in
//! `docs/log-format.md`; in short, each data line starts with its kind:
//!
//! | kind | fields | units |
//! |---|---|---|
//! | `landmark` | id, x, y | -, m, m |
//! | `start` | t, x, y, theta | s, m, m, rad |
//! | `odometry` | t, v, omega | s, m/s, rad/s |
//! | `measurement` | t, id, range, bearing | s, -, m (>= 0), rad |
//! | `truth` | t, x, y, theta | s, m, m, rad |
//!
//! Lines starting with `#` and blank lines are skipped. Odometry and truth
//! times must not decrease; measurements are listed in the order the robot
//! **received** them, so their times may go back (a late measurement);
//! landmark ids are unique. Errors name the file, line, column and field.

use std::path::{Path, PathBuf};

use crate::error::{Error, FieldProblem, RecordProblem, Result};
use crate::mrclam::{Groundtruth, Odometry, TruthPose};
use crate::text::{TimeOrder, csv_records, read_text};

/// A landmark of the map: an id and a position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapLandmark {
    /// The id measurements refer to.
    pub id: u32,
    /// x in the world frame, m.
    pub x: f64,
    /// y in the world frame, m.
    pub y: f64,
}

/// One `measurement` line: a range and bearing to a landmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandmarkMeasurement {
    /// Time the measurement was taken, s.
    pub time: f64,
    /// The landmark's id.
    pub id: u32,
    /// Range from the robot's centre, m (>= 0).
    pub range: f64,
    /// Bearing from the robot's heading, counter-clockwise positive, rad.
    pub bearing: f64,
}

/// A whole Locus log.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LocusLog {
    /// The landmark map, in file order.
    pub landmarks: Vec<MapLandmark>,
    /// The initial pose, if given (`start` line).
    pub start: Option<TruthPose>,
    /// Odometry (velocities held until the next record), time order.
    pub odometry: Vec<Odometry>,
    /// Measurements in the order received (times may go back).
    pub measurements: Vec<LandmarkMeasurement>,
    /// Ground truth (empty if the log has none), time order.
    pub truth: Groundtruth,
}

/// The kinds a line may start with.
const KINDS: &str = "one of landmark, start, odometry, measurement, truth";

/// Parses the text of a Locus log; `path` names it in errors.
///
/// # Errors
/// A malformed line ([`Error::Field`], [`Error::Record`]) with its line.
pub fn parse(text: &str, path: &Path) -> Result<LocusLog> {
    let mut log = LocusLog::default();
    let mut landmark_lines: Vec<usize> = Vec::new();
    let mut odometry_order = TimeOrder::new();
    let mut truth_order = TimeOrder::new();
    let mut truth: Vec<TruthPose> = Vec::new();
    let mut start_line: Option<usize> = None;
    for mut f in csv_records(text, path) {
        let kind = f.next_text("kind")?;
        let line = f.line;
        match kind {
            "landmark" => {
                let lm = MapLandmark {
                    id: f.u32("id")?,
                    x: f.f64("x")?,
                    y: f.f64("y")?,
                };
                if let Some(i) = log.landmarks.iter().position(|l| l.id == lm.id) {
                    return Err(f.record_error(RecordProblem::Duplicate {
                        what: "landmark id",
                        value: lm.id,
                        first_line: landmark_lines[i],
                    }));
                }
                f.end(4)?;
                log.landmarks.push(lm);
                landmark_lines.push(line);
            }
            "start" => {
                let pose = pose(&mut f)?;
                if let Some(first_line) = start_line {
                    return Err(f.record_error(RecordProblem::Duplicate {
                        what: "start line",
                        value: 1,
                        first_line,
                    }));
                }
                f.end(5)?;
                log.start = Some(pose);
                start_line = Some(line);
            }
            "odometry" => {
                let o = Odometry {
                    time: f.f64("time")?,
                    v: f.f64("v")?,
                    omega: f.f64("omega")?,
                };
                odometry_order.check(&f, o.time)?;
                f.end(4)?;
                log.odometry.push(o);
            }
            "measurement" => {
                let m = LandmarkMeasurement {
                    time: f.f64("time")?,
                    id: f.u32("id")?,
                    range: f.non_negative("range")?,
                    bearing: f.f64("bearing")?,
                };
                f.end(5)?;
                log.measurements.push(m);
            }
            "truth" => {
                let p = pose(&mut f)?;
                truth_order.check(&f, p.time)?;
                f.end(5)?;
                truth.push(p);
            }
            other => {
                return Err(f.field_error(
                    "kind",
                    FieldProblem::OutOfRange {
                        value: other.to_owned(),
                        expected: KINDS,
                    },
                ));
            }
        }
    }
    // Times were checked not to decrease.
    log.truth = Groundtruth::new(truth).unwrap_or_default();
    Ok(log)
}

fn pose(f: &mut crate::text::Fields<'_>) -> Result<TruthPose> {
    Ok(TruthPose {
        time: f.f64("time")?,
        x: f.f64("x")?,
        y: f.f64("y")?,
        theta: f.f64("theta")?,
    })
}

/// Reads a Locus log: `path` itself, or `path.xz` if only that exists; a
/// file ending in `.xz` (or starting with the xz magic bytes) is
/// decompressed.
///
/// # Errors
/// [`Error::NotFound`] naming the file if neither exists; read,
/// decompression and parse errors naming the file (and line).
pub fn read(path: &Path) -> Result<LocusLog> {
    let file = existing(path)?;
    parse(&read_text(&file)?, &file)
}

/// `path` if it is a file, else `path.xz` if that is.
fn existing(path: &Path) -> Result<PathBuf> {
    if path.is_file() {
        return Ok(path.to_path_buf());
    }
    let mut xz = path.as_os_str().to_owned();
    xz.push(".xz");
    let xz = PathBuf::from(xz);
    if xz.is_file() {
        return Ok(xz);
    }
    Err(Error::NotFound {
        path: path.to_path_buf(),
    })
}

/// Writes a log in this format (the inverse of [`parse`]; numbers in
/// Rust's shortest round-trip form, so `parse(write(log)) == log`).
#[must_use]
pub fn write(log: &LocusLog) -> String {
    use core::fmt::Write as _;
    let mut s = String::from("# Locus log v1 (docs/log-format.md); SI units\n");
    for l in &log.landmarks {
        let _ = writeln!(s, "landmark,{},{},{}", l.id, l.x, l.y);
    }
    if let Some(p) = log.start {
        let _ = writeln!(s, "start,{},{},{},{}", p.time, p.x, p.y, p.theta);
    }
    for p in log.truth.poses() {
        let _ = writeln!(s, "truth,{},{},{},{}", p.time, p.x, p.y, p.theta);
    }
    for o in &log.odometry {
        let _ = writeln!(s, "odometry,{},{},{}", o.time, o.v, o.omega);
    }
    for m in &log.measurements {
        let _ = writeln!(
            s,
            "measurement,{},{},{},{}",
            m.time, m.id, m.range, m.bearing
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("log.csv")
    }

    #[test]
    fn parses_every_kind_and_round_trips() {
        let text = "# a log\n\nlandmark,6,1.5,-2\nstart,0,0,0,0.1\nodometry,0,0.1,0\n\
                    odometry, 0.01 ,0.2,0.05\nmeasurement,0.02,6,2.5,0.3\n\
                    measurement,0.015,6,2.4,0.31\ntruth,0,0,0,0\ntruth,0.02,0.003,0,0.001\n";
        let log = parse(text, p()).unwrap();
        assert_eq!(log.landmarks.len(), 1);
        assert_eq!(log.odometry[1].v, 0.2);
        assert_eq!(log.measurements[1].time, 0.015, "measurements may go back");
        assert_eq!(log.truth.poses().len(), 2);
        assert_eq!(log.start.unwrap().theta, 0.1);
        assert_eq!(parse(&write(&log), p()).unwrap(), log);
    }

    #[test]
    fn malformed_lines_name_the_line_and_field() {
        let e = parse("landmark,6,1,2\nodometry,0,0.1\n", p()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "log.csv:2: field \"omega\" (column 4): missing"
        );
        let e = parse("odometry,1,0,0\nodometry,0.5,0,0\n", p()).unwrap_err();
        assert!(e.to_string().starts_with("log.csv:2: time 0.5 s"), "{e}");
        let e = parse("\nwheel,1,2\n", p()).unwrap_err();
        assert!(
            e.to_string().starts_with("log.csv:2: field \"kind\""),
            "{e}"
        );
        let e = parse("measurement,1,6,-2,0\n", p()).unwrap_err();
        assert!(e.to_string().contains("\"range\" (column 4)"), "{e}");
        let e = parse("measurement,1,6,,0\n", p()).unwrap_err();
        assert!(e.to_string().contains("\"range\""), "{e}");
        let e = parse("landmark,6,1,2\nlandmark,6,3,4\n", p()).unwrap_err();
        assert!(e.to_string().contains("already appeared on line 1"), "{e}");
        let e = parse("truth,0,1,2,3,4\n", p()).unwrap_err();
        assert!(e.to_string().contains("6 fields, the format has 5"), "{e}");
    }

    #[test]
    fn a_missing_file_is_named() {
        let e = read(Path::new("/nonexistent/robot.csv")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "/nonexistent/robot.csv: not found (nor /nonexistent/robot.csv.xz)"
        );
    }
}
