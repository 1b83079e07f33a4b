//! Chi-square gating of measurements on the normalised innovation squared.
//!
//! For a correction with innovation `y = z - h(X-)` (m components) and
//! innovation covariance `S = H P- H^T + V R V^T` (spec
//! `shared/spec/MODELS.md` section 1), the normalised innovation squared
//! `NIS = y^T S^-1 y` is dimensionless and, when the filter is consistent and
//! the measurement is not an outlier, chi-square distributed with `m` degrees
//! of freedom. A gate at confidence `c` accepts the measurement when the NIS is
//! at most the chi-square quantile `chi2_m(c)`, so a consistent measurement is
//! rejected with probability `1 - c`.

use crate::{Error, Scalar, cast, chi2};

/// Number of degrees of freedom (1..=16) whose thresholds are precomputed.
const TABLE_LEN: usize = 16;

/// A chi-square gate on the normalised innovation squared (NIS) at a fixed
/// confidence level.
///
/// The thresholds for 1 to 16 degrees of freedom (measurement dimensions) are
/// computed once by [`ChiSquareGate::new`] and stored in a fixed array in the
/// filter's scalar type `T` (`f32` or `f64`); larger dimensions are computed
/// on demand. No allocation.
///
/// ```
/// # use locus_core::ChiSquareGate;
/// let gate = ChiSquareGate::<f64>::new(0.95).unwrap();
/// assert!((gate.threshold(2) - 5.991464547107979).abs() < 1e-12);
/// assert!(gate.accepts(3.0, 2));
/// assert!(!gate.accepts(7.5, 2));
/// ```
///
/// A gate can also be built from one precomputed threshold
/// ([`ChiSquareGate::from_threshold`]), for a target that should not carry
/// the quantile's special functions (the firmware computes its threshold on
/// the host).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChiSquareGate<T> {
    /// The confidence the table was computed at; `None` for a gate built
    /// from one precomputed threshold.
    confidence: Option<f64>,
    /// Threshold for `dof = 1..=16`; NaN where unknown (a gate built from
    /// one threshold knows only its own degrees of freedom).
    thresholds: [T; TABLE_LEN],
}

