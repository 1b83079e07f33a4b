//! Evaluation of a run against its ground truth, the same for a simulated
//! scenario (`locus run`), a replayed log (`locus replay`) and the teaching
//! UI: the per-step [`Sample`] (truth, estimate, covariance, odometry alone,
//! NEES, NIS) that the summary, the pictures and the Monte Carlo statistics
//! are computed from, the [`Record`] trait of a run's CSV log, the
//! [`Summary`] built by a [`Tally`], [`nees`], the one NEES, and the
//! [`results`] schema every source writes its `metrics.json` in.
//!
//! A runner (a simulator scenario, the replay) filters, hands each step's
//! record to a sink as the run goes, and returns the [`Summary`] of a
//! [`Tally`] it fed with every step: the [`Sample`] of a step the truth
//! covers, the measurement counts of one it does not. Every figure that
//! cannot be computed is NaN, which [`results`] writes as `null`.
//!
//! Units: SI (m, rad, s). Planar scenarios put `z = 0`; the 3-D `hover`
//! scenario (paper 002) reports its body position in `position` and its
//! attitude error as the heading error.

use std::time::Instant;

use locus_core::chi2;
use locus_core::nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use locus_core::{Belief, Pose};

pub mod columns;
pub mod reference_error;
pub mod relations;
pub mod results;

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
    /// ([`planar_nees`]); z is 0. A truth with no heading (`truth.theta`
    /// NaN, e.g. a tracker of positions only) is compared in position
    /// only: the heading errors are NaN and the NEES is over the 2
    /// position dof (`nees_dof` 2).
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
        let (nees, nees_dof) = if truth.theta.is_nan() {
            let e = error.fixed_rows::<2>(0).into_owned();
            (nees(&e, &belief.p.fixed_view::<2, 2>(0, 0).into_owned()), 2)
        } else {
            (nees(&error, &belief.p), 3)
        };
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
            nees,
            nees_dof,
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

/// Summary of a run. Errors are against the truth, over the steps it
/// covers; `metrics.json` writes it as [`results::Results`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Steps tallied (simulated steps, or events of a log), compared with
    /// the truth or not.
    pub steps: usize,
    /// Steps compared with the truth (every step of a simulation).
    pub compared: usize,
    /// Time of the last step tallied (s): the simulated time, or the time
    /// a replay covers from its first odometry record.
    pub duration: f64,
    /// Laps of the path completed (scenarios that drive laps; else 0).
    pub laps_completed: usize,
    /// Position RMSE of the estimate (the filter's or the smoother's), m.
    pub position_rmse: f64,
    /// Heading RMSE of the estimate (rad, wrapped errors; for `hover` the attitude
    /// angle); NaN if the truth has no heading.
    pub heading_rmse: f64,
    /// Circular mean of the estimate's wrapped heading errors (truth minus
    /// estimate), rad in (-pi, pi]: a constant offset between the truth's
    /// heading frame and the robot's (motion capture rarely aligns them);
    /// NaN if the truth has no heading.
    pub heading_offset: f64,
    /// Heading RMSE about [`Summary::heading_offset`]: the RMS of
    /// the heading errors minus the offset, wrapped, rad; NaN if the truth
    /// has no heading.
    pub heading_rmse_about_offset: f64,
    /// Share of steps whose heading error minus
    /// [`Summary::heading_offset`] lies within 3 standard deviations of
    /// the estimate's own heading variance; NaN without a heading truth.
    pub within_3_sigma_heading_about_offset: f64,
    /// Mean NEES with the heading errors taken about
    /// [`Summary::heading_offset`] (`(e - c u)^T P^-1 (e - c u)`, `u`
    /// the heading axis); NaN without a heading truth or with mixed dof.
    pub mean_nees_about_offset: f64,
    /// Largest position error of the estimate (m).
    pub max_position_error: f64,
    /// Odometry-only position RMSE (m); NaN if the scenario has none.
    pub odometry_position_rmse: f64,
    /// Odometry-only heading RMSE (rad); NaN if the scenario has none or
    /// the truth has no heading.
    pub odometry_heading_rmse: f64,
    /// Odometry-only largest position error (m); NaN if none.
    pub odometry_max_position_error: f64,
    /// Mean NEES of the EKF (the state dimension for a consistent filter).
    pub mean_nees: f64,
    /// Degrees of freedom of the NEES (the state dimension; 2, the
    /// position, for a truth with no heading).
    pub nees_dof: u32,
    /// Share of steps whose NEES lies in the two-sided 95 % chi-square
    /// interval of `nees_dof` (0.95 for a consistent filter).
    pub nees_in_interval: f64,
    /// Share of steps whose error lies within 3 standard deviations of the
    /// filter's own covariance, per component: x, y, heading (0.997 each
    /// for a consistent Gaussian filter); heading NaN if the truth has no
    /// heading.
    pub within_3_sigma: [f64; 3],
    /// Steps where a measurement arrived (every step tallied).
    pub readings: usize,
    /// Measurements that reached the filter (associated; the others were
    /// dropped).
    pub associated: usize,
    /// Corrections that passed the gate and were applied.
    pub applied: usize,
    /// Share of associated measurements applied (`applied / associated`;
    /// NaN when nothing was associated).
    pub acceptance: f64,
    /// Wall-clock duration of the run (s), including the sink's time. Not
    /// reproducible.
    pub wall_clock: f64,
    /// [`Summary::duration`] over the wall-clock time. Not reproducible.
    pub real_time_factor: f64,
}

