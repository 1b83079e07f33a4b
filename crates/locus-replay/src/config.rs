//! The parameters of a replay and their checks.

use locus_models::calibrated_unicycle::{CalibratedUnicycle, GaussMarkov};

use locus_models::plausible::Limits;

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
    /// The odometry and sensor calibration the filter estimates.
    pub calibration: Calibration,
    /// Student-t degrees of freedom of the sightings' noise (heavy tails:
    /// see `locus_core::StudentT`), or `None` for Gaussian noise.
    pub robust_dof: Option<f64>,
    /// How long after an odometry record's time stamp the robot moves as
    /// it says, s (>= 0): commanded velocities lead the motion they
    /// command. Odometry records are applied at their time plus this.
    pub odometry_delay: f64,
    /// Compare each step with the ground truth (`false`: steps carry no
    /// truth and the report's summaries are empty; for replays whose only
    /// use is the innovation likelihood, e.g. the estimate's grids).
    pub evaluate: bool,
    /// Run the Rauch-Tung-Striebel smoother after the forward pass: every
    /// step then also carries its smoothed estimate, and the report the
    /// smoother's figures.
    pub smooth: bool,
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
    /// Longest plausible range of a sighting, m (> 0): a sighting beyond
    /// it is refused as unusable (counted, named by its line; the belief
    /// unchanged). 1 km by default: MRCLAM's camera reads at most 8.6 m,
    /// and a range of, say, 1e154 m (finite, so a valid field) would
    /// otherwise throw an ungated estimate that far away.
    pub max_range: f64,
    /// Where the initial pose comes from.
    pub start: Start,
    /// How the beams of range sensors are corrected.
    pub beams: Beams,
    /// What an odometry record may say (top speed and turn rate, longest
    /// gap between records; `locus_models::plausible`): a record beyond
    /// them is refused (counted, named by its line, the velocities before
    /// it held). Default [`Limits::GENERIC`].
    pub limits: Limits,
}

/// How a scan's beams are corrected (papers 000/003: each beam one scalar
/// update against the range cast in the map, one after the other).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beams {
    /// Standard deviation of a beam's range, m (> 0).
    pub sigma: f64,
    /// Beams a scan spends at most, spread evenly over its beams (>= 1):
    /// neighbouring beams see the same surface with errors alike, so each
    /// beam beyond a few tens adds little information for its time.
    pub per_scan: u32,
    /// Largest incidence on the surface a beam is used at, rad in
    /// `(0, pi/2)`: a grazing beam's range changes too fast with the
    /// heading to linearise.
    pub max_incidence: f64,
    /// A reading shorter than the range cast in the map by more than this
    /// many standard deviations of the innovation is taken for something
    /// not in the map (a person, a chair) and skipped (> 0).
    pub short_sigma: f64,
    /// The part of the range error that persists from scan to scan, shared
    /// by the beams of a scan: a Gauss-Markov range bias in the state
    /// (`locus_models::calibrated_unicycle`), started at 0 with its
    /// stationary standard deviation `sigma` (m, > 0) and time constant
    /// `tau` (s, > 0; infinite: a constant). Default: held at 0 (`sigma`
    /// 1e-6 m, `tau` infinite), the beams' errors taken as white.
    pub bias: GaussMarkov<f64>,
}

impl Beams {
    /// The range bias held at 0: the beams' errors taken as white.
    pub const HELD_BIAS: GaussMarkov<f64> = GaussMarkov {
        sigma: 1e-6,
        tau: f64::INFINITY,
    };
}

impl Default for Beams {
    fn default() -> Self {
        Self {
            sigma: 0.05,
            per_scan: 30,
            max_incidence: 1.2,
            short_sigma: 3.0,
            bias: Beams::HELD_BIAS,
        }
    }
}

/// Where a replay's initial pose comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Start {
    /// The log's `start` pose (with [`Config::initial_std`]); without one,
    /// the ground truth at the first odometry time; without that, the
    /// pose the first sightings fix ([`crate::initial`]).
    #[default]
    Log,
    /// The pose the first sightings fix, whatever else the log gives (a
    /// replay that takes nothing from the truth).
    Sightings,
}

/// The calibration states of the replay's filter (see
/// `locus_models::calibrated_unicycle`), in the order forward-speed scale
/// `s_v`, turn-rate scale `s_omega`, turn-rate bias `b_omega` (rad/s),
/// bearing bias `b_bearing` (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// Initial values.
    pub initial: [f64; 4],
    /// Initial standard deviations (in the units of each state).
    pub std: [f64; 4],
    /// Random-walk power spectral densities (unit^2/s): how fast each may
    /// drift.
    pub walk: [f64; 4],
}

impl Default for Calibration {
    /// Uncalibrated logs: both scale factors estimated from 1 +- 0.2
    /// (commanded velocities 10 % off lie well inside), with a random walk
    /// of 1e-6 /s each (about 0.1 % per sqrt(s)). The two biases are held
    /// at 0: standard deviation 1e-6 (rad/s, rad), no random walk, so the
    /// gate's recovery leaves them as they are and a bad sighting that gets
    /// through cannot move them for good. Give them a wider `std` (and a
    /// `walk`) for a robot whose turn rate or bearings are known to be
    /// biased. Why the biases are held by default: docs/replay.md,
    /// "Calibration states".
    fn default() -> Self {
        Self {
            initial: [1.0, 1.0, 0.0, 0.0],
            std: [0.2, 0.2, 1e-6, 1e-6],
            walk: [1e-6, 1e-6, 0.0, 0.0],
        }
    }
}

