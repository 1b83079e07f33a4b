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
//! | `ir_pair` | front, rear, association_range | -, -, m (version 5: two IR sensors read as paper 001's pair) |
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
//! range per beam; scan times do not decrease. Version 5: an `ir_pair`
//! names two one-beam sensors declared above it that form paper 001's pair
//! ([`IrPairRecord::sensor_problem`], [`IrPairRecord::pair_problem`]),
//! each sensor in one pair at most. Errors name the file, line, column and
//! field.

use std::path::{Path, PathBuf};

use crate::beam_sensor::{BeamSensor, MAX_BEAMS, MAX_MOUNT_OFFSET, MAX_RANGE_LIMIT};
use crate::decimal::push_f64;
use crate::error::{FieldProblem, RecordProblem, Result, excerpt};
use crate::ir_pair::IrPairRecord;
use crate::lines::Lines;
use crate::mrclam::{Groundtruth, Odometry, TruthPose};
use crate::noise::NoiseRecords;
use crate::scans::{MISSING, NO_RETURN, Scans};
use crate::sensor::SensorMount;
use crate::text::{Fields, TimeOrder, csv_records, existing, read_text};
use crate::wall::{MapPath, Wall};

mod beams;
#[cfg(test)]
mod tests;
mod write;

use beams::{beam_sensor, ir_pair, scan_ranges, wall};
pub use write::write;

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
    /// Beam sensors read as paper 001's IR pair (`ir_pair` lines), in file
    /// order (version 5).
    pub ir_pairs: Vec<IrPairRecord>,
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
                     truth, wall, map, beam_sensor, scan, ir_pair";

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
            "ir_pair" => {
                let p = ir_pair(&mut f, &log.beam_sensors, &log.ir_pairs, &lines.ir_pairs)?;
                f.end(4)?;
                log.ir_pairs.push(p);
                lines.ir_pairs.push(line);
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
