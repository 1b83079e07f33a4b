//! Finite-difference checks of every analytic Jacobian of the paper-001
//! models, at >= 1000 random valid points each (proptest), through the core's
//! checker (`locus_core::jacobian_check`: central differences, relative step
//! 1e-5, mixed relative/absolute tolerance 1e-6).
//!
//! Valid domains: the differential drive is valid everywhere (tested over
//! headings in (-pi, pi], wheel travels up to +-0.5 m per step, wheelbase
//! 0.05-0.5 m); the IR pair needs readings in its range (0.04-0.30 m), sensor
//! spacing 0.05-0.20 m and mounting offsets within +-0.1 m.

use locus_core::jacobian_check::{
    DEFAULT_STEP, DEFAULT_TOLERANCE, check_measurement_model, check_motion_model, check_project,
    check_propagate, compare, numeric_jacobian,
};
use locus_core::nalgebra::{Matrix3, SVector, Vector2, Vector3};
use locus_core::wrap_angle;
use locus_models::ir_wall::observe;
use locus_models::{AxisWall, DiffDrive, IrPair, IrPairObservation, WheelTravel};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 2000,
        ..ProptestConfig::default()
    }
}

fn wall(i: u8, lw: f64) -> AxisWall<f64> {
    match i % 4 {
        0 => AxisWall::x_plus(lw),
        1 => AxisWall::x_minus(lw),
        2 => AxisWall::y_plus(lw),
        _ => AxisWall::y_minus(lw),
    }
}

/// A random symmetric positive-definite covariance `L L^T` (entries of `L`
/// in +-`scale`, diagonal kept away from zero).
fn spd(l: [f64; 6], scale: f64) -> Matrix3<f64> {
    let l = Matrix3::new(
        scale * (1.0 + l[0].abs()),
        0.0,
        0.0,
        scale * l[1],
        scale * (1.0 + l[2].abs()),
        0.0,
        scale * l[3],
        scale * l[4],
        scale * (1.0 + l[5].abs()),
    );
    l * l.transpose()
}

/// The closed-form overrides (`DiffDrive::propagate`,
/// `IrPairObservation::project`) equal the core's dense products
/// `A P A^T + W Q W^T`, `P H^T` and `H P H^T` to 1e-12 relative.
const OVERRIDE_TOLERANCE: f64 = 1e-12;

