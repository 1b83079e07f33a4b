//! The logged step of `tricycle-slip` ([`TricycleSlipRecord`]) and its CSV
//! row.

use locus_core::wrap_angle;
use locus_eval::{Record, Sample, columns};
use locus_odometry::redundant::Reading;

/// One step of `tricycle-slip` (SI units, world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TricycleSlipRecord {
    /// The common figures; its odometry is the rear-only dead reckoning.
    pub sample: Sample,
    /// The slip-rejecting dead reckoning `[x, y, theta]` (m, m, rad).
    pub slip_rejecting: [f64; 3],
    /// The rear-only dead reckoning `[x, y, theta]` (m, m, rad).
    pub rear_only: [f64; 3],
    /// The step's encoder counts (left, right, front, steering).
    pub reading: Reading,
    /// Laser ranges of the beams this step (m), `None` when not scanned or
    /// no hit.
    pub ranges: [Option<f64>; 3],
}

impl TricycleSlipRecord {
    /// Position error (m) and wrapped heading error (rad) of the
    /// slip-rejecting odometry against the truth.
    #[must_use]
    pub fn slip_rejecting_error(&self) -> (f64, f64) {
        let s = &self.sample;
        (
            (s.truth[0] - self.slip_rejecting[0]).hypot(s.truth[1] - self.slip_rejecting[1]),
            wrap_angle(s.truth_heading - self.slip_rejecting[2]),
        )
    }

    /// Position error (m) and wrapped heading error (rad) of the rear-only
    /// odometry against the truth.
    #[must_use]
    pub fn rear_only_error(&self) -> (f64, f64) {
        let s = &self.sample;
        (
            (s.truth[0] - self.rear_only[0]).hypot(s.truth[1] - self.rear_only[1]),
            wrap_angle(s.truth_heading - self.rear_only[2]),
        )
    }
}

impl Record for TricycleSlipRecord {
    fn csv_header() -> String {
        const COLUMNS: [&str; 26] = columns::header(
            &["step", "time_s"],
            &[
                "rear_odo_x_m",
                "rear_odo_y_m",
                "rear_odo_theta_rad",
                "slip_rej_odo_x_m",
                "slip_rej_odo_y_m",
                "slip_rej_odo_theta_rad",
                "n_l",
                "n_r",
                "n_f",
                "n_s",
                "range_0_m",
                "range_1_m",
                "range_2_m",
                "nees",
            ],
        );
        COLUMNS.join(",")
    }

    fn csv_row(&self) -> String {
        let s = &self.sample;
        let (f, opt) = (columns::fixed, columns::optional);
        let truth = [s.truth[0], s.truth[1], s.truth_heading];
        let estimate = [s.estimate[0], s.estimate[1], s.estimate_heading];
        let rest = [
            f(self.rear_only[0]),
            f(self.rear_only[1]),
            f(self.rear_only[2]),
            f(self.slip_rejecting[0]),
            f(self.slip_rejecting[1]),
            f(self.slip_rejecting[2]),
            self.reading.n_l.to_string(),
            self.reading.n_r.to_string(),
            self.reading.n_f.to_string(),
            self.reading.n_s.to_string(),
            opt(self.ranges[0]),
            opt(self.ranges[1]),
            opt(self.ranges[2]),
            format!("{:.6}", s.nees),
        ];
        [s.step.to_string(), format!("{:.2}", s.time)]
            .into_iter()
            .chain(columns::pose_fields(truth, estimate, &s.covariance))
            .chain(rest)
            .collect::<Vec<_>>()
            .join(",")
    }

    fn sample(&self) -> Sample {
        self.sample
    }
}
