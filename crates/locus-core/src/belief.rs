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

/// [`all_finite`] of two slices (the filter checks a state and its
/// covariance together), exactly, with about half its operations on the
/// usual path: the plain sum of the values is NaN or infinite if any value
/// is (`inf + x = inf`; `inf - inf` and `NaN + x` are NaN), so a finite sum
/// proves every value finite. Finite values can overflow the sum (magnitudes
/// near the largest float); only then, on a branch that is otherwise never
/// taken, is each value checked with [`all_finite`].
///
/// The operations saved matter more than their number suggests: in
/// `predict` this check waits for the last entry of `P-`, and each waiting
/// operation holds a scheduler entry, so fewer of them let the correction's
/// independent work start earlier.
///
/// How the sum is formed depends on the scalar's width. For 8-byte scalars
/// (f64), in four interleaved partial sums (short dependency chains) whose
/// lanes run on across the two slices, so that a belief (`x` then `P`,
/// adjacent in memory) is summed as whole vectors. For 4-byte scalars
/// (f32), in one chain: LLVM packs four f32 lanes into SSE vectors with
/// more shuffles than the packing saves. Each form is the one that executes
/// fewer instructions on the `ekf_step` bench (docs/performance.md).
#[inline(always)]
pub(crate) fn all_finite_pair<T: Scalar>(a: &[T], b: &[T]) -> bool {
    let zero = T::zero();
    let sum = if core::mem::size_of::<T>() == 4 {
        let mut acc = zero;
        for v in a.iter() {
            acc += *v;
        }
        for v in b.iter() {
            acc += *v;
        }
        acc
    } else {
        let mut acc = [zero; 4];
        for (i, v) in a.iter().enumerate() {
            acc[i % 4] += *v;
        }
        let n = a.len();
        for (i, v) in b.iter().enumerate() {
            acc[(n + i) % 4] += *v;
        }
        (acc[0] + acc[1]) + (acc[2] + acc[3])
    };
    finite(sum) || (all_finite(a) && all_finite(b))
}

/// True if `v` is finite, with floating-point operations only (`v * 0` is
/// (+-)0 unless `v` is NaN or infinite). `is_finite` inspects the bits, which
/// moves the value to an integer register and back on the filter's critical
/// path.
#[inline(always)]
pub(crate) fn finite<T: Scalar>(v: T) -> bool {
    v * T::zero() == T::zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same answers for both sums (f32: one chain; f64: four lanes),
    /// `max` the largest finite value and `tiny` a subnormal.
    fn check_all_finite_pair<T: Scalar>(max: T, tiny: T) {
        let c = crate::cast::<T>;
        let big = [max, max, c(1.0)];
        // The sum overflows, every value is finite: the exact path answers.
        assert!(all_finite_pair(&big, &[max]));
        assert!(all_finite_pair(&big, &[max; 9]));
        assert!(all_finite_pair(&[max, max], &[-max, c(1.0)]));
        let inf = c(f64::INFINITY);
        for bad in [c(f64::NAN), inf, -inf] {
            assert!(!all_finite_pair(&[c(1.0), bad, c(2.0)], &[c(3.0); 9]));
            assert!(!all_finite_pair(&[c(1.0); 3], &[c(3.0), c(4.0), bad]));
            assert!(!all_finite_pair(&big, &[bad]));
        }
        // inf - inf in the sum is NaN, not finite.
        assert!(!all_finite_pair(&[inf], &[-inf]));
        // Zeros, a subnormal and large values whose sum stays finite.
        assert!(all_finite_pair(
            &[c(0.0), c(-0.0), tiny],
            &[-max / c(16.0); 9]
        ));
    }

    #[test]
    fn all_finite_pair_is_exact_when_the_sum_overflows() {
        check_all_finite_pair(f64::MAX, 1e-310);
        check_all_finite_pair(f32::MAX, 1e-40);
    }
}
