//! The UTIAS Multi-Robot Cooperative Localization and Mapping dataset
//! (MRCLAM): K. Y. K. Leung, Y. Halpern, T. D. Barfoot, H. H. T. Liu, IJRR
//! 30(8):969-974, 2011.
//!
//! Five differential-drive robots (subjects 1-5) and 15 barcoded landmarks
//! (subjects 6-20) in a 15 m x 8 m indoor area. Per dataset directory:
//!
//! | file | record | columns |
//! |---|---|---|
//! | `Barcodes.dat` | [`BarcodeEntry`] | subject, barcode |
//! | `Landmark_Groundtruth.dat` | [`SurveyedLandmark`] | subject, x \[m\], y \[m\], x std \[m\], y std \[m\] |
//! | `RobotN_Groundtruth.dat` | [`TruthPose`] | t \[s\], x \[m\], y \[m\], theta \[rad\] (Vicon) |
//! | `RobotN_Odometry.dat` | [`Odometry`] | t \[s\], v \[m/s\], omega \[rad/s\] (commanded) |
//! | `RobotN_Measurement.dat` | [`Measurement`] | t \[s\], barcode, range \[m\], bearing \[rad\] |
//!
//! Each file may be plain or xz-compressed (`NAME.dat.xz`, decompressed by
//! liblzma); lines starting with `#` are headers. Times are
//! UNIX seconds (about 1.25e9, millisecond resolution: `f64` keeps them to
//! about 2e-7 s). Poses are in the Vicon world frame; bearings are from the
//! robot's heading, counter-clockwise positive. The camera "is placed to align
//! with the robot body frame" (dataset web page): take the sensor at the
//! robot's centre.
//!
//! The measurement files' header says "Subject #", but the column holds the
//! **barcode**: map it through [`Barcodes`] ([`Sightings::split`] does that and
//! separates robot-to-robot sightings and unknown barcodes from landmark
//! sightings).
//!
//! Checks while reading: every field present and well-formed (finite numbers,
//! non-negative integers, ranges and standard deviations `>= 0`), no extra
//! fields, times never decreasing (repeated times are allowed: the odometry
//! has some), subjects and barcodes unique in `Barcodes.dat`, subjects unique
//! in `Landmark_Groundtruth.dat`. Errors name the file, line and field.

use core::ops::RangeInclusive;
use std::path::{Path, PathBuf};

use crate::error::{Error, RecordProblem, Result};
use crate::text::{Fields, TimeOrder, read_text, records, resolve};
pub use crate::truth_cursor::TruthCursor;

/// The robots' subject numbers (and the `N` of the `RobotN_*` files).
pub const ROBOTS: RangeInclusive<u32> = 1..=5;

/// The landmarks' subject numbers.
pub const LANDMARKS: RangeInclusive<u32> = 6..=20;

/// One line of `Barcodes.dat`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BarcodeEntry {
    /// Subject number (1-5 robots, 6-20 landmarks).
    pub subject: u32,
    /// The barcode that identifies the subject in the measurement files.
    pub barcode: u32,
}

/// The barcode <-> subject table of `Barcodes.dat`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Barcodes {
    entries: Vec<BarcodeEntry>,
}

/// What a measured barcode refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// A robot (subject in [`ROBOTS`]).
    Robot(u32),
    /// Any other known subject: a landmark (subject in [`LANDMARKS`] in the
    /// published datasets).
    Landmark(u32),
    /// A barcode absent from `Barcodes.dat` (a misread: dataset 6 has a few).
    Unknown,
}

impl Barcodes {
    /// A table from its entries (subjects and barcodes assumed unique).
    pub fn new(entries: Vec<BarcodeEntry>) -> Self {
        Self { entries }
    }

    /// The entries, in file order.
    pub fn entries(&self) -> &[BarcodeEntry] {
        &self.entries
    }

    /// The subject a barcode identifies.
    pub fn subject(&self, barcode: u32) -> Option<u32> {
        self.entries
            .iter()
            .find(|e| e.barcode == barcode)
            .map(|e| e.subject)
    }

    /// The barcode of a subject.
    pub fn barcode(&self, subject: u32) -> Option<u32> {
        self.entries
            .iter()
            .find(|e| e.subject == subject)
            .map(|e| e.barcode)
    }

