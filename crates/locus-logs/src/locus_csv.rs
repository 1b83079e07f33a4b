//! Locus's own log format: one comma-separated text file (plain or
//! xz-compressed) holding a robot's odometry, landmark measurements, an
//! optional ground truth and the landmark map. The format is specified in
//! `docs/log-format.md`; in short, each data line starts with its kind:
//!
//! | kind | fields | units |
//! |---|---|---|
//! | `sensor` | x, y, yaw | m, m, rad (robot frame) |
//! | `noise` | name, value | `q_v` m^2/s, `q_omega` rad^2/s, `sigma_range` m, `sigma_bearing` rad |
//! | `landmark` | id, x, y | -, m, m |
//! | `start` | t, x, y, theta | s, m, m, rad |
//! | `odometry` | t, v, omega | s, m/s, rad/s |
//! | `measurement` | t, id, range, bearing | s, -, m (>= 0), rad |
//! | `range` | t, id, range | s, -, m (>= 0) (version 3: range only) |
//! | `truth` | t, x, y, theta or t, x, y | s, m, m, rad (version 3: theta optional) |
//!
//! Lines starting with `#` and blank lines are skipped. Odometry and truth
//! times must not decrease; truth lines all give a heading or none;
//! measurements (`measurement` and `range` lines) are listed in the order
//! the robot **received** them, so their times may go back (a late measurement);
//! landmark ids are unique; `start` and `sensor` appear at most once, and
//! each noise name at most once. Measurements are taken by the sensor of the
//! `sensor` line (at the robot's centre, along its heading, if there is
//! none). Errors name the file, line, column and field.

use std::path::{Path, PathBuf};

use crate::decimal::push_f64;
use crate::error::{FieldProblem, RecordProblem, Result, excerpt};
use crate::lines::Lines;
use crate::mrclam::{Groundtruth, Odometry, TruthPose};
use crate::noise::NoiseRecords;
use crate::sensor::SensorMount;
use crate::text::{TimeOrder, csv_records, existing, read_text};

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

/// One `measurement` line (a range and bearing to a landmark) or `range`
/// line (a range alone, `bearing` `None`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandmarkMeasurement {
    /// Time the measurement was taken, s.
    pub time: f64,
    /// The landmark's id.
    pub id: u32,
    /// Range from the sensor's origin, m (>= 0).
    pub range: f64,
    /// Bearing from the sensor's x axis, counter-clockwise positive, rad;
    /// `None` for a `range` line.
    pub bearing: Option<f64>,
}

/// A whole Locus log.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LocusLog {
    /// The landmark sensor's mount (`sensor` line), if given; without one
    /// the sensor is at the robot's centre, along its heading.
    pub sensor: Option<SensorMount>,
    /// The noise levels the log declares (`noise` lines).
    pub noise: NoiseRecords,
    /// The landmark map, in file order.
    pub landmarks: Vec<MapLandmark>,
    /// The initial pose, if given (`start` line).
    pub start: Option<TruthPose>,
    /// Odometry (velocities held until the next record), time order.
    pub odometry: Vec<Odometry>,
    /// Measurements (`measurement` and `range` lines) in the order received
    /// (times may go back).
    pub measurements: Vec<LandmarkMeasurement>,
    /// Ground truth (empty if the log has none), time order; positions only
    /// ([`Groundtruth::positions`]) if its lines give no heading.
    pub truth: Groundtruth,
}

/// The kinds a line may start with.
const KINDS: &str = "one of sensor, noise, landmark, start, odometry, measurement, range, truth";

/// The names a `noise` line may give.
const NOISE_NAMES: &str = "one of q_v, q_omega, sigma_range, sigma_bearing";

/// What a repeated `noise` line is called in its error, by name (in the
/// order of [`NoiseRecords::NAMES`]).
const NOISE_WHAT: [&str; 4] = [
    "noise q_v",
    "noise q_omega",
    "noise sigma_range",
    "noise sigma_bearing",
];

