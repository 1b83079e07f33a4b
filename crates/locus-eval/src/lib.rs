//! Evaluation of a run against its ground truth, the same for a simulated
//! scenario (`locus run`), a replayed log (`locus replay`) and the teaching
//! UI: the per-step [`Sample`] (truth, estimate, covariance, odometry alone,
//! NEES, NIS) that the summary, the pictures and the Monte Carlo statistics
//! are computed from, the [`Record`] trait of a run's CSV log, the
//! [`Summary`] built by a [`Tally`], and [`nees`], the one NEES.
//!
//! A runner (a simulator scenario, the replay) filters, hands each step's
//! record to a sink as the run goes, and returns the [`Summary`] of a
//! [`Tally`] it fed with every step's [`Sample`]. The summary serialises
//! (serde) with every figure that cannot be computed as NaN, which
//! `serde_json` writes as `null`.
//!
//! Units: SI (m, rad, s). Planar scenarios put `z = 0`; the 3-D `hover`
//! scenario (paper 002) reports its body position in `position` and its
//! attitude error as the heading error.

use std::time::Instant;

use locus_core::chi2;
use locus_core::nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use locus_core::{Belief, Pose};

/// The NEES `e^T P^-1 e` of an estimate with error `e` (truth minus
/// estimate, angles wrapped) and covariance `P` ([`locus_core::nees`]);
/// NaN ("n/a") when `P` is not positive definite.
#[must_use]
pub fn nees<const N: usize>(error: &SVector<f64, N>, p: &SMatrix<f64, N, N>) -> f64 {
    locus_core::nees(error, p).unwrap_or(f64::NAN)
}

/// The NEES (3 dof) of a planar estimate `x = [x, y, theta]` (m, m, rad)
/// with covariance `p` against `truth`: [`nees`] of the error
/// `truth - x`, heading wrapped ([`Pose::error_to`]).
#[must_use]
pub fn planar_nees(x: &Vector3<f64>, p: &Matrix3<f64>, truth: &Pose<f64>) -> f64 {
    nees(&Pose::from_vector(x).error_to(truth), p)
}

/// A 3x3 covariance as the row-major array a [`Sample`] and the logs hold.
#[must_use]
pub fn matrix3(p: &Matrix3<f64>) -> [[f64; 3]; 3] {
    core::array::from_fn(|i| core::array::from_fn(|j| p[(i, j)]))
}

/// The common per-step figures of any scenario.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample {
    /// Step index (0-based).
    pub step: usize,
    /// Simulated time at the end of the step (s).
    pub time: f64,
    /// True position `[x, y, z]` (m).
    pub truth: [f64; 3],
    /// True heading (rad): yaw for planar robots (for `hover`, the yaw of the
    /// body; its attitude error is [`Sample::heading_error`]).
    pub truth_heading: f64,
    /// Estimated position `[x, y, z]` (m).
    pub estimate: [f64; 3],
    /// Estimated heading (rad).
    pub estimate_heading: f64,
    /// Estimate error in heading (rad): wrapped `truth - estimate` for planar
    /// robots; for `hover`, the angle of the attitude error rotation (>= 0).
    pub heading_error: f64,
    /// Covariance of the estimate's `[x, y, heading]` (m^2, m rad, rad^2),
    /// symmetric. For `hover`, `heading` is the yaw component.
    pub covariance: [[f64; 3]; 3],
    /// Variance of the estimate's z (m^2; 0 for planar scenarios).
    pub var_z: f64,
    /// Dead-reckoning (odometry-alone) position and heading error, if the
    /// scenario has one: `([x, y, z] (m), heading error (rad))`.
    pub odometry: Option<([f64; 3], f64)>,
    /// NEES `e^T P^-1 e` of the full state against the truth, and its
    /// degrees of freedom (the state dimension).
    pub nees: f64,
    /// Degrees of freedom of [`Sample::nees`].
    pub nees_dof: u32,
    /// This step's correction, if any: NIS, its degrees of freedom, and
    /// whether the gate applied it.
    pub correction: Option<(f64, u32, bool)>,
    /// Whether a measurement arrived this step (before association/gating).
    pub measured: bool,
}

