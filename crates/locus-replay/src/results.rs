//! A replay's own sections of the results (`metrics.json`,
//! `docs/results.md`), after the source-neutral
//! [`Results`](locus_eval::results::Results): the filter's final
//! calibration and the `replay` section (the settings replayed with, the
//! counts only a replay has, where the initial pose came from). Figures in
//! SI units under keys that name the unit; `null` where a figure does not
//! apply.

use locus_eval::results::Calibration;
use serde::Serialize;

use crate::{Config, Report, StartedFrom};

/// The replay's sections of the results, after the source-neutral ones.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Section {
    /// The filter's final calibration.
    pub calibration: Calibration,
    /// The replay's settings and counts.
    pub replay: Replay,
}

/// The `replay` section: the settings replayed with, the counts of what
/// happened to the log's records beyond the results' `counts` (whose
/// `readings` are the sightings replayed and `applied` those applied), and
/// where the initial pose came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Replay {
    /// Chi-square gate confidence in (0, 1); `None` (`null`) without a
    /// gate.
    pub gate_confidence: Option<f64>,
    /// Power spectral density of the forward-speed noise, m^2/s.
    pub q_v_m2_per_s: f64,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    pub q_omega_rad2_per_s: f64,
    /// Range noise standard deviation, m.
    pub sigma_range_m: f64,
    /// Bearing noise standard deviation, rad.
    pub sigma_bearing_rad: f64,
    /// The odometry delay replayed with, s.
    pub odometry_delay_s: f64,
    /// Where the initial pose came from.
    pub start: Start,
    /// Odometry records replayed.
    pub odometry_records: usize,
    /// Sightings the gate rejected.
    pub gated: usize,
    /// `gated / (applied + gated)`, 0 when none reached the gate.
    pub gated_share: f64,
    /// Covariance inflations (recoveries).
    pub inflations: usize,
    /// Sightings applied only after an inflation.
    pub recovered: usize,
    /// Robot-to-robot sightings left out by the log.
    pub robot_sightings: usize,
    /// Sightings of unknown targets left out by the log.
    pub unknown_sightings: usize,
    /// Sightings of landmarks not in the map (skipped).
    pub not_in_map: usize,
    /// Sightings that arrived out of order and were applied at their time.
    pub late: usize,
    /// Sightings older than the history, not applied.
    pub too_late: usize,
    /// Sightings the filter could not use (refused, listed with their line).
    pub unusable: usize,
    /// Sightings refused for an implausible time stamp.
    pub implausible_time: usize,
    /// Sightings where the model predicts no measurement (skipped).
    pub no_measurement: usize,
    /// Odometry records refused as implausible (listed with their line).
    pub implausible_odometry: usize,
    /// How late the ground truth's stamps were taken to be against the
    /// sensors, s (0: compared at its stamps; `locus_replay::truth_clock`).
    pub truth_offset_s: f64,
    /// The scans of beam sensors and their settings; `None` (absent)
    /// for a log without scans.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beams: Option<BeamsSection>,
}

/// The `beams` object of the `replay` section: the beams' settings and
/// what the scans' beams did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BeamsSection {
    /// The beams' white range noise, standard deviation, m.
    pub sigma_beam_m: f64,
    /// The range bias's stationary standard deviation, m; `None` (`null`)
    /// when held at 0.
    pub range_bias_sigma_m: Option<f64>,
    /// Its time constant, s; `None` (`null`) when held at 0.
    pub range_bias_tau_s: Option<f64>,
    /// Beams a scan spends at most.
    pub per_scan: u32,
    /// Scans replayed.
    pub scans: usize,
    /// Beams in them.
    pub beams: u32,
    /// Beams chosen.
    pub chosen: u32,
    /// Chosen beams applied.
    pub applied: u32,
    /// Of them, applied with a Student-t weight below 1.
    pub down_weighted: u32,
    /// Chosen beams the gate rejected.
    pub gated: u32,
    /// Chosen beams with no return or no valid reading.
    pub no_return: u32,
    /// Chosen beams whose cast met no surface within range, or met it
    /// grazing.
    pub no_surface: u32,
    /// Chosen beams read far shorter than the map's range (something not
    /// in the map).
    pub short: u32,
    /// Chosen beams the filter could not use.
    pub unusable: u32,
    /// Scans aligned to the map and corrected there (the iterated EKF).
    pub aligned_scans: u32,
}

impl Section {
    /// The sections of the replay that gave `report` with the settings
    /// `cfg`.
    #[must_use]
    pub fn new(cfg: &Config, report: &Report) -> Self {
        let r = report;
        Self {
            calibration: Calibration::from_pairs(r.calibration),
            replay: Replay {
                gate_confidence: cfg.gate,
                q_v_m2_per_s: cfg.q_v,
                q_omega_rad2_per_s: cfg.q_omega,
                sigma_range_m: cfg.sigma_range,
                sigma_bearing_rad: cfg.sigma_bearing,
                odometry_delay_s: cfg.odometry_delay,
                start: Start::new(&r.started_from),
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
                truth_offset_s: 0.0,
                beams: (r.scans > 0).then(|| {
                    let held = cfg.beams.bias == crate::Beams::HELD_BIAS;
                    let b = r.beams;
                    BeamsSection {
                        sigma_beam_m: cfg.beams.sigma,
                        range_bias_sigma_m: (!held).then_some(cfg.beams.bias.sigma),
                        range_bias_tau_s: (!held).then_some(cfg.beams.bias.tau),
                        per_scan: cfg.beams.per_scan,
                        scans: r.scans,
                        beams: b.beams,
                        chosen: b.chosen,
                        applied: b.applied,
                        down_weighted: b.down_weighted,
                        gated: b.gated,
                        no_return: b.no_return,
                        no_surface: b.no_surface,
                        short: b.short,
                        unusable: b.unusable,
                        aligned_scans: b.aligned,
                    }
                }),
            },
        }
    }

    /// The section with the truth's clock the replay compared at.
    #[must_use]
    pub fn with_truth_clock(mut self, clock: Option<&crate::truth_clock::TruthClock>) -> Self {
        self.replay.truth_offset_s = clock.filter(|c| c.applied).map_or(0.0, |c| c.offset);
        self
    }
}

/// The replay's `start`: where the initial pose came from (`log`, `truth`,
/// `truth_position` (a truth with no heading: its heading from the
/// direction of motion) or `sightings`), and for `sightings` the fix.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Start {
    /// `log`, `truth`, `truth_position` or `sightings`.
    pub from: &'static str,
    /// x, y (m) and heading (rad) at the first odometry time (from the
    /// sightings; for `truth_position`, the heading alone, x and y `null`).
    pub pose: Option<[f64; 3]>,
    /// Their standard deviations (m, m, rad).
    pub std: Option<[f64; 3]>,
    /// Sightings in the window that fixed the pose.
    pub sightings: Option<usize>,
    /// Those the fix agrees with.
    pub inliers: Option<usize>,
    /// `inliers / sightings`.
    pub inlier_share: Option<f64>,
    /// Landmarks the inliers see.
    pub landmarks: Option<usize>,
    /// Largest distance between two landmarks the inliers see, m.
    pub baseline_m: Option<f64>,
    /// From the first odometry time to the window's first sighting, s.
    pub from_s: Option<f64>,
    /// The window's span (for `truth_position`, the motion's), s.
    pub span_s: Option<f64>,
    /// RMS of the inliers' residuals, m.
    pub rms_m: Option<f64>,
}

impl Start {
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
