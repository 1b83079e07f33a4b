//! The continuous-time EKF observer of paper 002 (eq. 12-17; spec
//! `MODELS.md` section 4), integrated with explicit Euler steps.
//!
//! # Equations
//! For a plant `dx/dt = 0 + delta`, `y = h(x) + epsilon` (eq. 11; `A = 0`),
//! with `C = dh/dx` at the estimate (eq. 13):
//! ```text
//! dx^/dt = K (y - h(x^)),        x^(0) = x^_0              (eq. 12)
//! K      = P C^T Theta^-1                                   (eq. 14)
//! dP/dt  = 2 alpha P - P C^T Theta^-1 C P + Q,  P(0) = P0   (eq. 15-17)
//! ```
//! `alpha >= 0` (1/s) is the exponential-weighting (robustifying) factor
//! (`2 alpha P = A_alpha P + P A_alpha^T` with `A_alpha = alpha I`, eq. 16-17;
//! the paper takes `alpha > 0`, `alpha = 0` is the plain Kalman-Bucy
//! observer). `Q` (state units^2 per second) and `Theta` (measurement
//! units^2 times seconds) are continuous-time densities here; the paper uses
//! the numbers of its discrete noise (eq. 23: `Q = diag(0.1^2 x3,
//! 0.1396^2 x3)`, `Theta = 2^2 I`) directly as densities.
//!
//! # Integration
//! One explicit Euler step of length `dt` (s; the paper's fixed step is
//! 0.005 s) from `(x^, P)`, with `h`, `C` and `K` evaluated once at `x^`:
//! ```text
//! x^' = x^ + dt K (y - h(x^))
//! P'  = P + dt (2 alpha P - K C P + Q),   then symmetrised (P + P^T)/2
//! ```
//! The residual `y - h(x^)` goes through the model's
//! [`residual`](MeasurementModel::residual). The state is not wrapped (the
//! observer does not know which components are angles).
//!
//! With `Theta = L L^T` factorised once, the step forms `G = L^-1 C P`
//! (`M x N`), then `K nu = G^T L^-1 nu` and `K C P = G^T G`: half the work of
//! the direct products, and `G^T G` is exactly symmetric. For a diagonal
//! `Theta` (the paper's) `L^-1` is a row scaling. Cost for the four-mark
//! camera in f64: about 0.5 us per step (h and C included) on a busy
//! 2-core x86-64 development machine.
//!
//! # Stability of the explicit integration
//! Euler is stable only while the step is small against the fastest rates.
//! Near the true state the estimate error obeys `dzeta/dt = -P B zeta`
//! (`B = C^T Theta^-1 C`, eq. 13), which Euler integrates stably only while
//! `dt lambda(P B) < 2`. For `P0 = v_g Q` the matrix `U = P B` (at fixed `C`)
//! follows, eigenvalue by eigenvalue of `Q B`,
//! `u' = u + dt (2 alpha u - u^2 + lambda(Q B))`: once `u0` exceeds about
//! `2 alpha + 1/dt`, the first step turns `P` indefinite, the error grows
//! instead of decaying, and the estimate is thrown far off. So a large `P0`
//! makes the integration itself unstable at a fixed `dt` (the paper ran at the
//! same fixed step, and this is part of what its domain-of-attraction map
//! shows): the estimate swings until a mark passes behind the camera
//! ([`Error::NoMeasurement`]) or the values overflow ([`Error::NonFinite`]).
//! For the paper's camera at the \[assumed\] nominal pose,
//! `lambda_max(Q B) ~ 5.4e3` /s, so `u0 ~ 5.4e3 v_g`; with a tiny initial error
//! (0.001) and `dt = 0.005` s the runs were observed to fail from
//! `v_g ~ 0.055` at `alpha = 5`, `0.07` at `alpha = 50` and `0.1` at
//! `alpha = 125`. No step-size control is attempted, by design.
//!
//! Away from the true state other failures are possible and are not errors of
//! a step: the estimate can settle on the same pose written with the other
//! Euler triple (`phi +- pi, pi - theta, psi +- pi`), or drift away along the
//! optical axis where `C -> 0` while `P` grows like `exp(2 alpha t)`; a caller
//! judges convergence from the final error.
//!
//! # Errors
//! [`ContinuousObserver::step`] borrows the state and returns a new one; on
//! any error the caller's state is unchanged. It fails with
//! [`Error::NoMeasurement`] when the model predicts no measurement at `x^`
//! (for [`crate::camera::CameraMarks`]: a mark at depth `z_c <= min_depth`,
//! i.e. behind or at the camera plane; the spec's divergence rule), and with
//! [`Error::NonFinite`] on a non-finite state, covariance, measurement,
//! model output, or result (overflow of an unstable integration). It never
//! panics and does not allocate.