impl Default for Config {
    /// Values for MRCLAM-like logs (commanded velocities, a camera's range
    /// and bearing): `q_v` 0.002 m^2/s, `q_omega` 0.002 rad^2/s, range 1 m,
    /// bearing 0.01 rad; Student-t sightings with 4 degrees of freedom; a
    /// 99 % gate, inflation by 4 after 5 consecutive rejections; the
    /// calibration states of [`Calibration::default`]; a 1 s history.
    ///
    /// The range noise is deliberately wide, far above a camera's
    /// frame-to-frame spread: it stands for range errors that persist for
    /// seconds per landmark, which a filter taking each range as
    /// independent at that spread would be over-confident about; the
    /// bearings, tight and independent, then carry the position. The
    /// process noise is what [`crate::drift::process_noise`] finds from the
    /// sightings alone (how fast dead reckoning drifts between pose fixes)
    /// on MRCLAM dataset 6, to one significant digit. The measurements
    /// behind both: docs/replay.md, "Why these noise levels" and "Where
    /// the process noise comes from".
    fn default() -> Self {
        Self {
            q_v: 0.002,
            q_omega: 0.002,
            sigma_range: 1.0,
            sigma_bearing: 0.01,
            calibration: Calibration::default(),
            robust_dof: Some(4.0),
            odometry_delay: 0.0,
            evaluate: true,
            smooth: false,
            gate: Some(0.99),
            recover_after: 5,
            inflation: 4.0,
            initial_std: [0.05, 0.05, 0.05],
            horizon: 1.0,
            truth_max_gap: 0.25,
            max_range: 1000.0,
            limits: Limits::GENERIC,
            start: Start::Log,
            beams: Beams::default(),
        }
    }
}

impl Config {
    /// The filter's motion model with these noises.
    #[must_use]
    pub fn motion_model(&self) -> CalibratedUnicycle<f64> {
        CalibratedUnicycle {
            psd_v: self.q_v,
            psd_omega: self.q_omega,
            walk: self.calibration.walk,
            range_bias: self.beams.bias,
        }
    }

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
            (
                self.calibration.initial.iter().all(|v| v.is_finite()),
                "calibration initial values must be finite",
            ),
            (
                self.calibration.std.iter().all(|s| positive(*s)),
                "calibration standard deviations must be finite and > 0",
            ),
            (
                self.calibration
                    .walk
                    .iter()
                    .all(|w| w.is_finite() && *w >= 0.0),
                "calibration random walks must be finite and >= 0",
            ),
            (
                self.robust_dof.is_none_or(positive),
                "robust degrees of freedom must be finite and > 0",
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
                self.odometry_delay.is_finite() && (0.0..=10.0).contains(&self.odometry_delay),
                "odometry_delay must be in [0, 10] s",
            ),
            (
                positive(self.truth_max_gap),
                "truth_max_gap must be finite and > 0",
            ),
            (positive(self.max_range), "max_range must be finite and > 0"),
            (
                self.q_v <= self.limits.max_noise("q_v").unwrap_or(f64::INFINITY),
                "q_v must be at most max_speed^2 (m^2/s: a speed error of the top speed every second)",
            ),
            (
                self.q_omega <= self.limits.max_noise("q_omega").unwrap_or(f64::INFINITY),
                "q_omega must be at most max_turn_rate^2 (rad^2/s)",
            ),
            (
                self.sigma_range
                    <= self
                        .limits
                        .max_noise("sigma_range")
                        .unwrap_or(f64::INFINITY),
                "sigma_range must be at most max_coordinate (m)",
            ),
            (
                self.sigma_bearing <= core::f64::consts::PI,
                "sigma_bearing must be at most pi rad",
            ),
            (
                positive(self.beams.sigma) && self.beams.sigma <= 1e5,
                "the beams' sigma must be finite, > 0 and at most 1e5 m",
            ),
            (self.beams.per_scan >= 1, "beams per scan must be >= 1"),
            (
                self.beams.max_incidence > 0.0
                    && self.beams.max_incidence < core::f64::consts::FRAC_PI_2,
                "the beams' max incidence must be in (0, pi/2) rad",
            ),
            (
                positive(self.beams.short_sigma),
                "the beams' short-reading bound must be finite and > 0",
            ),
            (
                positive(self.beams.bias.sigma) && self.beams.bias.sigma <= 1e5,
                "the range bias's sigma must be finite, > 0 and at most 1e5 m",
            ),
            (
                self.beams.bias.tau > 0.0,
                "the range bias's time constant must be > 0 s (infinite: a constant)",
            ),
        ];
        if let Err(what) = self.limits.validate() {
            return Err(Error::InvalidConfig(what));
        }
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, what)) => Err(Error::InvalidConfig(what)),
            None => Ok(()),
        }
    }
}
