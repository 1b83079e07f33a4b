//! One IR correction of paper 001's localiser, kept whole so that a
//! teaching tool can show it step by step (eq. 14-22): the prior, the
//! linearisation, the gain, the innovation, the gate's decision and the
//! belief after it. The simulator and the link's host build the same
//! [`CorrectionDetail`] from it.

use locus_core::nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use locus_core::{Belief, MeasurementModel, Update};

use crate::IrPairObservation;

/// An IR reading the filter was given: its observation (the associated
/// wall, readings and `R`), the measurement `z`, the belief it corrected
/// (`x-`, `P-`) and what the running filter did with it.
#[derive(Debug, Clone, Copy)]
pub struct IrCorrection {
    /// The associated observation.
    pub observation: IrPairObservation<f64>,
    /// The measurement `z = [d, theta_m]` (m, rad).
    pub z: Vector2<f64>,
    /// The belief before the correction.
    pub prior: Belief<f64, 3>,
    /// The running filter's update.
    pub update: Update<f64, 3, 2>,
}

/// The details of one EKF correction, for showing it step by step.
/// Matrices are row-major (serialised as nested arrays).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub struct CorrectionDetail {
    /// The belief before the prediction(s) leading to this correction:
    /// `x` (m, m, rad).
    pub x_before_predict: [f64; 3],
    /// Its covariance.
    pub p_before_predict: [[f64; 3]; 3],
    /// The odometry input of the prediction `[d1, d2]` (m): the wheel
    /// travels since `x_before_predict` (over one or more prediction
    /// steps, eq. 7-13).
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

impl IrCorrection {
    /// The diagonal of `H G` (`G` the gain of the correction, `H` at the
    /// prior): the share of the wall-distance innovation moved into the
    /// estimate's wall distance and of the heading innovation into the
    /// heading. `[0, 0]` if the gate rejected the reading; `None` if the
    /// model predicts no measurement.
    #[must_use]
    pub fn gain_diagonal(&self) -> Option<[f64; 2]> {
        match &self.update {
            Update::Applied { correction, .. } => {
                let hg = self.observation.jacobian(&self.prior.x) * correction.gain;
                Some([hg[(0, 0)], hg[(1, 1)]])
            }
            Update::Gated { .. } => Some([0.0, 0.0]),
            Update::NoMeasurement => None,
        }
    }

    /// The [`CorrectionDetail`] of this correction, after predicting from
    /// `before` with wheel travels `u` (m), behind a gate of NIS threshold
    /// `gate_threshold`. The gain, `S` and NIS are those of the attempt on
    /// the prior; the posterior is the belief the filter kept. `None` if
    /// the model predicts no measurement.
    #[must_use]
    pub fn detail(
        &self,
        before: &Belief<f64, 3>,
        u: [f64; 2],
        gate_threshold: Option<f64>,
    ) -> Option<CorrectionDetail> {
        let first = self.update.first_attempt()?;
        let post = self.update.correction()?.belief;
        let (obs, prior) = (&self.observation, &self.prior);
        let h = obs.jacobian(&prior.x);
        let noise = obs.noise(&prior.x);
        let hx = obs.h(&prior.x).unwrap_or_else(Vector2::zeros);
        let g = &first.gain;
        Some(CorrectionDetail {
            x_before_predict: v3(&before.x),
            p_before_predict: m3(&before.p),
            u,
            x_prior: v3(&prior.x),
            p_prior: m3(&prior.p),
            z: [self.z[0], self.z[1]],
            h: [hx[0], hx[1]],
            jacobian: core::array::from_fn(|i| core::array::from_fn(|j| h[(i, j)])),
            noise: m2(&noise),
            s: m2(&first.s),
            k: core::array::from_fn(|i| core::array::from_fn(|j| g[(i, j)])),
            innovation: [first.innovation[0], first.innovation[1]],
            nis: first.nis,
            gate_threshold,
            applied: self.update.applied(),
            x_post: v3(&post.x),
            p_post: m3(&post.p),
        })
    }
}

fn v3(v: &Vector3<f64>) -> [f64; 3] {
    [v[0], v[1], v[2]]
}

fn m2(m: &Matrix2<f64>) -> [[f64; 2]; 2] {
    core::array::from_fn(|i| core::array::from_fn(|j| m[(i, j)]))
}

fn m3(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    core::array::from_fn(|i| core::array::from_fn(|j| m[(i, j)]))
}
