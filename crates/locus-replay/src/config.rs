//! The parameters of a replay and their checks.

use crate::Error;

/// Parameters of a replay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Power spectral density of the forward-speed noise, m^2/s (white
    /// noise on `v`: a step of `dt` seconds gets variance `q_v / dt`, so the
    /// position variance grows by about `q_v` per second whatever the
    /// odometry rate).
    pub q_v: f64,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    pub q_omega: f64,
    /// Range noise standard deviation, m.
    pub sigma_range: f64,
    /// Bearing noise standard deviation, rad.
    pub sigma_bearing: f64,
    /// Scale factor applied to the logged forward speed (1 = as logged).
    pub v_scale: f64,
    /// Scale factor applied to the logged turn rate (1 = as logged).
    pub omega_scale: f64,
    /// Chi-square gate confidence in (0, 1), or `None` for no gate.
    pub gate: Option<f64>,
    /// Consecutive gate rejections after which the covariance is inflated
    /// and the sighting retried (>= 1).
    pub recover_after: u32,
    /// Factor the covariance is multiplied by on recovery (> 1).
    pub inflation: f64,
    /// Initial standard deviations of x, y (m) and heading (rad).
    pub initial_std: [f64; 3],
    /// History kept for late sightings, s (> 0): a sighting up to this much
    /// older than the latest arrival is applied at its own time.
    pub horizon: f64,
    /// Widest spacing of two ground-truth samples to interpolate between,
    /// s; events in wider gaps are not compared.
    pub truth_max_gap: f64,
}

impl Default for Config {
    /// Values for MRCLAM-like logs (commanded velocities, a camera's range
    /// and bearing), picked by hand from two small grids (16 settings) on
    /// dataset 6, for the position RMSE of the five robots and its rise
    /// with 5 % corrupted sightings: `q_v` 0.01 m^2/s, `q_omega` 0.01
    /// rad^2/s, range 0.2 m, bearing 0.03 rad; a 99.9 % gate, inflation
    /// by 4 after 5 consecutive rejections; a 1 s history. Larger `q`
    /// (e.g. 0.1 and 0.5) let the covariance grow so wide during the
    /// logs' stretches without sightings (up to about 30 s) that corrupted
    /// sightings pass the gate.
    fn default() -> Self {
        Self {
            q_v: 0.01,
            q_omega: 0.01,
            sigma_range: 0.2,
            sigma_bearing: 0.03,
            v_scale: 1.0,
            omega_scale: 1.0,
            gate: Some(0.999),
            recover_after: 5,
            inflation: 4.0,
            initial_std: [0.05, 0.05, 0.05],
            horizon: 1.0,
            truth_max_gap: 0.25,
        }
    }
}

impl Config {
    /// Checks every value's range.
    ///
    /// # Errors
    /// [`Error::InvalidConfig`] naming the first bad value.
    pub fn validate(&self) -> Result<(), Error> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let checks = [
            (positive(self.q_v), "q_v must be finite and > 0"),
            (positive(self.q_omega), "q_omega must be finite and > 0"),
            (
                positive(self.sigma_range),
                "sigma_range must be finite and > 0",
            ),
            (
                positive(self.sigma_bearing),
                "sigma_bearing must be finite and > 0",
            ),
            (positive(self.v_scale), "v_scale must be finite and > 0"),
            (
                positive(self.omega_scale),
                "omega_scale must be finite and > 0",
            ),
            (
                self.gate.is_none_or(|g| g > 0.0 && g < 1.0),
                "gate confidence must be in (0, 1)",
            ),
            (self.recover_after >= 1, "recover_after must be >= 1"),
            (
                self.inflation.is_finite() && self.inflation > 1.0,
                "inflation must be finite and > 1",
            ),
            (
                self.initial_std.iter().all(|s| positive(*s)),
                "initial standard deviations must be finite and > 0",
            ),
            (positive(self.horizon), "horizon must be finite and > 0"),
            (
                positive(self.truth_max_gap),
                "truth_max_gap must be finite and > 0",
            ),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, what)) => Err(Error::InvalidConfig(what)),
            None => Ok(()),
        }
    }
}
