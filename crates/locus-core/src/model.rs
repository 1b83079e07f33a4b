//! Model traits: what a motion model and a measurement model must supply.
//!
//! A model supplies its function and the Jacobians beside it; the maths of
//! predict and correct lives in [`crate::ekf`]. Dimensions are const generics:
//! `N` state, `NQ` process noise, `M` measurement.
//!
//! Notation follows the spec (`../shared/spec/MODELS.md`, section 1):
//! `X- = f(X+, u, 0)`, `A = df/dX`, `W = df/dq`, `P- = A P+ A^T + W Q W^T`;
//! `z = h(X) + r`, `H = dh/dX`, `S = H P H^T + V R V^T`.

use nalgebra::{SMatrix, SVector};

use crate::Scalar;

/// A discrete-time motion model `X' = f(X, u, q)` with process noise
/// `q ~ N(0, Q)` of dimension `NQ`.
///
/// Implement [`f`](Self::f) and its two Jacobians; the filter evaluates them at
/// `q = 0`. The noise enters through `f` so that `W` can be checked against
/// finite differences like any other Jacobian.
pub trait MotionModel<T: Scalar, const N: usize, const NQ: usize> {
    /// The control input (wheel travels, commanded speeds, ...). Its units are
    /// the model's to document.
    type Input;

    /// The transition `f(X, u, q)`; `q` is the process-noise vector.
    fn f(&self, x: &SVector<T, N>, u: &Self::Input, q: &SVector<T, NQ>) -> SVector<T, N>;

    /// `A = df/dX`, evaluated at `(x, u, q = 0)`.
    fn jacobian_state(&self, x: &SVector<T, N>, u: &Self::Input) -> SMatrix<T, N, N>;

    /// `W = df/dq`, evaluated at `(x, u, q = 0)`.
    fn jacobian_noise(&self, x: &SVector<T, N>, u: &Self::Input) -> SMatrix<T, N, NQ>;

    /// The process-noise covariance `Q` (`NQ x NQ`), possibly depending on the
    /// input (e.g. noise proportional to the distance travelled).
    fn noise_cov(&self, u: &Self::Input) -> SMatrix<T, NQ, NQ>;

    /// Returns `false` if the input holds a non-finite value (NaN or
    /// infinity); `predict` then fails with `Error::NonFinite(Input::Control)`.
    /// The default accepts everything.
    fn input_is_finite(&self, _u: &Self::Input) -> bool {
        true
    }

    /// The difference `a - b` of two states, with angle components wrapped to
    /// (-pi, pi]. Default: plain subtraction.
    fn state_residual(&self, a: &SVector<T, N>, b: &SVector<T, N>) -> SVector<T, N> {
        a - b
    }

    /// `(f(X, u, 0), A, W)` together, as the filter needs them. The default
    /// calls the three methods; override it to share work between them (one
    /// `sin_cos` instead of three). The Jacobian checker verifies that an
    /// override agrees with the separate methods.
    #[inline]
    fn linearize(
        &self,
        x: &SVector<T, N>,
        u: &Self::Input,
    ) -> (SVector<T, N>, SMatrix<T, N, N>, SMatrix<T, N, NQ>) {
        (
            self.f(x, u, &SVector::zeros()),
            self.jacobian_state(x, u),
            self.jacobian_noise(x, u),
        )
    }

    /// The mapped process noise `W Q W^T` at `(x, u)`.
    fn process_noise(&self, x: &SVector<T, N>, u: &Self::Input) -> SMatrix<T, N, N> {
        let w = self.jacobian_noise(x, u);
        w * self.noise_cov(u) * w.transpose()
    }
}

/// A measurement model `z = h(X) (+ noise)` of dimension `M`.
///
/// A measurement model value describes one observation: it may carry the
/// context needed to predict it (which wall, the sensor mounting, the raw
/// readings that set `V`).
pub trait MeasurementModel<T: Scalar, const N: usize, const M: usize> {
    /// The predicted measurement `h(X)`, or `None` if no measurement can exist
    /// at this state (beam parallel to the wall, wall behind the sensor, out of
    /// range, hit off the segment, mark behind the camera, ...).
    fn h(&self, x: &SVector<T, N>) -> Option<SVector<T, M>>;

    /// `H = dh/dX` at `x` (only called where [`h`](Self::h) is `Some`).
    fn jacobian(&self, x: &SVector<T, N>) -> SMatrix<T, M, N>;

    /// The effective measurement noise `V R V^T` (`M x M`) at `x`. Models whose
    /// noise enters through a nonlinear map of raw readings (`V = dh/dr`)
    /// return the mapped covariance; otherwise this is `R`.
    fn noise(&self, x: &SVector<T, N>) -> SMatrix<T, M, M>;

    /// The residual `z - z_hat`, with angle components wrapped to (-pi, pi].
    /// Default: plain subtraction.
    fn residual(&self, z: &SVector<T, M>, z_hat: &SVector<T, M>) -> SVector<T, M> {
        z - z_hat
    }
}