use locus_core::nalgebra::{SMatrix, SVector};
use locus_core::{Belief, Error, Input, MeasurementModel, Scalar, cast};

use crate::camera::{SIGMA_PIXEL, paper_q};

/// Default integration step of paper 002 (s).
pub const DEFAULT_DT: f64 = 0.005;

/// The observer's state: the estimate `x^` and the Riccati matrix `P`
/// (paper 002, eq. 12, 15), as the core's [`Belief`] value. Units: those of
/// the model's state and their products. With `alpha > 0`, `P` is a weighted
/// (inflated) covariance, not the covariance of the estimate.
pub type ObserverState<T, const N: usize> = Belief<T, N>;

/// The continuous-time EKF observer of paper 002 (eq. 12-17), integrated by
/// explicit Euler steps: configuration only (`alpha`, `Q`, `Theta`, `dt`),
/// no estimate. `N` is the state dimension, `M` the measurement dimension.
///
/// Build it with [`ContinuousObserver::new`] (which checks the parameters and
/// factorises `Theta` once) or [`ContinuousObserver::paper_002`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContinuousObserver<T: Scalar, const N: usize, const M: usize> {
    alpha: T,
    q: SMatrix<T, N, N>,
    theta: SMatrix<T, M, M>,
    /// `L^-1` for the Cholesky factor `Theta = L L^T`, so that
    /// `Theta^-1 = L^-T L^-1`.
    whiten: SMatrix<T, M, M>,
    /// `Some(diag(L^-1))` when `Theta` is diagonal (the common case): the
    /// whitening is then a row scaling.
    whiten_diag: Option<SVector<T, M>>,
    dt: T,
}

impl<T: Scalar, const N: usize, const M: usize> ContinuousObserver<T, N, M> {
    /// An observer with weighting factor `alpha` (1/s, finite, >= 0), state
    /// noise density `Q` (`N x N`, symmetric PSD), measurement noise density
    /// `Theta` (`M x M`, symmetric positive definite) and Euler step `dt` (s,
    /// finite, > 0).
    ///
    /// Errors: [`Error::NonFinite`]`(Parameter)` for a non-finite value,
    /// [`Error::InvalidParameter`] for `alpha < 0` or `dt <= 0`,
    /// [`Error::NoiseNotPositiveDefinite`] if `Theta` has no Cholesky factor.
    pub fn new(
        alpha: T,
        q: SMatrix<T, N, N>,
        theta: SMatrix<T, M, M>,
        dt: T,
    ) -> Result<Self, Error> {
        if !(alpha.is_finite()
            && dt.is_finite()
            && all_finite(q.as_slice())
            && all_finite(theta.as_slice()))
        {
            return Err(Error::NonFinite(Input::Parameter));
        }
        if alpha < T::zero() {
            return Err(Error::InvalidParameter("observer alpha must be >= 0"));
        }
        if dt <= T::zero() {
            return Err(Error::InvalidParameter("observer step dt must be > 0"));
        }
        let chol = theta.cholesky().ok_or(Error::NoiseNotPositiveDefinite)?;
        let whiten = chol
            .l()
            .solve_lower_triangular(&SMatrix::<T, M, M>::identity())
            .ok_or(Error::NoiseNotPositiveDefinite)?;
        if !all_finite(whiten.as_slice()) {
            return Err(Error::NoiseNotPositiveDefinite);
        }
        let is_diagonal = (0..M).all(|i| (0..M).all(|j| i == j || theta[(i, j)] == T::zero()));
        Ok(Self {
            alpha,
            q,
            theta,
            whiten,
            whiten_diag: is_diagonal.then(|| whiten.diagonal()),
            dt,
        })
    }

    /// The weighting factor `alpha` (1/s).
    pub fn alpha(&self) -> T {
        self.alpha
    }

    /// The state noise density `Q`.
    pub fn q(&self) -> &SMatrix<T, N, N> {
        &self.q
    }

