//! The libRSF text format of TU Chemnitz's datasets (Pfeifer and Protzel;
//! the "Indoor UWB" labyrinth dataset in `../shared/data/indoor_uwb`), read
//! into a [`LocusLog`]: one measurement a line, whitespace-separated, its
//! kind first.
//!
//! | kind | columns after the kind | units |
//! |---|---|---|
//! | `range2` | t, range, variance, beacon x, beacon y, beacon id, SNR | s, m (>= 0), m^2 (>= 0), m, m, -, - |
//! | `odom2diff` | t, v left, v right, v y, half wheel distance, 3 variances | s, m/s, m/s, m/s (0), m (> 0), (m/s)^2 |
//! | `point2` (ground truth) | t, x, y, 4 covariance entries | s, m, m, m^2 |
//!
//! What becomes what:
//! * each beacon id becomes a landmark at the position its `range2` lines
//!   give (every line of one id must give the same position), in the order
//!   of first appearance; each `range2` line a range-only sighting
//!   (`bearing` `None`) by a sensor at the robot's centre, in file order;
//! * each `odom2diff` line an odometry record `v = (l + r) / 2`,
//!   `omega = (r - l) / (2 b)` (times must not decrease); a sideways
//!   speed other than 0 is refused (a differential drive has none). The
//!   columns are read as libRSF's own odometry factor
//!   (`OdometryFactor2DDifferential`) reads them, not as the dataset's
//!   readme names them: the first speed is the left wheel's (`v - b
//!   omega`), the second the right's, and the "wheel base" `b` is the
//!   distance from the centre to a wheel. On indoor_uwb this is what the
//!   ground truth says: the heading of its direction of motion follows
//!   `(c4 - c3) / (2 b)` integrated to 0.13 rad RMS about a constant, and
//!   the readme's `(c3 - c4) / b` turns the other way twice as fast;
//! * the `point2` lines of the ground-truth file a track of positions only
//!   ([`Groundtruth::positions`]).
//!
//! The variances the authors declare are kept ([`Librsf::range_variances`])
//! but do not become `noise` records: they are the authors' tuning, not a
//! measured property of the sensor.
//!
//! Errors name the file, line, column and field, as the other readers'.

use std::path::{Path, PathBuf};

use crate::error::{FieldProblem, RecordProblem, Result, excerpt};
use crate::locus_csv::{LandmarkMeasurement, LocusLog, MapLandmark};
use crate::mrclam::{Groundtruth, Odometry, TruthPose};
use crate::text::{TimeOrder, existing, read_text, records};

/// A libRSF input file (with its ground truth, if read) as a Locus log.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Librsf {
    /// The log: beacons as landmarks, range-only sightings, odometry,
    /// ground truth of positions only.
    pub log: LocusLog,
    /// The line of each measurement, odometry record and beacon in the
    /// input file.
    pub lines: crate::Lines,
    /// The range variance each `range2` line declares (m^2), in the order
    /// of [`LocusLog::measurements`]: information, not used as the noise.
    pub range_variances: Vec<f64>,
}

/// The kinds an input file's line may start with.
const INPUT_KINDS: &str = "one of range2, odom2diff";

