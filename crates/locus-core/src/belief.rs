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
/// Branch-free and without a serial dependency chain: `v * 0` is (+-)0 for a
/// finite `v` and NaN for NaN or an infinity, and the comparisons are
/// combined with a non-short-circuiting `&`.
#[inline(always)]
pub(crate) fn all_finite<T: Scalar>(values: &[T]) -> bool {
    let zero = T::zero();
    values.iter().fold(true, |ok, v| ok & (*v * zero == zero))
}
