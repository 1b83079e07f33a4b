//! Baselines for a robot on a rail ranging a wall ahead of it (the
//! laser_wall_1d data set: position `x` along the rail, a wall at
//! `x = wall`, one beam along the rail, speed odometry): what a replay of
//! such a log is judged beside.
//!
//! * **The range alone**: `x = wall - r` at each scan.
//! * **A linear Kalman filter given the published noise** (the course's
//!   model, Barfoot, "State Estimation for Robotics", 2017, section 3.3):
//!   `x_k = x_(k-1) + T v_k` with variance `T^2 v_var` added per step, the
//!   range `r_k = wall - x_k` with variance `r_var`; its `T` is the time
//!   between the odometry records and `v_k` the record at `k`.
//!
//! Each is compared with the log's truth at the scan times: position RMSE
//! (m) and the share of scans whose error lies within 3 of the estimate's
//! own standard deviations. Units: m, s.

use locus_logs::scans::Reading;

use crate::Log;

/// A baseline's figures against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Baseline {
    /// Scans compared with the truth.
    pub compared: usize,
    /// Position RMSE, m (NaN with none compared).
    pub rmse: f64,
    /// Share of compared scans inside the estimate's own 3 sigma; NaN for
    /// the range alone, which claims no uncertainty.
    pub within_3_sigma: f64,
}

/// The range alone and the linear Kalman filter of the module doc on
/// `log` (its first beam sensor's scans, its odometry and truth), with the
/// wall at `wall` (m) and the published range and speed variances `r_var`
/// (m^2) and `v_var` (m^2/s^2). The truth is interpolated at each scan's
/// time between samples at most `max_gap` (s) apart, as the replay's is
/// (`Config::truth_max_gap`).
#[must_use]
#[allow(clippy::cast_precision_loss)]
pub fn baselines(log: &Log, wall: f64, r_var: f64, v_var: f64, max_gap: f64) -> [Baseline; 2] {
    let mut truth = log.truth.cursor();
    let (mut range_sq, mut kf_sq, mut inside, mut n) = (0.0, 0.0, 0usize, 0usize);
    // The filter starts at the first range, with its variance.
    let mut x = f64::NAN;
    let mut p = r_var;
    let mut odometry = log.odometry.iter().peekable();
    let mut last_time = f64::NAN;
    for scan in log.scans.iter() {
        // Predict with every odometry record up to the scan.
        while let Some(o) = odometry.next_if(|o| o.time <= scan.time) {
            if last_time.is_finite() && x.is_finite() {
                let dt = o.time - last_time;
                x += dt * o.v;
                p += dt * dt * v_var;
            }
            last_time = o.time;
        }
        let Some(&stored) = scan.ranges.first() else {
            continue;
        };
        let Reading::Range(r) = Reading::of(stored) else {
            continue;
        };
        let z = wall - f64::from(r);
        if x.is_finite() {
            let k = p / (p + r_var);
            x += k * (z - x);
            p *= 1.0 - k;
        } else {
            x = z;
        }
        if let Some(t) = truth.pose_at(scan.time, max_gap) {
            n += 1;
            range_sq += (z - t.x).powi(2);
            kf_sq += (x - t.x).powi(2);
            inside += usize::from((x - t.x).abs() <= 3.0 * p.sqrt());
        }
    }
    let of = |sq: f64| {
        if n == 0 {
            f64::NAN
        } else {
            (sq / n as f64).sqrt()
        }
    };
    [
        Baseline {
            compared: n,
            rmse: of(range_sq),
            within_3_sigma: f64::NAN,
        },
        Baseline {
            compared: n,
            rmse: of(kf_sq),
            within_3_sigma: if n == 0 {
                f64::NAN
            } else {
                inside as f64 / n as f64
            },
        },
    ]
}
