//! The closed loop of paper 001 on the `square` scenario (spec section 3):
//! controller -> wheel speeds -> simulated differential-drive robot ->
//! quadrature encoders -> EKF prediction ([`DiffDrive`]) -> IR pair readings ->
//! data association ([`associate_ir_wall`]) -> EKF correction
//! ([`IrPairObservation`]), with the controller steering on the EKF estimate.
//! An odometry-only belief (prediction only) runs alongside for comparison.
//!
//! # One step of `dt` (s)
//! 1. The path controller ([`FollowPath::square`]) maps the EKF pose to
//!    `(V, W)`; [`wheel_speeds`] gives `V1` (right), `V2` (left).
//! 2. The robot moves (exact arc, [`Kinematics::DifferentialDrive`]), with
//!    random slip bumps making the encoders over-count.
//! 3. Each wheel's measured travel drives an [`Encoder`]; the wrapping 20-bit
//!    count difference since the last step times the count quantum gives
//!    `d1` (right) and `d2` (left), m. The right encoder also carries a
//!    constant calibration error ([`SquareConfig::right_scale_error`]).
//! 4. Both beliefs are predicted with [`DiffDrive`].
//! 5. The IR pair ([`IrPairSensor`]) reads the true walls; when both sensors
//!    are in range the estimate picks the wall (or drops the reading) and the
//!    EKF corrects (99 % chi-square gate by default).
//!
//! # The `square-ideal` scenario ([`NoiseModel::Ideal`])
//! The same loop with the simulated noise exactly as the filter assumes, for
//! checking the filter's consistency (NEES): no slip, no encoder
//! quantisation, no calibration error. Step 2-3 become: the odometry input
//! `u` is the commanded wheel travel (`V_i dt`), and the truth moves with the
//! filter's own discrete model, `X_true' = f(X_true, u, q)` ([`DiffDrive`])
//! with `q ~ N(0, diag(Q11, Q22))`, while the filter predicts with
//! `f(X, u, 0)`. Step 5 becomes: the noise-free readings of the IR pair are
//! cast on the true walls; when both are in the sensor's useful range and
//! see the wall the truth's IR pair points at (found by data association
//! on the true pose, so the association is always right), the observation is
//! `z = h(X_true) + V n` with `n ~ N(0, diag(R11, R22))` and `V` evaluated at
//! the noise-free readings, and the filter uses that same `V` (its
//! `V R V^T` is the exact covariance of `z`). Heading components are
//! wrapped. The record's `ir` field then holds the noise-free readings plus
//! `n`.
//!
//! All randomness comes from one `StdRng` seeded with the run's seed, so a
//! run is reproducible from `(config, seed)` (wall-clock timing aside).

use locus_control::{Controller, FollowPath, wheel_speeds};
use locus_core::nalgebra::{Matrix3, Vector2, Vector3};
use locus_core::{Belief, ChiSquareGate, Ekf, MeasurementModel, MotionModel, wrap_angle};
use locus_models::{DiffDrive, IrPair, IrPairObservation, WheelTravel, associate_ir_wall};
use locus_odometry::{Wheel as EncoderWheel, wrapping_diff};
use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::noise::gauss;
use crate::robot::{Command, Kinematics, Pose, Robot, RobotError, SlipSchedule, Wheel};
use crate::scenario::{Record, Sample, Summary, Tally};
use crate::sensors::{Encoder, IrPairSensor, SensorError, SharpIr};
use crate::world::World;

/// Width of the encoders' wrapping counter (bits), as in
/// [`locus_odometry::Counter::paper`].
const COUNTER_BITS: u32 = locus_odometry::counter::PAPER_BITS;

