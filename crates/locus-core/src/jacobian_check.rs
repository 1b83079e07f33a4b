//! Finite-difference Jacobian checker, called by every model's tests.
//!
//! Central differences: column `j` of the numerical Jacobian of `f` at `x` is
//! `(f(x + h_j e_j) - f(x - h_j e_j)) / (2 h_j)` with
//! `h_j = step * max(1, |x_j|)`. The truncation error is `O(h^2)` and the
//! rounding error `O(eps / h)`; the default step [`DEFAULT_STEP`] = 1e-5 (f64)
//! balances them to about 1e-10 for functions with derivatives of order one.
//! Output differences go through the model's residual, so angles are wrapped
//! and a check across +-pi works.
//!
//! Entries are compared with a mixed relative/absolute tolerance: the check
//! fails where `|analytic - numeric| > tol * max(1, |analytic|, |numeric|)`.
//! [`DEFAULT_TOLERANCE`] = 1e-6 (f64) is four orders above the expected error
//! and far below any real mistake in a Jacobian.

use core::fmt;

use nalgebra::{SMatrix, SVector};

use crate::{MeasurementModel, MotionModel, Scalar};

/// Default relative step of the central differences (f64).
pub const DEFAULT_STEP: f64 = 1e-5;
/// Default mixed relative/absolute tolerance of the comparison (f64).
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// Where an analytic Jacobian disagrees with its finite-difference estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mismatch<T> {
    /// Which Jacobian: `"A"` (df/dX), `"W"` (df/dq) or `"H"` (dh/dX), or the
    /// name a caller gave.
    pub jacobian: &'static str,
    /// Row of the mismatching entry.
    pub row: usize,
    /// Column of the mismatching entry.
    pub col: usize,
    /// The analytic value.
    pub analytic: T,
    /// The finite-difference value.
    pub numeric: T,
}

impl<T: fmt::Display> fmt::Display for Mismatch<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Jacobian {}[{}, {}]: analytic {} vs finite difference {}",
            self.jacobian, self.row, self.col, self.analytic, self.numeric
        )
    }
}

/// The central-difference Jacobian of `f` at `x`; `diff(a, b)` forms output
/// differences `a - b` (wrap angles there). Returns `None` if `f` returns
/// `None` at a perturbed point (the point is too close to the edge of the
/// model's valid domain).
pub fn numeric_jacobian<T, F, D, const N: usize, const M: usize>(
    mut f: F,
    diff: D,
    x: &SVector<T, N>,
    step: T,
) -> Option<SMatrix<T, M, N>>
where
    T: Scalar,
    F: FnMut(&SVector<T, N>) -> Option<SVector<T, M>>,
    D: Fn(&SVector<T, M>, &SVector<T, M>) -> SVector<T, M>,
{
    let mut jac = SMatrix::<T, M, N>::zeros();
    for j in 0..N {
        let h = step * T::one().max(x[j].abs());
        let mut xp = *x;
        let mut xm = *x;
        xp[j] += h;
        xm[j] -= h;
        // The actual step after rounding, for accuracy.
        let two_h = xp[j] - xm[j];
        let col = diff(&f(&xp)?, &f(&xm)?) / two_h;
        jac.set_column(j, &col);
    }
    Some(jac)
}

/// Compares an analytic Jacobian with a numerical one entry by entry.
pub fn compare<T: Scalar, const R: usize, const C: usize>(
    name: &'static str,
    analytic: &SMatrix<T, R, C>,
    numeric: &SMatrix<T, R, C>,
    tol: T,
) -> Result<(), Mismatch<T>> {
    for row in 0..R {
        for col in 0..C {
            let a = analytic[(row, col)];
            let n = numeric[(row, col)];
            let scale = T::one().max(a.abs()).max(n.abs());
            // Written as a positive test so that NaN fails it.
            let within = (a - n).abs() <= tol * scale;
            if !within {
                return Err(Mismatch {
                    jacobian: name,
                    row,
                    col,
                    analytic: a,
                    numeric: n,
                });
            }
        }
    }
    Ok(())
}

/// Checks a motion model's `A = df/dX` and `W = df/dq` at `(x, u, q = 0)`,
/// and that its `linearize` agrees with `f`, `A` and `W`.
pub fn check_motion_model<T, Mo, const N: usize, const NQ: usize>(
    model: &Mo,
    x: &SVector<T, N>,
    u: &Mo::Input,
    step: T,
    tol: T,
) -> Result<(), Mismatch<T>>
where
    T: Scalar,
    Mo: MotionModel<T, N, NQ>,
{
    let q0 = SVector::<T, NQ>::zeros();
    let diff = |a: &SVector<T, N>, b: &SVector<T, N>| model.state_residual(a, b);
    let num_a =
        numeric_jacobian(|xx| Some(model.f(xx, u, &q0)), diff, x, step).expect("f is total");
    compare("A", &model.jacobian_state(x, u), &num_a, tol)?;
    let num_w =
        numeric_jacobian(|qq| Some(model.f(x, u, qq)), diff, &q0, step).expect("f is total");
    compare("W", &model.jacobian_noise(x, u), &num_w, tol)?;
    // An overridden `linearize` must agree with the separate methods.
    let (fx, a, w) = model.linearize(x, u);
    let f0 = model.f(x, u, &q0);
    compare(
        "linearize f",
        &SMatrix::<T, N, 1>::from_column_slice(fx.as_slice()),
        &SMatrix::<T, N, 1>::from_column_slice(f0.as_slice()),
        tol,
    )?;
    compare("linearize A", &a, &model.jacobian_state(x, u), tol)?;
    compare("linearize W", &w, &model.jacobian_noise(x, u), tol)
}