impl Sample {
    /// The sample of a planar robot at `step` (`time`, s): its estimate
    /// `belief` of `[x, y, theta]` against `truth`, odometry alone at
    /// `odometry` if there is one, the step's correction `(NIS, dof,
    /// applied)` and whether a measurement arrived. NEES of 3 dof
    /// ([`planar_nees`]); z is 0.
    #[must_use]
    pub fn planar(
        step: usize,
        time: f64,
        truth: &Pose<f64>,
        belief: &Belief<f64, 3>,
        odometry: Option<&Pose<f64>>,
        correction: Option<(f64, u32, bool)>,
        measured: bool,
    ) -> Self {
        let x = &belief.x;
        let error = Pose::from_vector(x).error_to(truth);
        Self {
            step,
            time,
            truth: [truth.x, truth.y, 0.0],
            truth_heading: truth.theta,
            estimate: [x[0], x[1], 0.0],
            estimate_heading: x[2],
            heading_error: error[2],
            covariance: matrix3(&belief.p),
            var_z: 0.0,
            odometry: odometry.map(|o| ([o.x, o.y, 0.0], o.error_to(truth)[2])),
            nees: nees(&error, &belief.p),
            nees_dof: 3,
            correction,
            measured,
        }
    }

    /// Squared position error (m^2).
    #[must_use]
    pub fn position_error_sq(&self) -> f64 {
        (0..3)
            .map(|i| (self.truth[i] - self.estimate[i]).powi(2))
            .sum()
    }
}

/// A scenario's per-step log record: one CSV row, and the common sample.
pub trait Record {
    /// The CSV header line (no newline), units in the column names.
    fn csv_header() -> String
    where
        Self: Sized;
    /// The record as one CSV line (no newline), in the header's order.
    fn csv_row(&self) -> String;
    /// The figures common to all scenarios.
    fn sample(&self) -> Sample;
}

/// Summary of a run. Errors are against the truth.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Summary {
    /// Steps simulated.
    pub steps: usize,
    /// Simulated time (s).
    pub sim_time: f64,
    /// Laps of the path completed (scenarios that drive laps; else 0).
    pub laps_completed: usize,
    /// EKF position RMSE (m).
    pub ekf_position_rmse: f64,
    /// EKF heading RMSE (rad, wrapped errors; for `hover` the attitude angle).
    pub ekf_heading_rmse: f64,
    /// EKF largest position error (m).
    pub ekf_max_position_error: f64,
    /// Odometry-only position RMSE (m); NaN if the scenario has none.
    pub odometry_position_rmse: f64,
    /// Odometry-only heading RMSE (rad); NaN if the scenario has none.
    pub odometry_heading_rmse: f64,
    /// Odometry-only largest position error (m); NaN if none.
    pub odometry_max_position_error: f64,
    /// Mean NEES of the EKF (the state dimension for a consistent filter).
    pub mean_nees: f64,
    /// Degrees of freedom of the NEES (the state dimension).
    pub nees_dof: u32,
    /// Share of steps whose NEES lies in the two-sided 95 % chi-square
    /// interval of `nees_dof` (0.95 for a consistent filter).
    pub nees_in_interval: f64,
    /// Share of steps whose error lies within 3 standard deviations of the
    /// filter's own covariance, per component: x, y, heading (0.997 each
    /// for a consistent Gaussian filter).
    pub within_3_sigma: [f64; 3],
    /// Steps where a measurement arrived.
    pub readings: usize,
    /// Measurements that reached the filter (associated; the others were
    /// dropped).
    pub associated: usize,
    /// Corrections that passed the gate and were applied.
    pub corrections: usize,
    /// Share of associated measurements applied (`corrections /
    /// associated`; 0 when nothing was associated).
    pub acceptance: f64,
    /// Wall-clock duration of the run (s), including the sink's time. Not
    /// reproducible.
    pub wall_clock: f64,
    /// Simulated time over wall-clock time. Not reproducible.
    pub real_time_factor: f64,
}

impl Summary {
    /// The same summary with the wall-clock fields zeroed, for comparing
    /// runs.
    #[must_use]
    pub fn without_timing(mut self) -> Self {
        self.wall_clock = 0.0;
        self.real_time_factor = 0.0;
        self
    }
}

/// Accumulates [`Sample`]s into a [`Summary`].
#[derive(Debug, Clone)]
pub struct Tally {
    started: Instant,
    steps: usize,
    sim_time: f64,
    sq_pos: f64,
    sq_heading: f64,
    max_pos: f64,
    odo_n: usize,
    odo_sq_pos: f64,
    odo_sq_heading: f64,
    odo_max_pos: f64,
    nees_sum: f64,
    nees_in: usize,
    within_3_sigma: [usize; 3],
    nees_dof: u32,
    nees_bounds: (f64, f64),
    readings: usize,
    associated: usize,
    corrections: usize,
}

