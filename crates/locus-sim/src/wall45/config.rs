//! The `wall45` scenario's Table III constants and configuration
//! ([`Wall45Config`]) with its validation.

use serde::{Deserialize, Serialize};

use crate::closed_loop::Error;
use crate::scenario_file::within;

/// Table III of seed 000 (spec section 2), as the paper gives it: for each
/// instant 1..=6, `[real x (cm), real y (cm), real theta (deg), EKF x (cm),
/// EKF y (cm), EKF theta (deg)]`.
pub const PAPER_TABLE3: [[f64; 6]; 6] = [
    [0.0, 0.0, 0.0, -0.05, 0.1, -0.001],
    [27.36, 0.0, 0.0, 24.821, 0.092, 0.27],
    [27.36, 0.0, 47.5, 24.17, -1.36, 49.14],
    [38.38, 11.88, 47.5, 34.75, 10.92, 49.24],
    [38.38, 11.88, 61.7, 35.01, 11.52, 63.81],
    [46.47, 27.7, 61.7, 44.18, 30.13, 63.64],
];

/// Number of instants of Table III.
pub const INSTANTS: usize = 6;

/// Which laser measurement model the EKF corrects with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LaserModel {
    /// The paper's model (eq. 12-15, [`LaserWallPaper`]): `Z = [u, v]`, `H`
    /// with the hit point held fixed.
    ///
    /// [`LaserWallPaper`]: locus_models::laser_wall::LaserWallPaper
    #[default]
    Paper,
    /// The exact range model ([`LaserRange`]): `z = gamma`, exact Jacobian.
    ///
    /// [`LaserRange`]: locus_models::laser_wall::LaserRange
    Exact,
}

/// How the simulated noise is generated (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Wall45Noise {
    /// Exact-arc truth with a track error, noisy tread speeds, laser range
    /// noise; fixed true start at the origin.
    #[default]
    Realistic,
    /// Noise exactly as the filter's `Q` and `R` assume.
    Ideal,
}

/// Configuration of the `wall45` scenario (SI units: m, s, rad). The
/// defaults ([`Wall45Config::default`]) are the spec's values, \[assumed\]
/// where the paper gives none.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Wall45Config {
    /// Sample time `dT` (s). \[assumed\] 0.1 s.
    pub dt: f64,
    /// Straight-leg speed (m/s). \[assumed\] 0.10 m/s.
    pub speed: f64,
    /// Turn rate on the spot (rad/s). \[assumed\] 0.3 rad/s.
    pub turn_rate: f64,
    /// Time at rest at each of the six instants (s), the figures being taken
    /// at its end. \[assumed\] 2 s.
    pub dwell: f64,
    /// The wall `x + y = a`: `a` (m). 1.17 m.
    pub wall_a: f64,
    /// Effective track width `D` of the filter's model (m). \[assumed\] 0.50 m.
    pub track: f64,
    /// Relative error of the true effective track (`Realistic` only): the
    /// robot turns about `D (1 + track_error)`. \[assumed\] 0.03.
    pub track_error: f64,
    /// Standard deviation of each measured tread speed while moving
    /// (`Realistic` only, m/s). \[assumed\] 0.01 m/s.
    pub true_speed_sigma: f64,
    /// The filter's `s_VL = s_VR` while moving (m/s). \[assumed\] 0.02 m/s
    /// (covers the speed noise and the track error).
    pub filter_speed_sigma: f64,
    /// The filter's `s_VL = s_VR` at rest (m/s; the encoders read 0).
    /// \[assumed\] 1e-4 m/s.
    pub rest_speed_sigma: f64,
    /// Laser mount `[x_si (m), y_si (m), beta_i (rad)]`. `[0.17, 0, 0]`.
    pub mount: [f64; 3],
    /// Laser range noise at rest, 1 sigma (m): the simulated noise and the
    /// filter's `s_u = s_v = s_gamma`. \[assumed\] 0.005 m.
    pub laser_sigma_rest: f64,
    /// Laser range noise while moving (m). \[assumed\] 0.02 m (the scanner is
    /// less accurate in motion).
    pub laser_sigma_moving: f64,
    /// Largest laser range (m). 8 m.
    pub max_range: f64,
    /// The filter's measurement model. Default [`LaserModel::Paper`].
    pub model: LaserModel,
    /// Initial estimate `X0` (m, m, rad): the paper's `[2 cm, 0.1 cm, 0]`.
    pub start_estimate: [f64; 3],
    /// Standard deviation of the initial estimate (m, m, rad).
    /// \[assumed\] `[0.03, 0.03, 0.035]` (3 cm, 3 cm, 2 deg).
    pub initial_std: [f64; 3],
    /// Confidence of a chi-square gate on the NIS (`None`: no gate, as the
    /// paper). Default `None`.
    pub gate_confidence: Option<f64>,
    /// How the simulated noise is generated. Default `Realistic`.
    pub noise: Wall45Noise,
}