/// Errors of a closed-loop run.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A configuration value is invalid; the message names it.
    #[error("invalid configuration: {0}")]
    Config(&'static str),
    /// A configuration field is out of its domain.
    #[error("invalid configuration: `{field}` {reason}")]
    Invalid {
        /// The field's name as in a scenario file (`control.v_ref` for a
        /// nested one).
        field: &'static str,
        /// What the field must be.
        reason: &'static str,
    },
    /// The simulated robot rejected a command.
    #[error("robot: {0}")]
    Robot(#[from] RobotError),
    /// A sensor failed.
    #[error("sensor: {0}")]
    Sensor(#[from] SensorError),
    /// The filter failed (non-finite values, S not positive definite, ...).
    #[error("filter: {0}")]
    Filter(#[from] locus_core::Error),
}

/// How the simulated noise is generated (`"realistic"` or `"ideal"` in a
/// scenario file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoiseModel {
    /// The `square` scenario: exact-arc robot with slip bumps, quantised
    /// encoders with a calibration error, IR readings through the sensor
    /// curve.
    #[default]
    Realistic,
    /// The `square-ideal` scenario: noise exactly as the filter's `Q` and
    /// `R` assume (see the [module documentation](self)).
    Ideal,
}

/// Configuration of the `square` scenario. Every value is SI (m, s, rad);
/// variances are per filter step. See [`SquareConfig::default`] for the
/// \[assumed\] values of spec section 3.
///
/// In a scenario file (TOML) every field is optional and overrides the
/// default; `gate_confidence = "none"` turns the gate off, `[control]`
/// holds the controller's fields.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SquareConfig {
    /// Filter, controller and simulation step `dt` (s). Default 0.01 s (100 Hz).
    pub dt: f64,
    /// Number of laps of the square path. Default 2.
    pub laps: usize,
    /// Simulated time after which the run stops even if the laps are not
    /// done (s). Default 600 s.
    pub max_time: f64,
    /// Distance between the wheels `b` (m). Default 0.112 m (Lego NXT).
    pub wheelbase: f64,
    /// Wheel radius (m). Default 0.028 m (NXT 56 mm wheel).
    pub wheel_radius: f64,
    /// Encoder lines per shaft revolution `N`; with x4 decoding the count per
    /// wheel revolution is `4 N G`. Default 90 (with `G = 1`: 360 counts per
    /// wheel revolution, the NXT motor's 1-degree resolution; 0.49 mm per count).
    pub encoder_lines: u32,
    /// Encoder-shaft revolutions per wheel revolution `G`. Default 1.
    pub encoder_gear: f64,
    /// Relative over-count of the right encoder (calibration error: the
    /// true right wheel is this fraction larger than its nominal radius, the
    /// filter uses the nominal one). Default 0.005.
    pub right_scale_error: f64,
    /// Slip bumps per wheel, placed at random over the first lap's wheel
    /// travel. Default 3.
    pub slip_bumps_per_wheel: usize,
    /// Range of each bump's length (m of wheel travel). Default 0.02-0.08 m.
    pub slip_length: (f64, f64),
    /// Range of each bump's measured-travel scale. Default 1.02-1.10 (a
    /// bump adds up to 8 mm to one wheel: a heading jump of up to 0.07 rad).
    pub slip_scale: (f64, f64),
    /// Initial pose of the estimate (m, m, rad): the first corner of the
    /// path, heading along the first side. Default `(-0.85, -0.85, 0)`.
    pub start: [f64; 3],
    /// Standard deviation of the initial estimate (m, m, rad); the true
    /// start is drawn from it. Default `(0.01, 0.01, 0.02)`.
    pub initial_std: [f64; 3],
    /// IR pair spacing `L` (m). Default 0.10 m.
    pub ir_spacing: f64,
    /// IR distance noise standard deviation (m, >= 0; 0: noise-free
    /// readings). Default 0.005 m.
    pub ir_sigma: f64,
    /// Whether the EKF uses the IR readings. `false`: odometry only (the
    /// readings are still simulated, so the random draws stay those of a
    /// run with IR, but never reach the filter). Default `true`.
    pub use_ir: bool,
    /// Largest estimated pair-to-wall distance accepted by the data
    /// association (m): the 0.30 m range plus a margin. Default 0.40 m.
    pub association_range: f64,
    /// `Q11 = var(e_d)` (m^2 per step). Default `(0.5 mm)^2`, the order of the
    /// encoder quantum.
    pub q11: f64,
    /// `Q22 = var(e_dtheta)` (rad^2 per step). Default `(1e-3 rad)^2`
    /// (tuned on seeds 1-30: mean NEES ~2.5, ~93 % of steps in the 95 %
    /// interval).
    pub q22: f64,
    /// `R11 = var(e_ds1)` (m^2). Default `(0.005 m)^2`, the injected noise.
    pub r11: f64,
    /// `R22 = var(e_ds2)` (m^2). Default `(0.005 m)^2`.
    pub r22: f64,
    /// Confidence of the chi-square gate on the NIS (`None`: no gate).
    /// Default 0.99.
    #[serde(with = "gate_serde")]
    pub gate_confidence: Option<f64>,
    /// Path controller parameters (`V_ref` 0.1 m/s, ...).
    #[serde(with = "ControlDef")]
    pub control: locus_control::Config,
    /// How the simulated noise is generated. Default
    /// [`NoiseModel::Realistic`].
    pub noise: NoiseModel,
}

/// Serde mirror of [`locus_control::Config`] (the `[control]` table of a
/// scenario file; fields and units as there).
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(
    remote = "locus_control::Config",
    default = "locus_control::Config::default",
    deny_unknown_fields
)]
struct ControlDef {
    v_ref: f64,
    w_ref: f64,
    k_cross: f64,
    k_heading: f64,
    k_pos: f64,
    pos_tol: f64,
    heading_tol: f64,
}

/// `gate_confidence`: a number in (0, 1), or the string `"none"` for no
/// gate.
mod gate_serde {
    use serde::{Deserialize, Deserializer, Serializer};

    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Gate {
        Confidence(f64),
        Word(String),
    }

    #[allow(clippy::ref_option)]
    pub(super) fn serialize<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(c) => s.serialize_f64(*c),
            None => s.serialize_str("none"),
        }
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
        match Gate::deserialize(d) {
            Ok(Gate::Confidence(c)) => Ok(Some(c)),
            Ok(Gate::Word(w)) if w == "none" => Ok(None),
            _ => Err(serde::de::Error::custom(
                "expected a confidence in (0, 1) or \"none\"",
            )),
        }
    }
}

