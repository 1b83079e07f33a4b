//! Heavy-tailed measurement noise: Student-t weighting of a correction.
//!
//! A chi-square gate is all or nothing: a gross outlier that passes it moves
//! the estimate with full weight, and a filter that has become
//! over-confident rejects good measurements until something inflates it. A
//! Student-t noise model instead gives every measurement a weight that
//! falls smoothly with its normalised innovation squared `d^2` (NIS):
//!
//! `w = min(1, (nu + m) / (nu + d^2))`,
//!
//! and applies it with its noise covariance divided by `w` (`R / w`). This
//! is one iteration of the variational update for Student-t measurement
//! noise of Agamennoni, Nieto and Nebot, "Approximate inference in
//! state-space models with heavy-tailed noise", IEEE Trans. Signal
//! Processing 60(10), 2012 (also Piche, Sarkka and Hartikainen, "Recursive
//! outlier-robust filtering and smoothing for nonlinear systems using the
//! multivariate Student-t distribution", MLSP 2012), started from the
//! prior: `m` is the number of measured components and `nu` the degrees of
//! freedom (small: heavy tails; infinite: Gaussian). The weight is capped at
//! 1 so that a measurement that agrees well is applied as the Gaussian
//! filter would, never with more than its nominal weight.

use nalgebra::{SMatrix, SVector};

use crate::{Error, MeasurementModel, Scalar, cast};

/// Student-t weighting of corrections with `dof` degrees of freedom.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudentT<T> {
    dof: T,
}

impl<T: Scalar> StudentT<T> {
    /// Weighting with `dof` degrees of freedom (finite and > 0).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] otherwise.
    pub fn new(dof: T) -> Result<Self, Error> {
        if dof.is_finite() && dof > T::zero() {
            Ok(Self { dof })
        } else {
            Err(Error::InvalidParameter(
                "Student-t degrees of freedom must be finite and > 0",
            ))
        }
    }

    /// The degrees of freedom.
    pub fn dof(&self) -> T {
        self.dof
    }

    /// The weight of a measurement of `m` components with NIS `nis`, in
    /// (0, 1]: `min(1, (dof + m) / (dof + nis))`.
    pub fn weight(&self, nis: T, m: u32) -> T {
        let m = cast::<T>(f64::from(m));
        let w = (self.dof + m) / (self.dof + nis);
        if w < T::one() { w } else { T::one() }
    }
}

/// A measurement model whose noise covariance is multiplied by `factor`
/// (everything else delegated): how a weight `w` is applied, with
/// `factor = 1 / w`.
#[derive(Debug, Clone, Copy)]
pub struct ScaledNoise<'a, Me, T> {
    /// The model.
    pub inner: &'a Me,
    /// The factor on its noise covariance (> 0).
    pub factor: T,
}

impl<T: Scalar, const N: usize, const M: usize, Me> MeasurementModel<T, N, M>
    for ScaledNoise<'_, Me, T>
