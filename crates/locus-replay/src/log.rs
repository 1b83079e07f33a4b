//! A recorded robot log in the form the replay consumes: the landmark map,
//! odometry in time order, landmark sightings in the order they were
//! received, optional ground truth and initial pose. Built from an MRCLAM
//! dataset ([`Log::mrclam`]) or a Locus CSV log ([`Log::locus_csv`]).

use std::path::Path;

use locus_logs::locus_csv::{self, LocusLog};
use locus_logs::mrclam::{Dataset, Groundtruth, Odometry, TruthPose};
pub use locus_logs::{Landmark, Sighting};

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
    /// time is used.
    pub start: Option<TruthPose>,
    /// Sightings of other robots, left out of [`Log::sightings`] (they are
    /// not landmarks).
    pub robot_sightings: usize,
    /// Sightings of targets not in the map (MRCLAM: barcodes absent from
    /// `Barcodes.dat`), left out of [`Log::sightings`].
    pub unknown_sightings: usize,
}

impl Log {
    /// Robot `robot`'s log of an opened MRCLAM dataset: landmark sightings
    /// (barcodes mapped to subjects; robot sightings and unknown barcodes
    /// counted and left out), arrival = time.
    ///
    /// # Errors
    /// The reader's errors (missing file, malformed line, no such robot).
    pub fn mrclam(dataset: &Dataset, robot: u32) -> locus_logs::Result<Self> {
        let split = dataset.sightings(robot)?;
        let landmarks = dataset
            .landmarks
            .iter()
            .map(|l| Landmark {
                id: l.subject,
                x: l.x,
                y: l.y,
            })
            .collect();
        let sightings = split
            .landmarks
            .iter()
            .map(|s| Sighting {
                time: s.time,
                arrival: s.time,
                landmark: s.subject,
                range: s.range,
                bearing: s.bearing,
            })
            .collect();
        let name = dataset.dir().file_name().map_or_else(
            || "MRCLAM".to_string(),
            |n| n.to_string_lossy().into_owned(),
        );
        Ok(Self {
            name: format!("{name} robot {robot}"),
            landmarks,
            odometry: dataset.odometry(robot)?,
            sightings,
            truth: dataset.groundtruth(robot)?,
            start: None,
            robot_sightings: split.robots.len(),
            unknown_sightings: split.unknown.len(),
        })
    }

    /// A log from a parsed Locus CSV log. Each measurement arrives no
    /// earlier than every measurement listed before it (its arrival is the
    /// running maximum of the times so far): a line whose time goes back is
    /// a late measurement. Measurements of ids not in the map are counted
    /// in [`Log::unknown_sightings`] and left out.
    #[must_use]
    pub fn from_locus(name: &str, log: LocusLog) -> Self {
        let mut arrival = f64::NEG_INFINITY;
        let mut unknown = 0;
        let mut sightings = Vec::with_capacity(log.measurements.len());
        for m in &log.measurements {
            arrival = arrival.max(m.time);
            if log.landmarks.iter().any(|l| l.id == m.id) {
                sightings.push(Sighting {
                    time: m.time,
                    arrival,
                    landmark: m.id,
                    range: m.range,
                    bearing: m.bearing,
                });
            } else {
                unknown += 1;
            }
        }
        Self {
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
        }
    }

    /// Reads a Locus CSV log file (`.xz` read directly; `FILE.xz` tried if
    /// `FILE` does not exist).
    ///
    /// # Errors
    /// Missing file (named), malformed line (file and line).
    pub fn locus_csv(path: &Path) -> locus_logs::Result<Self> {
        let name = path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        Ok(Self::from_locus(&name, locus_csv::read(path)?))
    }

    /// The log as a Locus CSV log (measurements in arrival order), e.g. to
    /// convert an MRCLAM robot into the format.
    #[must_use]
    pub fn to_locus(&self) -> LocusLog {
        LocusLog {
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
