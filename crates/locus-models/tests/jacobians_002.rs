//! Finite-difference checks of the paper-002 models' analytic Jacobians, at
//! 2000 random points each (proptest), through the core's checker
//! (`locus_core::jacobian_check`: central differences, relative step 1e-5,
//! mixed relative/absolute tolerance 1e-6), plus a hand computation of one
//! projected mark.
//!
//! Valid domain of the camera model: every mark in front of the camera
//! (`z_c > min_depth` = 0.05 m). The random poses stay well inside it:
//! `tx, ty` within +-0.3 m, `tz` in 1.5..3.5 m, the three angles within
//! +-0.5 rad; the marks are at most 0.30 m from the body origin, so every
//! mark has `z_c >= 1.2 m` and every point is checked (no skips). The random
//! walk is valid everywhere (tested over any state and `dt` in 0..0.1 s).

use locus_core::MeasurementModel;
use locus_core::jacobian_check::{
    DEFAULT_STEP, DEFAULT_TOLERANCE, check_measurement_model, check_motion_model,
};
use locus_core::nalgebra::{SVector, Vector3};
use locus_models::camera::{
    CameraMark, CameraMarks, CameraMarks4, Intrinsics, RandomWalk6, nominal_pose,
};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 2000,
        ..ProptestConfig::default()
    }
}

