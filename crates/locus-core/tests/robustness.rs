//! Bad input: every non-finite input gives a typed error, and the caller's
//! belief is unchanged (the filter only borrows it; the next good step works
//! from the same belief as if the bad one never happened).

mod common;

use common::*;
use locus_core::nalgebra::{SMatrix, SVector, Vector2};
use locus_core::{Belief, CovarianceUpdate, Ekf, Error, Input, MeasurementModel};
use locus_models::{DiffDrive, WheelTravel};

const BAD: [f64; 3] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];

fn setup() -> (
    Belief<f64, 3>,
    DiffDrive<f64>,
    WheelTravel<f64>,
    locus_models::IrPairObservation<f64>,
) {
    let mut r = rng(42);
    let b = random_belief(&mut r, 1e3);
    (
        b,
        random_model(&mut r),
        random_travel(&mut r),
        random_ir(&mut r),
    )
}

#[test]
fn non_finite_inputs_to_predict_are_errors_and_leave_the_belief() {
    let (b, model, u, _) = setup();
    let ekf = Ekf::<f64>::default();
    let snapshot = b;
    let good = ekf.predict(&b, &model, &u).unwrap();
    for bad in BAD {
        for i in 0..3 {
            let mut bx = b;
            bx.x[i] = bad;
            assert_eq!(
                ekf.predict(&bx, &model, &u),
                Err(Error::NonFinite(Input::State))
            );
        }
        for i in 0..9 {
            let mut bp = b;
            bp.p[i] = bad;
            assert_eq!(
                ekf.predict(&bp, &model, &u),
                Err(Error::NonFinite(Input::Covariance))
            );
        }
        let bu = WheelTravel { d1: bad, ..u };
        assert_eq!(
            ekf.predict(&b, &model, &bu),
            Err(Error::NonFinite(Input::Control))
        );
        let bu = WheelTravel { d2: bad, ..u };
        assert_eq!(
            ekf.predict(&b, &model, &bu),
            Err(Error::NonFinite(Input::Control))
        );
        let bq = DiffDrive { q11: bad, ..model };
        assert_eq!(
            ekf.predict(&b, &bq, &u),
            Err(Error::NonFinite(Input::ProcessNoise))
        );
        let bq = DiffDrive { q22: bad, ..model };
        assert_eq!(
            ekf.predict(&b, &bq, &u),
            Err(Error::NonFinite(Input::ProcessNoise))
        );
        let bw = DiffDrive {
            wheelbase: bad,
            ..model
        };
        assert!(matches!(ekf.predict(&b, &bw, &u), Err(Error::NonFinite(_))));
    }
    // The belief the caller holds is the one it had, and the next step from it
    // is exactly the step that would have happened without the bad inputs.
    assert_eq!(b, snapshot);
    assert_eq!(ekf.predict(&b, &model, &u).unwrap(), good);
}

#[test]
fn non_finite_inputs_to_correct_are_errors_and_leave_the_belief() {
    let (b, _, _, obs) = setup();
    let z = obs.z();
    for update in [
        CovarianceUpdate::Joseph,
        CovarianceUpdate::Plain,
        CovarianceUpdate::ForcedSymmetric,
    ] {
        let ekf = Ekf::new(update);
        let good = ekf.correct(&b, &obs, &z).unwrap();
        let good_seq = ekf.correct_sequential(&b, &obs, &z).unwrap();
        for bad in BAD {
            for i in 0..2 {
                let mut bz = z;
                bz[i] = bad;
                assert_eq!(
                    ekf.correct(&b, &obs, &bz),
                    Err(Error::NonFinite(Input::Measurement))
                );
                assert_eq!(
                    ekf.correct_sequential(&b, &obs, &bz),
                    Err(Error::NonFinite(Input::Measurement))
                );
            }
            for i in 0..3 {
                let mut bx = b;
                bx.x[i] = bad;
                assert_eq!(
                    ekf.correct(&bx, &obs, &z),
                    Err(Error::NonFinite(Input::State))
                );
            }
            for i in 0..9 {
                let mut bp = b;
                bp.p[i] = bad;
                assert_eq!(
                    ekf.correct(&bp, &obs, &z),
                    Err(Error::NonFinite(Input::Covariance))
                );
                assert_eq!(
                    ekf.correct_sequential(&bp, &obs, &z),
                    Err(Error::NonFinite(Input::Covariance))
                );
            }
            let br = locus_models::IrPairObservation { r11: bad, ..obs };
            assert_eq!(
                ekf.correct(&b, &br, &z),
                Err(Error::NonFinite(Input::MeasurementNoise))
            );
            // A NaN reading makes V (hence V R V^T) non-finite.
            let bd = locus_models::IrPairObservation { ds1: bad, ..obs };
            assert!(matches!(ekf.correct(&b, &bd, &z), Err(Error::NonFinite(_))));
        }
        assert_eq!(ekf.correct(&b, &obs, &z).unwrap(), good);
        assert_eq!(ekf.correct_sequential(&b, &obs, &z).unwrap(), good_seq);
    }
}

