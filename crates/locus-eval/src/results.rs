//! The results schema of a run, the same for every source: a simulated
//! scenario (`locus run`), a Monte Carlo over seeds and a replayed log
//! (`locus replay`). `metrics.json` is [`Results`] under a [`SCHEMA`]
//! tag, with a section of its own for each source (written by the binary);
//! `docs/metrics.schema.json` describes the file and `docs/results.md`
//! gives it in prose.
//!
//! Every key names its unit (`_m`, `_rad`, `_s`, `_m2`, `_share` for a
//! fraction in [0, 1]; counts and the NEES have none). Units are SI. A
//! figure that cannot be computed (no ground truth, no odometry, nothing
//! judged) is NaN, which `serde_json` writes as `null`: "n/a", never 0.
//! An estimator's figures are an [`Accuracy`], the filter's and the
//! smoother's alike.

use serde::Serialize;

use crate::Summary;

/// The version tag written as `"schema"` at the top of `metrics.json`.
/// It changes when a key is renamed, moved or removed.
pub const SCHEMA: &str = "locus-metrics/2";

/// Where a `metrics.json` came from: its `"source"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// One run of a simulated scenario.
    Simulation,
    /// A simulated scenario over several seeds.
    MonteCarlo,
    /// A recorded log replayed.
    Replay,
}

/// The whole of a `metrics.json`: the [`SCHEMA`] tag, the source, the
/// scenario or log name, the results `R` (a
/// [`Results`], or their Monte
/// Carlo spreads) and the source's own section `S`.
#[derive(Serialize)]
pub struct Metrics<'a, R: Serialize, S: Serialize> {
    schema: &'static str,
    source: Source,
    /// Scenario or log name.
    scenario: &'a str,
    #[serde(flatten)]
    results: R,
    #[serde(flatten)]
    section: S,
}

impl<'a, R: Serialize, S: Serialize> Metrics<'a, R, S> {
    /// The metrics of `scenario` from `source`: `results`, then `section`
    /// (a struct whose one field names the source's section).
    pub fn new(source: Source, scenario: &'a str, results: R, section: S) -> Self {
        Self {
            schema: SCHEMA,
            source,
            scenario,
            results,
            section,
        }
    }
}

/// One estimator's figures against the ground truth (the filter's or the
/// smoother's): errors in SI units, the NEES and the shares of steps
/// inside the estimator's own 3 sigma. Errors are truth minus estimate,
/// headings wrapped to (-pi, pi].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Accuracy {
    /// Steps compared with the truth (those the truth covers).
    pub compared: usize,
    /// Position RMSE, m.
    pub position_rmse_m: f64,
    /// Heading RMSE, rad; NaN if the truth has no heading.
    pub heading_rmse_rad: f64,
    /// Circular mean of the heading errors, rad in (-pi, pi]: a constant
    /// offset between the truth's heading frame and the robot's; NaN if
    /// the truth has no heading.
    pub heading_offset_rad: f64,
    /// Heading RMSE about [`Accuracy::heading_offset_rad`], rad.
    pub heading_rmse_about_offset_rad: f64,
    /// Largest position error, m.
    pub max_position_error_m: f64,
    /// Mean NEES (the state's degrees of freedom for a consistent
    /// estimator); NaN when samples of different dof were mixed.
    pub mean_nees: f64,
    /// Degrees of freedom of the NEES: 3 (x, y, heading), 2 for a truth
    /// of positions only.
    pub nees_dof: u32,
    /// Share of steps whose NEES lies in the two-sided 95 % chi-square
    /// interval of [`Accuracy::nees_dof`] (0.95 when consistent).
    pub nees_in_95_interval_share: f64,
    /// Mean NEES with the heading errors taken about
    /// [`Accuracy::heading_offset_rad`]; NaN without a heading truth.
    pub mean_nees_about_offset: f64,
    /// Share of steps whose x error lies within 3 standard deviations of
    /// the estimator's own variance (0.997 for a consistent Gaussian).
    pub within_3_sigma_x_share: f64,
    /// As [`Accuracy::within_3_sigma_x_share`], for y.
    pub within_3_sigma_y_share: f64,
    /// As [`Accuracy::within_3_sigma_x_share`], for the heading; NaN
    /// without a heading truth.
    pub within_3_sigma_heading_share: f64,
    /// As [`Accuracy::within_3_sigma_heading_share`], the heading errors
    /// taken about [`Accuracy::heading_offset_rad`].
    pub within_3_sigma_heading_about_offset_share: f64,
}