impl Tally {
    /// Starts a tally (and the wall clock) for a state of `nees_dof`
    /// dimensions.
    ///
    /// # Errors
    /// [`locus_core::Error::InvalidParameter`] if `nees_dof` is 0.
    pub fn new(nees_dof: u32) -> Result<Self, locus_core::Error> {
        Ok(Self {
            started: Instant::now(),
            steps: 0,
            sim_time: 0.0,
            sq_pos: 0.0,
            sq_heading: 0.0,
            max_pos: 0.0,
            odo_n: 0,
            odo_sq_pos: 0.0,
            odo_sq_heading: 0.0,
            odo_max_pos: 0.0,
            nees_sum: 0.0,
            nees_in: 0,
            within_3_sigma: [0; 3],
            nees_dof,
            nees_bounds: (
                chi2::quantile(0.025, nees_dof)?,
                chi2::quantile(0.975, nees_dof)?,
            ),
            readings: 0,
            associated: 0,
            corrections: 0,
        })
    }

    /// Adds one step.
    pub fn push(&mut self, s: &Sample) {
        self.steps += 1;
        self.sim_time = s.time;
        let e2 = s.position_error_sq();
        self.sq_pos += e2;
        self.sq_heading += s.heading_error * s.heading_error;
        self.max_pos = self.max_pos.max(e2.sqrt());
        if let Some((pos, heading_err)) = s.odometry {
            let o2: f64 = (0..3).map(|i| (s.truth[i] - pos[i]).powi(2)).sum();
            self.odo_n += 1;
            self.odo_sq_pos += o2;
            self.odo_sq_heading += heading_err * heading_err;
            self.odo_max_pos = self.odo_max_pos.max(o2.sqrt());
        }
        self.nees_sum += s.nees;
        if (self.nees_bounds.0..=self.nees_bounds.1).contains(&s.nees) {
            self.nees_in += 1;
        }
        let errors = [
            s.truth[0] - s.estimate[0],
            s.truth[1] - s.estimate[1],
            s.heading_error,
        ];
        let variances = [s.covariance[0][0], s.covariance[1][1], s.covariance[2][2]];
        for ((count, e), v) in self.within_3_sigma.iter_mut().zip(errors).zip(variances) {
            if e * e <= 9.0 * v {
                *count += 1;
            }
        }
        self.readings += usize::from(s.measured);
        if let Some((_, _, applied)) = s.correction {
            self.associated += 1;
            self.corrections += usize::from(applied);
        }
    }

    /// The summary of the steps pushed so far, with `laps_completed`.
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn summary(&self, laps_completed: usize) -> Summary {
        // No step compared with the truth: every figure that needs it is
        // NaN ("n/a", null in JSON), never 0.
        let n = if self.steps > 0 {
            self.steps as f64
        } else {
            f64::NAN
        };
        let (odo_pos, odo_heading, odo_max) = if self.odo_n > 0 {
            let m = self.odo_n as f64;
            (
                (self.odo_sq_pos / m).sqrt(),
                (self.odo_sq_heading / m).sqrt(),
                self.odo_max_pos,
            )
        } else {
            (f64::NAN, f64::NAN, f64::NAN)
        };
        let wall_clock = self.started.elapsed().as_secs_f64();
        Summary {
            steps: self.steps,
            sim_time: self.sim_time,
            laps_completed,
            ekf_position_rmse: (self.sq_pos / n).sqrt(),
            ekf_heading_rmse: (self.sq_heading / n).sqrt(),
            ekf_max_position_error: if self.steps > 0 {
                self.max_pos
            } else {
                f64::NAN
            },
            odometry_position_rmse: odo_pos,
            odometry_heading_rmse: odo_heading,
            odometry_max_position_error: odo_max,
            mean_nees: self.nees_sum / n,
            nees_dof: self.nees_dof,
            nees_in_interval: self.nees_in as f64 / n,
            within_3_sigma: self.within_3_sigma.map(|c| c as f64 / n),
            readings: self.readings,
            associated: self.associated,
            corrections: self.corrections,
            acceptance: if self.associated > 0 {
                self.corrections as f64 / self.associated as f64
            } else {
                f64::NAN
            },
            wall_clock,
            real_time_factor: if wall_clock > 0.0 {
                self.sim_time / wall_clock
            } else {
                f64::INFINITY
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Tally;

    /// A run compared with no truth (a log without ground truth) has no
    /// error figures: they read "n/a" (NaN, `null` in JSON), never 0.
    #[test]
    fn an_empty_tally_reports_no_figure_as_zero() {
        let s = Tally::new(3).unwrap().summary(0);
        for (name, v) in [
            ("ekf_position_rmse", s.ekf_position_rmse),
            ("ekf_heading_rmse", s.ekf_heading_rmse),
            ("ekf_max_position_error", s.ekf_max_position_error),
            ("odometry_position_rmse", s.odometry_position_rmse),
            ("mean_nees", s.mean_nees),
            ("nees_in_interval", s.nees_in_interval),
            ("within_3_sigma x", s.within_3_sigma[0]),
            ("acceptance", s.acceptance),
        ] {
            assert!(v.is_nan(), "{name} = {v}");
        }
    }
}