/// Parses the text of a libRSF input file; `path` names it in errors.
///
/// # Errors
/// A malformed line ([`crate::Error::Field`], [`crate::Error::Record`]):
/// an unknown kind, a missing or malformed field, extra fields, odometry
/// times that go back, a beacon at two positions.
pub fn parse_input(text: &str, path: &Path) -> Result<Librsf> {
    let mut out = Librsf::default();
    let mut odometry_order = TimeOrder::new();
    for mut f in records(text, path) {
        let kind = f.next_text("kind")?;
        let line = f.line;
        match kind {
            "range2" => {
                let time = f.f64("time")?;
                let range = f.non_negative("range")?;
                let variance = f.non_negative("variance")?;
                let x = f.f64("beacon x")?;
                let y = f.f64("beacon y")?;
                let id = f.u32("beacon id")?;
                f.f64("SNR")?;
                match out.log.landmarks.iter().position(|l| l.id == id) {
                    Some(i) => {
                        let l = out.log.landmarks[i];
                        if l.x != x || l.y != y {
                            return Err(f.record_error(RecordProblem::Disagrees {
                                what: "this beacon's position differs from the one it has on",
                                first_line: out.lines.landmarks[i],
                            }));
                        }
                    }
                    None => {
                        out.log.landmarks.push(MapLandmark { id, x, y });
                        out.lines.landmarks.push(line);
                    }
                }
                f.end(8)?;
                out.log.measurements.push(LandmarkMeasurement {
                    time,
                    id,
                    range,
                    bearing: None,
                });
                out.lines.measurements.push(line);
                out.range_variances.push(variance);
            }
            "odom2diff" => {
                let time = f.f64("time")?;
                let left = f.f64("v left")?;
                let right = f.f64("v right")?;
                let sideways = f.f64("v y")?;
                if sideways != 0.0 {
                    return Err(f.field_error(
                        "v y",
                        FieldProblem::OutOfRange {
                            value: sideways.to_string(),
                            expected: "0 (a differential drive does not move sideways)",
                        },
                    ));
                }
                let half = f.positive("half wheel distance")?;
                for field in ["var v left", "var v right", "var v y"] {
                    f.non_negative(field)?;
                }
                odometry_order.check(&f, time)?;
                f.end(9)?;
                out.log.odometry.push(Odometry {
                    time,
                    v: 0.5 * (right + left),
                    omega: (right - left) / (2.0 * half),
                });
                out.lines.odometry.push(line);
            }
            other => {
                return Err(f.field_error(
                    "kind",
                    FieldProblem::OutOfRange {
                        value: excerpt(other),
                        expected: INPUT_KINDS,
                    },
                ));
            }
        }
    }
    Ok(out)
}

/// Parses the text of a libRSF ground-truth file (`point2` lines: time,
/// x, y and a 2x2 covariance); `path` names it in errors.
///
/// # Errors
/// A malformed line, a kind other than `point2`, times that go back.
pub fn parse_truth(text: &str, path: &Path) -> Result<Groundtruth> {
    let mut poses = Vec::new();
    let mut order = TimeOrder::new();
    for mut f in records(text, path) {
        let kind = f.next_text("kind")?;
        if kind != "point2" {
            return Err(f.field_error(
                "kind",
                FieldProblem::OutOfRange {
                    value: excerpt(kind),
                    expected: "point2",
                },
            ));
        }
        let time = f.f64("time")?;
        let x = f.f64("x")?;
        let y = f.f64("y")?;
        for field in ["cov xx", "cov xy", "cov yx", "cov yy"] {
            f.f64(field)?;
        }
        order.check(&f, time)?;
        f.end(8)?;
        poses.push(TruthPose {
            time,
            x,
            y,
            theta: 0.0,
        });
    }
    // Times were checked not to decrease.
    Ok(Groundtruth::positions(poses).unwrap_or_default())
}

/// The ground-truth file beside an input file: its name with `_Input`
/// replaced by `_GT` (`Indoor_UWB_Input.txt` -> `Indoor_UWB_GT.txt`), if
/// the name has `_Input` and that file exists.
#[must_use]
pub fn sibling_truth(input: &Path) -> Option<PathBuf> {
    let name = input.file_name()?.to_str()?;
    let at = name.rfind("_Input")?;
    let truth = input.with_file_name(format!("{}_GT{}", &name[..at], &name[at + 6..]));
    truth.is_file().then_some(truth)
}

