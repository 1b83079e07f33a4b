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
use crate::linalg::{mul, mul_bt, sandwich};

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

    /// The prediction `(X-, P-) = (f(X, u, 0), A P A^T + W Q W^T)` (spec
    /// section 1, eq. 1-2), `P-` exactly symmetric for a symmetric `P`.
    ///
    /// The default forms `A` and `W` with [`linearize`](Self::linearize) and
    /// multiplies densely. Override it when `A` or `W` has structure a dense
    /// product wastes work on (differential drive: `A` is the identity plus
    /// one column); [`crate::jacobian_check::check_propagate`] verifies an
    /// override against the dense products.
    #[inline(always)]
    fn propagate(
        &self,
        x: &SVector<T, N>,
        u: &Self::Input,
        p: &SMatrix<T, N, N>,
    ) -> (SVector<T, N>, SMatrix<T, N, N>) {
        let q = self.noise_cov(u);
        let (x, a, w) = self.linearize(x, u);
        (x, sandwich(&a, p) + sandwich(&w, &q))
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

    /// `(h(X), H)` together, `None` where [`h`](Self::h) is `None`. The
    /// default calls the two methods; override it to share work between
    /// them (a camera model computes its rotation once instead of twice).
    /// [`crate::jacobian_check::check_measurement_model`] verifies that an
    /// override agrees with the separate methods.
    #[inline(always)]
    fn linearize(&self, x: &SVector<T, N>) -> Option<(SVector<T, M>, SMatrix<T, M, N>)> {
        let z_hat = self.h(x)?;
        Some((z_hat, self.jacobian(x)))
    }

    /// The covariance projections `(P H^T, H P H^T)` at `x` that the
    /// correction needs (spec section 1, eq. 3-4: `S = H P H^T + V R V^T`,
    /// `G = P H^T S^-1`).
    ///
    /// The default multiplies densely with [`jacobian`](Self::jacobian).
    /// Override it when `H` has structure, e.g. rows that select state
    /// components (the IR pair of paper 001 measures `x` or `y`, and
    /// `theta`): `P H^T` is then columns of `P`, with no multiplication.
    /// [`crate::jacobian_check::check_project`] verifies an override against
    /// the dense products.
    #[inline(always)]
    fn project(
        &self,
        x: &SVector<T, N>,
        p: &SMatrix<T, N, N>,
    ) -> (SMatrix<T, N, M>, SMatrix<T, M, M>) {
        let h = self.jacobian(x);
        let pht = mul_bt(p, &h);
        (pht, mul(&h, &pht))
    }
}
