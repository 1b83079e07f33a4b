//! Model traits: what a motion model and a measurement model must supply.
//!
//! A model supplies its function and the Jacobians beside it, from one
//! method; the maths of predict and correct lives in [`crate::ekf`]. Dimensions are const generics:
//! `N` state, `NQ` process noise, `M` measurement.
//!
//! Notation follows the spec (`../shared/spec/MODELS.md`, section 1):
//! `X- = f(X+, u, 0)`, `A = df/dX`, `W = df/dq`, `P- = A P+ A^T + W Q W^T`;
//! `z = h(X) + r`, `H = dh/dX`, `S = H P H^T + V R V^T`.

use nalgebra::{SMatrix, SVector};

use crate::Scalar;
use crate::linalg::{mul, mul_bt, sandwich};

/// The Jacobians of a motion model at one point: `A = df/dX` (`N x N`) and
/// `W = df/dq` (`N x NQ`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionJacobians<T: Scalar, const N: usize, const NQ: usize> {
    /// `A = df/dX`.
    pub a: SMatrix<T, N, N>,
    /// `W = df/dq`.
    pub w: SMatrix<T, N, NQ>,
}

impl<T: Scalar, const N: usize, const NQ: usize> MotionJacobians<T, N, NQ> {
    /// Both Jacobians zero (a model writes every entry it needs).
    #[must_use]
    pub fn zeros() -> Self {
        Self {
            a: SMatrix::zeros(),
            w: SMatrix::zeros(),
        }
    }
}

/// A discrete-time motion model `X' = f(X, u, q)` with process noise
/// `q ~ N(0, Q)` of dimension `NQ`.
///
/// Implement [`evaluate`](Self::evaluate): the transition and, when asked,
/// its two Jacobians beside it, from one evaluation (as GTSAM's factors
/// return their error and its Jacobians together), and
/// [`noise_cov`](Self::noise_cov). That is all a model needs, and it is the
/// fast way: the filter asks for the value and the Jacobians in one call, so
/// a `sin_cos` is computed once per prediction. The filter evaluates at
/// `q = 0`; the noise enters through `f` so that `W` can be checked against
/// finite differences like any other Jacobian
/// ([`crate::jacobian_check::check_motion_model`]).
///
/// ```
/// use locus_core::nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2, Vector3};
/// use locus_core::{MotionJacobians, MotionModel};
///
/// /// Forward distance `d` and turn `dth` over one step (m, rad).
/// struct Step { d: f64, dth: f64 }
///
/// /// A unicycle driven by odometry increments, noise on both.
/// struct Drive { q: Matrix2<f64> }
///
/// impl MotionModel<f64, 3, 2> for Drive {
///     type Input = Step;
///
///     fn evaluate(
///         &self,
///         x: &Vector3<f64>,
///         u: &Step,
///         q: &Vector2<f64>,
///         jacobians: Option<&mut MotionJacobians<f64, 3, 2>>,
///     ) -> Vector3<f64> {
///         let (d, dth) = (u.d + q[0], u.dth + q[1]);
///         let (s, c) = (x[2] + 0.5 * dth).sin_cos();
///         if let Some(j) = jacobians {
///             j.a = Matrix3::new(1.0, 0.0, -d * s, 0.0, 1.0, d * c, 0.0, 0.0, 1.0);
///             j.w = Matrix3x2::new(c, -0.5 * d * s, s, 0.5 * d * c, 0.0, 1.0);
///         }
///         Vector3::new(x[0] + d * c, x[1] + d * s, x[2] + dth)
///     }
///
///     fn noise_cov(&self, _u: &Step) -> Matrix2<f64> {
///         self.q
///     }
/// }
/// # let m = Drive { q: Matrix2::identity() * 1e-4 };
/// # let x = Vector3::new(1.0, 2.0, 0.3);
/// # locus_core::jacobian_check::check_motion_model(&m, &x, &Step { d: 0.1, dth: 0.05 }, 1e-5, 1e-6).unwrap();
/// ```
pub trait MotionModel<T: Scalar, const N: usize, const NQ: usize> {
    /// The control input (wheel travels, commanded speeds, ...). Its units are
    /// the model's to document.
    type Input;

    /// The transition `f(X, u, q)` (`q` the process-noise vector) and, when
    /// `jacobians` is given, `A = df/dX` and `W = df/dq` at the same point,
    /// written into it (every entry: it may hold anything on entry).
    fn evaluate(
        &self,
        x: &SVector<T, N>,
        u: &Self::Input,
        q: &SVector<T, NQ>,
        jacobians: Option<&mut MotionJacobians<T, N, NQ>>,
    ) -> SVector<T, N>;

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

