//! What the teaching UI needs of the closed loop: teleoperation, the live
//! parameters, and the details of each correction.

use locus_core::nalgebra::{Matrix2, Vector2, Vector3};
use locus_core::{Belief, MeasurementModel, Update};
use locus_models::IrPairObservation;

#[cfg(doc)]
use super::SquareSim;
use super::{SquareConfig, StepRecord};
use locus_eval::matrix3;

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
    /// The innovation covariance `S = H P- H^T + V R V^T` (2x2), as the
    /// filter computed it.
    pub s: [[f64; 2]; 2],
    /// The Kalman gain `K = P- H^T S^-1` (3x2), as the filter computed it.
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

/// An IR reading the filter was given: its observation (the associated
/// wall, readings and `R`), the measurement `z`, the belief it corrected
/// and what the running filter did with it.
#[derive(Debug, Clone, Copy)]
pub(super) struct Corrected {
    pub(super) observation: IrPairObservation<f64>,
    pub(super) z: Vector2<f64>,
    pub(super) prior: Belief<f64, 3>,
    pub(super) update: Update<f64, 3, 2>,
}

impl Corrected {
    /// The diagonal of `H G` (`G` the gain of the correction, `H` at the
    /// prior): the share of the wall-distance innovation moved into the
    /// estimate's wall distance and of the heading innovation into the
    /// heading. `[0, 0]` if the gate rejected the reading; `None` if the
    /// model predicts no measurement.
    pub(super) fn gain_diagonal(&self) -> Option<[f64; 2]> {
        match &self.update {
            Update::Applied { correction, .. } => {
                let hg = self.observation.jacobian(&self.prior.x) * correction.gain;
                Some([hg[(0, 0)], hg[(1, 1)]])
            }
            Update::Gated { .. } => Some([0.0, 0.0]),
            Update::NoMeasurement => None,
        }
    }

    /// The [`CorrectionDetail`] of this correction, after a prediction from
    /// `before` with wheel travels `u` (m), behind a gate of NIS threshold
    /// `gate_threshold`. `None` if the model predicts no measurement.
    pub(super) fn detail(
        &self,
        before: &Belief<f64, 3>,
        u: [f64; 2],
        gate_threshold: Option<f64>,
    ) -> Option<CorrectionDetail> {
        // The attempt on the prior (its S, gain and NIS) and the belief the
        // filter kept.
        let first = self.update.first_attempt()?;
        let post = self.update.correction()?.belief;
        let (obs, prior) = (&self.observation, &self.prior);
        let h = obs.jacobian(&prior.x);
        let noise = obs.noise(&prior.x);
        let hx = obs.h(&prior.x).unwrap_or_else(Vector2::zeros);
        let m2 = |m: &Matrix2<f64>| [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]];
        let v3 = |v: &Vector3<f64>| [v[0], v[1], v[2]];
        let g = &first.gain;
        Some(CorrectionDetail {
            x_before_predict: v3(&before.x),
            p_before_predict: matrix3(&before.p),
            u,
            x_prior: v3(&prior.x),
            p_prior: matrix3(&prior.p),
            z: [self.z[0], self.z[1]],
            h: [hx[0], hx[1]],
            jacobian: [
                [h[(0, 0)], h[(0, 1)], h[(0, 2)]],
                [h[(1, 0)], h[(1, 1)], h[(1, 2)]],
            ],
            noise: m2(&noise),
            s: m2(&first.s),
            k: [
                [g[(0, 0)], g[(0, 1)]],
                [g[(1, 0)], g[(1, 1)]],
                [g[(2, 0)], g[(2, 1)]],
            ],
            innovation: [first.innovation[0], first.innovation[1]],
            nis: first.nis,
            gate_threshold,
            applied: self.update.applied(),
            x_post: v3(&post.x),
            p_post: matrix3(&post.p),
        })
    }
}