/// Parses the text of a Locus log; `path` names it in errors.
///
/// # Errors
/// A malformed line ([`crate::Error::Field`], [`crate::Error::Record`])
/// with its line.
pub fn parse(text: &str, path: &Path) -> Result<LocusLog> {
    parse_with_lines(text, path).map(|(log, _)| log)
}

/// As [`parse`], with the line (1-based) of each record ([`Lines`]): what
/// a reader of the log names when it refuses one.
///
/// # Errors
/// As [`parse`].
pub fn parse_with_lines(text: &str, path: &Path) -> Result<(LocusLog, Lines)> {
    let mut log = LocusLog::default();
    let mut lines = Lines::default();
    let measurement_lines = &mut lines.measurements;
    let landmark_lines = &mut lines.landmarks;
    let odometry_lines = &mut lines.odometry;
    let mut odometry_order = TimeOrder::new();
    let mut truth_order = TimeOrder::new();
    let mut truth: Vec<TruthPose> = Vec::new();
    // The first truth line and whether it gives a heading.
    let mut truth_heading: Option<(usize, bool)> = None;
    let start_line = &mut lines.start;
    let sensor_line = &mut lines.sensor;
    // The line of each noise name's record, in the order of NoiseRecords::NAMES.
    let noise_lines = &mut lines.noise;
    for mut f in csv_records(text, path) {
        let kind = f.next_text("kind")?;
        let line = f.line;
        match kind {
            "sensor" => {
                let mount = SensorMount {
                    x: f.f64("x")?,
                    y: f.f64("y")?,
                    yaw: f.f64("yaw")?,
                };
                if let Some(first_line) = *sensor_line {
                    return Err(f.record_error(RecordProblem::DuplicateRecord {
                        what: "sensor line",
                        first_line,
                    }));
                }
                f.end(4)?;
                log.sensor = Some(mount);
                *sensor_line = Some(line);
            }
            "noise" => {
                let name = f.next_text("name")?;
                let Some(k) = NoiseRecords::NAMES.iter().position(|n| *n == name) else {
                    return Err(f.field_error(
                        "name",
                        FieldProblem::OutOfRange {
                            value: excerpt(name),
                            expected: NOISE_NAMES,
                        },
                    ));
                };
                let value = f.positive("value")?;
                if let Some(first_line) = noise_lines[k] {
                    return Err(f.record_error(RecordProblem::DuplicateRecord {
                        what: NOISE_WHAT[k],
                        first_line,
                    }));
                }
                f.end(3)?;
                if let Some(slot) = log.noise.get_mut(name) {
                    *slot = Some(value);
                }
                noise_lines[k] = Some(line);
            }
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
                if let Some(first_line) = *start_line {
                    return Err(f.record_error(RecordProblem::DuplicateRecord {
                        what: "start line",
                        first_line,
                    }));
                }
                f.end(5)?;
                log.start = Some(pose);
                *start_line = Some(line);
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
                odometry_lines.push(line);
            }
            "measurement" => {
                let m = LandmarkMeasurement {
                    time: f.f64("time")?,
                    id: f.u32("id")?,
                    range: f.non_negative("range")?,
                    bearing: Some(f.f64("bearing")?),
                };
                f.end(5)?;
                log.measurements.push(m);
                measurement_lines.push(line);
            }
            "range" => {
                let m = LandmarkMeasurement {
                    time: f.f64("time")?,
                    id: f.u32("id")?,
                    range: f.non_negative("range")?,
                    bearing: None,
                };
                f.end(4)?;
                log.measurements.push(m);
                measurement_lines.push(line);
            }
            "truth" => {
                let time = f.f64("time")?;
                let x = f.f64("x")?;
                let y = f.f64("y")?;
                let theta = f.optional_f64("theta")?;
                truth_order.check(&f, time)?;
                let heading = theta.is_some();
                match truth_heading {
                    None => truth_heading = Some((line, heading)),
                    Some((first_line, h)) if h != heading => {
                        return Err(f.record_error(RecordProblem::Disagrees {
                            what: "truth lines give a heading or none, all alike: this one differs from",
                            first_line,
                        }));
                    }
                    Some(_) => {}
                }
                f.end(5)?;
                truth.push(TruthPose {
                    time,
                    x,
                    y,
                    theta: theta.unwrap_or(0.0),
                });
            }
            other => {
                return Err(f.field_error(
                    "kind",
                    FieldProblem::OutOfRange {
                        value: excerpt(other),
                        expected: KINDS,
                    },
                ));
            }
        }
    }
    // Times were checked not to decrease.
    log.truth = if matches!(truth_heading, Some((_, false))) {
        Groundtruth::positions(truth)
    } else {
        Groundtruth::new(truth)
    }
    .unwrap_or_default();
    Ok((log, lines))
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
/// [`crate::Error::NotFound`] naming the file if neither exists;
/// [`crate::Error::NotAFile`] for a directory, FIFO, socket or device
/// (never opened); [`crate::Error::Io`] with the system's reason (a loop of
/// symbolic links, no permission); read, decompression and parse errors
/// naming the file (and line).
pub fn read(path: &Path) -> Result<LocusLog> {
    read_with_lines(path).map(|(log, _, _)| log)
}