impl Default for SquareConfig {
    fn default() -> Self {
        Self {
            dt: 0.01,
            laps: 2,
            max_time: 600.0,
            wheelbase: 0.112,
            wheel_radius: 0.028,
            encoder_lines: 90,
            encoder_gear: 1.0,
            right_scale_error: 0.005,
            slip_bumps_per_wheel: 3,
            slip_length: (0.02, 0.08),
            slip_scale: (1.02, 1.10),
            start: [
                -locus_control::SQUARE_HALF_SIDE,
                -locus_control::SQUARE_HALF_SIDE,
                0.0,
            ],
            initial_std: [0.01, 0.01, 0.02],
            ir_spacing: 0.10,
            ir_sigma: 0.005,
            use_ir: true,
            association_range: 0.40,
            q11: 0.5e-3 * 0.5e-3,
            q22: 1e-3 * 1e-3,
            r11: 0.005 * 0.005,
            r22: 0.005 * 0.005,
            gate_confidence: Some(0.99),
            control: locus_control::Config::default(),
            noise: NoiseModel::Realistic,
        }
    }
}

impl SquareConfig {
    /// The true robot of a run, and its start pose: the start drawn from
    /// the initial estimate's distribution (`start`, `initial_std`), then
    /// the slip bumps of each wheel over the first lap. Draws from `rng` in
    /// this fixed order, so [`run_square`] and the UDP robot endpoint
    /// (`locus-net`) simulate the same robot from the same seed.
    pub fn true_robot(&self, rng: &mut StdRng) -> (Robot, Pose) {
        let (s, sd) = (self.start, self.initial_std);
        let true_start = Pose::new(
            s[0] + gauss(rng, sd[0]),
            s[1] + gauss(rng, sd[1]),
            s[2] + gauss(rng, sd[2]),
        );
        // Slip bumps over the first lap's wheel travel.
        let lap_length = 8.0 * locus_control::SQUARE_HALF_SIDE;
        let mut slip = SlipSchedule::random_bumps(
            rng,
            Wheel::Left,
            (0.0, lap_length),
            self.slip_bumps_per_wheel,
            self.slip_length,
            self.slip_scale,
        );
        for z in SlipSchedule::random_bumps(
            rng,
            Wheel::Right,
            (0.0, lap_length),
            self.slip_bumps_per_wheel,
            self.slip_length,
            self.slip_scale,
        )
        .zones
        {
            slip.push(z);
        }
        let robot = Robot::new(
            Kinematics::DifferentialDrive {
                wheelbase: self.wheelbase,
                wheel_radius: self.wheel_radius,
            },
            true_start,
        )
        .with_slip(slip);
        (robot, true_start)
    }

    /// The localiser's part of the configuration (robot geometry, encoder,
    /// IR pair, `Q`, `R`, gate, initial belief), for counters
    /// `counter_bits` wide (20: the simulated decoder; 32: the robot link).
    #[must_use]
    pub fn localiser(&self, counter_bits: u32) -> locus_models::LocaliserConfig<f64> {
        locus_models::LocaliserConfig {
            wheelbase: self.wheelbase,
            wheel_radius: self.wheel_radius,
            encoder_lines: self.encoder_lines,
            encoder_gear: self.encoder_gear,
            counter_bits,
            ir_spacing: self.ir_spacing,
            association_range: self.association_range,
            q11: self.q11,
            q22: self.q22,
            r11: self.r11,
            r22: self.r22,
            gate_confidence: self.gate_confidence,
            start: self.start,
            initial_std: self.initial_std,
        }
    }

    /// The `square-ideal` scenario: the default configuration with
    /// [`NoiseModel::Ideal`] (simulated noise exactly as the filter's `Q` and
    /// `R` assume: no slip, no quantisation, no calibration error) and no
    /// gate (`gate_confidence: None`), so every associated reading is
    /// applied and the NEES is the filter's own. The slip, encoder and
    /// calibration fields are ignored in this mode.
    #[must_use]
    pub fn ideal() -> Self {
        Self {
            noise: NoiseModel::Ideal,
            gate_confidence: None,
            ..Self::default()
        }
    }

    /// `Ok(())` if every value is in its domain.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first bad field (as in a scenario
    /// file).
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let range = |r: (f64, f64)| r.0.is_finite() && r.1.is_finite() && r.0 <= r.1;
        let c = &self.control;
        let checks: [(bool, &'static str, &'static str); 23] = [
            (pos(self.dt), "dt", "must be finite and > 0 s"),
            (self.laps > 0, "laps", "must be >= 1"),
            (pos(self.max_time), "max_time", "must be finite and > 0 s"),
            (pos(self.wheelbase), "wheelbase", "must be finite and > 0 m"),
            (
                pos(self.wheel_radius),
                "wheel_radius",
                "must be finite and > 0 m",
            ),
            (self.encoder_lines > 0, "encoder_lines", "must be >= 1"),
            (
                pos(self.encoder_gear),
                "encoder_gear",
                "must be finite and > 0",
            ),
            (
                self.right_scale_error.is_finite() && self.right_scale_error > -1.0,
                "right_scale_error",
                "must be finite and > -1",
            ),
            (
                range(self.slip_length) && self.slip_length.0 >= 0.0,
                "slip_length",
                "must be [min, max] with 0 <= min <= max (m)",
            ),
            (
                range(self.slip_scale) && self.slip_scale.0 > 0.0,
                "slip_scale",
                "must be [min, max] with 0 < min <= max",
            ),
            (
                self.start.iter().all(|v| v.is_finite()),
                "start",
                "must be finite",
            ),
            (
                self.initial_std.iter().all(|v| pos(*v)),
                "initial_std",
                "must be finite and > 0",
            ),
            (
                pos(self.ir_spacing),
                "ir_spacing",
                "must be finite and > 0 m",
            ),
            (
                self.ir_sigma.is_finite() && self.ir_sigma >= 0.0,
                "ir_sigma",
                "must be finite and >= 0 m",
            ),
            (
                pos(self.association_range),
                "association_range",
                "must be finite and > 0 m",
            ),
            (pos(self.q11), "q11", "must be finite and > 0 m^2"),
            (pos(self.q22), "q22", "must be finite and > 0 rad^2"),
            (pos(self.r11), "r11", "must be finite and > 0 m^2"),
            (pos(self.r22), "r22", "must be finite and > 0 m^2"),
            (
                self.gate_confidence
                    .is_none_or(|g| g.is_finite() && g > 0.0 && g < 1.0),
                "gate_confidence",
                "must be in (0, 1) or \"none\"",
            ),
            (pos(c.v_ref), "control.v_ref", "must be finite and > 0 m/s"),
            (
                pos(c.w_ref),
                "control.w_ref",
                "must be finite and > 0 rad/s",
            ),
            (
                [c.k_cross, c.k_heading, c.k_pos, c.pos_tol, c.heading_tol]
                    .iter()
                    .all(|v| pos(*v)),
                "control",
                "gains and tolerances must be finite and > 0",
            ),
        ];
        match checks.iter().find(|(ok, _, _)| !ok) {
            Some(&(_, field, reason)) => Err(Error::Invalid { field, reason }),
            None => Ok(()),
        }
    }
}