impl Accuracy {
    /// The estimator's figures of `s`.
    #[must_use]
    pub fn of(s: &Summary) -> Self {
        Self {
            compared: s.compared,
            position_rmse_m: s.position_rmse,
            heading_rmse_rad: s.heading_rmse,
            heading_offset_rad: s.heading_offset,
            heading_rmse_about_offset_rad: s.heading_rmse_about_offset,
            max_position_error_m: s.max_position_error,
            mean_nees: s.mean_nees,
            nees_dof: s.nees_dof,
            nees_in_95_interval_share: s.nees_in_interval,
            mean_nees_about_offset: s.mean_nees_about_offset,
            within_3_sigma_x_share: s.within_3_sigma[0],
            within_3_sigma_y_share: s.within_3_sigma[1],
            within_3_sigma_heading_share: s.within_3_sigma[2],
            within_3_sigma_heading_about_offset_share: s.within_3_sigma_heading_about_offset,
        }
    }
}

/// Odometry alone (dead reckoning) against the same truth: the baseline
/// the filter is judged against. NaN where the source has no odometry or
/// the truth no heading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Baseline {
    /// Position RMSE, m.
    pub position_rmse_m: f64,
    /// Heading RMSE, rad.
    pub heading_rmse_rad: f64,
    /// Largest position error, m.
    pub max_position_error_m: f64,
}

impl Baseline {
    /// The odometry-alone figures of `s`.
    #[must_use]
    pub fn of(s: &Summary) -> Self {
        Self {
            position_rmse_m: s.odometry_position_rmse,
            heading_rmse_rad: s.odometry_heading_rmse,
            max_position_error_m: s.odometry_max_position_error,
        }
    }
}

/// What happened to the measurements, over every step (whether or not the
/// truth covers it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Counts {
    /// Measurements that arrived (IR readings, landmark sightings, ...).
    pub readings: usize,
    /// Those that reached the gate (associated with the map).
    pub associated: usize,
    /// Those the gate passed and the filter applied.
    pub applied: usize,
    /// `applied / associated`; NaN when none was associated.
    pub acceptance_share: f64,
}

impl Counts {
    /// The measurement counts of `s`.
    #[must_use]
    pub fn of(s: &Summary) -> Self {
        Self {
            readings: s.readings,
            associated: s.associated,
            applied: s.applied,
            acceptance_share: s.acceptance,
        }
    }
}

/// How long the run took. Not reproducible.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timing {
    /// Wall-clock duration, s (including writing the step log).
    pub wall_clock_s: f64,
    /// [`Results::duration_s`] over the wall-clock duration.
    pub real_time_factor: f64,
}

/// A run's results, whatever its source: its extent, the filter's figures
/// (and the smoother's, if one ran), odometry alone, the measurement
/// counts and the timing.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Results {
    /// Steps the filter took (simulator steps, or events of a log).
    pub steps: usize,
    /// Time the run covers, s: simulated time, or a log's span from its
    /// first odometry record to its last event.
    pub duration_s: f64,
    /// The filter against the truth.
    pub filter: Accuracy,
    /// The smoother against the same truth (absent without one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smoother: Option<Accuracy>,
    /// Odometry alone against the truth.
    pub odometry: Baseline,
    /// The measurement counts.
    pub counts: Counts,
    /// Wall clock and real-time factor.
    pub timing: Timing,
}

impl Results {
    /// The results of the filter's summary `s`, without a smoother.
    #[must_use]
    pub fn of(s: &Summary) -> Self {
        Self {
            steps: s.steps,
            duration_s: s.duration,
            filter: Accuracy::of(s),
            smoother: None,
            odometry: Baseline::of(s),
            counts: Counts::of(s),
            timing: Timing {
                wall_clock_s: s.wall_clock,
                real_time_factor: s.real_time_factor,
            },
        }
    }

    /// The same results with the smoother's figures of `smoother`.
    #[must_use]
    pub fn with_smoother(self, smoother: Option<&Summary>) -> Self {
        Self {
            smoother: smoother.map(Accuracy::of),
            ..self
        }
    }
}

/// A quantity estimated with its uncertainty.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeanStd {
    /// The estimate.
    pub mean: f64,
    /// Its standard deviation, in the same unit.
    pub std: f64,
}

impl From<(f64, f64)> for MeanStd {
    fn from((mean, std): (f64, f64)) -> Self {
        Self { mean, std }
    }
}

