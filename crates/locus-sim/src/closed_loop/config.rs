//! The `square` scenario's configuration ([`SquareConfig`], spec section
//! 3), its scenario-file form (serde, with the controller's `[control]`
//! table and the `"none"` gate) and its validation.

use locus_models::settings;

use super::Error;
use crate::scenario_file::{MAX_STEPS, within};

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
    /// `R` assume (see the [module documentation](super)).
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

    /// `Ok(())` if every value is in its domain: the settings a user may
    /// also change live (`Q`, `R`, `ir_sigma`, the gate, the controller's
    /// speeds and gains, the initial belief) in their ranges of
    /// [`locus_models::settings`], every other field in its plausible
    /// range.
    ///
    /// # Errors
    /// [`Error::Invalid`] or [`Error::OutOfRange`] naming the first bad
    /// field (as in a scenario file).
    pub fn validate(&self) -> Result<(), Error> {
        // Plausible ranges (SI): a value outside is refused before a run,
        // naming the field; the guide's tiny and huge Q and R are inside.
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let range = |r: (f64, f64)| r.0.is_finite() && r.1.is_finite() && r.0 <= r.1;
        let c = &self.control;
        let checks: [(bool, &'static str, &'static str); 17] = [
            (
                within(self.dt, 1e-4, 1.0),
                "dt",
                "must be in [1e-4, 1] s (and max_time / dt at most 1e7 steps)",
            ),
            (
                (1..=10_000).contains(&self.laps),
                "laps",
                "must be in [1, 10000]",
            ),
            (
                within(self.max_time, 1e-4, 1e7),
                "max_time",
                "must be in [1e-4, 1e7] s",
            ),
            (
                self.max_time / self.dt <= MAX_STEPS,
                "max_time",
                "over dt makes more than 1e7 steps, the most a run may have (max_time / dt)",
            ),
            (
                within(self.wheelbase, 0.01, 10.0),
                "wheelbase",
                "must be in [0.01, 10] m",
            ),
            (
                within(self.wheel_radius, 1e-3, 1.0),
                "wheel_radius",
                "must be in [0.001, 1] m",
            ),
            (
                (1..=1_000_000).contains(&self.encoder_lines),
                "encoder_lines",
                "must be in [1, 1000000]",
            ),
            (
                within(self.encoder_gear, 1e-3, 1e3),
                "encoder_gear",
                "must be in [0.001, 1000]",
            ),
            (
                self.right_scale_error > -0.5 && self.right_scale_error < 0.5,
                "right_scale_error",
                "must be in (-0.5, 0.5)",
            ),
            (
                self.slip_bumps_per_wheel <= 1000,
                "slip_bumps_per_wheel",
                "must be in [0, 1000]",
            ),
            (
                range(self.slip_length) && self.slip_length.0 >= 0.0 && self.slip_length.1 <= 10.0,
                "slip_length",
                "must be [min, max] with 0 <= min <= max <= 10 (m)",
            ),
            (
                range(self.slip_scale) && self.slip_scale.0 > 0.0 && self.slip_scale.1 <= 10.0,
                "slip_scale",
                "must be [min, max] with 0 < min <= max <= 10",
            ),
            (
                pos(self.ir_spacing) && self.ir_spacing <= 1.0,
                "ir_spacing",
                "must be in (0, 1] m",
            ),
            (
                pos(self.association_range) && self.association_range <= 10.0,
                "association_range",
                "must be in (0, 10] m",
            ),
            (
                self.gate_confidence.is_none_or(|g| g > 0.0),
                "gate_confidence",
                "must be > 0 or \"none\" (no gate)",
            ),
            (
                pos(c.pos_tol) && c.pos_tol <= 10.0,
                "control.pos_tol",
                "must be in (0, 10] m",
            ),
            (
                pos(c.heading_tol) && c.heading_tol <= 4.0,
                "control.heading_tol",
                "must be in (0, 4] rad",
            ),
        ];
        if let Some(&(_, field, reason)) = checks.iter().find(|(ok, _, _)| !ok) {
            return Err(Error::Invalid { field, reason });
        }
        // The settings a user may also change live: the one table the
        // teaching UI and the host check too.
        let (s, sd) = (self.start, self.initial_std);
        let table = [
            ("start", settings::START_X, s[0]),
            ("start", settings::START_Y, s[1]),
            ("start", settings::START_THETA, s[2]),
            ("initial_std", settings::STD_X, sd[0]),
            ("initial_std", settings::STD_Y, sd[1]),
            ("initial_std", settings::STD_THETA, sd[2]),
            ("ir_sigma", settings::IR_SIGMA, self.ir_sigma),
            ("q11", settings::Q11, self.q11),
            ("q22", settings::Q22, self.q22),
            ("r11", settings::R11, self.r11),
            ("r22", settings::R22, self.r22),
            (
                "gate_confidence",
                settings::GATE,
                self.gate_confidence.unwrap_or(0.0),
            ),
            ("control.v_ref", settings::V_REF, c.v_ref),
            ("control.w_ref", settings::W_REF, c.w_ref),
            ("control.k_cross", settings::K_CROSS, c.k_cross),
            ("control.k_heading", settings::K_HEADING, c.k_heading),
            ("control.k_pos", settings::K_POS, c.k_pos),
        ];
        match table.into_iter().find(|(_, l, v)| !l.contains(*v)) {
            Some((field, limit, value)) => Err(Error::OutOfRange {
                field,
                limit,
                value,
            }),
            None => Ok(()),
        }
    }
}