    /// What a measured barcode refers to.
    pub fn classify(&self, barcode: u32) -> Target {
        match self.subject(barcode) {
            Some(s) if ROBOTS.contains(&s) => Target::Robot(s),
            Some(s) => Target::Landmark(s),
            None => Target::Unknown,
        }
    }
}

/// One line of `Landmark_Groundtruth.dat`: a landmark's surveyed position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurveyedLandmark {
    /// Subject number (6-20).
    pub subject: u32,
    /// x in the world frame, m.
    pub x: f64,
    /// y in the world frame, m.
    pub y: f64,
    /// Standard deviation of x, m.
    pub x_std: f64,
    /// Standard deviation of y, m.
    pub y_std: f64,
}

/// A ground-truth pose (one line of `RobotN_Groundtruth.dat`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthPose {
    /// Time, s (UNIX).
    pub time: f64,
    /// x in the world frame, m.
    pub x: f64,
    /// y in the world frame, m.
    pub y: f64,
    /// Heading from the world x axis, counter-clockwise, rad (as recorded:
    /// within (-pi, pi]). In a track of positions only
    /// ([`Groundtruth::positions`]) its stored value is 0 and unused, and
    /// the track's lookups return NaN ("no heading").
    pub theta: f64,
}

/// One line of `RobotN_Odometry.dat`: **commanded** velocities, not encoder
/// readings, held until the next record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Odometry {
    /// Time, s (UNIX).
    pub time: f64,
    /// Forward speed along the robot's x axis, m/s.
    pub v: f64,
    /// Turn rate, counter-clockwise positive, rad/s.
    pub omega: f64,
}

/// One line of `RobotN_Measurement.dat`, as recorded (barcode not mapped).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Time, s (UNIX).
    pub time: f64,
    /// The barcode read (map it with [`Barcodes`]).
    pub barcode: u32,
    /// Range from the camera to the barcode, m (>= 0).
    pub range: f64,
    /// Bearing from the robot's heading, counter-clockwise positive, rad.
    pub bearing: f64,
}

/// A measurement whose barcode has been mapped to a subject.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubjectSighting {
    /// Time, s (UNIX).
    pub time: f64,
    /// The subject seen.
    pub subject: u32,
    /// Range, m.
    pub range: f64,
    /// Bearing from the robot's heading, counter-clockwise positive, rad.
    pub bearing: f64,
}

/// A robot's measurements sorted by what they saw.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sightings {
    /// Sightings of landmarks (known subjects outside [`ROBOTS`]).
    pub landmarks: Vec<SubjectSighting>,
    /// Sightings of other robots (subjects in [`ROBOTS`]).
    pub robots: Vec<SubjectSighting>,
    /// Measurements whose barcode is not in `Barcodes.dat`.
    pub unknown: Vec<Measurement>,
}

impl Sightings {
    /// Maps each measurement's barcode to its subject and sorts it into
    /// landmark sightings, robot sightings and unknown barcodes (order kept).
    pub fn split(measurements: &[Measurement], barcodes: &Barcodes) -> Self {
        let mut out = Self::default();
        for m in measurements {
            let sighting = |subject| SubjectSighting {
                time: m.time,
                subject,
                range: m.range,
                bearing: m.bearing,
            };
            match barcodes.classify(m.barcode) {
                Target::Landmark(s) => out.landmarks.push(sighting(s)),
                Target::Robot(s) => out.robots.push(sighting(s)),
                Target::Unknown => out.unknown.push(*m),
            }
        }
        out
    }
}

/// A robot's ground-truth track: poses in non-decreasing time order, with
/// a heading (MRCLAM's Vicon) or positions only (a tracker that gives no
/// heading, such as the UWB dataset's).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Groundtruth {
    poses: Vec<TruthPose>,
    /// Whether the track gives positions only (its poses' `theta` unused).
    position_only: bool,
}

impl Groundtruth {
    /// A track from poses, which must be in non-decreasing time order (as
    /// the readers guarantee); returns `None` otherwise.
    pub fn new(poses: Vec<TruthPose>) -> Option<Self> {
        poses
            .windows(2)
            .all(|w| w[0].time <= w[1].time)
            .then_some(Self {
                poses,
                position_only: false,
            })
    }