proptest! {
    #![proptest_config(config())]

    #[test]
    fn diff_drive_propagate_equals_the_dense_product(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -core::f64::consts::PI..core::f64::consts::PI,
        d1 in -0.5..0.5f64, d2 in -0.5..0.5f64, b in 0.05..0.5f64,
        l in prop::array::uniform6(-1.0..1.0f64), scale in 1e-3..1.0f64,
    ) {
        let model = DiffDrive::new(b, 1e-4, 1e-3);
        let res = check_propagate(
            &model, &Vector3::new(x, y, th), &WheelTravel { d1, d2 }, &spd(l, scale), OVERRIDE_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    #[test]
    fn ir_pair_project_equals_the_dense_products(
        x in -0.95..0.95f64, y in -0.95..0.95f64, th in -core::f64::consts::PI..core::f64::consts::PI,
        w in 0u8..4, l in prop::array::uniform6(-1.0..1.0f64), scale in 1e-3..1.0f64,
    ) {
        let obs = IrPairObservation {
            pair: IrPair::centred(0.1), wall: wall(w, 1.0), ds1: 0.15, ds2: 0.16, r11: 1e-4, r22: 2e-4,
        };
        let checked = check_project(&obs, &Vector3::new(x, y, th), &spd(l, scale), OVERRIDE_TOLERANCE);
        prop_assert_eq!(checked, Ok(true));
    }

    #[test]
    fn diff_drive_a_and_w_match_finite_differences(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -core::f64::consts::PI..core::f64::consts::PI,
        d1 in -0.5..0.5f64, d2 in -0.5..0.5f64, b in 0.05..0.5f64,
    ) {
        let model = DiffDrive::new(b, 1e-4, 1e-3);
        let res = check_motion_model(
            &model, &Vector3::new(x, y, th), &WheelTravel { d1, d2 }, DEFAULT_STEP, DEFAULT_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    #[test]
    fn ir_pair_h_and_v_match_finite_differences(
        x in -0.95..0.95f64, y in -0.95..0.95f64, th in -core::f64::consts::PI..core::f64::consts::PI,
        ds1 in 0.04..0.30f64, ds2 in 0.04..0.30f64, spacing in 0.05..0.20f64,
        e in -0.1..0.1f64, c in -0.1..0.1f64, w in 0u8..4,
    ) {
        let pair = IrPair { spacing, lateral_offset: e, forward_offset: c };
        let wall = wall(w, 1.0);
        let obs = IrPairObservation { pair, wall, ds1, ds2, r11: 1e-4, r22: 2e-4 };
        // H = dh/dX.
        let checked = check_measurement_model(&obs, &Vector3::new(x, y, th), DEFAULT_STEP, DEFAULT_TOLERANCE);
        prop_assert_eq!(checked, Ok(true));
        // V = dz/d(d_s1, d_s2), through the reading-to-observation map (eq. 3-5).
        let f = |r: &SVector<f64, 2>| Some(observe(&pair, &wall, r[0], r[1]));
        let diff = |a: &SVector<f64, 2>, b: &SVector<f64, 2>| Vector2::new(a[0] - b[0], wrap_angle(a[1] - b[1]));
        let num = numeric_jacobian(f, diff, &Vector2::new(ds1, ds2), DEFAULT_STEP).unwrap();
        let res = compare("V", &obs.v(), &num, DEFAULT_TOLERANCE);
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }
}

#[test]
fn the_checker_catches_a_wrong_jacobian() {
    // A model whose A has a sign error in one entry must fail the check.
    struct Wrong(DiffDrive<f64>);
    impl locus_core::MotionModel<f64, 3, 2> for Wrong {
        type Input = WheelTravel<f64>;
        fn evaluate(
            &self,
            x: &SVector<f64, 3>,
            u: &Self::Input,
            q: &SVector<f64, 2>,
            jacobians: Option<&mut locus_core::MotionJacobians<f64, 3, 2>>,
        ) -> SVector<f64, 3> {
            let Some(j) = jacobians else {
                return self.0.f(x, u, q);
            };
            let fx = self.0.evaluate(x, u, q, Some(&mut *j));
            j.a[(0, 2)] = -j.a[(0, 2)];
            fx
        }
        fn noise_cov(&self, u: &Self::Input) -> locus_core::nalgebra::Matrix2<f64> {
            self.0.noise_cov(u)
        }
    }
    let m = Wrong(DiffDrive::new(0.12, 1e-4, 1e-3));
    let err = check_motion_model(
        &m,
        &Vector3::new(0.0, 0.0, 0.3),
        &WheelTravel { d1: 0.1, d2: 0.05 },
        DEFAULT_STEP,
        DEFAULT_TOLERANCE,
    )
    .unwrap_err();
    assert_eq!((err.jacobian, err.row, err.col), ("A", 0, 2));
}

#[test]
fn ir_observation_matches_the_paper_table_with_centred_sensors() {
    // e = c = 0 reduces to the paper's eq. 4-5 (with the sign fix): robot at
    // x = 0.85 heading +pi/2, wall x+ at 1 m, rotated by 0.1 rad away from it.
    let pair = IrPair::centred(0.10);
    let ang: f64 = 0.1;
    let dw = 0.15;
    // Readings that give ObsAng = 0.1 and d_w = 0.15.
    let mean = dw / ang.cos();
    let half = 0.10 * ang.tan() / 2.0;
    let z = observe(&pair, &AxisWall::x_plus(1.0), mean + half, mean - half);
    assert!((z[0] - (1.0 - dw)).abs() < 1e-12);
    assert!((z[1] - (core::f64::consts::FRAC_PI_2 + ang)).abs() < 1e-12);
    let z = observe(&pair, &AxisWall::y_minus(1.0), mean + half, mean - half);
    assert!((z[0] - (-(1.0 - dw))).abs() < 1e-12);
    assert!((z[1] - ang).abs() < 1e-12);
}