/// A robot's calibration as estimated by the filter: each term's mean and
/// standard deviation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Calibration {
    /// Forward-speed scale `s_v`, dimensionless: the robot moves at `s_v`
    /// times its logged forward speed.
    pub speed_scale: MeanStd,
    /// Turn-rate scale `s_omega`, dimensionless: it turns at `s_omega`
    /// times its logged turn rate plus the bias.
    pub turn_rate_scale: MeanStd,
    /// Turn-rate bias `b_omega`, rad/s.
    pub turn_rate_bias_rad_per_s: MeanStd,
    /// Bearing bias of the range-bearing sensor, rad.
    pub bearing_bias_rad: MeanStd,
}

impl Calibration {
    /// The calibration from `(mean, std)` pairs in the order forward-speed
    /// scale, turn-rate scale, turn-rate bias (rad/s), bearing bias (rad).
    #[must_use]
    pub fn from_pairs([speed, turn, bias, bearing]: [(f64, f64); 4]) -> Self {
        Self {
            speed_scale: speed.into(),
            turn_rate_scale: turn.into(),
            turn_rate_bias_rad_per_s: bias.into(),
            bearing_bias_rad: bearing.into(),
        }
    }
}

/// One trajectory's errors over a set of relative poses
/// ([`crate::relations`]): how many relations it was judged on, and the
/// mean and standard deviation (divided by the count) of the translational
/// (m) and rotational (rad) errors; NaN when none was judged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RelationFigures {
    /// Relations judged (both ends covered by the trajectory).
    pub compared: usize,
    /// Mean translational error, m.
    pub mean_translation_m: f64,
    /// Its standard deviation, m.
    pub std_translation_m: f64,
    /// Mean rotational error (absolute, wrapped), rad.
    pub mean_rotation_rad: f64,
    /// Its standard deviation, rad.
    pub std_rotation_rad: f64,
}

impl From<&crate::relations::RelationErrors> for RelationFigures {
    fn from(e: &crate::relations::RelationErrors) -> Self {
        Self {
            compared: e.judged,
            mean_translation_m: e.mean_translation,
            std_translation_m: e.std_translation,
            mean_rotation_rad: e.mean_rotation,
            std_rotation_rad: e.std_rotation,
        }
    }
}

/// The `relations` section of a replay judged against relative poses
/// measured apart from the log (Kuemmerle et al. 2009; `locus replay carmen
/// --relations`): how many relations the file holds and fall on the log's
/// scans, and the errors of the filter, the smoother, the log's own truth
/// and its odometry over them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Relations {
    /// Relations in the file.
    pub in_file: usize,
    /// Of those, the ones with both ends on a scan's time stamp.
    pub on_scans: usize,
    /// Of those, the ones left out with an end on an ambiguous scan (one
    /// that two different relation times fall on); the others are judged.
    pub ambiguous: usize,
    /// How near a scan's stamp an end must be to fall on it, s.
    pub match_tolerance_s: f64,
    /// The filter's estimate after each scan.
    pub filter: RelationFigures,
    /// The smoother's estimate at each scan (with a smoother only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smoother: Option<RelationFigures>,
    /// The log's ground truth at the scans (a CARMEN log's corrected
    /// poses).
    pub truth: RelationFigures,
    /// The log's odometry alone, composed from scan to scan (no filter,
    /// no calibration, no delay).
    pub odometry: RelationFigures,
    /// The truth's own error at a pose, from its errors over the relations
    /// ([`crate::reference_error`]); `None` (`null`) with too few.
    pub truth_error: Option<TruthError>,
    /// The filter's (and the smoother's) consistency with the truth at the
    /// scans, alone and with the truth's own error.
    pub consistency: ConsistencyAtScans,
}

/// A truth's own error at one pose, estimated from its errors over
/// relations measured apart from it ([`crate::reference_error`]: robust,
/// an upper bound).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TruthError {
    /// Relations it is estimated from.
    pub relations: usize,
    /// Standard deviation of each of x and y, m.
    pub sigma_xy_m: f64,
    /// Standard deviation of the heading, rad.
    pub sigma_heading_rad: f64,
}

impl From<&crate::reference_error::ReferenceError> for TruthError {
    fn from(e: &crate::reference_error::ReferenceError) -> Self {
        Self {
            relations: e.relations,
            sigma_xy_m: e.sigma_xy,
            sigma_heading_rad: e.sigma_theta,
        }
    }
}

/// The filter's and the smoother's [`Consistency`] at the scans.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ConsistencyAtScans {
    /// The filter's estimate after each scan.
    pub filter: Consistency,
    /// The smoother's estimate at each scan (with a smoother only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub smoother: Option<Consistency>,
}

