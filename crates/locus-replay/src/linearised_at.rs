//! A scalar measurement linearised at a chosen state: the iterated EKF's
//! step (Bell and Cathey, "The iterated Kalman filter update as a
//! Gauss-Newton method", IEEE TAC 38(2), 1993).
//!
//! The EKF linearises `h` at the prior mean. Where the prior is far from
//! the state the measurements say (a scan whose alignment to the map moved
//! the pose), the iterated EKF linearises at that better state `a`
//! instead: `h(x) ~ h(a) + H(a) (x - a)`. Applied from the prior, one beam
//! after the other, the update is a Gauss-Newton step of the posterior
//! taken at `a`, not at the prior.

use locus_core::MeasurementModel;
use locus_core::nalgebra::{SMatrix, SVector};

use crate::filter::{STATE, StateVector};

/// `h(x) = h0 + H (x - at)`, the heading difference wrapped, with noise
/// variance `var`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearisedAt {
    /// `h(at)`.
    pub h0: f64,
    /// `H = dh/dx` at `at`.
    pub h: SMatrix<f64, 1, STATE>,
    /// The state of the linearisation.
    pub at: StateVector,
    /// The measurement's noise variance.
    pub var: f64,
}

impl MeasurementModel<f64, STATE, 1> for LinearisedAt {
    fn evaluate(
        &self,
        x: &StateVector,
        jacobian: Option<&mut SMatrix<f64, 1, STATE>>,
    ) -> Option<SVector<f64, 1>> {
        if let Some(j) = jacobian {
            *j = self.h;
        }
        let mut d = x - self.at;
        d[2] = locus_core::wrap_angle(d[2]);
        Some(SVector::<f64, 1>::new(self.h0 + (self.h * d)[(0, 0)]))
    }

    fn noise(&self, _x: &StateVector) -> SMatrix<f64, 1, 1> {
        SMatrix::<f64, 1, 1>::new(self.var)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_the_tangent_at_its_state_with_the_heading_wrapped() {
        let mut at = StateVector::zeros();
        at[2] = 3.1;
        let h = SMatrix::<f64, 1, STATE>::from_fn(|_, j| f64::from(u8::try_from(j).unwrap()) + 1.0);
        let m = LinearisedAt {
            h0: 2.0,
            h,
            at,
            var: 0.01,
        };
        let mut j = SMatrix::<f64, 1, STATE>::zeros();
        assert_eq!(m.evaluate(&at, Some(&mut j)).unwrap()[0], 2.0);
        assert_eq!(j, h);
        // 0.1 m in x and a heading across +-pi, 0.1 rad on: 2 + 0.1 + 3 * 0.1.
        let mut x = at;
        x[0] = 0.1;
        x[2] = 3.2 - 2.0 * core::f64::consts::PI;
        let z = m.evaluate(&x, None).unwrap()[0];
        assert!((z - 2.4).abs() < 1e-12, "{z}");
        assert_eq!(m.noise(&x)[(0, 0)], 0.01);
    }
}
