//! A recorded robot log in the form the replay consumes: the landmark map,
//! odometry in time order, landmark sightings in the order they were
//! received, optional ground truth and initial pose, the landmark sensor's
//! mount and the noise levels the log declares. Built from an MRCLAM
//! dataset ([`Log::mrclam`]) or a Locus CSV log ([`Log::locus_csv`]).

use std::path::Path;

use locus_logs::locus_csv::{self, LocusLog};
use locus_logs::mrclam::{Dataset, Groundtruth, Odometry, TruthPose};
pub use locus_logs::{Landmark, NoiseRecords, SensorMount, Sighting};

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
    /// The landmark sensor's mount in the robot frame (m, m, rad): every
    /// sighting's range is from its origin and its bearing from its x axis.
    /// All zeros (the default) is a sensor at the robot's centre, along its
    /// heading.
    pub sensor: SensorMount,
    /// The noise levels the log declares (none for MRCLAM).
    pub noise: NoiseRecords,
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
            odometry,
            sightings,
            truth,
            start: None,
            robot_sightings: split.robots.len(),
            unknown_sightings: split.unknown.len(),
            sensor: SensorMount::default(),
            noise: NoiseRecords::default(),
        })
    }

    /// A log from a parsed Locus CSV log. Each measurement arrives no
    /// earlier than every measurement listed before it (its arrival is the
    /// running maximum of the times so far): a line whose time goes back is
    /// a late measurement. Measurements of ids not in the map are counted
    /// in [`Log::unknown_sightings`] and left out. A log without a `sensor`
    /// line has its sensor at the robot's centre ([`SensorMount::default`]).
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
            sensor: log.sensor.unwrap_or_default(),
            noise: log.noise,
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
    use super::*;

    fn parse(text: &str) -> LocusLog {
        locus_csv::parse(text, Path::new("t.csv")).unwrap()
    }

    #[test]
    fn sensor_and_noise_pass_through_both_ways() {
        let csv = parse(
            "sensor,0.1,-0.05,0.2\nnoise,q_v,0.02\nnoise,sigma_bearing,0.05\n\
             landmark,6,1,2\nodometry,0,0,0\nmeasurement,0.5,6,2,0.1\n",
        );
        let log = Log::from_locus("t", csv.clone());
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
        assert_eq!(Log::from_locus("t", log.to_locus()), log);
    }

    #[test]
    fn a_centred_sensor_is_the_default_and_is_not_written() {
        let csv = parse("landmark,6,1,2\nodometry,0,0,0\n");
        let log = Log::from_locus("t", csv.clone());
        assert_eq!(log.sensor, SensorMount::default());
        assert_eq!(log.noise, NoiseRecords::default());
        assert_eq!(log.to_locus(), csv);
        // Given explicitly, it reads the same and is left out on the way back.
        let explicit =
            Log::from_locus("t", parse("sensor,0,0,0\nlandmark,6,1,2\nodometry,0,0,0\n"));
        assert_eq!(explicit, log);
        assert_eq!(explicit.to_locus().sensor, None);
    }
}