/// As [`read`], with the line of each record (as [`parse_with_lines`])
/// and the file actually read (`path` or `path.xz`).
///
/// # Errors
/// As [`read`].
pub fn read_with_lines(path: &Path) -> Result<(LocusLog, Lines, PathBuf)> {
    let file = existing(path)?;
    let (log, lines) = parse_with_lines(&read_text(&file)?, &file)?;
    Ok((log, lines, file))
}

/// Writes a log in this format (the inverse of [`parse`]; numbers as
/// Rust's `Display` writes them, the shortest form that reads back to the
/// same value, so `parse(write(log)) == log`).
#[must_use]
pub fn write(log: &LocusLog) -> String {
    use core::fmt::Write as _;
    let lines = 1 + log.landmarks.len() + log.truth.poses().len() + log.odometry.len();
    let mut s = String::with_capacity(64 * (lines + log.measurements.len()));
    s.push_str("# Locus log v3 (docs/log-format.md); SI units\n");
    if let Some(m) = log.sensor {
        record(&mut s, "sensor", &[m.x, m.y, m.yaw]);
    }
    for (name, value) in log.noise.iter() {
        s.push_str("noise,");
        s.push_str(name);
        record(&mut s, "", &[value]);
    }
    for l in &log.landmarks {
        let _ = write!(s, "landmark,{}", l.id);
        record(&mut s, "", &[l.x, l.y]);
    }
    if let Some(p) = log.start {
        record(&mut s, "start", &[p.time, p.x, p.y, p.theta]);
    }
    let heading = log.truth.has_heading();
    for p in log.truth.poses() {
        if heading {
            record(&mut s, "truth", &[p.time, p.x, p.y, p.theta]);
        } else {
            record(&mut s, "truth", &[p.time, p.x, p.y]);
        }
    }
    for o in &log.odometry {
        record(&mut s, "odometry", &[o.time, o.v, o.omega]);
    }
    for m in &log.measurements {
        s.push_str(if m.bearing.is_some() {
            "measurement,"
        } else {
            "range,"
        });
        push_f64(&mut s, m.time);
        let _ = write!(s, ",{}", m.id);
        match m.bearing {
            Some(b) => record(&mut s, "", &[m.range, b]),
            None => record(&mut s, "", &[m.range]),
        }
    }
    s
}

