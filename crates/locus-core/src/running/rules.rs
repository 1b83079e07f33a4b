//! How the running filter corrects: the stateless [`Ekf`] (covariance
//! update form and optional gate) and the recovery from over-confidence
//! ([`Recovery`]: after consecutive gate rejections, the covariance of the
//! free states inflated and the measurement tried once more).

use nalgebra::SMatrix;

use crate::{Ekf, Error, Scalar};

/// Recovery from over-confidence: after `after` consecutive gate rejections
/// the covariance is inflated by `inflation` and the rejected measurement
/// is tried once more.
///
/// The inflation respects what the model holds fixed: the variances of the
/// states in `held` (a constant the prior says is known, e.g. a bias held
/// at 0 +- 1e-6) stay as they are. With `D = diag(d)`, `d_i = sqrt(k)` for
/// a free state and 1 for a held one, the covariance becomes `D P D`: free
/// variances and their covariances grow by `k`, a covariance between a free
/// and a held state by `sqrt(k)`, every correlation is kept, and `P` stays
/// positive definite. Inflating the whole `P` would make a held state free
/// after a few recoveries (`k^n` compounds: 15 inflations by 4 turn a
/// standard deviation of 1e-6 into 0.03), and a "known" bias could then
/// absorb any error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Recovery<T> {
    /// Consecutive rejections that trigger an inflation (>= 1).
    pub after: u32,
    /// Factor the free variances are multiplied by (finite, > 1).
    pub inflation: T,
    /// The states the inflation leaves alone: bit `i` set holds state `i`
    /// (states 64 and above cannot be held).
    pub held: u64,
}

impl<T: Scalar> Recovery<T> {
    /// A recovery policy.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] unless `after >= 1` and `inflation` is
    /// finite and > 1.
    pub fn new(after: u32, inflation: T) -> Result<Self, Error> {
        if after == 0 {
            return Err(Error::InvalidParameter("recovery: `after` must be >= 1"));
        }
        if !(inflation > T::one() && inflation.is_finite()) {
            return Err(Error::InvalidParameter(
                "recovery: inflation must be finite and > 1",
            ));
        }
        Ok(Self {
            after,
            inflation,
            held: 0,
        })
    }

    /// The same policy, leaving the states `indices` as they are (see
    /// [`Recovery`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if an index is 64 or more.
    pub fn holding(mut self, indices: &[usize]) -> Result<Self, Error> {
        for &i in indices {
            if i >= 64 {
                return Err(Error::InvalidParameter(
                    "recovery: only states 0 to 63 can be held",
                ));
            }
            self.held |= 1 << i;
        }
        Ok(self)
    }

    /// Inflates `p` in place: `D P D` (see [`Recovery`]); exactly `k P` when
    /// nothing is held.
    pub fn inflate<const N: usize>(&self, p: &mut SMatrix<T, N, N>) {
        let k = self.inflation;
        if self.held == 0 {
            *p *= k;
            return;
        }
        let root = k.sqrt();
        let free = |i: usize| i >= 64 || self.held & (1 << i) == 0;
        for j in 0..N {
            for i in 0..N {
                let factor = match (free(i), free(j)) {
                    (true, true) => k,
                    (false, false) => continue,
                    _ => root,
                };
                p[(i, j)] *= factor;
            }
        }
    }
}

/// How the running filter corrects: the stateless [`Ekf`] (covariance
/// update form and optional gate) and an optional [`Recovery`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rules<T: Scalar> {
    /// Update form and gate.
    pub ekf: Ekf<T>,
    /// Recovery after consecutive gate rejections (`None`: a rejected
    /// measurement is only counted).
    pub recovery: Option<Recovery<T>>,
}

impl<T: Scalar> Rules<T> {
    /// Rules with `ekf` and no recovery.
    pub fn new(ekf: Ekf<T>) -> Self {
        Self {
            ekf,
            recovery: None,
        }
    }

    /// The same rules with a recovery policy.
    #[must_use]
    pub fn with_recovery(mut self, recovery: Recovery<T>) -> Self {
        self.recovery = Some(recovery);
        self
    }
}