/// What one step of the closed loop produced (SI units, world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRecord {
    /// Step index (0-based).
    pub step: usize,
    /// Simulated time at the end of the step (s).
    pub time: f64,
    /// True pose.
    pub truth: Pose,
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
    /// Innovation `z - h(X-)` `[m, rad]` when a reading was associated with
    /// a wall.
    pub innovation: Option<[f64; 2]>,
    /// NIS of that innovation (2 dof).
    pub nis: Option<f64>,
    /// Whether the correction was applied (passed the gate).
    pub applied: bool,
    /// Diagonal of `H K` (K the Kalman gain) when a reading was associated:
    /// the share of the position innovation moved into the measured
    /// position coordinate and of the heading innovation into the heading
    /// (0: measurement ignored, 1: taken as is). `[0, 0]` if the gate
    /// rejected the correction.
    pub gain: Option<[f64; 2]>,
    /// NEES of the EKF after the step (3 dof, heading error wrapped).
    pub nees: f64,
}

impl StepRecord {
    /// Column names of [`StepRecord::csv_row`], units in brackets.
    pub const CSV_COLUMNS: [&'static str; 24] = [
        "step",
        "time[s]",
        "true_x[m]",
        "true_y[m]",
        "true_theta[rad]",
        "ekf_x[m]",
        "ekf_y[m]",
        "ekf_theta[rad]",
        "p_xx[m2]",
        "p_yy[m2]",
        "p_thth[rad2]",
        "p_xy[m2]",
        "odo_x[m]",
        "odo_y[m]",
        "odo_theta[rad]",
        "ir_s1[m]",
        "ir_s2[m]",
        "innov_pos[m]",
        "innov_theta[rad]",
        "nis",
        "applied",
        "nees",
        "gain_pos",
        "gain_theta",
    ];
}

impl Record for StepRecord {
    /// The CSV header line (no newline): [`StepRecord::CSV_COLUMNS`].
    fn csv_header() -> String {
        Self::CSV_COLUMNS.join(",")
    }