impl Summary {
    /// The same summary with every figure that needs the truth NaN ("n/a",
    /// `null` in JSON), as a tally of no compared step gives them: for a
    /// run whose only steps compared with the truth carry nothing to judge
    /// (a start pose copied from that truth). The counts, the duration and
    /// the timing stay.
    #[must_use]
    pub fn without_truth_figures(mut self) -> Self {
        for v in [
            &mut self.position_rmse,
            &mut self.heading_rmse,
            &mut self.heading_offset,
            &mut self.heading_rmse_about_offset,
            &mut self.within_3_sigma_heading_about_offset,
            &mut self.mean_nees_about_offset,
            &mut self.max_position_error,
            &mut self.odometry_position_rmse,
            &mut self.odometry_heading_rmse,
            &mut self.odometry_max_position_error,
            &mut self.mean_nees,
            &mut self.nees_in_interval,
        ] {
            *v = f64::NAN;
        }
        self.within_3_sigma = [f64::NAN; 3];
        self
    }

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
    /// Steps pushed or counted.
    steps: usize,
    /// Steps pushed (compared with the truth).
    compared: usize,
    duration: f64,
    sq_pos: f64,
    sq_heading: f64,
    /// The EKF's wrapped heading errors (rad) of the steps whose truth has
    /// a heading.
    heading_errors: Vec<f64>,
    /// Their estimates' heading variances (rad^2): the share inside 3
    /// sigma about the offset needs the offset first.
    heading_variances: Vec<f32>,
    /// Over the 3-dof samples: sums of `(P^-1 e)_theta` and
    /// `(P^-1)_theta,theta`, for the NEES about the heading offset.
    offset_terms: (f64, f64),
    max_pos: f64,
    odo_n: usize,
    odo_sq_pos: f64,
    odo_sq_heading: f64,
    odo_heading_n: usize,
    odo_max_pos: f64,
    nees_sum: f64,
    nees_in: usize,
    within_3_sigma: [usize; 3],
    nees_dof: u32,
    nees_bounds: (f64, f64),
    /// Whether samples of different NEES dof were pushed (their mean is
    /// then no figure: NaN).
    mixed_dof: bool,
    readings: usize,
    associated: usize,
    applied: usize,
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
            compared: 0,
            duration: 0.0,
            sq_pos: 0.0,
            sq_heading: 0.0,
            heading_errors: Vec::new(),
            heading_variances: Vec::new(),
            offset_terms: (0.0, 0.0),
            max_pos: 0.0,
            odo_n: 0,
            odo_sq_pos: 0.0,
            odo_sq_heading: 0.0,
            odo_heading_n: 0,
            odo_max_pos: 0.0,
            nees_sum: 0.0,
            nees_in: 0,
            within_3_sigma: [0; 3],
            nees_dof,
            nees_bounds: (
                chi2::quantile(0.025, nees_dof)?,
                chi2::quantile(0.975, nees_dof)?,
            ),
            mixed_dof: false,
            readings: 0,
            associated: 0,
            applied: 0,
        })
    }

    /// Adds one step compared with the truth. Its heading figures count
    /// only if its heading error is a number (a truth with no heading gives
    /// NaN); the NEES takes the sample's dof: the first sample's replaces
    /// the tally's, and samples of different dof make the NEES figures
    /// NaN. Its measurement counts as [`Tally::count`]'s.
    pub fn push(&mut self, s: &Sample) {
        if s.nees_dof != self.nees_dof {
            match (
                self.compared,
                chi2::quantile(0.025, s.nees_dof),
                chi2::quantile(0.975, s.nees_dof),
            ) {
                (0, Ok(lo), Ok(hi)) => {
                    self.nees_dof = s.nees_dof;
                    self.nees_bounds = (lo, hi);
                }
                _ => self.mixed_dof = true,
            }
        }
        self.compared += 1;
        let e2 = s.position_error_sq();
        self.sq_pos += e2;
        if !s.heading_error.is_nan() {
            self.sq_heading += s.heading_error * s.heading_error;
            self.heading_errors.push(s.heading_error);
            #[allow(clippy::cast_possible_truncation)]
            self.heading_variances.push(s.covariance[2][2] as f32);
            let p = Matrix3::from_fn(|i, j| s.covariance[i][j]);
            if let Some(inverse) = p.try_inverse() {
                let e = Vector3::new(
                    s.truth[0] - s.estimate[0],
                    s.truth[1] - s.estimate[1],
                    s.heading_error,
                );
                self.offset_terms.0 += (inverse * e)[2];
                self.offset_terms.1 += inverse[(2, 2)];
            } else {
                self.offset_terms.0 = f64::NAN;
            }
        }
        self.max_pos = self.max_pos.max(e2.sqrt());
        if let Some((pos, heading_err)) = s.odometry {
            let o2: f64 = (0..3).map(|i| (s.truth[i] - pos[i]).powi(2)).sum();
            self.odo_n += 1;
            self.odo_sq_pos += o2;
            if !heading_err.is_nan() {
                self.odo_sq_heading += heading_err * heading_err;
                self.odo_heading_n += 1;
            }
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
        // A NaN heading error (no heading in the truth) counts nowhere: its
        // share is over the steps with a heading.
        for ((count, e), v) in self.within_3_sigma.iter_mut().zip(errors).zip(variances) {
            if e * e <= 9.0 * v {
                *count += 1;
            }
        }
        self.count(
            s.time,
            s.measured,
            s.correction.map(|(_, _, applied)| applied),
        );
    }

    /// Adds one step with no truth to compare with: its time `time` (s),
    /// whether a measurement arrived, and whether it reached the gate
    /// (`Some`) and was applied (`Some(true)`).
    pub fn count(&mut self, time: f64, measured: bool, applied: Option<bool>) {
        self.steps += 1;
        self.duration = time;
        self.readings += usize::from(measured);
        if let Some(applied) = applied {
            self.associated += 1;
            self.applied += usize::from(applied);
        }
    }

    /// The summary of the steps pushed so far, with `laps_completed`.
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn summary(&self, laps_completed: usize) -> Summary {
        // No step compared with the truth: every figure that needs it is
        // NaN ("n/a", null in JSON), never 0.
        let n = if self.compared > 0 {
            self.compared as f64
        } else {
            f64::NAN
        };
        let (odo_pos, odo_max) = if self.odo_n > 0 {
            let m = self.odo_n as f64;
            ((self.odo_sq_pos / m).sqrt(), self.odo_max_pos)
        } else {
            (f64::NAN, f64::NAN)
        };
        let odo_heading = (self.odo_sq_heading / nonzero(self.odo_heading_n)).sqrt();
        let heading_n = nonzero(self.heading_errors.len());
        let (offset, about_offset) = heading_offset(&self.heading_errors);
        let inside_about_offset = self
            .heading_errors
            .iter()
            .zip(&self.heading_variances)
            .filter(|(e, v)| {
                let d = locus_core::wrap_angle(*e - offset);
                d * d <= 9.0 * f64::from(**v)
            })
            .count() as f64
            / heading_n;
        let nees_n = if self.mixed_dof { f64::NAN } else { n };
        // Only when every sample had a heading (3 dof). The heading errors
        // enter unwrapped: exact unless they straddle +-pi.
        let nees_about_offset = if self.heading_errors.len() == self.compared {
            (self.nees_sum - 2.0 * offset * self.offset_terms.0
                + offset * offset * self.offset_terms.1)
                / nees_n
        } else {
            f64::NAN
        };
        let wall_clock = self.started.elapsed().as_secs_f64();
        Summary {
            steps: self.steps,
            compared: self.compared,
            duration: self.duration,
            laps_completed,
            position_rmse: (self.sq_pos / n).sqrt(),
            heading_rmse: (self.sq_heading / heading_n).sqrt(),
            heading_offset: offset,
            heading_rmse_about_offset: about_offset,
            within_3_sigma_heading_about_offset: inside_about_offset,
            mean_nees_about_offset: nees_about_offset,
            max_position_error: if self.compared > 0 {
                self.max_pos
            } else {
                f64::NAN
            },
            odometry_position_rmse: odo_pos,
            odometry_heading_rmse: odo_heading,
            odometry_max_position_error: odo_max,
            mean_nees: self.nees_sum / nees_n,
            nees_dof: self.nees_dof,
            nees_in_interval: self.nees_in as f64 / nees_n,
            within_3_sigma: [
                self.within_3_sigma[0] as f64 / n,
                self.within_3_sigma[1] as f64 / n,
                self.within_3_sigma[2] as f64 / heading_n,
            ],
            readings: self.readings,
            associated: self.associated,
            applied: self.applied,
            acceptance: if self.associated > 0 {
                self.applied as f64 / self.associated as f64
            } else {
                f64::NAN
            },
            wall_clock,
            real_time_factor: if wall_clock > 0.0 {
                self.duration / wall_clock
            } else {
                f64::INFINITY
            },
        }
    }
}

