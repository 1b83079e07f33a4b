//! A recorded robot log in the form the replay consumes: the landmark map,
//! odometry in time order, landmark sightings in the order they were
//! received, optional ground truth and initial pose, the landmark sensor's
//! mount and the noise levels the log declares; and for range sensors that
//! see walls (version 4), the map of walls or grid, the beam sensors and
//! their scans. Built from an MRCLAM dataset ([`Log::mrclam`]), a Locus
//! CSV log ([`Log::locus_csv`]), a libRSF log ([`Log::librsf`]) or a ROS 2
//! bag ([`Log::bag`]).

use alloc::sync::Arc;

pub use locus_logs::MapPath;
use locus_logs::locus_csv::{self, LocusLog};
use locus_logs::mrclam::{Dataset, Groundtruth, Odometry, TruthPose};
pub use locus_logs::{
    BeamSensor, IrPairRecord, Landmark, Lines, NoiseRecords, Scans, SensorMount, Sighting,
};
pub use locus_map::Map;

mod files;

/// A map shared by the replays of one log (the estimate replays a log many
/// times; a grid is loaded once). Two are equal when they are one map or
/// hold the same walls or the same grid.
#[derive(Debug, Clone)]
pub struct SharedMap(pub Arc<Map>);

impl PartialEq for SharedMap {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
            || match (&*self.0, &*other.0) {
                (Map::Segments(a), Map::Segments(b)) => a.segments() == b.segments(),
                (Map::Grid(a), Map::Grid(b)) => a == b,
                _ => false,
            }
    }
}

impl From<Map> for SharedMap {
    fn from(map: Map) -> Self {
        Self(Arc::new(map))
    }
}

impl core::ops::Deref for SharedMap {
    type Target = Map;

    fn deref(&self) -> &Map {
        &self.0
    }
}
use locus_models::plausible::{Implausible, Limits};

use crate::Error;

/// A robot's log, ready to replay.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Log {
    /// A name for reports (e.g. `MRCLAM_Dataset6 robot 3`).
    pub name: String,
    /// The landmark map.
    pub landmarks: Vec<Landmark>,
    /// Odometry: velocities held from each record's time to the next's, in
    /// non-decreasing time order.
    pub odometry: Vec<Odometry>,
    /// Landmark sightings in non-decreasing arrival order (their times may
    /// go back: late sightings).
    pub sightings: Vec<Sighting>,
    /// Ground truth (empty if the log has none).
    pub truth: Groundtruth,
    /// The initial pose; if `None`, the ground truth at the first odometry
    /// time is used, and without that the pose the first sightings fix
    /// ([`crate::initial`]).
    pub start: Option<TruthPose>,
    /// Sightings of other robots, left out of [`Log::sightings`] (they are
    /// not landmarks).
    pub robot_sightings: usize,
    /// Sightings of targets not in the map (MRCLAM: barcodes absent from
    /// `Barcodes.dat`), left out of [`Log::sightings`].
    pub unknown_sightings: usize,
    /// The landmark sensor's mount in the robot frame (m, m, rad): every
    /// sighting's range is from its origin and its bearing from its x axis.
    /// All zeros (the default) is a sensor at the robot's centre, along its
    /// heading.
    pub sensor: SensorMount,
    /// The noise levels the log declares (none for MRCLAM), those
    /// [`Limits::GENERIC`] refuses left out ([`Log::refused_noise`]).
    pub noise: NoiseRecords,
    /// Noise records refused as implausible: left out of [`Log::noise`],
    /// so the replay estimates those levels (or takes its defaults).
    pub refused_noise: Vec<RefusedRecord>,
    /// The line of each record in its file (a log read from a file; empty
    /// where not known): `measurements` in the order of [`Log::sightings`],
    /// `odometry` in the order of [`Log::odometry`].
    pub lines: Lines,
    /// Sightings refused because their time stamp is implausible
    /// ([`TIME_TOLERANCE`]), left out of [`Log::sightings`].
    pub refused_times: Vec<RefusedTime>,
    /// The map the beam sensors see (the log's walls, or its map file),
    /// shared by the replays of one log; `None` without one.
    pub map: Option<SharedMap>,
    /// The map file the log names (`map` record), kept for export.
    pub map_file: Option<MapPath>,
    /// The range sensors whose beams are cast in [`Log::map`].
    pub beam_sensors: Vec<BeamSensor>,
    /// Their scans, in non-decreasing time order.
    pub scans: Scans,
    /// Beam sensors read as paper 001's IR pair (version 5): their scans
    /// of one instant are one correction of the pose, not two.
    pub ir_pairs: Vec<IrPairRecord>,
}