impl<T: Scalar> ChiSquareGate<T> {
    /// Creates a gate accepting a consistent measurement with probability
    /// `confidence` (e.g. `0.95`, `0.99`), precomputing the thresholds
    /// `chi2_m(confidence)` for `m = 1..=16`.
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] unless `confidence` is finite and strictly
    /// inside `(0, 1)`.
    pub fn new(confidence: f64) -> Result<Self, Error> {
        if !(confidence > 0.0 && confidence < 1.0) {
            return Err(Error::InvalidParameter(
                "gate confidence must be finite and strictly inside (0, 1)",
            ));
        }
        let mut thresholds = [T::zero(); TABLE_LEN];
        for (dof, t) in (1u32..).zip(thresholds.iter_mut()) {
            *t = cast(chi2::quantile(confidence, dof)?);
        }
        Ok(Self {
            confidence: Some(confidence),
            thresholds,
        })
    }

    /// A gate for measurements of `dof` components (1 to 16) with a
    /// precomputed NIS threshold, e.g. `chi2::quantile(c, dof)` computed
    /// on a host and rounded to `T`. It accepts exactly what a gate from
    /// [`ChiSquareGate::new`] whose table holds that threshold accepts; a
    /// measurement of any other number of components is rejected (the gate
    /// has no threshold for it).
    ///
    /// ```
    /// # use locus_core::ChiSquareGate;
    /// let table = ChiSquareGate::<f32>::new(0.99).unwrap();
    /// let fixed = ChiSquareGate::<f32>::from_threshold(2, table.threshold(2)).unwrap();
    /// assert_eq!(fixed.accepts(9.0, 2), table.accepts(9.0, 2));
    /// assert!(!fixed.accepts(0.1, 1));
    /// ```
    ///
    /// # Errors
    ///
    /// [`Error::InvalidParameter`] unless `dof` is in `1..=16` and
    /// `threshold` is positive (`+infinity` allowed: accept everything).
    pub fn from_threshold(dof: usize, threshold: T) -> Result<Self, Error> {
        if !(1..=TABLE_LEN).contains(&dof) {
            return Err(Error::InvalidParameter(
                "gate degrees of freedom must be in 1..=16",
            ));
        }
        if threshold.partial_cmp(&T::zero()) != Some(core::cmp::Ordering::Greater) {
            return Err(Error::InvalidParameter("gate threshold must be > 0"));
        }
        let mut thresholds = [cast::<T>(f64::NAN); TABLE_LEN];
        thresholds[dof - 1] = threshold;
        Ok(Self {
            confidence: None,
            thresholds,
        })
    }

    /// The confidence level the gate was built with, in `(0, 1)`; `None`
    /// for a gate built from a precomputed threshold.
    #[must_use]
    pub fn confidence(&self) -> Option<f64> {
        self.confidence
    }

    /// The NIS threshold `chi2_dof(confidence)` (dimensionless) for a
    /// measurement with `dof` components.
    ///
    /// `dof` in `1..=16` is read from the precomputed table; larger values are
    /// computed on the fly (no allocation; a few microseconds for moderate
    /// `dof`). `dof = 0` (nothing measured, so nothing to gate) returns
    /// `+infinity`, i.e. any non-NaN NIS is accepted. A gate built from one
    /// threshold returns NaN (nothing passes) for any other `dof >= 1`.
    #[must_use]
    pub fn threshold(&self, dof: usize) -> T {
        match dof {
            0 => cast(f64::INFINITY),
            1..=TABLE_LEN => self.thresholds[dof - 1],
            _ => match self.confidence {
                Some(confidence) => {
                    let dof = u32::try_from(dof).unwrap_or(u32::MAX);
                    // Cannot fail: confidence was validated in `new` and dof >= 17.
                    cast(chi2::quantile(confidence, dof).unwrap_or(f64::INFINITY))
                }
                None => cast(f64::NAN),
            },
        }
    }

    /// Whether a measurement with normalised innovation squared `nis`
    /// (dimensionless, `y^T S^-1 y`) and `dof` components passes the gate:
    /// `nis <= threshold(dof)`.
    ///
    /// A NaN `nis` is never accepted; `+infinity` is rejected for every
    /// `dof >= 1`.
    #[must_use]
    pub fn accepts(&self, nis: T, dof: usize) -> bool {
        // `<=` is false for NaN.
        nis <= self.threshold(dof)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thresholds_match_quantiles() {
        let g64 = ChiSquareGate::<f64>::new(0.99).unwrap();
        let g32 = ChiSquareGate::<f32>::new(0.99).unwrap();
        assert_eq!(g64.confidence(), Some(0.99));
        assert_eq!(g32.confidence(), Some(0.99));
        for dof in 1..=40usize {
            let q = chi2::quantile(0.99, dof as u32).unwrap();
            assert_eq!(g64.threshold(dof), q, "f64 threshold, dof {dof}");
            assert_eq!(g32.threshold(dof), q as f32, "f32 threshold, dof {dof}");
        }
        assert!((g64.threshold(2) - 9.210_340_371_976_184).abs() < 1e-12);
        let g95 = ChiSquareGate::<f64>::new(0.95).unwrap();
        assert!((g95.threshold(1) - 3.841_458_820_694_124).abs() < 1e-12);
        assert!((g95.threshold(2) - 5.991_464_547_107_979).abs() < 1e-12);
        assert!(g95.threshold(16) < g95.threshold(17));
        assert!(g95.threshold(0).is_infinite() && g95.threshold(0) > 0.0);
        assert!(g32.threshold(0).is_infinite());
    }

    #[test]
    fn accepts_and_rejects() {
        let g = ChiSquareGate::<f64>::new(0.95).unwrap();
        let t = g.threshold(3);
        assert!(g.accepts(0.0, 3));
        assert!(g.accepts(t, 3));
        assert!(!g.accepts(t * (1.0 + 1e-12), 3));
        assert!(!g.accepts(f64::NAN, 3));
        assert!(!g.accepts(f64::NAN, 0));
        assert!(!g.accepts(f64::INFINITY, 3));
        assert!(g.accepts(1e300, 0));
        assert!(g.accepts(20.0, 20) && !g.accepts(40.0, 20));

        let g = ChiSquareGate::<f32>::new(0.95).unwrap();
        assert!(g.accepts(5.9f32, 2));
        assert!(!g.accepts(6.0f32, 2));
        assert!(!g.accepts(f32::NAN, 2));
    }

    #[test]
    fn invalid_confidence() {
        for c in [0.0, 1.0, -0.1, 1.1, f64::NAN, f64::INFINITY] {
            assert!(
                matches!(
                    ChiSquareGate::<f64>::new(c),
                    Err(Error::InvalidParameter(_))
                ),
                "confidence {c} must be rejected"
            );
            assert!(ChiSquareGate::<f32>::new(c).is_err());
        }
    }

    #[test]
    fn from_threshold_matches_the_table_for_its_dof_only() {
        let table = ChiSquareGate::<f32>::new(0.99).unwrap();
        let fixed = ChiSquareGate::<f32>::from_threshold(2, table.threshold(2)).unwrap();
        assert_eq!(fixed.confidence(), None);
        let t = table.threshold(2);
        for nis in [
            0.0,
            t * 0.5,
            t,
            f32::from_bits(t.to_bits() + 1),
            1e30,
            f32::NAN,
        ] {
            assert_eq!(fixed.accepts(nis, 2), table.accepts(nis, 2), "nis {nis}");
        }
        for dof in [1, 3, 16, 17, 40] {
            assert!(!fixed.accepts(0.0, dof), "dof {dof} has no threshold");
        }
        assert!(fixed.accepts(1e30, 0));
        for (dof, t) in [(0, 1.0), (17, 1.0), (2, 0.0), (2, -1.0), (2, f32::NAN)] {
            assert!(ChiSquareGate::<f32>::from_threshold(dof, t).is_err());
        }
        assert!(ChiSquareGate::<f32>::from_threshold(2, f32::INFINITY).is_ok());
    }

    #[test]
    fn copy_and_eq() {
        let a = ChiSquareGate::<f32>::new(0.9).unwrap();
        let b = a;
        assert_eq!(a, b);
        assert_ne!(a, ChiSquareGate::<f32>::new(0.95).unwrap());
    }
}
