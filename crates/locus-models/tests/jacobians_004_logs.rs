//! Finite-difference checks of the analytic Jacobians of the paper-004
//! tricycle models and of the log models (unicycle, range-bearing), at 2000
//! random points each (proptest), through the core's checker
//! (`locus_core::jacobian_check`: central differences, relative step 1e-5,
//! mixed relative/absolute tolerance 1e-6); plus the models' values at points
//! worked out by hand.
//!
//! Domains tested: headings over (-pi, pi]; tricycle counts up to +-3000 per
//! step (about +-0.5 m), radii 0.02-0.10 m, N 100-4000 counts/rev, track
//! 0.2-0.6 m, wheelbase 0.2-0.8 m, steering +-1.2 rad (beyond the 40 deg
//! limit too: the clamp acts on the reading, `W` stays exact); unicycle
//! |v| <= 1 m/s, |omega| <= 3 rad/s and separately |omega| <= 1e-4 rad/s
//! (including 0), dt 1 ms-0.5 s; range-bearing with the landmark 0.2-8 m from
//! a sensor mounted up to 0.3 m off the centre, and the range-only
//! model on the calibrated 7-state with the same geometry.

use core::f64::consts::PI;

use locus_core::jacobian_check::{
    DEFAULT_STEP, DEFAULT_TOLERANCE, check_measurement_model, check_motion_model,
};
use locus_core::nalgebra::SVector;
use locus_core::nalgebra::{Vector2, Vector3};
use locus_core::{MeasurementModel, MotionModel};
use locus_models::calibrated_range::CalibratedRange;
use locus_models::calibrated_unicycle::STATE;
use locus_models::range_bearing::RangeBearing;
use locus_models::tricycle::{
    CountNoise, FrontReading, RearCounts, TricycleFront, TricycleRear, counts_per_rev,
};
use locus_models::unicycle::{Unicycle, Velocities};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 2000,
        ..ProptestConfig::default()
    }
}

