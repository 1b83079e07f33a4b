//! The logged step of `wall45` ([`Wall45Record`]) and its CSV row.

use locus_core::Belief;
use locus_core::nalgebra::{Matrix2, Matrix2x3, Vector2};
use locus_eval::{Record, Sample, columns};

/// What one correction with the paper's laser model (m = 2) was given: the
/// prior and the quantities the papers' Nios II computed in software for
/// the FPGA core (`H`, `R`, `z`, `h(X-)`), so that the core can be run on
/// the same corrections.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserCorrection {
    /// The prior belief `X-`, `P-` (m, m, rad).
    pub prior: Belief<f64, 3>,
    /// The measurement Jacobian `H` at `X-`.
    pub h: Matrix2x3<f64>,
    /// The measurement noise `R` (m^2).
    pub r: Matrix2<f64>,
    /// The measurement `Z = [u, v]` (m).
    pub z: Vector2<f64>,
    /// The predicted measurement `h(X-)` (m).
    pub hx: Vector2<f64>,
}

/// One step of `wall45` (SI units, world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall45Record {
    /// The common figures (truth, estimate, covariance, odometry alone,
    /// NEES, NIS).
    pub sample: Sample,
    /// The Table III instant (1..=6) whose dwell ends at this step, if any.
    pub instant: Option<usize>,
    /// Whether the robot was moving during the step.
    pub moving: bool,
    /// Measured tread speeds `[V_L, V_R]` (m/s) given to the filter.
    pub tread_speeds: [f64; 2],
    /// The laser range reading (m), if the beam hit the wall.
    pub range: Option<f64>,
    /// Innovation of the correction (m): the range component (`u` for the
    /// paper's model, `gamma` for the exact one), if corrected.
    pub innovation: Option<f64>,
    /// The correction's inputs, for the paper's model.
    pub laser: Option<LaserCorrection>,
}

impl Record for Wall45Record {
    fn csv_header() -> String {
        const COLUMNS: [&str; 24] = columns::header(
            &["step", "time_s", "instant", "moving"],
            &[
                "odo_x_m",
                "odo_y_m",
                "odo_theta_err_rad",
                "v_l_m_per_s",
                "v_r_m_per_s",
                "range_m",
                "innovation_m",
                "nis",
                "applied",
                "nees",
            ],
        );
        COLUMNS.join(",")
    }

    fn csv_row(&self) -> String {
        let s = &self.sample;
        let (f, opt) = (columns::fixed, columns::optional);
        let (odo, odo_th) = s.odometry.unwrap_or(([f64::NAN; 3], f64::NAN));
        let (nis, applied) = s.correction.map_or((None, String::new()), |(n, _, a)| {
            (Some(n), u8::from(a).to_string())
        });
        let lead = [
            s.step.to_string(),
            format!("{:.2}", s.time),
            self.instant.map_or_else(String::new, |i| i.to_string()),
            u8::from(self.moving).to_string(),
        ];
        let truth = [s.truth[0], s.truth[1], s.truth_heading];
        let estimate = [s.estimate[0], s.estimate[1], s.estimate_heading];
        let rest = [
            f(odo[0]),
            f(odo[1]),
            f(odo_th),
            f(self.tread_speeds[0]),
            f(self.tread_speeds[1]),
            opt(self.range),
            opt(self.innovation),
            opt(nis),
            applied,
            format!("{:.6}", s.nees),
        ];
        lead.into_iter()
            .chain(columns::pose_fields(truth, estimate, &s.covariance))
            .chain(rest)
            .collect::<Vec<_>>()
            .join(",")
    }

    fn sample(&self) -> Sample {
        self.sample
    }
}