    /// The transition `f(X, u, q)` alone.
    #[inline]
    fn f(&self, x: &SVector<T, N>, u: &Self::Input, q: &SVector<T, NQ>) -> SVector<T, N> {
        self.evaluate(x, u, q, None)
    }

    /// `A = df/dX`, evaluated at `(x, u, q = 0)`.
    fn jacobian_state(&self, x: &SVector<T, N>, u: &Self::Input) -> SMatrix<T, N, N> {
        self.linearize(x, u).1
    }

    /// `W = df/dq`, evaluated at `(x, u, q = 0)`.
    fn jacobian_noise(&self, x: &SVector<T, N>, u: &Self::Input) -> SMatrix<T, N, NQ> {
        self.linearize(x, u).2
    }

    /// `(f(X, u, 0), A, W)` from one [`evaluate`](Self::evaluate), as the
    /// filter needs them.
    #[inline(always)]
    fn linearize(
        &self,
        x: &SVector<T, N>,
        u: &Self::Input,
    ) -> (SVector<T, N>, SMatrix<T, N, N>, SMatrix<T, N, NQ>) {
        let mut j = MotionJacobians::zeros();
        let x = self.evaluate(x, u, &SVector::zeros(), Some(&mut j));
        (x, j.a, j.w)
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
///
/// Implement [`evaluate`](Self::evaluate) (the prediction and, when asked,
/// `H` beside it) and [`noise`](Self::noise); wrap angle components in
/// [`residual`](Self::residual).
pub trait MeasurementModel<T: Scalar, const N: usize, const M: usize> {
    /// The predicted measurement `h(X)` and, when `jacobian` is given,
    /// `H = dh/dX` at `x` written into it (every entry); `None` if no
    /// measurement can exist at this state (beam parallel to the wall, wall
    /// behind the sensor, out of range, hit off the segment, mark behind the
    /// camera, ...).
    fn evaluate(
        &self,
        x: &SVector<T, N>,
        jacobian: Option<&mut SMatrix<T, M, N>>,
    ) -> Option<SVector<T, M>>;

    /// The effective measurement noise `V R V^T` (`M x M`) at `x`. Models whose
    /// noise enters through a nonlinear map of raw readings (`V = dh/dr`)
    /// return the mapped covariance; otherwise this is `R`.
    fn noise(&self, x: &SVector<T, N>) -> SMatrix<T, M, M>;

    /// The residual `z - z_hat`, with angle components wrapped to (-pi, pi].
    /// Default: plain subtraction.
    fn residual(&self, z: &SVector<T, M>, z_hat: &SVector<T, M>) -> SVector<T, M> {
        z - z_hat
    }

    /// The predicted measurement `h(X)` alone.
    #[inline]
    fn h(&self, x: &SVector<T, N>) -> Option<SVector<T, M>> {
        self.evaluate(x, None)
    }

    /// `H = dh/dX` at `x` (meaningful only where [`h`](Self::h) is `Some`).
    fn jacobian(&self, x: &SVector<T, N>) -> SMatrix<T, M, N> {
        let mut h = SMatrix::zeros();
        let _ = self.evaluate(x, Some(&mut h));
        h
    }

    /// `(h(X), H)` from one [`evaluate`](Self::evaluate), `None` where
    /// [`h`](Self::h) is `None`.
    #[inline(always)]
    fn linearize(&self, x: &SVector<T, N>) -> Option<(SVector<T, M>, SMatrix<T, M, N>)> {
        let mut h = SMatrix::zeros();
        let z_hat = self.evaluate(x, Some(&mut h))?;
        Some((z_hat, h))
    }

    /// The covariance projections `(P H^T, H P H^T)` at `x`, given `h`, the
    /// model's `H` there, that the correction needs (spec section 1, eq.
    /// 3-4: `S = H P H^T + V R V^T`, `G = P H^T S^-1`).
    ///
    /// The default multiplies densely with `h`. Override it when `H` has
    /// structure, e.g. rows that select state components (the IR pair of
    /// paper 001 measures `x` or `y`, and `theta`): `P H^T` is then columns
    /// of `P`, with no multiplication.
    /// [`crate::jacobian_check::check_project`] verifies an override against
    /// the dense products.
    #[inline(always)]
    fn project(
        &self,
        x: &SVector<T, N>,
        h: &SMatrix<T, M, N>,
        p: &SMatrix<T, N, N>,
    ) -> (SMatrix<T, N, M>, SMatrix<T, M, M>) {
        let _ = x;
        let pht = mul_bt(p, h);
        (pht, mul(h, &pht))
    }
}