    /// A track of positions only, with no heading: as [`Groundtruth::new`]
    /// (times must not decrease, else `None`); each pose's `theta` is set to
    /// 0 and unused, and [`Groundtruth::pose_at`] returns NaN for it.
    pub fn positions(mut poses: Vec<TruthPose>) -> Option<Self> {
        for p in &mut poses {
            p.theta = 0.0;
        }
        let mut track = Self::new(poses)?;
        track.position_only = !track.poses.is_empty();
        Some(track)
    }

    /// Whether the track has a heading (false for a track of positions
    /// only; true for an empty one).
    #[must_use]
    pub fn has_heading(&self) -> bool {
        !self.position_only
    }

    /// The poses (their `theta` is 0 and unused if the track has no
    /// heading, [`Groundtruth::has_heading`]).
    pub fn poses(&self) -> &[TruthPose] {
        &self.poses
    }

    /// The track with every time moved by `seconds` (a truth whose clock
    /// runs `-seconds` behind the robot's put on the robot's).
    #[must_use]
    pub fn shifted(&self, seconds: f64) -> Self {
        let mut track = self.clone();
        for p in &mut track.poses {
            p.time += seconds;
        }
        track
    }

    /// First and last time, s; `None` if empty.
    pub fn span(&self) -> Option<(f64, f64)> {
        Some((self.poses.first()?.time, self.poses.last()?.time))
    }

    /// The pose at time `t` (s), linearly interpolated between the two
    /// samples around `t` (theta along the shorter way round, result wrapped
    /// to (-pi, pi]). `None` if `t` is outside the track or the two samples
    /// are more than `max_gap` seconds apart (a gap in the coverage). A `t`
    /// equal to a sample's time returns that sample. A track with no
    /// heading gives theta NaN.
    pub fn pose_at(&self, t: f64, max_gap: f64) -> Option<TruthPose> {
        interpolate(
            &self.poses,
            self.poses.partition_point(|p| p.time <= t),
            t,
            max_gap,
        )
        .map(|p| self.headed(p))
    }

    /// `p` with theta NaN if the track has no heading.
    pub(crate) fn headed(&self, mut p: TruthPose) -> TruthPose {
        if self.position_only {
            p.theta = f64::NAN;
        }
        p
    }

    /// A cursor for looking poses up at times that mostly do not decrease
    /// (a replay's events): [`TruthCursor::pose_at`] returns what
    /// [`Groundtruth::pose_at`] does, walking on from the previous lookup
    /// instead of searching the whole track each time.
    #[must_use]
    pub fn cursor(&self) -> TruthCursor<'_> {
        TruthCursor::new(self)
    }
}

/// The pose at `t` (s) from `poses` (non-decreasing times) and `after`, the
/// index of the first pose whose time is `> t` (`poses.len()` if none):
/// [`Groundtruth::pose_at`]'s interpolation, shared with [`TruthCursor`].
pub(crate) fn interpolate(
    poses: &[TruthPose],
    after: usize,
    t: f64,
    max_gap: f64,
) -> Option<TruthPose> {
    let a = *poses.get(after.checked_sub(1)?)?;
    if a.time == t {
        return Some(a);
    }
    let b = *poses.get(after)?;
    let dt = b.time - a.time;
    if dt > max_gap {
        return None;
    }
    let w = (t - a.time) / dt;
    Some(TruthPose {
        time: t,
        x: a.x + w * (b.x - a.x),
        y: a.y + w * (b.y - a.y),
        theta: wrap(a.theta + w * wrap(b.theta - a.theta)),
    })
}

/// Wraps an angle (rad) to (-pi, pi].
fn wrap(a: f64) -> f64 {
    use core::f64::consts::PI;
    let r = a - 2.0 * PI * ((a + PI) / (2.0 * PI)).floor();
    if r <= -PI { r + 2.0 * PI } else { r }
}

/// Parses the text of `Barcodes.dat`; `path` names it in errors.
pub fn parse_barcodes(text: &str, path: &Path) -> Result<Barcodes> {
    let mut entries: Vec<(usize, BarcodeEntry)> = Vec::new();
    for mut f in records(text, path) {
        let entry = BarcodeEntry {
            subject: f.u32("subject")?,
            barcode: f.u32("barcode")?,
        };
        for (first_line, e) in &entries {
            let dup = if e.subject == entry.subject {
                Some(("subject", entry.subject))
            } else if e.barcode == entry.barcode {
                Some(("barcode", entry.barcode))
            } else {
                None
            };
            if let Some((what, value)) = dup {
                return Err(f.record_error(RecordProblem::Duplicate {
                    what,
                    value,
                    first_line: *first_line,
                }));
            }
        }
        let line = f.line;
        f.end(2)?;
        entries.push((line, entry));
    }
    Ok(Barcodes::new(entries.into_iter().map(|(_, e)| e).collect()))
}