/// A measurement whose innovation covariance can be made singular or indefinite.
struct Raw {
    h: SMatrix<f64, 2, 3>,
    r: SMatrix<f64, 2, 2>,
    valid: bool,
}

impl MeasurementModel<f64, 3, 2> for Raw {
    fn evaluate(
        &self,
        x: &SVector<f64, 3>,
        jacobian: Option<&mut SMatrix<f64, 2, 3>>,
    ) -> Option<SVector<f64, 2>> {
        if let Some(j) = jacobian {
            *j = self.h;
        }
        self.valid.then(|| self.h * x)
    }
    fn noise(&self, _x: &SVector<f64, 3>) -> SMatrix<f64, 2, 2> {
        self.r
    }
}

#[test]
fn singular_or_indefinite_innovation_covariance_is_an_error() {
    let b = Belief::new(
        SVector::<f64, 3>::new(0.1, 0.2, 0.3),
        SMatrix::<f64, 3, 3>::zeros(),
    );
    let ekf = Ekf::<f64>::default();
    let z = Vector2::new(0.0, 0.0);
    // P = 0 and R = 0: S = 0.
    let singular = Raw {
        h: SMatrix::identity(),
        r: SMatrix::zeros(),
        valid: true,
    };
    assert_eq!(
        ekf.correct(&b, &singular, &z),
        Err(Error::InnovationNotPositiveDefinite)
    );
    assert_eq!(
        ekf.correct_sequential(&b, &singular, &z),
        Err(Error::InnovationNotPositiveDefinite)
    );
    assert_eq!(
        locus_core::schedule::correct_11_step(&b, &singular, &z),
        Err(Error::InnovationNotPositiveDefinite)
    );
    // Indefinite noise.
    let indefinite = Raw {
        h: SMatrix::identity(),
        r: SMatrix::<f64, 2, 2>::new(1.0, 2.0, 2.0, 1.0),
        valid: true,
    };
    assert_eq!(
        ekf.correct(&b, &indefinite, &z),
        Err(Error::InnovationNotPositiveDefinite)
    );
    assert_eq!(
        ekf.correct_sequential(&b, &indefinite, &z),
        Err(Error::NoiseNotPositiveDefinite)
    );
    // The model says there is no measurement here.
    let none = Raw {
        h: SMatrix::identity(),
        r: SMatrix::identity(),
        valid: false,
    };
    assert_eq!(ekf.correct(&b, &none, &z), Err(Error::NoMeasurement));
    assert_eq!(
        ekf.correct_sequential(&b, &none, &z),
        Err(Error::NoMeasurement)
    );
}

#[test]
fn errors_display_what_went_wrong() {
    assert_eq!(
        Error::NonFinite(Input::Measurement).to_string(),
        "non-finite value (NaN or infinity) in the measurement z"
    );
    assert_eq!(
        Error::InnovationNotPositiveDefinite.to_string(),
        "innovation covariance S is not positive definite"
    );
}

/// A numerically singular S (two measurements of the same coordinate whose
/// noises have correlation 1 - eps/2, the largest f64 below 1: det S is
/// about eps/2 relative to its diagonal) is reported as not positive
/// definite, and no posterior is produced from its rounding noise; a well
/// conditioned S (correlation 0.9) is applied and finite.
#[test]
fn numerically_singular_innovation_covariance_is_an_error() {
    let b = Belief::new(
        SVector::<f64, 3>::new(0.1, 0.2, 0.3),
        SMatrix::<f64, 3, 3>::identity() * 1e-4,
    );
    let ekf = Ekf::<f64>::new(CovarianceUpdate::Plain);
    let z = Vector2::new(0.1, 0.1);
    let same_coordinate = |rho: f64| Raw {
        h: SMatrix::<f64, 2, 3>::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.0),
        r: SMatrix::<f64, 2, 2>::new(1e-4, rho * 1e-4, rho * 1e-4, 1e-4),
        valid: true,
    };
    assert_eq!(
        ekf.correct(&b, &same_coordinate(1.0 - f64::EPSILON / 2.0), &z),
        Err(Error::InnovationNotPositiveDefinite)
    );
    // Correlation 0.9: S is well conditioned, the update is applied.
    let c = ekf.correct(&b, &same_coordinate(0.9), &z).unwrap();
    assert!(c.applied);
    assert!(
        c.belief
            .x
            .iter()
            .chain(c.belief.p.iter())
            .all(|v| v.is_finite())
    );
}