/// A record refused as implausible, with its line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefusedRecord {
    /// Its line in the file, if known.
    pub line: Option<usize>,
    /// What it is (`noise q_v`, `odometry`).
    pub what: &'static str,
    /// Why it is implausible.
    pub why: Implausible,
}

/// What `noise` record each noise level comes from, in the order of
/// [`NoiseRecords::NAMES`].
const NOISE_WHAT: [&str; 4] = [
    "noise q_v",
    "noise q_omega",
    "noise sigma_range",
    "noise sigma_bearing",
];

/// How far a sighting's time may lie beyond the last odometry record, or
/// ahead of the measurements listed on both sides of it, s: the replay's
/// default re-run window ([`Config::horizon`](crate::Config::horizon)). A
/// time beyond it is implausible (see [`TimeProblem`]).
pub const TIME_TOLERANCE: f64 = 1.0;

/// Why a sighting's time stamp is implausible.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeProblem {
    /// More than [`TIME_TOLERANCE`] after the last odometry record: the
    /// filter has no motion to carry the estimate there, and every
    /// sighting listed after it would be taken as arriving that late.
    AfterOdometry {
        /// The last odometry time, s.
        last: f64,
    },
    /// More than [`TIME_TOLERANCE`] ahead both of every measurement listed
    /// before it and of the one listed next: not a late measurement, and
    /// taken as arriving then it would make the next ones too late.
    AheadOfNeighbours {
        /// The latest time listed before it, s.
        previous: f64,
        /// The time listed next, s.
        next: f64,
    },
}

impl core::fmt::Display for TimeProblem {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TimeProblem::AfterOdometry { last } => write!(
                f,
                "more than {TIME_TOLERANCE} s after the last odometry record ({last} s)"
            ),
            TimeProblem::AheadOfNeighbours { previous, next } if previous.is_finite() => write!(
                f,
                "more than {TIME_TOLERANCE} s ahead of the measurements listed before \
                 ({previous} s) and after it ({next} s)"
            ),
            TimeProblem::AheadOfNeighbours { next, .. } => write!(
                f,
                "the first measurement listed, more than {TIME_TOLERANCE} s ahead of the \
                 one listed after it ({next} s)"
            ),
        }
    }
}

/// A sighting refused for its time stamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefusedTime {
    /// Its line in the file, if known.
    pub line: Option<usize>,
    /// Its time stamp, s.
    pub time: f64,
    /// The landmark's id.
    pub landmark: u32,
    /// Why it is implausible.
    pub problem: TimeProblem,
}

/// For each measurement time (in the order listed), whether it is
/// implausible: after `last_odometry` (if any) by more than
/// [`TIME_TOLERANCE`], or ahead by more than that of the latest plausible
/// time listed before it and of the time listed next.
fn time_problems(times: &[f64], last_odometry: Option<f64>) -> Vec<Option<TimeProblem>> {
    let mut latest = f64::NEG_INFINITY;
    let mut out = Vec::with_capacity(times.len());
    for (i, &t) in times.iter().enumerate() {
        let problem = match (last_odometry, times.get(i + 1)) {
            (Some(last), _) if t > last + TIME_TOLERANCE => {
                Some(TimeProblem::AfterOdometry { last })
            }
            (_, Some(&next)) if t > latest + TIME_TOLERANCE && t > next + TIME_TOLERANCE => {
                Some(TimeProblem::AheadOfNeighbours {
                    previous: latest,
                    next,
                })
            }
            _ => None,
        };
        if problem.is_none() {
            latest = latest.max(t);
        }
        out.push(problem);
    }
    out
}

