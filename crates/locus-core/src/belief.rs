//! The belief: a Gaussian over the state, `N(x, P)`.
//!
//! The filter keeps no hidden state: a [`Belief`] goes into `predict`/`correct`
//! and a new one comes out. Running many filters side by side, checkpointing or
//! re-running from a history is copying a value.

use nalgebra::{SMatrix, SVector};

use crate::{Error, Input, Scalar};

/// A Gaussian belief over an `N`-dimensional state: mean `x` and covariance `P`
/// (units: those of the state components, and their products).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Belief<T: Scalar, const N: usize> {
    /// State mean `x`.
    pub x: SVector<T, N>,
    /// State covariance `P` (symmetric, positive semi-definite).
    pub p: SMatrix<T, N, N>,
}

impl<T: Scalar, const N: usize> Belief<T, N> {
    /// A belief from a mean and a covariance (not checked: see [`Belief::validate`]).
    pub fn new(x: SVector<T, N>, p: SMatrix<T, N, N>) -> Self {
        Self { x, p }
    }

    /// A belief with a diagonal covariance given by its standard deviations.
    pub fn from_std(x: SVector<T, N>, std: SVector<T, N>) -> Self {
        Self {
            x,
            p: SMatrix::from_diagonal(&std.component_mul(&std)),
        }
    }

    /// Checks that every entry of `x` and `P` is finite.
    pub fn validate(&self) -> Result<(), Error> {
        if !all_finite(self.x.as_slice()) {
            return Err(Error::NonFinite(Input::State));
        }
        if !all_finite(self.p.as_slice()) {
            return Err(Error::NonFinite(Input::Covariance));
        }
        Ok(())
    }

    /// Standard deviations (square roots of the diagonal of `P`; negative
    /// diagonal entries, which a valid belief never has, give NaN).
    pub fn std(&self) -> SVector<T, N> {
        self.p.diagonal().map(|v| v.sqrt())
    }
}

/// True if every value is finite (no NaN, no infinity).
///
/// Branch-free, with one comparison: `v * 0` is (+-)0 for a finite `v` and
/// NaN for NaN or an infinity, so the sum of the `v * 0` is zero exactly when
/// every value is finite (a sum of zeros cannot overflow). Four interleaved
/// partial sums keep the dependency chains short.
#[inline(always)]
pub(crate) fn all_finite<T: Scalar>(values: &[T]) -> bool {
    let zero = T::zero();
    let mut acc = [zero; 4];
    for (i, v) in values.iter().enumerate() {
        acc[i % 4] += *v * zero;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) == zero
}

/// [`all_finite`] of two slices with one comparison and no branch between
/// them (the filter checks a state and its covariance together).
#[inline(always)]
pub(crate) fn all_finite_pair<T: Scalar>(a: &[T], b: &[T]) -> bool {
    nonfinite_marker(a) + nonfinite_marker(b) == T::zero()
}

/// Zero if every value is finite, NaN otherwise (see [`all_finite`]).
#[inline(always)]
fn nonfinite_marker<T: Scalar>(values: &[T]) -> T {
    let zero = T::zero();
    let mut acc = [zero; 4];
    for (i, v) in values.iter().enumerate() {
        acc[i % 4] += *v * zero;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// True if `v` is finite, with floating-point operations only (`v * 0` is
/// (+-)0 unless `v` is NaN or infinite). `is_finite` inspects the bits, which
/// moves the value to an integer register and back on the filter's critical
/// path.
#[inline(always)]
pub(crate) fn finite<T: Scalar>(v: T) -> bool {
    v * T::zero() == T::zero()
}