    /// The measurement noise density `Theta`.
    pub fn theta(&self) -> &SMatrix<T, M, M> {
        &self.theta
    }

    /// The Euler step `dt` (s).
    pub fn dt(&self) -> T {
        self.dt
    }

    /// One explicit Euler step of eq. 12-15 from `state`, with measurement
    /// `y` (measurement units; held constant over the step) and the
    /// measurement model giving `h` and `C`:
    /// `x^' = x^ + dt K (y - h(x^))`, `P' = P + dt (2 alpha P - K C P + Q)`.
    ///
    /// Errors (the caller's state is unchanged): [`Error::NonFinite`] for a
    /// non-finite state, covariance, measurement, model output or result;
    /// [`Error::NoMeasurement`] if the model predicts none at `x^` (a mark
    /// behind the camera). Does not allocate.
    pub fn step<Me>(
        &self,
        state: &ObserverState<T, N>,
        model: &Me,
        y: &SVector<T, M>,
    ) -> Result<ObserverState<T, N>, Error>
    where
        Me: MeasurementModel<T, N, M>,
    {
        state.validate()?;
        if !all_finite(y.as_slice()) {
            return Err(Error::NonFinite(Input::Measurement));
        }
        let (y_hat, c) = model.linearize(&state.x).ok_or(Error::NoMeasurement)?;
        if !(all_finite(y_hat.as_slice()) && all_finite(c.as_slice())) {
            return Err(Error::NonFinite(Input::MeasurementModel));
        }
        let p = &state.p;
        let nu = model.residual(y, &y_hat);
        // Whitened C~ = L^-1 C and nu~ = L^-1 nu (Theta = L L^T), so that
        // B = C^T Theta^-1 C = C~^T C~ (eq. 13). With G = C~ P (P symmetric):
        //   K nu = P C^T Theta^-1 nu = G^T nu~                      (eq. 12, 14)
        //   P B P = G^T G  (exactly symmetric in floating point)    (eq. 15)
        let (cw, nuw) = match &self.whiten_diag {
            Some(w) => {
                let mut cw = c;
                for (i, wi) in w.iter().enumerate() {
                    cw.row_mut(i).scale_mut(*wi);
                }
                (cw, nu.component_mul(w))
            }
            None => (self.whiten * c, self.whiten * nu),
        };
        let g = cw * p;
        let x = state.x + g.tr_mul(&nuw) * self.dt;
        // dP/dt = 2 alpha P - P C^T Theta^-1 C P + Q.
        let two_alpha = self.alpha + self.alpha;
        // G^T G on its upper triangle, mirrored (exactly symmetric, and
        // nearly half the multiplications of the full product).
        let mut gtg = SMatrix::<T, N, N>::zeros();
        for j in 0..N {
            for i in 0..=j {
                let v = g.column(i).dot(&g.column(j));
                gtg[(i, j)] = v;
                gtg[(j, i)] = v;
            }
        }
        let p_dot = p * two_alpha - gtg + self.q;
        let p_next = p + p_dot * self.dt;
        // Removes the asymmetry of a caller's P0 or Q (the step itself keeps
        // a symmetric P exactly symmetric).
        let p_next = (p_next + p_next.transpose()) * cast::<T>(0.5);
        if !all_finite(x.as_slice()) {
            return Err(Error::NonFinite(Input::State));
        }
        if !all_finite(p_next.as_slice()) {
            return Err(Error::NonFinite(Input::Covariance));
        }
        Ok(ObserverState { x, p: p_next })
    }
}

impl<T: Scalar> ContinuousObserver<T, 6, 8> {
    /// The paper-002 observer for the four-mark camera
    /// ([`crate::camera::CameraMarks4`]): `Q = diag(0.1^2 x3, 0.1396^2 x3)`
    /// (eq. 23), `Theta = 2^2 I_8` (px^2), `dt = 0.005` s, and the given
    /// `alpha` (1/s). Errors as [`ContinuousObserver::new`].
    pub fn paper_002(alpha: T) -> Result<Self, Error> {
        Self::new(
            alpha,
            paper_q(),
            SMatrix::<T, 8, 8>::identity() * cast::<T>(SIGMA_PIXEL * SIGMA_PIXEL),
            cast(DEFAULT_DT),
        )
    }
}

#[inline]
fn all_finite<T: Scalar>(values: &[T]) -> bool {
    values.iter().all(|v| v.is_finite())
}