impl Default for Wall45Config {
    fn default() -> Self {
        Self {
            dt: 0.1,
            speed: 0.10,
            turn_rate: 0.3,
            dwell: 2.0,
            wall_a: 1.17,
            track: locus_models::skid_steer::DEFAULT_EFFECTIVE_TRACK,
            track_error: 0.03,
            true_speed_sigma: 0.01,
            filter_speed_sigma: 0.02,
            rest_speed_sigma: 1e-4,
            mount: [0.17, 0.0, 0.0],
            laser_sigma_rest: 0.005,
            laser_sigma_moving: 0.02,
            max_range: locus_models::laser_wall::DEFAULT_MAX_RANGE,
            model: LaserModel::Paper,
            start_estimate: [0.02, 0.001, 0.0],
            initial_std: [0.03, 0.03, 0.035],
            gate_confidence: None,
            noise: Wall45Noise::Realistic,
        }
    }
}

impl Wall45Config {
    /// The ideal-noise variant ([`Wall45Noise::Ideal`]) of the default.
    #[must_use]
    pub fn ideal() -> Self {
        Self {
            noise: Wall45Noise::Ideal,
            ..Self::default()
        }
    }

    /// `Ok(())` if every value is in its domain.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first bad field.
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        // Plausible ranges (SI): the path is Table III's (about 0.5 m and
        // 1.1 rad), so with these bounds a run stays far below 1e7 steps.
        let checks: [(bool, &'static str, &'static str); 16] = [
            (
                within(self.dt, 1e-4, 1.0),
                "dt",
                "must be in [1e-4, 1] s (a run is at most 1e7 steps)",
            ),
            (
                within(self.speed, 1e-3, 10.0),
                "speed",
                "must be in [0.001, 10] m/s",
            ),
            (
                within(self.turn_rate, 1e-3, 10.0),
                "turn_rate",
                "must be in [0.001, 10] rad/s",
            ),
            (
                within(self.dwell, 0.5 * self.dt, 100.0),
                "dwell",
                "must be in [dt / 2, 100] s (one step at rest per instant)",
            ),
            (
                within(self.wall_a, -100.0, 100.0),
                "wall_a",
                "must be in [-100, 100] m",
            ),
            (
                within(self.track, 0.01, 10.0),
                "track",
                "must be in [0.01, 10] m",
            ),
            (
                self.track_error > -0.5 && self.track_error < 0.5,
                "track_error",
                "must be in (-0.5, 0.5)",
            ),
            (
                within(self.true_speed_sigma, 0.0, 10.0),
                "true_speed_sigma",
                "must be in [0, 10] m/s",
            ),
            (
                pos(self.filter_speed_sigma) && self.filter_speed_sigma <= 10.0,
                "filter_speed_sigma",
                "must be in (0, 10] m/s",
            ),
            (
                pos(self.rest_speed_sigma) && self.rest_speed_sigma <= 10.0,
                "rest_speed_sigma",
                "must be in (0, 10] m/s",
            ),
            (
                self.mount.iter().all(|v| within(*v, -10.0, 10.0)),
                "mount",
                "must be in [-10, 10] (m, m, rad)",
            ),
            (
                pos(self.laser_sigma_rest) && self.laser_sigma_rest <= 10.0,
                "laser_sigma_rest",
                "must be in (0, 10] m",
            ),
            (
                pos(self.laser_sigma_moving) && self.laser_sigma_moving <= 10.0,
                "laser_sigma_moving",
                "must be in (0, 10] m",
            ),
            (
                pos(self.max_range) && self.max_range <= 1000.0,
                "max_range",
                "must be in (0, 1000] m",
            ),
            (
                self.start_estimate
                    .iter()
                    .all(|v| within(*v, -100.0, 100.0))
                    && self.initial_std.iter().all(|v| pos(*v) && *v <= 10.0),
                "start_estimate",
                "must be in [-100, 100] (m, m, rad) and initial_std in (0, 10]",
            ),
            (
                self.gate_confidence
                    .is_none_or(|c| c.is_finite() && c > 0.0 && c < 1.0),
                "gate_confidence",
                "must be in (0, 1)",
            ),
        ];
        match checks.iter().find(|(ok, _, _)| !ok) {
            Some(&(_, field, reason)) => Err(Error::Invalid { field, reason }),
            None => Ok(()),
        }
    }
}