/// Parses the text of `Landmark_Groundtruth.dat`; `path` names it in errors.
pub fn parse_landmarks(text: &str, path: &Path) -> Result<Vec<SurveyedLandmark>> {
    let mut out: Vec<(usize, SurveyedLandmark)> = Vec::new();
    for mut f in records(text, path) {
        let lm = SurveyedLandmark {
            subject: f.u32("subject")?,
            x: f.f64("x")?,
            y: f.f64("y")?,
            x_std: f.non_negative("x std")?,
            y_std: f.non_negative("y std")?,
        };
        if let Some((first_line, _)) = out.iter().find(|(_, l)| l.subject == lm.subject) {
            return Err(f.record_error(RecordProblem::Duplicate {
                what: "subject",
                value: lm.subject,
                first_line: *first_line,
            }));
        }
        let line = f.line;
        f.end(5)?;
        out.push((line, lm));
    }
    Ok(out.into_iter().map(|(_, l)| l).collect())
}

/// Parses time-stamped records: the time first, then `rest`, then the end of
/// the line (`columns` in all); times must not decrease.
fn parse_timed<T>(
    text: &str,
    path: &Path,
    columns: usize,
    mut rest: impl FnMut(f64, &mut Fields<'_>) -> Result<T>,
) -> Result<Vec<T>> {
    let mut out = Vec::with_capacity(text.len() / 32);
    let mut order = TimeOrder::new();
    for mut f in records(text, path) {
        let time = f.f64("time")?;
        let record = rest(time, &mut f)?;
        order.check(&f, time)?;
        f.end(columns)?;
        out.push(record);
    }
    Ok(out)
}

/// Parses the text of `RobotN_Groundtruth.dat`; `path` names it in errors.
pub fn parse_groundtruth(text: &str, path: &Path) -> Result<Groundtruth> {
    let poses = parse_timed(text, path, 4, |time, f| {
        Ok(TruthPose {
            time,
            x: f.f64("x")?,
            y: f.f64("y")?,
            theta: f.f64("theta")?,
        })
    })?;
    Ok(Groundtruth {
        poses,
        position_only: false,
    })
}

/// Parses the text of `RobotN_Odometry.dat`; `path` names it in errors.
pub fn parse_odometry(text: &str, path: &Path) -> Result<Vec<Odometry>> {
    parse_timed(text, path, 3, |time, f| {
        Ok(Odometry {
            time,
            v: f.f64("v")?,
            omega: f.f64("omega")?,
        })
    })
}

/// Parses the text of `RobotN_Measurement.dat`; `path` names it in errors.
pub fn parse_measurements(text: &str, path: &Path) -> Result<Vec<Measurement>> {
    parse_timed(text, path, 4, |time, f| {
        Ok(Measurement {
            time,
            barcode: f.u32("barcode")?,
            range: f.non_negative("range")?,
            bearing: f.f64("bearing")?,
        })
    })
}

/// Reads `Barcodes.dat` (plain or xz, by extension or content).
pub fn read_barcodes(path: &Path) -> Result<Barcodes> {
    parse_barcodes(&read_text(path)?, path)
}

/// Reads `Landmark_Groundtruth.dat` (plain or xz).
pub fn read_landmarks(path: &Path) -> Result<Vec<SurveyedLandmark>> {
    parse_landmarks(&read_text(path)?, path)
}

/// Reads a `RobotN_Groundtruth.dat` (plain or xz).
pub fn read_groundtruth(path: &Path) -> Result<Groundtruth> {
    parse_groundtruth(&read_text(path)?, path)
}

/// Reads a `RobotN_Odometry.dat` (plain or xz).
pub fn read_odometry(path: &Path) -> Result<Vec<Odometry>> {
    parse_odometry(&read_text(path)?, path)
}

/// Reads a `RobotN_Measurement.dat` (plain or xz).
pub fn read_measurements(path: &Path) -> Result<Vec<Measurement>> {
    parse_measurements(&read_text(path)?, path)
}

/// One MRCLAM dataset directory: the barcode table and the landmark map,
/// read when opened; the robots' logs read on demand.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    dir: PathBuf,
    /// The barcode <-> subject table.
    pub barcodes: Barcodes,
    /// The landmarks' surveyed positions.
    pub landmarks: Vec<SurveyedLandmark>,
}

