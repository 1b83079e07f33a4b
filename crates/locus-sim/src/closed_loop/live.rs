//! What the teaching UI needs of the closed loop: teleoperation, the live
//! parameters, and the details of each correction.

use locus_models::CorrectionDetail;

#[cfg(doc)]
use super::SquareSim;
use super::{SquareConfig, StepRecord};

/// Teleoperation of one step: the body twist `(V, W)` (m/s, rad/s) used
/// instead of the path controller's.
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

/// What one [`SquareSim::step`] produced besides its [`StepRecord`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimStep {
    /// The step's record (as logged by `locus run`).
    pub record: StepRecord,
    /// The body twist `(V, W)` (m/s, rad/s) applied (from the path
    /// controller or teleoperation).
    pub twist: (f64, f64),
    /// The wheel speeds `(V1, V2)` (m/s, right and left).
    pub wheel_speeds: (f64, f64),
    /// Whether the twist came from teleoperation.
    pub teleop: bool,
    /// The correction's details when a reading was associated and used
    /// (and [`SquareSim::with_details`] is on).
    pub correction: Option<CorrectionDetail>,
}