/// Checks a measurement model's `H = dh/dX` at `x`, and that its
/// `linearize` agrees with `h` and `H`.
///
/// Returns `Ok(false)` without checking if the model has no measurement at
/// `x` or at one of the perturbed points (so random test points near the edge
/// of the valid domain can be skipped and counted), `Ok(true)` if checked.
pub fn check_measurement_model<T, Me, const N: usize, const M: usize>(
    model: &Me,
    x: &SVector<T, N>,
    step: T,
    tol: T,
) -> Result<bool, Mismatch<T>>
where
    T: Scalar,
    Me: MeasurementModel<T, N, M>,
{
    if model.h(x).is_none() {
        return Ok(false);
    }
    let diff = |a: &SVector<T, M>, b: &SVector<T, M>| model.residual(a, b);
    let Some(num) = numeric_jacobian(|xx| model.h(xx), diff, x, step) else {
        return Ok(false);
    };
    compare("H", &model.jacobian(x), &num, tol)?;
    // An overridden `linearize` must agree with the separate methods.
    let Some((z_hat, h)) = model.linearize(x) else {
        return Err(Mismatch {
            jacobian: "linearize h (None where h is Some)",
            row: 0,
            col: 0,
            analytic: T::zero(),
            numeric: T::zero(),
        });
    };
    let h0 = model.h(x).expect("checked above");
    compare(
        "linearize h",
        &SMatrix::<T, M, 1>::from_column_slice(z_hat.as_slice()),
        &SMatrix::<T, M, 1>::from_column_slice(h0.as_slice()),
        tol,
    )?;
    compare("linearize H", &h, &model.jacobian(x), tol)?;
    Ok(true)
}

/// Checks a motion model's [`MotionModel::propagate`] against the dense
/// `(f(x, u, 0), A P A^T + W Q W^T)` of its `f`, `A`, `W` and `Q`; `tol` is
/// relative to the largest entry of each reference. Also checks that the
/// covariance is exactly symmetric.
pub fn check_propagate<T, Mo, const N: usize, const NQ: usize>(
    model: &Mo,
    x: &SVector<T, N>,
    u: &Mo::Input,
    p: &SMatrix<T, N, N>,
    tol: T,
) -> Result<(), Mismatch<T>>
where
    T: Scalar,
    Mo: MotionModel<T, N, NQ>,
{
    let (xp, pp) = model.propagate(x, u, p);
    let f0 = model.f(x, u, &SVector::<T, NQ>::zeros());
    let a = model.jacobian_state(x, u);
    let w = model.jacobian_noise(x, u);
    let dense = a * p * a.transpose() + w * model.noise_cov(u) * w.transpose();
    compare_scaled("propagate x", &xp, &f0, tol)?;
    compare_scaled("propagate P", &pp, &dense, tol)?;
    compare("propagate P symmetric", &pp, &pp.transpose(), T::zero())
}

/// Checks a measurement model's [`MeasurementModel::project`] against the
/// dense `(P H^T, H P H^T)` of its `H`; `tol` relative to the largest entry
/// of each reference. Skips (returns `Ok(false)`) where `h(x)` is `None`.
pub fn check_project<T, Me, const N: usize, const M: usize>(
    model: &Me,
    x: &SVector<T, N>,
    p: &SMatrix<T, N, N>,
    tol: T,
) -> Result<bool, Mismatch<T>>
where
    T: Scalar,
    Me: MeasurementModel<T, N, M>,
{
    if model.h(x).is_none() {
        return Ok(false);
    }
    let h = model.jacobian(x);
    let (pht, hph) = model.project(x, &h, p);
    compare_scaled("project P H^T", &pht, &(p * h.transpose()), tol)?;
    compare_scaled("project H P H^T", &hph, &(h * p * h.transpose()), tol)?;
    Ok(true)
}

/// Entry-by-entry comparison with the tolerance scaled by the reference's
/// largest entry (so a zero reference needs an exact match); `analytic` in
/// the mismatch is the model's override, `numeric` the dense reference.
fn compare_scaled<T: Scalar, const R: usize, const C: usize>(
    what: &'static str,
    got: &SMatrix<T, R, C>,
    reference: &SMatrix<T, R, C>,
    tol: T,
) -> Result<(), Mismatch<T>> {
    let scale = reference.iter().fold(T::zero(), |m, v| m.max(v.abs()));
    for col in 0..C {
        for row in 0..R {
            let (g, r) = (got[(row, col)], reference[(row, col)]);
            // Written as a positive test so that NaN fails it.
            let within = (g - r).abs() <= tol * scale;
            if !within {
                return Err(Mismatch {
                    jacobian: what,
                    row,
                    col,
                    analytic: g,
                    numeric: r,
                });
            }
        }
    }
    Ok(())
}