where
    Me: MeasurementModel<T, N, M>,
{
    fn evaluate(
        &self,
        x: &SVector<T, N>,
        jacobian: Option<&mut SMatrix<T, M, N>>,
    ) -> Option<SVector<T, M>> {
        self.inner.evaluate(x, jacobian)
    }

    fn noise(&self, x: &SVector<T, N>) -> SMatrix<T, M, M> {
        self.inner.noise(x) * self.factor
    }

    fn residual(&self, z: &SVector<T, M>, z_hat: &SVector<T, M>) -> SVector<T, M> {
        self.inner.residual(z, z_hat)
    }

    fn linearize(&self, x: &SVector<T, N>) -> Option<(SVector<T, M>, SMatrix<T, M, N>)> {
        self.inner.linearize(x)
    }

    fn project(
        &self,
        x: &SVector<T, N>,
        h: &SMatrix<T, M, N>,
        p: &SMatrix<T, N, N>,
    ) -> (SMatrix<T, N, M>, SMatrix<T, M, M>) {
        self.inner.project(x, h, p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weight_is_one_for_agreeing_measurements_and_falls_with_the_nis() {
        let t = StudentT::new(4.0_f64).unwrap();
        assert_eq!(t.weight(0.0, 2), 1.0);
        assert_eq!(t.weight(2.0, 2), 1.0);
        assert!((t.weight(8.0, 2) - 0.5).abs() < 1e-15);
        assert!(t.weight(1e6, 2) < 1e-5);
        assert!(t.weight(1e6, 2) > 0.0);
    }

    #[test]
    fn rejects_bad_degrees_of_freedom() {
        assert!(StudentT::new(0.0_f64).is_err());
        assert!(StudentT::new(-1.0_f64).is_err());
        assert!(StudentT::new(f64::NAN).is_err());
        assert!(StudentT::new(f64::INFINITY).is_err());
    }
}

#[cfg(test)]
mod track_tests {
    use nalgebra::{Matrix1, Matrix1x2, Matrix2, Vector1, Vector2};

    use crate::{Belief, Ekf, MeasurementModel, Rules, StudentT, Track, Update};

    /// The first of two states seen directly, variance `r`.
    struct First {
        r: f64,
    }

    impl MeasurementModel<f64, 2, 1> for First {
        fn evaluate(
            &self,
            x: &Vector2<f64>,
            jacobian: Option<&mut Matrix1x2<f64>>,
        ) -> Option<Vector1<f64>> {
            if let Some(j) = jacobian {
                *j = Matrix1x2::new(1.0, 0.0);
            }
            Some(Vector1::new(x[0]))
        }
        fn noise(&self, _x: &Vector2<f64>) -> Matrix1<f64> {
            Matrix1::new(self.r)
        }
    }

    fn track() -> Track<f64, 2> {
        Track::new(
            Belief::new(Vector2::new(0.0, 1.0), Matrix2::new(1.0, 0.5, 0.5, 2.0)),
            0.0,
            (),
        )
    }

    #[test]
    fn an_agreeing_measurement_is_applied_as_the_gaussian_filter_would() {
        let rules = Rules::new(Ekf::default());
        let t = StudentT::new(4.0).unwrap();
        let z = Vector1::new(0.5);
        let (mut a, mut b) = (track(), track());
        let ua = a.correct(&rules, &First { r: 1.0 }, &z).unwrap();
        let ub = b.correct_robust(&rules, &t, &First { r: 1.0 }, &z).unwrap();
        assert_eq!(a, b);
        assert!(matches!(ub, Update::Applied { weight, .. } if weight == 1.0));
        assert!(matches!(ua, Update::Applied { weight, .. } if weight == 1.0));
    }

    #[test]
    fn an_outlier_is_down_weighted_and_moves_the_belief_less() {
        let rules = Rules::new(Ekf::default());
        let t = StudentT::new(4.0).unwrap();
        let z = Vector1::new(20.0); // NIS = 400 / 2 = 200
        let (mut a, mut b) = (track(), track());
        a.correct(&rules, &First { r: 1.0 }, &z).unwrap();
        let u = b.correct_robust(&rules, &t, &First { r: 1.0 }, &z).unwrap();
        let Update::Applied {
            correction, weight, ..
        } = u
        else {
            panic!("applied without a gate");
        };
        // w = (4 + 1) / (4 + 200); the NIS reported is the nominal one.
        assert!((weight - 5.0 / 204.0).abs() < 1e-12);
        assert!((correction.nis - 200.0).abs() < 1e-9);
        assert!(b.belief.x[0] < 0.1 * a.belief.x[0]);
        assert!(b.belief.p[(0, 0)] > a.belief.p[(0, 0)]);
        // Equal to a Gaussian correction with the noise divided by w.
        let mut c = track();
        c.correct(&rules, &First { r: 1.0 / weight }, &z).unwrap();
        assert!((c.belief.x - b.belief.x).norm() < 1e-12);
    }
}