fn pose(tx: f64, ty: f64, tz: f64, phi: f64, theta: f64, psi: f64) -> SVector<f64, 6> {
    SVector::<f64, 6>::from([tx, ty, tz, phi, theta, psi])
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn camera_c_matches_finite_differences(
        tx in -0.3..0.3f64, ty in -0.3..0.3f64, tz in 1.5..3.5f64,
        phi in -0.5..0.5f64, theta in -0.5..0.5f64, psi in -0.5..0.5f64,
    ) {
        let model = CameraMarks4::<f64>::paper_002();
        let x = pose(tx, ty, tz, phi, theta, psi);
        let checked = check_measurement_model(&model, &x, DEFAULT_STEP, DEFAULT_TOLERANCE);
        prop_assert_eq!(checked, Ok(true));
    }

    #[test]
    fn single_mark_c_matches_finite_differences_for_any_mark_and_lens(
        tx in -0.3..0.3f64, ty in -0.3..0.3f64, tz in 1.5..3.5f64,
        phi in -0.5..0.5f64, theta in -0.5..0.5f64, psi in -0.5..0.5f64,
        mx in -0.3..0.3f64, my in -0.3..0.3f64, mz in -0.3..0.3f64,
        kc1 in -0.4..0.4f64,
    ) {
        // Marks off every axis and a range of lenses exercise every term of
        // eq. 18 (the paper's marks have zero components that hide some).
        let intr = Intrinsics { kc1, ..Intrinsics::paper_002() };
        let model = CameraMark::new(intr, [Vector3::new(mx, my, mz)]);
        let x = pose(tx, ty, tz, phi, theta, psi);
        let checked = check_measurement_model(&model, &x, DEFAULT_STEP, DEFAULT_TOLERANCE);
        prop_assert_eq!(checked, Ok(true));
    }

    #[test]
    fn random_walk_a_and_w_match_finite_differences(
        tx in -5.0..5.0f64, ty in -5.0..5.0f64, tz in -5.0..5.0f64,
        phi in -3.1..3.1f64, theta in -3.1..3.1f64, psi in -3.1..3.1f64,
        dt in 0.0..0.1f64,
    ) {
        let model = RandomWalk6::<f64>::default();
        let res = check_motion_model(
            &model, &pose(tx, ty, tz, phi, theta, psi), &dt, DEFAULT_STEP, DEFAULT_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }
}

#[test]
fn nominal_image_of_the_first_mark_matches_a_hand_computation() {
    // Mark 1 X_O = (0.30, 0, 0) at T = (0, 0, 2.5), R = I:
    // X_C = (0.30, 0, 2.5); n = (0.12, 0); r^2 = 0.0144;
    // d = (1 - 0.19457 * 0.0144) * 0.12 = 0.997198192 * 0.12 = 0.11966378304;
    // u = 1865.33 * 0.11966378304 + 510.68 = 733.8924444...; v = o_y = 619.68.
    let model = CameraMarks4::<f64>::paper_002();
    let y = model.h(&nominal_pose()).expect("every mark is in front");
    let u = 1865.33 * 0.119_663_783_04 + 510.68;
    assert!((y[0] - u).abs() < 1e-9, "u = {} vs {}", y[0], u);
    assert!((y[0] - 733.892_444).abs() < 1e-6);
    assert!((y[1] - 619.68).abs() < 1e-12);
    // Mark 4 X_O = (0, -0.10, 0.15): X_C = (0, -0.10, 2.65),
    // n_y = -0.10 / 2.65, d_y = (1 + Kc1 n_y^2) n_y, v = l_y d_y + o_y.
    let ny = -0.10 / 2.65;
    let v4 = 1868.57 * (1.0 - 0.19457 * ny * ny) * ny + 619.68;
    assert!((y[6] - 510.68).abs() < 1e-12);
    assert!((y[7] - v4).abs() < 1e-9);
    assert!((y[7] - 549.187_461).abs() < 1e-6, "v4 = {}", y[7]);
}

#[test]
fn nominal_jacobian_of_the_first_mark_matches_a_hand_computation() {
    // At the nominal pose, mark 1: z = 2.5, n = (0.12, 0), Kc1 = -0.19457.
    // du/dtx = l_x (1 + 3 Kc1 n_x^2) / z; du/dtz = -l_x (1 + 3 Kc1 n_x^2) n_x / z;
    // dv/dty = l_y (1 + Kc1 n_x^2) / z; dR/dpsi X_O = e3 x X_O = (0, 0.3, 0),
    // so dv/dpsi = 0.3 dv/dty; dR/dtheta X_O = e2 x X_O = (0, 0, -0.3), so
    // du/dtheta = -0.3 du/dtz; dR/dphi X_O = e1 x X_O = 0.
    let model = CameraMarks4::<f64>::paper_002();
    let c = model.jacobian(&nominal_pose());
    let (k, nx, z) = (-0.19457, 0.12, 2.5);
    let dudtx = 1865.33 * (1.0 + 3.0 * k * nx * nx) / z;
    let dudtz = -dudtx * nx;
    let dvdty = 1868.57 * (1.0 + k * nx * nx) / z;
    let expected_row_u = [dudtx, 0.0, dudtz, 0.0, -0.3 * dudtz, 0.0];
    let expected_row_v = [0.0, dvdty, 0.0, 0.0, 0.0, 0.3 * dvdty];
    for j in 0..6 {
        assert!((c[(0, j)] - expected_row_u[j]).abs() < 1e-9, "u col {j}");
        assert!((c[(1, j)] - expected_row_v[j]).abs() < 1e-9, "v col {j}");
    }
}

#[test]
fn no_measurement_when_a_mark_is_behind_or_too_close() {
    let model = CameraMarks4::<f64>::paper_002();
    // Body origin 0.2 m in front: mark 1 at z_c = 0.2 - 0.3 sin(theta)...
    // Pitch by +pi/2 turns mark 1 (0.3, 0, 0) to (0, 0, -0.3): z_c = -0.1.
    let x = pose(0.0, 0.0, 0.2, 0.0, core::f64::consts::FRAC_PI_2, 0.0);
    assert!(model.h(&x).is_none());
    assert!(!model.all_visible(&x));
    // Exactly at the minimum depth is not a measurement; just beyond it is.
    let at = pose(0.0, 0.0, 0.05, 0.0, 0.0, 0.0);
    let m = CameraMark::new(Intrinsics::paper_002(), [Vector3::zeros()]);
    assert!(m.h(&at).is_none());
    assert!(m.h(&pose(0.0, 0.0, 0.0501, 0.0, 0.0, 0.0)).is_some());
    // A NaN depth gives no measurement.
    assert!(model.h(&pose(0.0, 0.0, f64::NAN, 0.0, 0.0, 0.0)).is_none());
}

#[test]
fn f32_agrees_with_f64() {
    let m64 = CameraMarks4::<f64>::paper_002();
    let m32 = CameraMarks4::<f32>::paper_002();
    let x64 = pose(0.1, -0.2, 2.0, 0.3, -0.2, 0.4);
    let x32 = x64.map(|v| v as f32);
    let (y64, y32) = (m64.h(&x64).unwrap(), m32.h(&x32).unwrap());
    let (c64, c32) = (m64.jacobian(&x64), m32.jacobian(&x32));
    for i in 0..8 {
        assert!((y64[i] - y32[i] as f64).abs() < 1e-3 * y64[i].abs().max(1.0));
        for j in 0..6 {
            assert!((c64[(i, j)] - c32[(i, j)] as f64).abs() < 1e-3 * c64[(i, j)].abs().max(1.0));
        }
    }
}

#[test]
fn random_walk_discretises_the_density() {
    use locus_core::MotionModel;
    let m = RandomWalk6::<f64>::default();
    let qd = m.process_noise(&nominal_pose(), &0.005);
    assert!((qd[(0, 0)] - 0.1 * 0.1 * 0.005).abs() < 1e-18);
    assert!((qd[(5, 5)] - 0.1396 * 0.1396 * 0.005).abs() < 1e-18);
    assert_eq!(qd[(0, 1)], 0.0);
    // The angles are wrapped by f.
    let x = pose(0.0, 0.0, 2.5, 3.1, 0.0, 0.0);
    let mut q = SVector::<f64, 6>::zeros();
    q[3] = 0.1;
    let y = m.f(&x, &0.005, &q);
    assert!((y[3] - (3.2 - 2.0 * core::f64::consts::PI)).abs() < 1e-12);
}

// A mismatched dimension must not compile (uncomment to see the error):
// let _ = CameraMarks::<f64, 4, 6>::new(Intrinsics::paper_002(), [Vector3::zeros(); 4]);
#[allow(dead_code)]
fn the_generic_form_names_both_dimensions() -> CameraMarks<f64, 2, 4> {
    CameraMarks::new(Intrinsics::paper_002(), [Vector3::zeros(); 2])
}