/// `n` as a divisor: NaN for 0, so that a mean over nothing is NaN.
#[allow(clippy::cast_precision_loss)]
fn nonzero(n: usize) -> f64 {
    if n > 0 { n as f64 } else { f64::NAN }
}

/// The circular mean of wrapped heading errors (rad, in (-pi, pi]) and
/// the RMS of the errors minus it, each difference wrapped (rad); both NaN
/// for no errors (or errors whose mean direction is undefined).
#[must_use]
pub fn heading_offset(errors: &[f64]) -> (f64, f64) {
    let (sin, cos) = errors
        .iter()
        .fold((0.0, 0.0), |(s, c), e| (s + e.sin(), c + e.cos()));
    if errors.is_empty() || (sin == 0.0 && cos == 0.0) {
        return (f64::NAN, f64::NAN);
    }
    let offset = locus_core::wrap_angle(sin.atan2(cos));
    let sq: f64 = errors
        .iter()
        .map(|e| locus_core::wrap_angle(e - offset).powi(2))
        .sum();
    (offset, (sq / nonzero(errors.len())).sqrt())
}

#[cfg(test)]
mod tests {
    use super::{Sample, Tally};
    use locus_core::nalgebra::{Matrix3, Vector3};
    use locus_core::{Belief, Pose, wrap_angle};