/// Appends `head`, then `,value` for each value, then a line end.
fn record(s: &mut String, head: &str, values: &[f64]) {
    s.push_str(head);
    for v in values {
        s.push(',');
        push_f64(s, *v);
    }
    s.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

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
        assert_eq!(log.sensor, None, "a version 1 log has no sensor line");
        assert_eq!(log.noise, NoiseRecords::default());
        assert_eq!(parse(&write(&log), p()).unwrap(), log);
    }

    #[test]
    fn parses_sensor_and_noise_and_round_trips() {
        let text = "# Locus log v2\nnoise,sigma_bearing,0.03\nsensor, 0.1 ,-0.02,1.5707963267948966\n\
                    landmark,6,1.5,-2\nnoise,q_v,1e-2\nodometry,0,0.1,0\nmeasurement,0.02,6,2.5,0.3\n";
        let log = parse(text, p()).unwrap();
        assert_eq!(
            log.sensor,
            Some(SensorMount {
                x: 0.1,
                y: -0.02,
                yaw: core::f64::consts::FRAC_PI_2
            })
        );
        assert_eq!(
            log.noise,
            NoiseRecords {
                q_v: Some(0.01),
                sigma_bearing: Some(0.03),
                ..NoiseRecords::default()
            }
        );
        let written = write(&log);
        assert!(written.starts_with("# Locus log v3"), "{written}");
        assert!(
            written.contains("\nsensor,0.1,-0.02,1.5707963267948966\n"),
            "{written}"
        );
        assert!(
            written.contains("\nnoise,q_v,0.01\nnoise,sigma_bearing,0.03\n"),
            "{written}"
        );
        assert_eq!(parse(&written, p()).unwrap(), log);

        // A centred sensor given explicitly is kept as given.
        let log = parse(
            "sensor,0,0,0\nnoise,q_omega,2\nnoise,sigma_range,0.2\n",
            p(),
        )
        .unwrap();
        assert_eq!(log.sensor, Some(SensorMount::default()));
        assert_eq!(parse(&write(&log), p()).unwrap(), log);
        assert!(!write(&LocusLog::default()).contains("sensor"));
    }

    /// The error of parsing `text`, as its message.
    fn message(text: &str) -> String {
        parse(text, p()).unwrap_err().to_string()
    }

    #[test]
    fn malformed_sensor_lines_name_the_line_and_field() {
        assert_eq!(
            message("landmark,6,1,2\nsensor,0.1,0\n"),
            "log.csv:2: field \"yaw\" (column 4): missing"
        );
        assert_eq!(
            message("sensor,0.1,inf,0\n"),
            "log.csv:1: field \"y\" (column 3): \"inf\" is not finite"
        );
        assert_eq!(
            message("sensor,NaN,0,0\n"),
            "log.csv:1: field \"x\" (column 2): \"NaN\" is not finite"
        );
        assert_eq!(
            message("sensor,0.1,0,0x1\n"),
            "log.csv:1: field \"yaw\" (column 4): \"0x1\" is not a number"
        );
        assert_eq!(
            message("sensor,0,0,0,0\n"),
            "log.csv:1: 5 fields, the format has 4"
        );
        assert_eq!(
            message("# a\nsensor,0.1,0,0\nlandmark,6,1,2\nsensor,0.1,0,0\n"),
            "log.csv:4: sensor line already appeared on line 2"
        );
        let e = parse("sensor,0,0,0\nsensor,0,0,0\n", p()).unwrap_err();
        assert!(
            matches!(
                e,
                Error::Record {
                    line: 2,
                    problem: RecordProblem::DuplicateRecord {
                        what: "sensor line",
                        first_line: 1
                    },
                    ..
                }
            ),
            "{e:?}"
        );
    }

    #[test]
    fn malformed_noise_lines_name_the_line_and_field() {
        assert_eq!(
            message("noise,q_v\n"),
            "log.csv:1: field \"value\" (column 3): missing"
        );
        assert_eq!(
            message("noise\n"),
            "log.csv:1: field \"name\" (column 2): missing"
        );
        assert_eq!(
            message("\nnoise,sigma_rng,0.2\n"),
            "log.csv:2: field \"name\" (column 2): sigma_rng is out of range: \
             one of q_v, q_omega, sigma_range, sigma_bearing"
        );
        assert_eq!(
            message("noise,q_omega,0\n"),
            "log.csv:1: field \"value\" (column 3): 0 is out of range: > 0"
        );
        assert_eq!(
            message("noise,sigma_range,-0.2\n"),
            "log.csv:1: field \"value\" (column 3): -0.2 is out of range: > 0"
        );
        assert_eq!(
            message("noise,sigma_bearing,inf\n"),
            "log.csv:1: field \"value\" (column 3): \"inf\" is not finite"
        );
        assert_eq!(
            message("noise,q_v,0.1,0.2\n"),
            "log.csv:1: 4 fields, the format has 3"
        );
        assert_eq!(
            message("noise,q_v,0.1\nnoise,q_omega,0.1\nnoise,q_v,0.2\n"),
            "log.csv:3: noise q_v already appeared on line 1"
        );
        assert_eq!(
            message("noise,sigma_bearing,0.1\n\nnoise,sigma_bearing,0.1\n"),
            "log.csv:3: noise sigma_bearing already appeared on line 1"
        );
    }

    #[test]
    fn range_lines_and_truth_without_heading_read_and_round_trip() {
        let text = "# Locus log v3\nsensor,0.1,0,0\nlandmark,105,-0.02,-0.01\nodometry,0,0.1,0\n\
                    range,0.13,105,2.955\nmeasurement,0.2,105,2.9,0.5\nrange,0.1,105,0\n\
                    truth,0,1.65,2.22\ntruth,0.13,1.66,2.21\n";
        let (log, lines) = parse_with_lines(text, p()).unwrap();
        assert_eq!(lines.measurements, [5, 6, 7]);
        assert_eq!(
            log.measurements[0],
            LandmarkMeasurement {
                time: 0.13,
                id: 105,
                range: 2.955,
                bearing: None
            }
        );
        assert_eq!(log.measurements[1].bearing, Some(0.5));
        assert!(!log.truth.has_heading());
        assert!(log.truth.pose_at(0.05, 1.0).unwrap().theta.is_nan());
        assert!((log.truth.pose_at(0.13, 1.0).unwrap().x - 1.66).abs() < 1e-12);
        let written = write(&log);
        assert!(written.contains("\nrange,0.13,105,2.955\n"), "{written}");
        assert!(written.contains("\ntruth,0.13,1.66,2.21\n"), "{written}");
        assert_eq!(parse(&written, p()).unwrap(), log);
        // Truth with a heading stays so.
        let log = parse("truth,0,1,2,0.5\n", p()).unwrap();
        assert!(log.truth.has_heading());
        assert_eq!(log.truth.pose_at(0.0, 1.0).unwrap().theta, 0.5);
    }

    #[test]
    fn malformed_range_and_truth_lines_name_the_line_and_field() {
        assert_eq!(
            message("range,1,105\n"),
            "log.csv:1: field \"range\" (column 4): missing"
        );
        assert_eq!(
            message("range,1,105,-0.5\n"),
            "log.csv:1: field \"range\" (column 4): -0.5 is out of range: >= 0"
        );
        assert_eq!(
            message("range,1,b105,0.5\n"),
            "log.csv:1: field \"id\" (column 3): \"b105\" is not a non-negative integer"
        );
        assert_eq!(
            message("range,1,105,0.5,0.1\n"),
            "log.csv:1: 5 fields, the format has 4"
        );
        assert_eq!(
            message("truth,0,1\n"),
            "log.csv:1: field \"y\" (column 4): missing"
        );
        assert_eq!(
            message("truth,0,1,2,x\n"),
            "log.csv:1: field \"theta\" (column 5): \"x\" is not a number"
        );
        assert_eq!(
            message("truth,0,1,2\n\ntruth,1,1,2,0.3\n"),
            "log.csv:3: truth lines give a heading or none, all alike: this one differs from line 1"
        );
        assert_eq!(
            message("truth,0,1,2,0\ntruth,1,1,2\n"),
            "log.csv:2: truth lines give a heading or none, all alike: this one differs from line 1"
        );
    }

    #[test]
    fn a_second_start_line_names_the_first() {
        assert_eq!(
            message("start,0,0,0,0\nstart,1,0,0,0\n"),
            "log.csv:2: start line already appeared on line 1"
        );
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