fn q0() -> Vector2<f64> {
    Vector2::zeros()
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn tricycle_rear_a_and_w_match_finite_differences(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -PI..PI,
        n_l in -3000.0..3000.0f64, n_r in -3000.0..3000.0f64,
        radius in 0.02..0.10f64, n in 100.0..4000.0f64, track in 0.2..0.6f64,
    ) {
        let model = TricycleRear::new(radius, n, track, CountNoise::assumed());
        let res = check_motion_model(
            &model, &Vector3::new(x, y, th), &RearCounts { n_l, n_r }, DEFAULT_STEP, DEFAULT_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    #[test]
    fn tricycle_front_a_and_w_match_finite_differences(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -PI..PI,
        n_f in -3000.0..3000.0f64, phi in -1.2..1.2f64,
        radius in 0.02..0.10f64, n in 100.0..4000.0f64, wheelbase in 0.2..0.8f64,
    ) {
        let model = TricycleFront { radius, counts_per_rev: n, wheelbase, ..TricycleFront::assumed() };
        let res = check_motion_model(
            &model, &Vector3::new(x, y, th), &FrontReading { n_f, phi }, DEFAULT_STEP, DEFAULT_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    #[test]
    fn unicycle_a_and_w_match_finite_differences(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -PI..PI,
        v in -1.0..1.0f64, omega in -3.0..3.0f64, dt in 0.001..0.5f64,
    ) {
        let model = Unicycle::new(1e-4, 1e-3).with_relative(0.01, 0.02);
        let res = check_motion_model(
            &model, &Vector3::new(x, y, th), &Velocities { v, omega, dt }, DEFAULT_STEP, DEFAULT_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    #[test]
    fn unicycle_a_and_w_match_finite_differences_near_zero_turn_rate(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -PI..PI,
        v in -1.0..1.0f64, omega in prop_oneof![Just(0.0f64), -1e-4..1e-4f64], dt in 0.001..0.5f64,
    ) {
        let model = Unicycle::new(1e-4, 1e-3);
        let res = check_motion_model(
            &model, &Vector3::new(x, y, th), &Velocities { v, omega, dt }, DEFAULT_STEP, DEFAULT_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    #[test]
    fn range_bearing_h_matches_finite_differences(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -PI..PI,
        range in 0.2..8.0f64, dir in -PI..PI,
        sx in -0.3..0.3f64, sy in -0.3..0.3f64,
    ) {
        // Place the landmark `range` from the sensor, in direction `dir`.
        let base = RangeBearing::new(Vector2::zeros(), Vector2::new(sx, sy), 0.05, 0.01);
        let state = Vector3::new(x, y, th);
        let (p, _) = base.sensor_world(&state);
        let model = base.with_landmark(p + range * Vector2::new(dir.cos(), dir.sin()));
        let checked = check_measurement_model(&model, &state, DEFAULT_STEP, DEFAULT_TOLERANCE);
        prop_assert_eq!(checked, Ok(true));
    }

    #[test]
    fn calibrated_range_h_matches_finite_differences(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -PI..PI,
        range in 0.2..8.0f64, dir in -PI..PI,
        sx in -0.3..0.3f64, sy in -0.3..0.3f64,
        s_v in 0.8..1.2f64, s_omega in 0.8..1.2f64, b_omega in -0.05..0.05f64, b_bearing in -0.1..0.1f64,
    ) {
        // A range-only beacon `range` from the mounted sensor, in direction `dir`.
        let base = RangeBearing::new(Vector2::zeros(), Vector2::new(sx, sy), 0.05, 1.0);
        let (p, _) = base.sensor_world(&Vector3::new(x, y, th));
        let model = CalibratedRange { inner: base.with_landmark(p + range * Vector2::new(dir.cos(), dir.sin())) };
        let state = SVector::<f64, STATE>::from([x, y, th, s_v, s_omega, b_omega, b_bearing, 0.0]);
        let checked = check_measurement_model(&model, &state, DEFAULT_STEP, DEFAULT_TOLERANCE);
        prop_assert_eq!(checked, Ok(true));
    }
}

#[test]
fn counts_per_rev_is_four_times_lines_times_gear() {
    assert_eq!(counts_per_rev(500.0f64, 1.0), 2000.0);
    assert_eq!(counts_per_rev(500.0f64, 3.0), 6000.0);
}

#[test]
fn tricycle_rear_one_revolution_of_both_wheels_rolls_one_circumference() {
    let m = TricycleRear::<f64>::assumed();
    let x = m.f(
        &Vector3::new(1.0, 2.0, PI / 2.0),
        &RearCounts::from_counts(2000, 2000),
        &q0(),
    );
    let circ = 2.0 * PI * 0.05;
    assert!((x - Vector3::new(1.0, 2.0 + circ, PI / 2.0)).norm() < 1e-12);
    // Right wheel one revolution, left none: eq. 1-2.
    let (ds, dth) = m.increments(&RearCounts::from_counts(0, 2000));
    assert!((ds - circ / 2.0).abs() < 1e-15);
    assert!((dth - circ / 0.40).abs() < 1e-15);
}

#[test]
fn tricycle_front_y_equation_uses_cos_phi_sin_theta() {
    // The spec's [fix]: y' = y + dsF cos(phi) sin(theta). Heading +y, steer 0.3 rad.
    let m = TricycleFront::<f64>::assumed();
    let phi = 0.3;
    let x = m.f(
        &Vector3::new(0.0, 0.0, PI / 2.0),
        &FrontReading::from_count(1000, phi),
        &q0(),
    );
    let ds_f = 2.0 * PI * 0.06 * 1000.0 / 2000.0;
    assert!(x[0].abs() < 1e-12);
    assert!((x[1] - ds_f * phi.cos()).abs() < 1e-12);
    assert!((x[2] - (PI / 2.0 + ds_f * phi.sin() / 0.45)).abs() < 1e-12);
}

#[test]
fn tricycle_front_and_rear_agree_on_a_consistent_turn() {
    // A turn of the rear-axle midpoint about a circle of radius rho: the rear
    // wheels roll (rho -+ D/2) dth, the front wheel sqrt(rho^2 + L^2) dth at
    // steering phi = atan(L / rho). Both models must give the same (ds, dth).
    let rear = TricycleRear::<f64>::assumed();
    let front = TricycleFront::<f64>::assumed();
    let (rho, dth) = (1.5, 0.02);
    let per_m_rear = 2000.0 / (2.0 * PI * 0.05);
    let per_m_front = 2000.0 / (2.0 * PI * 0.06);
    let rc = RearCounts {
        n_l: (rho - 0.20) * dth * per_m_rear,
        n_r: (rho + 0.20) * dth * per_m_rear,
    };
    let fr = FrontReading {
        n_f: (rho * rho + 0.45 * 0.45).sqrt() * dth * per_m_front,
        phi: (0.45f64 / rho).atan(),
    };
    let (ds_r, dth_r) = rear.increments(&rc);
    let (ds_f, dth_f) = front.increments(&fr);
    assert!((ds_r - rho * dth).abs() < 1e-12 && (dth_r - dth).abs() < 1e-12);
    assert!((ds_f - rho * dth).abs() < 1e-12 && (dth_f - dth).abs() < 1e-12);
}

#[test]
fn tricycle_front_clamps_steering_beyond_the_limit() {
    let m = TricycleFront::<f64>::assumed();
    let limit = 40.0f64.to_radians();
    assert!((m.steering_limit - limit).abs() < 1e-15);
    assert!(m.steering_in_range(0.5) && !m.steering_in_range(0.8) && !m.steering_in_range(-0.8));
    let x0 = Vector3::new(0.3, -0.2, 1.0);
    let at_stop = m.f(&x0, &FrontReading::from_count(500, limit), &q0());
    let beyond = m.f(&x0, &FrontReading::from_count(500, 1.2), &q0());
    assert_eq!(at_stop, beyond);
    let at_neg = m.f(&x0, &FrontReading::from_count(500, -limit), &q0());
    let beyond_neg = m.f(&x0, &FrontReading::from_count(500, -3.0), &q0());
    assert_eq!(at_neg, beyond_neg);
    assert!(!m.input_is_finite(&FrontReading {
        n_f: 1.0,
        phi: f64::NAN
    }));
}

#[test]
fn unicycle_matches_the_textbook_arc_and_the_straight_line() {
    let m = Unicycle::new(1e-4, 1e-3);
    let x0 = Vector3::new(1.0, -1.0, 0.7);
    let (v, dt) = (0.4, 0.25);
    // Turning: the textbook closed form.
    let omega = 1.3;
    let got = m.f(&x0, &Velocities { v, omega, dt }, &q0());
    let r = v / omega;
    let th1 = 0.7 + omega * dt;
    let want = Vector3::new(
        1.0 + r * (th1.sin() - 0.7f64.sin()),
        -1.0 - r * (th1.cos() - 0.7f64.cos()),
        th1,
    );
    assert!((got - want).norm() < 1e-14, "{got} vs {want}");
    // omega = 0 and omega -> 0: the straight line, continuously.
    let line = Vector3::new(
        1.0 + v * dt * 0.7f64.cos(),
        -1.0 + v * dt * 0.7f64.sin(),
        0.7,
    );
    for omega in [0.0, 1e-12, -1e-9, 1e-6] {
        let got = m.f(&x0, &Velocities { v, omega, dt }, &q0());
        assert!(
            (got - line).norm() < omega.abs() * dt * (1.0 + v * dt) + 1e-14,
            "{omega}"
        );
        assert!(got.iter().all(|c| c.is_finite()));
    }
}

#[test]
fn range_bearing_values_with_an_offset_sensor() {
    // Robot at (1, 1) heading +y; sensor 0.1 m ahead -> world (1, 1.1).
    // Landmark at (0, 1.1): 1 m straight left of the sensor, bearing +pi/2.
    let m = RangeBearing::new(Vector2::new(0.0, 1.1), Vector2::new(0.1, 0.0), 0.05, 0.01);
    let z = m.h(&Vector3::new(1.0, 1.0, PI / 2.0)).unwrap();
    assert!(
        (z[0] - 1.0).abs() < 1e-12 && (z[1] - PI / 2.0).abs() < 1e-12,
        "{z}"
    );
    // Landmark behind: bearing pi, and the residual wraps across it.
    let m = m.with_landmark(Vector2::new(1.0, 0.0));
    let z = m.h(&Vector3::new(1.0, 1.0, PI / 2.0)).unwrap();
    assert!(
        (z[0] - 1.1).abs() < 1e-12 && (z[1].abs() - PI).abs() < 1e-12,
        "{z}"
    );
    let res = m.residual(
        &Vector2::new(1.0, PI - 0.01),
        &Vector2::new(1.0, -PI + 0.01),
    );
    assert!((res[1] + 0.02).abs() < 1e-12, "{res}");
    let r = m.noise(&Vector3::zeros());
    let want = locus_core::nalgebra::Matrix2::new(0.05 * 0.05, 0.0, 0.0, 0.01 * 0.01);
    assert!((r - want).norm() < 1e-18, "{r}");
}

#[test]
fn range_bearing_has_no_measurement_at_the_sensor() {
    let m = RangeBearing::new(Vector2::new(2.0, 3.0), Vector2::new(0.2, -0.1), 0.05, 0.01);
    // The sensor of a robot at (1.8, 3.1) heading 0 sits on the landmark.
    assert_eq!(m.h(&Vector3::new(1.8, 3.1, 0.0)), None);
    assert_eq!(m.h(&Vector3::new(1.8, 3.1 + 5e-4, 0.0)), None);
    assert!(m.h(&Vector3::new(1.8, 3.1 + 2e-3, 0.0)).is_some());
    assert_eq!(m.h(&Vector3::new(f64::NAN, 3.1, 0.0)), None);
}

#[test]
fn models_run_in_f32() {
    let x = Vector3::new(0.5f32, -0.5, 0.1);
    let rear = TricycleRear::<f32>::assumed();
    let front = TricycleFront::<f32>::assumed();
    let uni = Unicycle::new(1e-4f32, 1e-3);
    let rb = RangeBearing::new(
        Vector2::new(2.0f32, 1.0),
        Vector2::new(0.1, 0.0),
        0.05,
        0.01,
    );
    let q = Vector2::<f32>::zeros();
    assert!(
        rear.f(&x, &RearCounts::from_counts(100, 120), &q)
            .iter()
            .all(|c| c.is_finite())
    );
    assert!(
        front
            .f(&x, &FrontReading::from_count(100, 0.2), &q)
            .iter()
            .all(|c| c.is_finite())
    );
    let u = Velocities {
        v: 0.3f32,
        omega: 1e-7,
        dt: 0.01,
    };
    assert!(uni.jacobian_noise(&x, &u).iter().all(|c| c.is_finite()));
    assert!(rb.h(&x).is_some() && rb.jacobian(&x).iter().all(|c| c.is_finite()));
}
