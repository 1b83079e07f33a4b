//! Locus's own log format: one comma-separated text file (plain or
//! xz-compressed) holding a robot's odometry, landmark measurements, an
//! optional ground truth and the landmark map. The format is specified in
//! `docs/log-format.md`; in short, each data line starts with its kind:
//!
//! | kind | fields | units |
//! |---|---|---|
//! | `sensor` | x, y, yaw | m, m, rad (robot frame) |
//! | `noise` | name, value | `q_v` m^2/s, `q_omega` rad^2/s, `sigma_range` m, `sigma_bearing` rad, `sigma_beam` m |
//! | `landmark` | id, x, y | -, m, m |
//! | `start` | t, x, y, theta | s, m, m, rad |
//! | `odometry` | t, v, omega | s, m/s, rad/s |
//! | `measurement` | t, id, range, bearing | s, -, m (>= 0), rad |
//! | `range` | t, id, range | s, -, m (>= 0) (version 3: range only) |
//! | `truth` | t, x, y, theta or t, x, y | s, m, m, rad (version 3: theta optional) |
//! | `wall` | x1, y1, x2, y2 | m (version 4) |
//! | `map` | path | relative to the log's directory (version 4) |
//! | `beam_sensor` | id, x, y, yaw, min_range, max_range, angle_0, angle_step, count | -, m, m, rad, m, m, rad, rad, - (version 4) |
//! | `scan` | t, id, r_1 ... r_count | s, -, m or `max` or `-` (version 4) |
//!
//! Lines starting with `#` and blank lines are skipped. Odometry and truth
//! times must not decrease; truth lines all give a heading or none;
//! measurements (`measurement` and `range` lines) are listed in the order
//! the robot **received** them, so their times may go back (a late measurement);
//! landmark ids are unique; `start` and `sensor` appear at most once, and
//! each noise name at most once. Measurements are taken by the sensor of the
//! `sensor` line (at the robot's centre, along its heading, if there is
//! none). Version 4: walls and at most one `map` line; beam sensor ids are
//! unique, a `scan` names a beam sensor declared above it and gives one
//! range per beam; scan times do not decrease. Errors name the file, line,
//! column and field.

use std::path::{Path, PathBuf};

use crate::beam_sensor::{BeamSensor, MAX_BEAMS, MAX_MOUNT_OFFSET, MAX_RANGE_LIMIT};
use crate::decimal::push_f64;
use crate::error::{FieldProblem, RecordProblem, Result, excerpt};
use crate::lines::Lines;
use crate::mrclam::{Groundtruth, Odometry, TruthPose};
use crate::noise::NoiseRecords;
use crate::scans::{MISSING, NO_RETURN, Scans};
use crate::sensor::SensorMount;
use crate::text::{Fields, TimeOrder, csv_records, existing, read_text};
use crate::wall::{MapPath, Wall};

/// Largest coordinate of a wall a reader accepts, m (100 km, as the
/// replay's limit on a landmark's).
pub const MAX_COORDINATE: f64 = 1e5;

/// One turn, rad: the largest angle (mount yaw, first beam angle, angle
/// step) a reader accepts, in magnitude.
const TURN: f64 = core::f64::consts::TAU;

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
    /// Walls of the map (`wall` lines), in file order (version 4).
    pub walls: Vec<Wall>,
    /// The map file (`map` line), if given, as recorded (version 4); see
    /// [`MapPath::resolve`].
    pub map: Option<MapPath>,
    /// Beam sensors (`beam_sensor` lines), in file order (version 4).
    pub beam_sensors: Vec<BeamSensor>,
    /// Scans (`scan` lines), in file order, times not decreasing
    /// (version 4).
    pub scans: Scans,
}

impl LocusLog {
    /// The beam sensor of id `id`, if the log declares one.
    #[must_use]
    pub fn beam_sensor(&self, id: u32) -> Option<&BeamSensor> {
        self.beam_sensors.iter().find(|s| s.id == id)
    }
}