impl Log {
    /// Robot `robot`'s log of an opened MRCLAM dataset: landmark sightings
    /// (barcodes mapped to subjects; robot sightings and unknown barcodes
    /// counted and left out), arrival = time. The sensor is at the robot's
    /// centre (the dataset's camera "is placed to align with the robot body
    /// frame") and no noise levels are declared.
    ///
    /// # Errors
    /// The reader's errors (missing file, malformed line, no such robot).
    pub fn mrclam(dataset: &Dataset, robot: u32) -> locus_logs::Result<Self> {
        // The three files are decoded and parsed side by side.
        let (split, (odometry, truth)) = rayon::join(
            || dataset.sightings(robot),
            || rayon::join(|| dataset.odometry(robot), || dataset.groundtruth(robot)),
        );
        let (split, odometry, truth) = (split?, odometry?, truth?);
        let landmarks = dataset
            .landmarks
            .iter()
            .map(|l| Landmark {
                id: l.subject,
                x: l.x,
                y: l.y,
            })
            .collect();
        let times: Vec<f64> = split.landmarks.iter().map(|s| s.time).collect();
        let problems = time_problems(&times, odometry.last().map(|o| o.time));
        let mut sightings = Vec::with_capacity(split.landmarks.len());
        let mut refused_times = Vec::new();
        for (s, problem) in split.landmarks.iter().zip(problems) {
            if let Some(problem) = problem {
                refused_times.push(RefusedTime {
                    line: None,
                    time: s.time,
                    landmark: s.subject,
                    problem,
                });
                continue;
            }
            sightings.push(Sighting {
                time: s.time,
                arrival: s.time,
                landmark: s.subject,
                range: s.range,
                bearing: Some(s.bearing),
            });
        }
        let name = dataset.dir().file_name().map_or_else(
            || "MRCLAM".to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Ok(Self {
            name: format!("{name} robot {robot}"),
            landmarks,
            odometry,
            sightings,
            truth,
            start: None,
            robot_sightings: split.robots.len(),
            unknown_sightings: split.unknown.len(),
            sensor: SensorMount::default(),
            noise: NoiseRecords::default(),
            refused_noise: Vec::new(),
            lines: Lines::default(),
            refused_times,
            map: None,
            map_file: None,
            beam_sensors: Vec::new(),
            scans: Scans::default(),
            ir_pairs: Vec::new(),
        })
    }

    /// A log from a parsed Locus CSV log. Each measurement arrives no
    /// earlier than every measurement listed before it (its arrival is the
    /// running maximum of the times so far): a line whose time goes back is
    /// a late measurement. Measurements of ids not in the map are counted
    /// in [`Log::unknown_sightings`] and left out. A log without a `sensor`
    /// line has its sensor at the robot's centre ([`SensorMount::default`]).
    /// A measurement whose time is implausible ([`TimeProblem`]) is
    /// refused: listed in [`Log::refused_times`], left out, and not taken
    /// into the arrival of the ones after it. A noise record
    /// [`Limits::GENERIC`] finds implausible is refused: listed in
    /// [`Log::refused_noise`] and left out.
    ///
    /// # Errors
    /// [`Error::Implausible`] for a sensor mount, landmark or start pose
    /// that [`Limits::GENERIC`] refuses (every sighting, or the start,
    /// depends on it: nothing sensible can be replayed).
    pub fn from_locus(name: &str, log: LocusLog) -> Result<Self, Error> {
        Self::from_locus_lines(name, log, Lines::default())
    }

    /// As [`Log::from_locus`], with the line of each record in the file
    /// (empty if not known).
    ///
    /// # Errors
    /// As [`Log::from_locus`].
    pub fn from_locus_lines(name: &str, log: LocusLog, lines: Lines) -> Result<Self, Error> {
        let limits = Limits::GENERIC;
        let implausible = |line: Option<usize>, what: &'static str, why| Error::Implausible {
            file: name.to_string(),
            line,
            what,
            why,
        };
        if let Some(m) = log.sensor {
            limits
                .check_mount(m.x, m.y, m.yaw)
                .map_err(|why| implausible(lines.sensor, "sensor", why))?;
        }
        for (i, l) in log.landmarks.iter().enumerate() {
            limits
                .check_coordinate(l.x)
                .and_then(|()| limits.check_coordinate(l.y))
                .map_err(|why| implausible(lines.landmarks.get(i).copied(), "landmark", why))?;
        }
        if let Some(p) = log.start {
            limits
                .check_coordinate(p.x)
                .and_then(|()| limits.check_coordinate(p.y))
                .map_err(|why| implausible(lines.start, "start", why))?;
            if p.theta.abs() > core::f64::consts::TAU {
                return Err(implausible(
                    lines.start,
                    "start",
                    Implausible::MountYaw { value: p.theta },
                ));
            }
        }
        let mut noise = log.noise;
        let mut refused_noise = Vec::new();
        for (k, name) in NoiseRecords::NAMES.into_iter().enumerate() {
            let Some(slot) = noise.get_mut(name) else {
                continue;
            };
            let limit = limits.max_noise(name).unwrap_or(f64::INFINITY);
            if let Some(value) = *slot
                && value > limit
            {
                refused_noise.push(RefusedRecord {
                    line: lines.noise[k],
                    what: NOISE_WHAT[k],
                    why: Implausible::Noise { value, limit },
                });
                *slot = None;
            }
        }
        let mut arrival = f64::NEG_INFINITY;
        let mut unknown = 0;
        let mut sightings = Vec::with_capacity(log.measurements.len());
        let mut sighting_lines = Vec::with_capacity(lines.measurements.len());
        let mut refused_times = Vec::new();
        let times: Vec<f64> = log.measurements.iter().map(|m| m.time).collect();
        let problems = time_problems(&times, log.odometry.last().map(|o| o.time));
        for (i, (m, problem)) in log.measurements.iter().zip(problems).enumerate() {
            let line = lines.measurements.get(i).copied();
            if let Some(problem) = problem {
                refused_times.push(RefusedTime {
                    line,
                    time: m.time,
                    landmark: m.id,
                    problem,
                });
                continue;
            }
            arrival = arrival.max(m.time);
            if log.landmarks.iter().any(|l| l.id == m.id) {
                sightings.push(Sighting {
                    time: m.time,
                    arrival,
                    landmark: m.id,
                    range: m.range,
                    bearing: m.bearing,
                });
                sighting_lines.extend(line);
            } else {
                unknown += 1;
            }
        }
        let map = if log.walls.is_empty() {
            None
        } else {
            let walls = log
                .walls
                .iter()
                .map(|w| [w.x1, w.y1, w.x2, w.y2].into())
                .collect();
            let segments = locus_map::SegmentMap::new(walls).map_err(|e| Error::Map {
                file: name.to_string(),
                line: lines.walls.first().copied(),
                reason: e.to_string(),
            })?;
            Some(SharedMap(Arc::new(Map::Segments(segments))))
        };
        let map_file = log.map.clone();
        Ok(Self {
            name: name.to_string(),
            landmarks: log
                .landmarks
                .iter()
                .map(|l| Landmark {
                    id: l.id,
                    x: l.x,
                    y: l.y,
                })
                .collect(),
            odometry: log.odometry,
            sightings,
            truth: log.truth,
            start: log.start,
            robot_sightings: 0,
            unknown_sightings: unknown,
            sensor: log.sensor.unwrap_or_default(),
            noise,
            refused_noise,
            lines: Lines {
                measurements: sighting_lines,
                ..lines
            },
            refused_times,
            map,
            map_file,
            beam_sensors: log.beam_sensors,
            scans: log.scans,
            ir_pairs: log.ir_pairs,
        })
    }