/// An estimator's consistency with a truth that has its own error
/// ([`crate::reference_error::Consistency`]): the shares inside 3 sigma and
/// the mean NEES (3 dof) of the estimate's covariance alone, and of it plus
/// the truth's error ([`TruthError`]; NaN without one).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Consistency {
    /// Poses compared.
    pub compared: usize,
    /// Share of x errors inside 3 standard deviations of the estimate's.
    pub within_3_sigma_x_share: f64,
    /// As `within_3_sigma_x_share`, for y.
    pub within_3_sigma_y_share: f64,
    /// As `within_3_sigma_x_share`, for the heading.
    pub within_3_sigma_heading_share: f64,
    /// Mean NEES of the estimate's covariance.
    pub mean_nees: f64,
    /// Share of x errors inside 3 standard deviations of the estimate's
    /// variance plus the truth's.
    pub with_truth_error_within_3_sigma_x_share: f64,
    /// As `with_truth_error_within_3_sigma_x_share`, for y.
    pub with_truth_error_within_3_sigma_y_share: f64,
    /// As `with_truth_error_within_3_sigma_x_share`, for the heading.
    pub with_truth_error_within_3_sigma_heading_share: f64,
    /// Mean NEES of the estimate's covariance plus the truth's.
    pub with_truth_error_mean_nees: f64,
}

impl From<&crate::reference_error::Consistency> for Consistency {
    fn from(c: &crate::reference_error::Consistency) -> Self {
        let [x, y, heading] = c.within_3_sigma;
        let [rx, ry, rheading] = c.within_3_sigma_with_reference;
        Self {
            compared: c.compared,
            within_3_sigma_x_share: x,
            within_3_sigma_y_share: y,
            within_3_sigma_heading_share: heading,
            mean_nees: c.mean_nees,
            with_truth_error_within_3_sigma_x_share: rx,
            with_truth_error_within_3_sigma_y_share: ry,
            with_truth_error_within_3_sigma_heading_share: rheading,
            with_truth_error_mean_nees: c.mean_nees_with_reference,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Tally;
    use locus_core::nalgebra::{Matrix3, Vector3};
    use locus_core::{Belief, Pose};

    fn summary() -> Summary {
        let mut t = Tally::new(3).unwrap();
        let belief = Belief::new(
            Vector3::new(1.1, 2.0, 0.0),
            Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 0.0025)),
        );
        let truth = Pose::new(1.0, 2.0, f64::NAN);
        t.push(&crate::Sample::planar(
            0, 0.5, &truth, &belief, None, None, true,
        ));
        t.summary(0)
    }

    /// The filter and the smoother write one shape: the same keys, with
    /// units, the 3-sigma shares and the NEES; a figure with no value is
    /// `null`.
    #[test]
    fn the_filter_and_the_smoother_share_one_shape_and_nan_is_null() {
        let s = summary();
        let value = serde_json::to_value(Results::of(&s).with_smoother(Some(&s))).unwrap();
        assert_eq!(value["filter"], value["smoother"]);
        let keys: Vec<&String> = value["filter"].as_object().unwrap().keys().collect();
        assert_eq!(keys.len(), 14, "{keys:?}");
        assert_eq!(value["filter"]["within_3_sigma_x_share"], 1.0);
        assert_eq!(value["filter"]["nees_dof"], 2);
        assert!(value["filter"]["heading_rmse_rad"].is_null(), "{value}");
        assert!(value["odometry"]["position_rmse_m"].is_null(), "{value}");
        assert!(value["counts"]["acceptance_share"].is_null(), "{value}");
        assert_eq!(value["counts"]["readings"], 1);
        assert_eq!(value["duration_s"], 0.5);
        let none = serde_json::to_value(Results::of(&s)).unwrap();
        assert!(none.get("smoother").is_none());
    }

    #[test]
    fn the_calibration_names_its_terms() {
        let c = Calibration::from_pairs([(1.0, 0.1), (0.9, 0.2), (-0.01, 0.001), (0.02, 0.003)]);
        let value = serde_json::to_value(c).unwrap();
        assert_eq!(value["speed_scale"]["mean"], 1.0);
        assert_eq!(value["turn_rate_scale"]["std"], 0.2);
        assert_eq!(value["turn_rate_bias_rad_per_s"]["mean"], -0.01);
        assert_eq!(value["bearing_bias_rad"]["std"], 0.003);
    }
}