    /// The record as one CSV line (no newline); absent values are empty.
    fn csv_row(&self) -> String {
        fn opt(v: Option<f64>) -> String {
            v.map_or_else(String::new, |v| format!("{v:.9}"))
        }
        let f = |v: f64| format!("{v:.9}");
        let (s1, s2) = self.ir.unzip();
        let fields = [
            self.step.to_string(),
            format!("{:.2}", self.time),
            f(self.truth.x),
            f(self.truth.y),
            f(self.truth.theta),
            f(self.ekf[0]),
            f(self.ekf[1]),
            f(self.ekf[2]),
            format!("{:.6e}", self.ekf_cov[0][0]),
            format!("{:.6e}", self.ekf_cov[1][1]),
            format!("{:.6e}", self.ekf_cov[2][2]),
            format!("{:.6e}", self.ekf_cov[0][1]),
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
        fields.join(",")
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

/// NEES `e^T P^-1 e` of `x` against `truth` (heading error wrapped); NaN
/// if `P` is not positive definite.
fn nees(x: &Vector3<f64>, p: &Matrix3<f64>, truth: &Pose) -> f64 {
    let e = Vector3::new(
        truth.x - x[0],
        truth.y - x[1],
        wrap_angle(truth.theta - x[2]),
    );
    locus_eval::nees(&e, p)
}

/// Diagonal of `H K = H P H^T S^-1` at the prior `belief` for `obs`
/// (`S = H P H^T + V R V^T`); `[0, 0]` if `S` is singular.
fn gain_diagonal(obs: &IrPairObservation<f64>, belief: &Belief<f64, 3>) -> [f64; 2] {
    let h = obs.jacobian(&belief.x);
    let hph = h * belief.p * h.transpose();
    let s = hph + obs.noise(&belief.x);
    s.try_inverse().map_or([0.0, 0.0], |si| {
        let hk = hph * si;
        [hk[(0, 0)], hk[(1, 1)]]
    })
}

/// An ideal-mode observation and its `z` (m, rad).
type IdealObservation = (IrPairObservation<f64>, Vector2<f64>);

/// The ideal-mode observation at the true state `true_x` with reading noise
/// `noise` (m): `None` unless both noise-free readings are in the sensor's
/// useful range and both beams see the wall the data association on the
/// true pose returns; otherwise the observation (noise-free readings, the
/// true wall, `R` of `cfg`) and `z = h(X_true) + V n`, heading wrapped.
fn ideal_observation(
    cfg: &SquareConfig,
    ir: &IrPairSensor,
    world: &World,
    true_x: &Vector3<f64>,
    noise: &Vector2<f64>,
) -> Result<Option<IdealObservation>, Error> {
    let (t1, t2) = ir.true_distances(&world.walls, [true_x[0], true_x[1], true_x[2]])?;
    let in_range =
        |t: Option<f64>, s: &SharpIr| t.filter(|d| (s.min_range..=s.max_range).contains(d));
    let (Some(ds1), Some(ds2)) = (in_range(t1, &ir.front), in_range(t2, &ir.rear)) else {
        return Ok(None);
    };
    let Some(wall) = associate_ir_wall(true_x, &ir.pair, &world.walls, cfg.association_range)
    else {
        return Ok(None);
    };
    let obs = IrPairObservation {
        pair: ir.pair,
        wall,
        ds1,
        ds2,
        r11: cfg.r11,
        r22: cfg.r22,
    };
    let Some(h) = obs.h(true_x) else {
        return Ok(None);
    };
    // Both beams on that wall: the noise-free readings give exactly h.
    let r = obs.residual(&obs.z(), &h);
    if r[0].abs() > 1e-9 || r[1].abs() > 1e-9 {
        return Ok(None);
    }
    let e = obs.v() * noise;
    Ok(Some((
        obs,
        Vector2::new(h[0] + e[0], wrap_angle(h[1] + e[1])),
    )))
}

/// Teleoperation of one step: the wheel command `(V, W)` (m/s, rad/s)
/// used instead of the path controller's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Teleop {
    /// Linear speed `V` (m/s).
    pub v: f64,
    /// Turn rate `W` (rad/s), counter-clockwise.
    pub w: f64,
}

/// The parameters of a [`SquareSim`] that may change while it runs: the
/// filter's `Q` and `R`, the gate, the injected IR noise and the
/// controller (speeds and gains). Everything else of the
/// [`SquareConfig`] takes effect on a new simulation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveParams {
    /// `Q11` (m^2 per step).
    pub q11: f64,
    /// `Q22` (rad^2 per step).
    pub q22: f64,
    /// `R11` (m^2).
    pub r11: f64,
    /// `R22` (m^2).
    pub r22: f64,
    /// IR distance noise standard deviation injected in the readings (m).
    pub ir_sigma: f64,
    /// Whether the EKF uses the IR readings.
    pub use_ir: bool,
    /// Gate confidence (`None`: no gate).
    pub gate_confidence: Option<f64>,
    /// The path controller's parameters.
    pub control: locus_control::Config,
}

impl LiveParams {
    /// The live parameters of `cfg`.
    #[must_use]
    pub fn of(cfg: &SquareConfig) -> Self {
        Self {
            q11: cfg.q11,
            q22: cfg.q22,
            r11: cfg.r11,
            r22: cfg.r22,
            ir_sigma: cfg.ir_sigma,
            use_ir: cfg.use_ir,
            gate_confidence: cfg.gate_confidence,
            control: cfg.control,
        }
    }

    /// `cfg` with these live parameters.
    #[must_use]
    pub fn apply_to(&self, cfg: &SquareConfig) -> SquareConfig {
        SquareConfig {
            q11: self.q11,
            q22: self.q22,
            r11: self.r11,
            r22: self.r22,
            ir_sigma: self.ir_sigma,
            use_ir: self.use_ir,
            gate_confidence: self.gate_confidence,
            control: self.control,
            ..*cfg
        }
    }
}

/// The details of one EKF correction, for showing it step by step: the
/// prediction it starts from, the linearisation, the gain, the innovation,
/// the gate's decision and the belief after it. Matrices are row-major
/// (serialised as nested arrays).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CorrectionDetail {
    /// The belief before the step's prediction: `x` (m, m, rad).
    pub x_before_predict: [f64; 3],
    /// Its covariance.
    pub p_before_predict: [[f64; 3]; 3],
    /// The odometry input of the prediction `[d1, d2]` (m).
    pub u: [f64; 2],
    /// The predicted state `x-` (m, m, rad).
    pub x_prior: [f64; 3],
    /// The predicted covariance `P-`.
    pub p_prior: [[f64; 3]; 3],
    /// The measurement `z = [d, theta_m]` (m, rad) from the IR pair.
    pub z: [f64; 2],
    /// The predicted measurement `h(x-)` (m, rad).
    pub h: [f64; 2],
    /// The measurement Jacobian `H` (2x3) at `x-`.
    pub jacobian: [[f64; 3]; 2],
    /// The measurement noise in measurement space `V R V^T` (2x2).
    pub noise: [[f64; 2]; 2],
    /// The innovation covariance `S = H P- H^T + V R V^T` (2x2).
    pub s: [[f64; 2]; 2],
    /// The Kalman gain `K = P- H^T S^-1` (3x2).
    pub k: [[f64; 2]; 3],
    /// The innovation `z - h(x-)` (m, rad; heading wrapped).
    pub innovation: [f64; 2],
    /// The NIS `y^T S^-1 y`.
    pub nis: f64,
    /// The gate's NIS threshold (`None`: no gate).
    pub gate_threshold: Option<f64>,
    /// Whether the correction was applied.
    pub applied: bool,
    /// The state after the correction (the prior if rejected).
    pub x_post: [f64; 3],
    /// Its covariance.
    pub p_post: [[f64; 3]; 3],
}