    /// Why `limits` refuses odometry record `i` ([`Limits::check_odometry`]:
    /// its speed, turn rate, and time since the record listed before it),
    /// if it does. The replay skips such a record (the velocities before
    /// it held).
    #[must_use]
    pub fn odometry_problem(&self, i: usize, limits: &Limits) -> Option<Implausible> {
        let o = self.odometry.get(i)?;
        let gap = i
            .checked_sub(1)
            .and_then(|p| self.odometry.get(p))
            .map(|p| o.time - p.time);
        limits.check_odometry(o.v, o.omega, gap).err()
    }

    /// The odometry records `limits` refuses, in log order, with their
    /// lines ([`Log::odometry_problem`]).
    pub fn refused_odometry<'a>(
        &'a self,
        limits: &'a Limits,
    ) -> impl Iterator<Item = RefusedRecord> + 'a {
        (0..self.odometry.len()).filter_map(move |i| {
            self.odometry_problem(i, limits).map(|why| RefusedRecord {
                line: self.lines.odometry.get(i).copied(),
                what: "odometry",
                why,
            })
        })
    }

    /// The log as a Locus CSV log (measurements in arrival order), e.g. to
    /// convert an MRCLAM robot into the format. The sensor is written only
    /// if it is not at the robot's centre ([`SensorMount::is_centred`]), so
    /// that a log with a centred sensor reads back the same either way.
    #[must_use]
    pub fn to_locus(&self) -> LocusLog {
        LocusLog {
            sensor: (!self.sensor.is_centred()).then_some(self.sensor),
            noise: self.noise,
            landmarks: self
                .landmarks
                .iter()
                .map(|l| locus_csv::MapLandmark {
                    id: l.id,
                    x: l.x,
                    y: l.y,
                })
                .collect(),
            start: self.start,
            odometry: self.odometry.clone(),
            measurements: self
                .sightings
                .iter()
                .map(|s| locus_csv::LandmarkMeasurement {
                    time: s.time,
                    id: s.landmark,
                    range: s.range,
                    bearing: s.bearing,
                })
                .collect(),
            truth: self.truth.clone(),
            // Walls as given, or the map file's name (a grid is not
            // written inline).
            walls: match (&self.map, &self.map_file) {
                (Some(m), None) => match &**m {
                    Map::Segments(s) => s
                        .segments()
                        .iter()
                        .map(|&seg| {
                            let [x1, y1, x2, y2]: [f64; 4] = seg.into();
                            locus_logs::Wall { x1, y1, x2, y2 }
                        })
                        .collect(),
                    Map::Grid(_) => Vec::new(),
                },
                _ => Vec::new(),
            },
            map: self.map_file.clone(),
            beam_sensors: self.beam_sensors.clone(),
            scans: self.scans.clone(),
            ir_pairs: self.ir_pairs.clone(),
        }
    }

    /// Duration covered by the odometry, s (0 if fewer than two records).
    #[must_use]
    pub fn duration(&self) -> f64 {
        match (self.odometry.first(), self.odometry.last()) {
            (Some(a), Some(b)) => b.time - a.time,
            _ => 0.0,
        }
    }

    /// A landmark by id.
    #[must_use]
    pub fn landmark(&self, id: u32) -> Option<&Landmark> {
        self.landmarks.iter().find(|l| l.id == id)
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;

    fn parse(text: &str) -> LocusLog {
        locus_csv::parse(text, Path::new("t.csv")).unwrap()
    }

    #[test]
    fn implausible_times_are_the_future_and_lone_spikes_not_late_lines() {
        let kinds = |times: &[f64]| -> Vec<Option<&'static str>> {
            time_problems(times, Some(10.0))
                .iter()
                .map(|p| {
                    p.map(|p| match p {
                        TimeProblem::AfterOdometry { .. } => "after",
                        TimeProblem::AheadOfNeighbours { .. } => "spike",
                    })
                })
                .collect()
        };
        // In order, late lines (going back, even by more than the window),
        // a jump ahead that the next lines follow, up to 1 s past the end.
        assert_eq!(kinds(&[1.0, 2.0, 1.5, 3.0, 0.5, 6.0, 6.5, 11.0]), [None; 8]);
        // Beyond the odometry by more than 1 s: refused wherever listed,
        // and not taken as the arrival of the lines after it.
        assert_eq!(
            kinds(&[1.0, 1e6, 1e6, 2.0, 11.5]),
            [None, Some("after"), Some("after"), None, Some("after")]
        );
        // Ahead of both neighbours by more than 1 s: a lone spike.
        assert_eq!(
            kinds(&[1.0, 8.0, 2.0, 3.0]),
            [None, Some("spike"), None, None]
        );
        assert_eq!(kinds(&[8.0, 2.0, 3.0]), [Some("spike"), None, None]);
        // Without odometry only the spike rule applies.
        assert_eq!(time_problems(&[1.0, 1e6], None), [None, None]);
    }

    #[test]
    fn refused_lines_are_left_out_with_their_line_and_the_arrivals_stay_true() {
        let text = "landmark,6,1,2\nodometry,0,0,0\nodometry,10,0,0\n\
                    measurement,1,6,2,0.1\nmeasurement,1000000,6,2,0.1\nmeasurement,2,6,2,0.1\n";
        let (csv, lines) = locus_csv::parse_with_lines(text, Path::new("t.csv")).unwrap();
        assert_eq!(lines.measurements, [4, 5, 6]);
        let log = Log::from_locus_lines("t", csv, lines.clone()).unwrap();
        assert_eq!(log.lines.measurements, [4, 6]);
        assert_eq!(log.sightings.len(), 2);
        assert_eq!(log.sightings[1].arrival, 2.0, "not 1e6");
        assert_eq!(log.refused_times.len(), 1);
        assert_eq!(log.refused_times[0].line, Some(5));
        assert_eq!(
            log.refused_times[0].problem,
            TimeProblem::AfterOdometry { last: 10.0 }
        );
    }

    #[test]
    fn sensor_and_noise_pass_through_both_ways() {
        let csv = parse(
            "sensor,0.1,-0.05,0.2\nnoise,q_v,0.02\nnoise,sigma_bearing,0.05\n\
             landmark,6,1,2\nodometry,0,0,0\nmeasurement,0.5,6,2,0.1\n",
        );
        let log = Log::from_locus("t", csv.clone()).unwrap();
        assert_eq!(
            log.sensor,
            SensorMount {
                x: 0.1,
                y: -0.05,
                yaw: 0.2
            }
        );
        assert_eq!(log.noise.q_v, Some(0.02));
        assert_eq!(log.noise.sigma_bearing, Some(0.05));
        assert_eq!(log.noise.q_omega, None);
        assert_eq!(log.to_locus(), csv);
        assert_eq!(Log::from_locus("t", log.to_locus()).unwrap(), log);
    }

    #[test]
    fn a_centred_sensor_is_the_default_and_is_not_written() {
        let csv = parse("landmark,6,1,2\nodometry,0,0,0\n");
        let log = Log::from_locus("t", csv.clone()).unwrap();
        assert_eq!(log.sensor, SensorMount::default());
        assert_eq!(log.noise, NoiseRecords::default());
        assert_eq!(log.to_locus(), csv);
        // Given explicitly, it reads the same and is left out on the way back.
        let explicit =
            Log::from_locus("t", parse("sensor,0,0,0\nlandmark,6,1,2\nodometry,0,0,0\n")).unwrap();
        assert_eq!(explicit, log);
        assert_eq!(explicit.to_locus().sensor, None);
    }
}
