//! `metrics.json`'s replay sections: the filter's calibration and the
//! `replay` section (the settings, the counts only a replay has and where
//! the initial pose came from).

use locus_eval::results::Calibration;
use locus_replay::{Config, Report, StartedFrom};
use serde::Serialize;

/// The replay's sections of `metrics.json`, after the results.
#[derive(Serialize)]
pub(super) struct ReplaySection {
    /// The filter's final calibration.
    calibration: Calibration,
    /// The replay's settings and counts.
    replay: Replay,
}

/// `metrics.json`'s `replay`: the settings replayed with, the counts of
/// what happened to the log's records beyond the results' `counts`
/// (whose `readings` are the sightings replayed and `applied` those
/// applied), and where the initial pose came from.
#[derive(Serialize)]
struct Replay {
    /// Chi-square gate confidence; `null` without a gate.
    gate_confidence: Option<f64>,
    q_v_m2_per_s: f64,
    q_omega_rad2_per_s: f64,
    sigma_range_m: f64,
    sigma_bearing_rad: f64,
    /// The odometry delay replayed with, s.
    odometry_delay_s: f64,
    /// Where the initial pose came from.
    start: StartMetrics,
    /// Odometry records replayed.
    odometry_records: usize,
    /// Sightings the gate rejected.
    gated: usize,
    /// `gated / (applied + gated)`, 0 when none reached the gate.
    gated_share: f64,
    /// Covariance inflations (recoveries).
    inflations: usize,
    /// Sightings applied only after an inflation.
    recovered: usize,
    robot_sightings: usize,
    unknown_sightings: usize,
    not_in_map: usize,
    /// Sightings that arrived out of order and were applied at their time.
    late: usize,
    /// Sightings older than the history, not applied.
    too_late: usize,
    /// Sightings the filter could not use (refused, listed with their line).
    unusable: usize,
    /// Sightings refused for an implausible time stamp.
    implausible_time: usize,
    /// Sightings where the model predicts no measurement (skipped).
    no_measurement: usize,
    /// Odometry records refused as implausible (listed with their line).
    implausible_odometry: usize,
}

impl ReplaySection {
    pub(super) fn new(cfg: &Config, r: &Report) -> Self {
        Self {
            calibration: Calibration::from_pairs(r.calibration),
            replay: Replay {
                gate_confidence: cfg.gate,
                q_v_m2_per_s: cfg.q_v,
                q_omega_rad2_per_s: cfg.q_omega,
                sigma_range_m: cfg.sigma_range,
                sigma_bearing_rad: cfg.sigma_bearing,
                odometry_delay_s: cfg.odometry_delay,
                start: StartMetrics::new(&r.started_from),
                odometry_records: r.odometry,
                gated: r.gated,
                gated_share: r.gated_share(),
                inflations: r.inflations,
                recovered: r.recovered,
                robot_sightings: r.robot_sightings,
                unknown_sightings: r.unknown_sightings,
                not_in_map: r.not_in_map,
                late: r.late,
                too_late: r.too_late,
                unusable: r.unusable,
                implausible_time: r.implausible_time,
                no_measurement: r.no_measurement,
                implausible_odometry: r.implausible_odometry,
            },
        }
    }
}

/// `metrics.json`'s `start`: where the initial pose came from (`log`,
/// `truth`, `truth_position` (a truth with no heading: its heading from
/// the direction of motion) or `sightings`), and for `sightings` the fix.
#[derive(Serialize)]
struct StartMetrics {
    from: &'static str,
    /// x, y (m) and heading (rad) at the first odometry time.
    pose: Option<[f64; 3]>,
    /// Their standard deviations (m, m, rad).
    std: Option<[f64; 3]>,
    sightings: Option<usize>,
    inliers: Option<usize>,
    /// `inliers / sightings`.
    inlier_share: Option<f64>,
    landmarks: Option<usize>,
    /// Largest distance between two landmarks the inliers see, m.
    baseline_m: Option<f64>,
    /// From the first odometry time to the window's first sighting, s.
    from_s: Option<f64>,
    span_s: Option<f64>,
    rms_m: Option<f64>,
}

impl StartMetrics {
    fn new(from: &StartedFrom) -> Self {
        let none = |from| Self {
            from,
            pose: None,
            std: None,
            sightings: None,
            inliers: None,
            inlier_share: None,
            landmarks: None,
            baseline_m: None,
            from_s: None,
            span_s: None,
            rms_m: None,
        };
        match from {
            StartedFrom::Log => none("log"),
            StartedFrom::Truth => none("truth"),
            StartedFrom::TruthPosition(h) => Self {
                // The heading's assumed std; the position's is the
                // configured initial one (not a figure of the start).
                std: Some([f64::NAN, f64::NAN, h.std]),
                pose: Some([f64::NAN, f64::NAN, h.heading]),
                span_s: Some(h.span),
                ..none("truth_position")
            },
            StartedFrom::Sightings(f) => Self {
                from: "sightings",
                pose: Some([f.pose[0], f.pose[1], f.pose[2]]),
                std: Some([0, 1, 2].map(|k| f.covariance[(k, k)].sqrt())),
                sightings: Some(f.sightings),
                inliers: Some(f.inliers),
                inlier_share: Some(f.share()),
                landmarks: Some(f.landmarks),
                baseline_m: Some(f.baseline),
                from_s: Some(f.from),
                span_s: Some(f.span),
                rms_m: Some(f.rms),
            },
        }
    }
}