/// What one [`SquareSim::step`] produced besides its [`StepRecord`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimStep {
    /// The step's record (as logged by `locus run`).
    pub record: StepRecord,
    /// The command `(V, W)` (m/s, rad/s) applied.
    pub command: (f64, f64),
    /// The wheel speeds `(V1, V2)` (m/s, right and left).
    pub wheel_speeds: (f64, f64),
    /// Whether the command came from teleoperation.
    pub teleop: bool,
    /// The correction's details when a reading was associated and used
    /// (and [`SquareSim::with_details`] is on).
    pub correction: Option<CorrectionDetail>,
}

fn mat3(p: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [
        [p[(0, 0)], p[(0, 1)], p[(0, 2)]],
        [p[(1, 0)], p[(1, 1)], p[(1, 2)]],
        [p[(2, 0)], p[(2, 1)], p[(2, 2)]],
    ]
}

/// The `square` closed loop as a stepper: [`SquareSim::step`] runs one step
/// of `dt` (the loop of the [module documentation](self)), so a caller can
/// interleave steps with parameter changes and teleoperation (the teaching
/// UI). [`run_square`] is a loop over it.
#[derive(Debug)]
pub struct SquareSim {
    cfg: SquareConfig,
    rng: StdRng,
    world: World,
    robot: Robot,
    wheel: EncoderWheel<f64>,
    enc_right: Encoder,
    enc_left: Encoder,
    last_right: u32,
    last_left: u32,
    pair: IrPair<f64>,
    ir: IrPairSensor,
    model: DiffDrive<f64>,
    ekf: Ekf<f64>,
    belief: Belief<f64, 3>,
    odo: Belief<f64, 3>,
    true_x: Vector3<f64>,
    truth: Pose,
    controller: FollowPath<4>,
    max_steps: usize,
    laps: usize,
    steps: usize,
    finished: bool,
    details: bool,
}

impl SquareSim {
    /// A simulation of `cfg` from `seed`, before its first step (the same
    /// draws from the seed as [`run_square`]).
    ///
    /// # Errors
    /// [`Error::Invalid`] for an invalid configuration; a sensor or gate
    /// construction error.
    #[allow(clippy::cast_precision_loss, clippy::cast_sign_loss)]
    pub fn new(cfg: &SquareConfig, seed: u64) -> Result<Self, Error> {
        cfg.validate()?;
        let mut rng = StdRng::seed_from_u64(seed);
        let world = World::square_arena();

        let (robot, true_start) = cfg.true_robot(&mut rng);
        let (s, sd) = (cfg.start, cfg.initial_std);

        let wheel = EncoderWheel::new(cfg.encoder_lines, cfg.encoder_gear, cfg.wheel_radius);
        let enc_right = Encoder::new(wheel)?;
        let enc_left = Encoder::new(wheel)?;
        let (last_right, last_left) = (enc_right.read(), enc_left.read());

        let pair = IrPair::centred(cfg.ir_spacing);
        let ir = IrPairSensor::new(pair, SharpIr::assumed(cfg.ir_sigma)?)?;

        let model = DiffDrive::new(cfg.wheelbase, cfg.q11, cfg.q22);
        let ekf = Self::ekf(cfg.gate_confidence)?;
        let x0 = Vector3::new(s[0], s[1], s[2]);
        let p0 = Matrix3::from_diagonal(&Vector3::new(sd[0] * sd[0], sd[1] * sd[1], sd[2] * sd[2]));
        let belief = Belief::new(x0, p0);

        Ok(Self {
            cfg: *cfg,
            rng,
            world,
            robot,
            wheel,
            enc_right,
            enc_left,
            last_right,
            last_left,
            pair,
            ir,
            model,
            ekf,
            belief,
            odo: belief,
            true_x: Vector3::new(true_start.x, true_start.y, true_start.theta),
            truth: true_start,
            controller: FollowPath::square(cfg.control),
            max_steps: (cfg.max_time / cfg.dt).ceil() as usize,
            laps: 0,
            steps: 0,
            finished: false,
            details: false,
        })
    }

    fn ekf(gate: Option<f64>) -> Result<Ekf<f64>, Error> {
        let mut ekf = Ekf::<f64>::default();
        if let Some(c) = gate {
            ekf = ekf.with_gate(ChiSquareGate::new(c)?);
        }
        Ok(ekf)
    }

    /// Whether [`SimStep::correction`] is filled in (off by default: it
    /// costs a second linearisation per correction).
    #[must_use]
    pub fn with_details(mut self, on: bool) -> Self {
        self.details = on;
        self
    }

    /// The configuration in use (with the live parameters last set).
    #[must_use]
    pub fn config(&self) -> &SquareConfig {
        &self.cfg
    }