/// Reads a libRSF input file and, if given, its ground-truth file (plain
/// or `.xz`, as the other readers).
///
/// # Errors
/// A missing file (named), a path that is not a regular file, a malformed
/// line (file, line, field).
pub fn read(input: &Path, truth: Option<&Path>) -> Result<Librsf> {
    let file = existing(input)?;
    let mut out = parse_input(&read_text(&file)?, &file)?;
    if let Some(truth) = truth {
        let file = existing(truth)?;
        out.log.truth = parse_truth(&read_text(&file)?, &file)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("in.txt")
    }

    fn message(text: &str) -> String {
        parse_input(text, p()).unwrap_err().to_string()
    }

    #[test]
    fn ranges_become_range_only_sightings_and_odometry_a_unicycle_input() {
        let text = "range2 0.1 2.9 0.01 -0.02 -0.01 105 0\n\
                    odom2diff 0.1 0.3 0.1 0 0.08 0.0001 0.0001 0.0001\n\
                    range2 0.2 1.6 0.02 -0.02 2.365 107 0\n\
                    range2 0.3 2.8 0.01 -0.02 -0.01 105 0\n";
        let r = parse_input(text, p()).unwrap();
        assert_eq!(
            r.log.landmarks,
            [
                MapLandmark {
                    id: 105,
                    x: -0.02,
                    y: -0.01
                },
                MapLandmark {
                    id: 107,
                    x: -0.02,
                    y: 2.365
                }
            ]
        );
        assert_eq!(r.log.measurements.len(), 3);
        assert_eq!(r.log.measurements[1].range, 1.6);
        assert!(r.log.measurements.iter().all(|m| m.bearing.is_none()));
        assert_eq!(r.lines.measurements, [1, 3, 4]);
        assert_eq!(r.range_variances, [0.01, 0.02, 0.01]);
        let o = r.log.odometry[0];
        assert!(
            (o.v - 0.2).abs() < 1e-15 && (o.omega + 1.25).abs() < 1e-12,
            "{o:?}"
        );
        assert_eq!(r.log.noise, crate::NoiseRecords::default());
        assert!(r.log.sensor.is_none());
    }

    #[test]
    fn malformed_lines_name_the_line_and_field() {
        assert_eq!(
            message("range2 0.1 2.9 0.01 -0.02 -0.01\n"),
            "in.txt:1: field \"beacon id\" (column 7): missing"
        );
        assert_eq!(
            message("\nrange2 0.1 -2.9 0.01 -0.02 -0.01 105 0\n"),
            "in.txt:2: field \"range\" (column 3): -2.9 is out of range: >= 0"
        );
        assert_eq!(
            message(
                "range2 0.1 2.9 0.01 -0.02 -0.01 105 0\nrange2 0.2 2.9 0.01 -0.02 -0.02 105 0\n"
            ),
            "in.txt:2: this beacon's position differs from the one it has on line 1"
        );
        assert_eq!(
            message("range2 0.1 2.9 0.01 -0.02 -0.01 105 0 7\n"),
            "in.txt:1: 9 fields, the format has 8"
        );
        assert_eq!(
            message("odom2diff 0.1 0.3 0.1 0.2 0.08 0 0 0\n"),
            "in.txt:1: field \"v y\" (column 5): 0.2 is out of range: \
             0 (a differential drive does not move sideways)"
        );
        assert_eq!(
            message("odom2diff 0.1 0.3 0.1 0 0 0 0 0\n"),
            "in.txt:1: field \"half wheel distance\" (column 6): 0 is out of range: > 0"
        );
        assert!(
            message("odom2diff 1 0 0 0 0.08 0 0 0\nodom2diff 0.5 0 0 0 0.08 0 0 0\n")
                .starts_with("in.txt:2: time 0.5 s is earlier")
        );
        assert_eq!(
            message("point2 0 1 2 0 0 0 0\n"),
            "in.txt:1: field \"kind\" (column 1): point2 is out of range: one of range2, odom2diff"
        );
        let e = parse_truth("point2 0 1 x 0 0 0 0\n", Path::new("gt.txt")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "gt.txt:1: field \"y\" (column 4): \"x\" is not a number"
        );
    }

    #[test]
    fn truth_is_positions_only() {
        let t = parse_truth("point2 0 1 2 0 0 0 0\npoint2 1 2 2 0 0 0 0\n", p()).unwrap();
        assert!(!t.has_heading());
        let q = t.pose_at(0.5, 2.0).unwrap();
        assert!((q.x - 1.5).abs() < 1e-15 && q.theta.is_nan());
    }

    #[test]
    fn the_truth_file_is_the_input_file_with_gt_for_input() {
        let dir = std::env::temp_dir().join(format!("locus-librsf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let input = dir.join("Run_Input.txt");
        assert_eq!(sibling_truth(&input), None);
        std::fs::write(dir.join("Run_GT.txt"), "").unwrap();
        assert_eq!(sibling_truth(&input), Some(dir.join("Run_GT.txt")));
        assert_eq!(sibling_truth(&dir.join("other.txt")), None);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