/// The kinds a line may start with.
const KINDS: &str = "one of sensor, noise, landmark, start, odometry, measurement, range, \
                     truth, wall, map, beam_sensor, scan";

/// The names a `noise` line may give.
const NOISE_NAMES: &str = "one of q_v, q_omega, sigma_range, sigma_bearing, sigma_beam";

/// What a repeated `noise` line is called in its error, by name (in the
/// order of [`NoiseRecords::ALL_NAMES`]).
const NOISE_WHAT: [&str; 5] = [
    "noise q_v",
    "noise q_omega",
    "noise sigma_range",
    "noise sigma_bearing",
    "noise sigma_beam",
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
    let mut scan_order = TimeOrder::new();
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
                let Some(k) = NoiseRecords::ALL_NAMES.iter().position(|n| *n == name) else {
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
            "wall" => {
                let w = wall(&mut f)?;
                f.end(5)?;
                log.walls.push(w);
                lines.walls.push(line);
            }
            "map" => {
                let text = f.next_text("path")?;
                let Some(path) = MapPath::new(text) else {
                    return Err(f.field_error(
                        "path",
                        FieldProblem::OutOfRange {
                            value: format!("{:?}", excerpt(text)),
                            expected: "a non-empty path",
                        },
                    ));
                };
                if let Some(first_line) = lines.map {
                    return Err(f.record_error(RecordProblem::DuplicateRecord {
                        what: "map line",
                        first_line,
                    }));
                }
                f.end(2)?;
                log.map = Some(path);
                lines.map = Some(line);
            }
            "beam_sensor" => {
                let s = beam_sensor(&mut f)?;
                if let Some(i) = log.beam_sensors.iter().position(|b| b.id == s.id) {
                    return Err(f.record_error(RecordProblem::Duplicate {
                        what: "beam sensor id",
                        value: s.id,
                        first_line: lines.beam_sensors[i],
                    }));
                }
                f.end(10)?;
                log.beam_sensors.push(s);
                lines.beam_sensors.push(line);
            }
            "scan" => {
                let time = f.f64("time")?;
                scan_order.check(&f, time)?;
                let id = f.u32("id")?;
                let Some(sensor) = log.beam_sensors.iter().find(|b| b.id == id) else {
                    return Err(f.field_error(
                        "id",
                        FieldProblem::OutOfRange {
                            value: id.to_string(),
                            expected: "the id of a beam_sensor line above this one",
                        },
                    ));
                };
                scan_ranges(&mut f, sensor, &mut log.scans)?;
                log.scans.close(time, id);
                lines.scans.push(line);
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

/// The next field as a finite number within `+-limit`.
fn within(
    f: &mut Fields<'_>,
    field: &'static str,
    limit: f64,
    expected: &'static str,
) -> Result<f64> {
    f.bounded(field, |v| v.abs() <= limit, expected)
}

/// The fields of a `wall` line after its kind.
fn wall(f: &mut Fields<'_>) -> Result<Wall> {
    const WITHIN: &str = "within +-1e5 m";
    let w = Wall {
        x1: within(f, "x1", MAX_COORDINATE, WITHIN)?,
        y1: within(f, "y1", MAX_COORDINATE, WITHIN)?,
        x2: within(f, "x2", MAX_COORDINATE, WITHIN)?,
        y2: within(f, "y2", MAX_COORDINATE, WITHIN)?,
    };
    if w.x1 == w.x2 && w.y1 == w.y2 {
        return Err(f.field_error(
            "y2",
            FieldProblem::OutOfRange {
                value: w.y2.to_string(),
                expected: "a second end apart from the first (a wall of non-zero length)",
            },
        ));
    }
    Ok(w)
}

/// The fields of a `beam_sensor` line after its kind.
fn beam_sensor(f: &mut Fields<'_>) -> Result<BeamSensor> {
    const OFFSET: &str = "within +-10 m of the robot's centre";
    const ANGLE: &str = "within one turn, +-2 pi rad";
    let id = f.u32("id")?;
    let mount = SensorMount {
        x: within(f, "x", MAX_MOUNT_OFFSET, OFFSET)?,
        y: within(f, "y", MAX_MOUNT_OFFSET, OFFSET)?,
        yaw: within(f, "yaw", TURN, ANGLE)?,
    };
    let min_range = f.bounded(
        "min_range",
        |v| (0.0..MAX_RANGE_LIMIT).contains(&v),
        ">= 0 and < 1e5 m",
    )?;
    let max_range = f.bounded(
        "max_range",
        |v| v > min_range && v <= MAX_RANGE_LIMIT,
        "> min_range and <= 1e5 m",
    )?;
    let angle_0 = within(f, "angle_0", TURN, ANGLE)?;
    let angle_step = within(f, "angle_step", TURN, ANGLE)?;
    let text = f.next_text("count")?;
    let count = match text.parse::<u32>() {
        Ok(n) if (1..=MAX_BEAMS).contains(&n) => n,
        Ok(n) => {
            return Err(f.field_error(
                "count",
                FieldProblem::OutOfRange {
                    value: n.to_string(),
                    expected: "1 to 100000 beams",
                },
            ));
        }
        Err(_) => {
            return Err(f.field_error("count", FieldProblem::NotAnInteger(excerpt(text))));
        }
    };
    if angle_step.abs() * f64::from(count - 1) > TURN * (1.0 + 1e-12) {
        // The column of the step, two fields back.
        return Err(f.field_error(
            "angle_step",
            FieldProblem::OutOfRange {
                value: angle_step.to_string(),
                expected: "beams within one turn: |angle_step| (count - 1) <= 2 pi rad",
            },
        ));
    }
    Ok(BeamSensor {
        id,
        mount,
        min_range,
        max_range,
        angle_0,
        angle_step,
        count,
    })
}

/// Reads the ranges of a `scan` line (after its id) into `scans`: exactly
/// `sensor.count` of them, each a number `>= 0`, `max` or `-`, stored as
/// [`BeamSensor::classify`] says.
fn scan_ranges(f: &mut Fields<'_>, sensor: &BeamSensor, scans: &mut Scans) -> Result<()> {
    let count = |found| FieldProblem::BeamCount {
        found,
        expected: sensor.count,
        sensor: sensor.id,
    };
    for k in 0..sensor.count as usize {
        let Some(text) = f.optional_text() else {
            return Err(f.field_error("range", count(k)));
        };
        let stored = match text {
            "max" => NO_RETURN,
            "-" => MISSING,
            _ => {
                // Checked as f64 (finite, >= 0), stored as the f32 nearest
                // the text (not rounded twice).
                let v = match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => v,
                    Ok(_) => {
                        return Err(f.field_error("range", FieldProblem::NotFinite(excerpt(text))));
                    }
                    Err(_) => {
                        return Err(f.field_error("range", FieldProblem::NotANumber(excerpt(text))));
                    }
                };
                if v < 0.0 {
                    return Err(f.field_error(
                        "range",
                        FieldProblem::OutOfRange {
                            value: v.to_string(),
                            expected: ">= 0, max or -",
                        },
                    ));
                }
                sensor.classify(text.parse::<f32>().unwrap_or(NO_RETURN))
            }
        };
        scans.push_range(stored);
    }
    if f.optional_text().is_some() {
        let found = sensor.count as usize + 1 + f.count_rest();
        return Err(f.field_error("range", count(found)));
    }
    Ok(())
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
/// same value, so `parse(write(log)) == log`). Scan ranges are written as
/// the shortest text that reads back to the same `f32`, `max` for
/// [`NO_RETURN`] and `-` for any other non-finite value; the round trip
/// holds for a log whose scans name its beam sensors, with as many ranges
/// as beams, each [`NO_RETURN`], [`MISSING`] or within the sensor's limits
/// (what [`parse`] gives), and whose map path a [`MapPath`] accepted.
#[must_use]
pub fn write(log: &LocusLog) -> String {
    use core::fmt::Write as _;
    let lines = 1 + log.landmarks.len() + log.truth.poses().len() + log.odometry.len();
    let mut s = String::with_capacity(64 * (lines + log.measurements.len()));
    s.reserve(12 * log.scans.ranges_len() + 48 * log.scans.len());
    s.push_str("# Locus log v4 (docs/log-format.md); SI units\n");
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
    for w in &log.walls {
        record(&mut s, "wall", &[w.x1, w.y1, w.x2, w.y2]);
    }
    if let Some(m) = &log.map {
        s.push_str("map,");
        s.push_str(m.as_str());
        s.push('\n');
    }
    for b in &log.beam_sensors {
        let _ = write!(s, "beam_sensor,{}", b.id);
        let m = b.mount;
        let values = [
            m.x,
            m.y,
            m.yaw,
            b.min_range,
            b.max_range,
            b.angle_0,
            b.angle_step,
        ];
        for v in values {
            s.push(',');
            push_f64(&mut s, v);
        }
        let _ = writeln!(s, ",{}", b.count);
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
    let mut buffer = ryu::Buffer::new();
    for scan in log.scans.iter() {
        s.push_str("scan,");
        push_f64(&mut s, scan.time);
        let _ = write!(s, ",{}", scan.sensor);
        for r in scan.ranges {
            s.push(',');
            if *r == NO_RETURN {
                s.push_str("max");
            } else if r.is_finite() {
                let text = buffer.format_finite(*r);
                s.push_str(text.strip_suffix(".0").unwrap_or(text));
            } else {
                s.push('-');
            }
        }
        s.push('\n');
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
        assert!(written.starts_with("# Locus log v4"), "{written}");
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
             one of q_v, q_omega, sigma_range, sigma_bearing, sigma_beam"
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

    /// A version 4 log: a map, two beam sensors (a lidar and an IR
    /// sensor) and their scans.
    const V4: &str = "# Locus log v4\nwall,0,-1,4,-1\nwall, 4 ,-1,4,3\nmap,maps/arena.yaml\n\
                      beam_sensor,0,0.1,0,0,0.05,8,-1.5707963267948966,0.7853981633974483,5\n\
                      beam_sensor,7,0,0.05,1.5707963267948966,0.1,0.8,0,0,1\n\
                      noise,sigma_beam,0.02\nodometry,0,0.1,0\n\
                      scan,0.1,0,1.5,max,-,2.25,8\nscan,0.1,7,0.5\nscan,0.2,7,0.01\n\
                      scan,0.3,0,9,0.04,1e-1,3.0000003,7.99\n";

    #[test]
    fn version_4_records_read_and_round_trip() {
        let (log, lines) = parse_with_lines(V4, p()).unwrap();
        assert_eq!(
            log.walls,
            [
                Wall {
                    x1: 0.0,
                    y1: -1.0,
                    x2: 4.0,
                    y2: -1.0
                },
                Wall {
                    x1: 4.0,
                    y1: -1.0,
                    x2: 4.0,
                    y2: 3.0
                }
            ]
        );
        assert_eq!(log.map.as_ref().unwrap().as_str(), "maps/arena.yaml");
        assert_eq!(lines.walls, [2, 3]);
        assert_eq!(lines.map, Some(4));
        assert_eq!(lines.beam_sensors, [5, 6]);
        assert_eq!(lines.scans, [9, 10, 11, 12]);
        assert_eq!(lines.noise[4], Some(7));
        assert_eq!(log.noise.sigma_beam, Some(0.02));
        let lidar = log.beam_sensor(0).unwrap();
        assert_eq!(lidar.count, 5);
        assert_eq!(lidar.mount.x, 0.1);
        assert!((lidar.angle(4) - core::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert_eq!(
            log.beam_sensor(7).unwrap().mount.yaw,
            core::f64::consts::FRAC_PI_2
        );
        assert!(log.beam_sensor(1).is_none());
        assert_eq!(log.scans.len(), 4);
        let first = log.scans.get(0).unwrap();
        assert_eq!((first.time, first.sensor), (0.1, 0));
        assert_eq!(first.ranges[0], 1.5);
        assert_eq!(first.ranges[1], NO_RETURN);
        assert!(first.ranges[2].is_nan());
        assert_eq!(
            first.ranges[4], NO_RETURN,
            "a reading at max_range is no return"
        );
        assert!(
            log.scans.get(2).unwrap().ranges[0].is_nan(),
            "a reading below min_range is missing"
        );
        let last = log.scans.get(3).unwrap();
        assert_eq!(last.ranges[0], NO_RETURN, "beyond max_range");
        assert!(last.ranges[1].is_nan(), "below min_range");
        assert_eq!(last.ranges[2], 0.1);
        assert_eq!(last.ranges[3], 3.000_000_3_f32);
        assert_eq!(last.ranges[4], 7.99_f32);
        let written = write(&log);
        assert!(written.contains("\nwall,4,-1,4,3\n"), "{written}");
        assert!(written.contains("\nmap,maps/arena.yaml\n"), "{written}");
        assert!(
            written.contains("\nbeam_sensor,7,0,0.05,1.5707963267948966,0.1,0.8,0,0,1\n"),
            "{written}"
        );
        assert!(
            written.contains("\nscan,0.1,0,1.5,max,-,2.25,max\n"),
            "{written}"
        );
        assert!(
            written.contains("\nscan,0.3,0,max,-,0.1,3.0000002,7.99\n"),
            "{written}"
        );
        assert!(written.contains("\nnoise,sigma_beam,0.02\n"), "{written}");
        assert_eq!(parse(&written, p()).unwrap(), log);
        assert_eq!(write(&parse(&written, p()).unwrap()), written);
    }

    #[test]
    fn malformed_version_4_lines_name_the_line_and_field() {
        let sensor = "beam_sensor,0,0,0,0,0.1,4,0,0.1,3\n";
        let with = |line: &str| message(&format!("{sensor}{line}"));
        assert_eq!(
            with("scan,1,0,1,2\n"),
            "log.csv:2: field \"range\" (column 6): 2 ranges, beam sensor 0 has 3 beams"
        );
        assert_eq!(
            with("scan,1,0,1,2,3,4,5\n"),
            "log.csv:2: field \"range\" (column 7): 5 ranges, beam sensor 0 has 3 beams"
        );
        assert_eq!(
            with("scan,1,0,1,-2,3\n"),
            "log.csv:2: field \"range\" (column 5): -2 is out of range: >= 0, max or -"
        );
        assert_eq!(
            with("scan,1,0,1,inf,3\n"),
            "log.csv:2: field \"range\" (column 5): \"inf\" is not finite"
        );
        assert_eq!(
            with("scan,1,0,1,,3\n"),
            "log.csv:2: field \"range\" (column 5): \"\" is not a number"
        );
        assert_eq!(
            with("scan,1,3,1,2,3\n"),
            "log.csv:2: field \"id\" (column 3): 3 is out of range: \
             the id of a beam_sensor line above this one"
        );
        assert_eq!(
            message("scan,1,0,1,2,3\nbeam_sensor,0,0,0,0,0.1,4,0,0.1,3\n"),
            "log.csv:1: field \"id\" (column 3): 0 is out of range: \
             the id of a beam_sensor line above this one"
        );
        assert!(
            with("scan,2,0,1,2,3\nscan,1,0,1,2,3\n")
                .starts_with("log.csv:3: time 1 s is earlier than the previous record's 2 s"),
        );
        assert_eq!(
            with("beam_sensor,0,0,0,0,0,1,0,0,1\n"),
            "log.csv:2: beam sensor id 0 already appeared on line 1"
        );
        for (line, field, column, why) in [
            (
                "beam_sensor,0,11,0,0,0,1,0,0,1",
                "x",
                3,
                "11 is out of range: within +-10 m of the robot's centre",
            ),
            (
                "beam_sensor,0,0,0,7,0,1,0,0,1",
                "yaw",
                5,
                "7 is out of range: within one turn, +-2 pi rad",
            ),
            (
                "beam_sensor,0,0,0,0,-1,1,0,0,1",
                "min_range",
                6,
                "-1 is out of range: >= 0 and < 1e5 m",
            ),
            (
                "beam_sensor,0,0,0,0,2,1,0,0,1",
                "max_range",
                7,
                "1 is out of range: > min_range and <= 1e5 m",
            ),
            (
                "beam_sensor,0,0,0,0,0,1e6,0,0,1",
                "max_range",
                7,
                "1000000 is out of range: > min_range and <= 1e5 m",
            ),
            (
                "beam_sensor,0,0,0,0,0,1,0,0,0",
                "count",
                10,
                "0 is out of range: 1 to 100000 beams",
            ),
            (
                "beam_sensor,0,0,0,0,0,1,0,0,100001",
                "count",
                10,
                "100001 is out of range: 1 to 100000 beams",
            ),
            (
                "beam_sensor,0,0,0,0,0,1,0,0,-3",
                "count",
                10,
                "\"-3\" is not a non-negative integer",
            ),
            (
                "beam_sensor,0,0,0,0,0,1,0,0.1,100",
                "angle_step",
                10,
                "0.1 is out of range: beams within one turn: |angle_step| (count - 1) <= 2 pi rad",
            ),
            (
                "wall,0,0,1e6,0",
                "x2",
                4,
                "1000000 is out of range: within +-1e5 m",
            ),
            (
                "wall,1,2,1,2",
                "y2",
                5,
                "2 is out of range: a second end apart from the first (a wall of non-zero length)",
            ),
            ("map,", "path", 2, "\"\" is out of range: a non-empty path"),
            ("noise,sigma_beam,0", "value", 3, "0 is out of range: > 0"),
        ] {
            assert_eq!(
                message(&format!("{line}\n")),
                format!("log.csv:1: field \"{field}\" (column {column}): {why}"),
                "{line}"
            );
        }
        assert_eq!(
            message("map,a.yaml\nmap,b.yaml\n"),
            "log.csv:2: map line already appeared on line 1"
        );
        assert_eq!(
            message("map,a,b.yaml\n"),
            "log.csv:1: 3 fields, the format has 2"
        );
        assert_eq!(
            message("wall,0,0,1,1,2\n"),
            "log.csv:1: 6 fields, the format has 5"
        );
        assert_eq!(
            message("beam_sensor,0,0,0,0,0,1,0,0,1,9\n"),
            "log.csv:1: 11 fields, the format has 10"
        );
    }

    #[test]
    fn a_lidar_scan_of_1081_beams_reads_within_the_line_bound() {
        let mut text = String::from(
            "beam_sensor,3,0,0,0,0.02,30,-2.356194490192345,0.004363323129985824,1081\nscan,5",
        );
        text.push_str(",3");
        for k in 0..1081 {
            text.push_str(if k % 100 == 0 { ",max" } else { ",12.345678" });
        }
        text.push('\n');
        let log = parse(&text, p()).unwrap();
        assert_eq!(log.scans.ranges_len(), 1081);
        assert!(text.len() < crate::MAX_LINE);
        assert_eq!(parse(&write(&log), p()).unwrap(), log);
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