    /// Changes the live parameters from the next step on (the filter's
    /// `Q`, `R` and gate, the injected IR noise, the controller's speeds
    /// and gains, keeping its progress along the path).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first bad field; the simulation then
    /// keeps its previous parameters.
    pub fn set_live(&mut self, live: &LiveParams) -> Result<(), Error> {
        let cfg = live.apply_to(&self.cfg);
        cfg.validate()?;
        let ir = IrPairSensor::new(self.pair, SharpIr::assumed(cfg.ir_sigma)?)?;
        let ekf = Self::ekf(cfg.gate_confidence)?;
        self.ir = ir;
        self.ekf = ekf;
        self.model = DiffDrive::new(cfg.wheelbase, cfg.q11, cfg.q22);
        self.controller.set_config(cfg.control);
        self.cfg = cfg;
        Ok(())
    }

    /// The EKF belief now.
    #[must_use]
    pub fn belief(&self) -> &Belief<f64, 3> {
        &self.belief
    }

    /// The true pose now.
    #[must_use]
    pub fn truth(&self) -> Pose {
        self.truth
    }

    /// The odometry-only belief now.
    #[must_use]
    pub fn odometry(&self) -> &Belief<f64, 3> {
        &self.odo
    }

    /// The arena's walls.
    #[must_use]
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The IR pair sensor (its beams' mountings: [`IrPairSensor::mounts`]).
    #[must_use]
    pub fn ir_sensor(&self) -> &IrPairSensor {
        &self.ir
    }

    /// Steps run so far.
    #[must_use]
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Laps of the square completed so far.
    #[must_use]
    pub fn laps(&self) -> usize {
        self.laps
    }

    /// Whether the run has ended (laps done or `max_time` reached).
    #[must_use]
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Runs one step of `dt`: with `teleop`, its command instead of the
    /// path controller's (the controller then neither advances nor ends
    /// the run). `Ok(None)` once the run has ended (the laps are done or
    /// `max_time` is reached; teleoperation still runs after the laps,
    /// up to `max_time`).
    ///
    /// # Errors
    /// A robot, sensor or filter error; the simulation should not be
    /// stepped further.
    #[allow(clippy::cast_precision_loss, clippy::too_many_lines)]
    pub fn step(&mut self, teleop: Option<Teleop>) -> Result<Option<SimStep>, Error> {
        let cfg = self.cfg;
        if self.steps >= self.max_steps {
            self.finished = true;
            return Ok(None);
        }
        if self.finished && teleop.is_none() {
            return Ok(None);
        }
        let belief_before = self.belief;
        let command = if let Some(t) = teleop {
            locus_control::Command {
                v: t.v,
                w: t.w,
                done: false,
            }
        } else {
            let est =
                locus_control::Pose::new(self.belief.x[0], self.belief.x[1], self.belief.x[2]);
            let mut command = self.controller.command(est);
            if command.done {
                self.laps += 1;
                if self.laps >= cfg.laps {
                    self.finished = true;
                    return Ok(None);
                }
                self.controller.reset();
                command = self.controller.command(est);
            }
            command
        };
        let (v1, v2) = wheel_speeds(command, cfg.wheelbase);
        let ideal = cfg.noise == NoiseModel::Ideal;
        let (truth, u) = if ideal {
            // The truth moves with the filter's model and noise.
            let u = WheelTravel {
                d1: v1 * cfg.dt,
                d2: v2 * cfg.dt,
            };
            let q_std = [cfg.q11.sqrt(), cfg.q22.sqrt()];
            let q = Vector2::new(
                gauss(&mut self.rng, q_std[0]),
                gauss(&mut self.rng, q_std[1]),
            );
            self.true_x = self.model.f(&self.true_x, &u, &q);
            let x = &self.true_x;
            (Pose::new(x[0], x[1], x[2]), u)
        } else {
            let out = self.robot.step(
                &Command::Wheels {
                    left: v2,
                    right: v1,
                },
                cfg.dt,
            )?;

            // Encoders -> wrapping count differences -> wheel travels.
            self.enc_right.advance(
                out.measured_travel.right * (1.0 + cfg.right_scale_error),
                &mut self.rng,
            )?;
            self.enc_left
                .advance(out.measured_travel.left, &mut self.rng)?;
            let (now_right, now_left) = (self.enc_right.read(), self.enc_left.read());
            let wheel = &self.wheel;
            let u = WheelTravel {
                d1: wheel.distance(wrapping_diff(now_right, self.last_right, COUNTER_BITS)),
                d2: wheel.distance(wrapping_diff(now_left, self.last_left, COUNTER_BITS)),
            };
            (self.last_right, self.last_left) = (now_right, now_left);
            (out.pose, u)
        };
        self.truth = truth;

        self.belief = self.ekf.predict(&self.belief, &self.model, &u)?;
        self.odo = self.ekf.predict(&self.odo, &self.model, &u)?;

        let (mut innovation, mut nis, mut applied, mut gain) = (None, None, false, None);
        let mut detail = None;
        // The raw readings (for the log) and, if associated, the observation.
        let (reading, observation) = if ideal {
            let r_std = [cfg.r11.sqrt(), cfg.r22.sqrt()];
            let noise = Vector2::new(
                gauss(&mut self.rng, r_std[0]),
                gauss(&mut self.rng, r_std[1]),
            );
            match ideal_observation(&cfg, &self.ir, &self.world, &self.true_x, &noise)? {
                Some((obs, z)) => (
                    Some((obs.ds1 + noise[0], obs.ds2 + noise[1])),
                    Some((obs, z)),
                ),
                None => (None, None),
            }
        } else {
            let reading = self.ir.read(
                &self.world.walls,
                [truth.x, truth.y, truth.theta],
                &mut self.rng,
            )?;
            let (pair, walls, belief) = (self.pair, &self.world.walls, &self.belief);
            let observation = reading.and_then(|(ds1, ds2)| {
                let wall = associate_ir_wall(&belief.x, &pair, walls, cfg.association_range)?;
                let obs = IrPairObservation {
                    pair,
                    wall,
                    ds1,
                    ds2,
                    r11: cfg.r11,
                    r22: cfg.r22,
                };
                Some((obs, obs.z()))
            });
            (reading, observation)
        };
        let observation = observation.filter(|_| cfg.use_ir);
        if let Some((obs, z)) = observation {
            let prior = self.belief;
            let c = self.ekf.correct(&prior, &obs, &z)?;
            gain = Some(if c.applied {
                gain_diagonal(&obs, &prior)
            } else {
                [0.0, 0.0]
            });
            innovation = Some([c.innovation[0], c.innovation[1]]);
            nis = Some(c.nis);
            applied = c.applied;
            self.belief = c.belief;
            detail = self.details.then(|| {
                correction_detail(
                    &obs,
                    &z,
                    &belief_before,
                    [u.d1, u.d2],
                    &prior,
                    &c,
                    self.ekf.gate.map(|g| g.threshold(2)),
                )
            });
        }

        let belief = &self.belief;
        let n = nees(&belief.x, &belief.p, &truth);
        self.steps += 1;
        let record = StepRecord {
            step: self.steps - 1,
            time: self.steps as f64 * cfg.dt,
            truth,
            ekf: [belief.x[0], belief.x[1], belief.x[2]],
            ekf_cov: mat3(&belief.p),
            odometry: [self.odo.x[0], self.odo.x[1], self.odo.x[2]],
            wheel_travel: [u.d1, u.d2],
            ir: reading,
            innovation,
            nis,
            applied,
            gain,
            nees: n,
        };
        Ok(Some(SimStep {
            record,
            command: (command.v, command.w),
            wheel_speeds: (v1, v2),
            teleop: teleop.is_some(),
            correction: detail,
        }))
    }
}

/// The [`CorrectionDetail`] of the correction `c` of `prior` by `obs`
/// with measurement `z`.
fn correction_detail(
    obs: &IrPairObservation<f64>,
    z: &Vector2<f64>,
    before: &Belief<f64, 3>,
    u: [f64; 2],
    prior: &Belief<f64, 3>,
    c: &locus_core::Correction<f64, 3, 2>,
    gate_threshold: Option<f64>,
) -> CorrectionDetail {
    let h = obs.jacobian(&prior.x);
    let noise = obs.noise(&prior.x);
    let s = h * prior.p * h.transpose() + noise;
    let k = s
        .try_inverse()
        .map_or_else(locus_core::nalgebra::Matrix3x2::zeros, |si| {
            prior.p * h.transpose() * si
        });
    let hx = obs.h(&prior.x).unwrap_or_else(Vector2::zeros);
    let m2 =
        |m: &locus_core::nalgebra::Matrix2<f64>| [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]];
    let v3 = |v: &Vector3<f64>| [v[0], v[1], v[2]];
    CorrectionDetail {
        x_before_predict: v3(&before.x),
        p_before_predict: mat3(&before.p),
        u,
        x_prior: v3(&prior.x),
        p_prior: mat3(&prior.p),
        z: [z[0], z[1]],
        h: [hx[0], hx[1]],
        jacobian: [
            [h[(0, 0)], h[(0, 1)], h[(0, 2)]],
            [h[(1, 0)], h[(1, 1)], h[(1, 2)]],
        ],
        noise: m2(&noise),
        s: m2(&s),
        k: [
            [k[(0, 0)], k[(0, 1)]],
            [k[(1, 0)], k[(1, 1)]],
            [k[(2, 0)], k[(2, 1)]],
        ],
        innovation: [c.innovation[0], c.innovation[1]],
        nis: c.nis,
        gate_threshold,
        applied: c.applied,
        x_post: v3(&c.belief.x),
        p_post: mat3(&c.belief.p),
    }
}

/// Runs the `square` scenario with `cfg` from `seed`, calling `sink` with
/// every step's record as the run goes, and returns the summary (a
/// [`Tally`] of every step's [`Record::sample`]). A loop over
/// [`SquareSim::step`] without teleoperation.
///
/// # Errors
/// [`Error::Config`] for an invalid configuration; a robot, sensor or
/// filter error stops the run (the records already sunk stay valid).
pub fn run_square(
    cfg: &SquareConfig,
    seed: u64,
    sink: &mut impl FnMut(&StepRecord),
) -> Result<Summary, Error> {
    cfg.validate()?;
    let mut tally = Tally::new(3)?;
    let mut sim = SquareSim::new(cfg, seed)?;
    while let Some(step) = sim.step(None)? {
        tally.push(&step.record.sample());
        sink(&step.record);
    }
    Ok(tally.summary(sim.laps()))
}