impl Dataset {
    /// Opens a dataset directory (e.g. `.../MRCLAM_Dataset6`): reads
    /// `Barcodes.dat` and `Landmark_Groundtruth.dat` (each plain or `.xz`).
    pub fn open(dir: impl AsRef<Path>) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        let barcodes = read_barcodes(&resolve(&dir, "Barcodes.dat")?)?;
        let landmarks = read_landmarks(&resolve(&dir, "Landmark_Groundtruth.dat")?)?;
        Ok(Self {
            dir,
            barcodes,
            landmarks,
        })
    }

    /// The dataset's directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// A landmark's surveyed position by subject number.
    pub fn landmark(&self, subject: u32) -> Option<&SurveyedLandmark> {
        self.landmarks.iter().find(|l| l.subject == subject)
    }

    fn robot_file(&self, robot: u32, kind: &str) -> Result<PathBuf> {
        if !ROBOTS.contains(&robot) {
            return Err(Error::NoSuchRobot {
                robot,
                first: *ROBOTS.start(),
                last: *ROBOTS.end(),
            });
        }
        resolve(&self.dir, &format!("Robot{robot}_{kind}.dat"))
    }

    /// Robot `robot`'s (1-5) ground truth.
    pub fn groundtruth(&self, robot: u32) -> Result<Groundtruth> {
        read_groundtruth(&self.robot_file(robot, "Groundtruth")?)
    }

    /// Robot `robot`'s (1-5) odometry (commanded velocities).
    pub fn odometry(&self, robot: u32) -> Result<Vec<Odometry>> {
        read_odometry(&self.robot_file(robot, "Odometry")?)
    }

    /// Robot `robot`'s (1-5) measurements, barcodes as recorded.
    pub fn measurements(&self, robot: u32) -> Result<Vec<Measurement>> {
        read_measurements(&self.robot_file(robot, "Measurement")?)
    }

    /// Robot `robot`'s (1-5) measurements, mapped and split
    /// ([`Sightings::split`]).
    pub fn sightings(&self, robot: u32) -> Result<Sightings> {
        Ok(Sightings::split(&self.measurements(robot)?, &self.barcodes))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track() -> Groundtruth {
        let p = |time, x, theta| TruthPose {
            time,
            x,
            y: 0.0,
            theta,
        };
        Groundtruth::new(vec![p(0.0, 0.0, 3.0), p(0.1, 1.0, -3.0), p(0.5, 2.0, 0.0)]).unwrap()
    }

    #[test]
    fn interpolation_wraps_theta_and_respects_gaps() {
        let g = track();
        let p = g.pose_at(0.05, 0.1).unwrap();
        assert!((p.x - 0.5).abs() < 1e-12);
        // Halfway from 3.0 to -3.0 the short way round: +-pi.
        assert!((p.theta.abs() - core::f64::consts::PI).abs() < 1e-12);
        assert!(g.pose_at(0.3, 0.1).is_none(), "0.4 s gap");
        assert!(g.pose_at(0.3, 0.5).is_some());
        assert_eq!(g.pose_at(0.5, 0.1).unwrap().x, 2.0);
        assert_eq!(g.pose_at(0.0, 0.1).unwrap().x, 0.0);
        assert!(g.pose_at(-0.01, 0.1).is_none());
        assert!(g.pose_at(0.51, 1.0).is_none());
        assert!(Groundtruth::default().pose_at(0.0, 1.0).is_none());
        assert!(Groundtruth::new(vec![track().poses[1], track().poses[0]]).is_none());
    }

    #[test]
    fn wrap_range() {
        use core::f64::consts::PI;
        assert_eq!(wrap(PI), PI);
        assert!((wrap(-PI) - PI).abs() < 1e-15);
        assert!((wrap(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert_eq!(wrap(0.25), 0.25);
    }
}
