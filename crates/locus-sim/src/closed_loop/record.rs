//! What one step of the closed loop logs: [`StepRecord`], its CSV row
//! (`log.csv` of `locus run`) and its evaluation [`Sample`].

use locus_core::wrap_angle;

use crate::robot::Pose;
use crate::sensors::IrReading;
use locus_eval::{Record, Sample, columns};

/// What one step of the closed loop produced (SI units, world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRecord {
    /// Step index (0-based).
    pub step: usize,
    /// Simulated time at the end of the step (s).
    pub time: f64,
    /// True pose.
    pub truth: Pose<f64>,
    /// EKF estimate `[x, y, theta]` (m, m, rad).
    pub ekf: [f64; 3],
    /// EKF covariance of `[x, y, theta]` (m^2, m rad, rad^2), symmetric.
    pub ekf_cov: [[f64; 3]; 3],
    /// Odometry-only estimate `[x, y, theta]` (m, m, rad).
    pub odometry: [f64; 3],
    /// Wheel travels from the encoders `[d1 (right), d2 (left)]` (m).
    pub wheel_travel: [f64; 2],
    /// IR readings `(d_s1, d_s2)` (m) when both were in range.
    pub ir: Option<(f64, f64)>,
    /// What each IR sensor read, `[s1, s2]` (front, rear): a distance
    /// (m), or why it read none. [`StepRecord::ir`] is the pair of them
    /// when both read a distance (in the ideal mode, when the truth's pair
    /// also sees one wall).
    pub ir_each: [IrReading; 2],
    /// Innovation `z - h(X-)` `[m, rad]` when a reading was associated with
    /// a wall.
    pub innovation: Option<[f64; 2]>,
    /// NIS of that innovation (2 dof).
    pub nis: Option<f64>,
    /// Whether the correction was applied (passed the gate).
    pub applied: bool,
    /// Diagonal of `H G` (`G = P- H^T S^-1` the gain of the correction,
    /// `H` at the prior) when a reading was associated: the share of the
    /// position innovation moved into the measured position coordinate and
    /// of the heading innovation into the heading (0: measurement ignored,
    /// 1: taken as is). `[0, 0]` if the gate rejected the correction.
    pub gain: Option<[f64; 2]>,
    /// NEES of the EKF after the step (3 dof, heading error wrapped).
    pub nees: f64,
}

impl StepRecord {
    /// Column names of [`StepRecord::csv_row`], each ending in its unit
    /// (`_s`, `_m`, `_rad`, `_m2`, `_rad2`; none for a count or a ratio).
    pub const CSV_COLUMNS: [&'static str; 24] = columns::header(
        &["step", "time_s"],
        &[
            "odo_x_m",
            "odo_y_m",
            "odo_theta_rad",
            "ir_s1_m",
            "ir_s2_m",
            "innov_pos_m",
            "innov_theta_rad",
            "nis",
            "applied",
            "nees",
            "gain_pos",
            "gain_theta",
        ],
    );
}

impl Record for StepRecord {
    /// The CSV header line (no newline): [`StepRecord::CSV_COLUMNS`].
    fn csv_header() -> String {
        Self::CSV_COLUMNS.join(",")
    }

    /// The record as one CSV line (no newline); absent values are empty.
    fn csv_row(&self) -> String {
        let (f, opt) = (columns::fixed, columns::optional);
        let (s1, s2) = self.ir.unzip();
        let t = &self.truth;
        let pose = columns::pose_fields([t.x, t.y, t.theta], self.ekf, &self.ekf_cov);
        let rest = [
            f(self.odometry[0]),
            f(self.odometry[1]),
            f(self.odometry[2]),
            opt(s1),
            opt(s2),
            opt(self.innovation.map(|i| i[0])),
            opt(self.innovation.map(|i| i[1])),
            opt(self.nis),
            u8::from(self.applied).to_string(),
            format!("{:.6}", self.nees),
            opt(self.gain.map(|g| g[0])),
            opt(self.gain.map(|g| g[1])),
        ];
        [self.step.to_string(), format!("{:.2}", self.time)]
            .into_iter()
            .chain(pose)
            .chain(rest)
            .collect::<Vec<_>>()
            .join(",")
    }

    fn sample(&self) -> Sample {
        let t = &self.truth;
        Sample {
            step: self.step,
            time: self.time,
            truth: [t.x, t.y, 0.0],
            truth_heading: t.theta,
            estimate: [self.ekf[0], self.ekf[1], 0.0],
            estimate_heading: self.ekf[2],
            heading_error: wrap_angle(t.theta - self.ekf[2]),
            covariance: self.ekf_cov,
            var_z: 0.0,
            odometry: Some((
                [self.odometry[0], self.odometry[1], 0.0],
                wrap_angle(t.theta - self.odometry[2]),
            )),
            nees: self.nees,
            nees_dof: 3,
            correction: self.nis.map(|nis| (nis, 2, self.applied)),
            measured: self.ir.is_some(),
        }
    }
}