    /// A sample of an estimate at `(x, y, theta)` with covariance
    /// `diag(0.01, 0.01, 0.0025)` against `truth`, odometry at the truth.
    fn sample(k: usize, truth: &Pose<f64>, x: f64, y: f64, theta: f64) -> Sample {
        let belief = Belief::new(
            Vector3::new(x, y, theta),
            Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 0.0025)),
        );
        Sample::planar(k, k as f64, truth, &belief, Some(truth), None, false)
    }

    /// A truth whose heading frame is turned by a constant 0.7 rad from the
    /// robot's: the heading RMSE as is reads about 0.7 rad, about its offset
    /// about 0 (here the estimate's own small errors), and the offset is
    /// recovered, across the +-pi wrap too.
    #[test]
    fn a_constant_heading_offset_is_recovered_and_taken_out() {
        for offset in [0.7, -3.0] {
            let mut t = Tally::new(3).unwrap();
            for k in 0..200 {
                let theta = wrap_angle(0.05 * k as f64);
                // The estimate's own heading error: +-0.01 rad, mean 0.
                let own = if k % 2 == 0 { 0.01 } else { -0.01 };
                let truth = Pose::new(0.1 * k as f64, 1.0, wrap_angle(theta + offset));
                t.push(&sample(
                    k,
                    &truth,
                    truth.x,
                    truth.y,
                    wrap_angle(theta - own),
                ));
            }
            let s = t.summary(0);
            assert!((s.heading_offset - offset).abs() < 1e-9, "{s:?}");
            assert!((s.heading_rmse_about_offset - 0.01).abs() < 1e-9, "{s:?}");
            assert!((s.heading_rmse - offset.abs()).abs() < 0.02, "{s:?}");
            // About the offset, the estimate's own errors are honest.
            assert_eq!(s.within_3_sigma[2], 0.0, "{s:?}");
            assert_eq!(s.within_3_sigma_heading_about_offset, 1.0, "{s:?}");
            assert!(s.mean_nees_about_offset < 0.5 * s.mean_nees, "{s:?}");
        }
    }

    /// A truth with no heading: heading figures NaN (never 0), the NEES
    /// over the 2 position dof.
    #[test]
    fn a_truth_without_heading_is_compared_in_position_only() {
        let mut t = Tally::new(3).unwrap();
        for k in 0..10 {
            let truth = Pose::new(1.0, 2.0, f64::NAN);
            let s = sample(k, &truth, 1.1, 2.0, 0.4);
            assert_eq!(s.nees_dof, 2);
            assert!((s.nees - 1.0).abs() < 1e-12, "0.1^2 / 0.01 = 1: {}", s.nees);
            t.push(&s);
        }
        let s = t.summary(0);
        assert_eq!(s.nees_dof, 2);
        assert!((s.mean_nees - 1.0).abs() < 1e-12);
        assert!((s.position_rmse - 0.1).abs() < 1e-12);
        assert_eq!(s.within_3_sigma[..2], [1.0, 1.0]);
        for v in [
            s.heading_rmse,
            s.heading_offset,
            s.heading_rmse_about_offset,
            s.odometry_heading_rmse,
            s.within_3_sigma[2],
        ] {
            assert!(v.is_nan(), "{s:?}");
        }
        // Samples of both kinds in one tally: no mean NEES.
        t.push(&sample(10, &Pose::new(1.0, 2.0, 0.0), 1.0, 2.0, 0.0));
        assert!(t.summary(0).mean_nees.is_nan());
    }

    /// A step the truth does not cover counts its measurement and its
    /// time, and leaves the errors to the compared steps.
    #[test]
    fn a_step_without_truth_is_counted_not_compared() {
        let mut t = Tally::new(3).unwrap();
        t.push(&sample(0, &Pose::new(0.0, 0.0, 0.0), 0.1, 0.0, 0.0));
        t.count(5.0, true, Some(true));
        t.count(6.0, true, Some(false));
        t.count(7.0, true, None);
        t.count(8.0, false, None);
        let s = t.summary(0);
        assert_eq!((s.steps, s.compared), (5, 1));
        assert_eq!((s.readings, s.associated, s.applied), (3, 2, 1));
        assert_eq!(s.acceptance, 0.5);
        assert_eq!(s.duration, 8.0);
        assert!((s.position_rmse - 0.1).abs() < 1e-12, "{s:?}");
        assert_eq!(s.within_3_sigma[..2], [1.0, 1.0]);
    }

    /// A run compared with no truth (a log without ground truth) has no
    /// error figures: they read "n/a" (NaN, `null` in JSON), never 0.
    #[test]
    fn an_empty_tally_reports_no_figure_as_zero() {
        let s = Tally::new(3).unwrap().summary(0);
        for (name, v) in [
            ("position_rmse", s.position_rmse),
            ("heading_rmse", s.heading_rmse),
            ("heading_offset", s.heading_offset),
            ("heading_rmse_about_offset", s.heading_rmse_about_offset),
            ("within_3_sigma heading", s.within_3_sigma[2]),
            ("max_position_error", s.max_position_error),
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
