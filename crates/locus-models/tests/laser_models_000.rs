//! Behaviour of the paper-000 models through `locus_core::Ekf`: the paper's
//! laser `H` against the exact range model on the paper's geometry, when a
//! measurement exists, and the skid-steer kinematics.
//!
//! Geometry (spec section 2): the wall is the line `x + y = a`, `a = 1.17 m`;
//! the laser sits at `x_si = 0.17 m`, `y_si = 0`, `beta = 0`. With the robot at
//! the origin heading 0 the beam hits the wall at (1.17, 0), range 1 m.

use core::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_4, PI};

use locus_core::nalgebra::{Matrix3, SMatrix, SVector, Vector1, Vector2, Vector3};
use locus_core::{Belief, Ekf, Error, MeasurementModel, MotionModel};
use locus_models::laser_wall::{
    BeamLimits, LaserMount, LaserRange, LaserWallPaper, Segment, WallLine,
};
use locus_models::skid_steer::{SkidSteer, TreadSpeeds};

const A: f64 = 1.17;
/// The wall `x + y = 1.17` as a long segment, from (2.17, -1) to (-0.83, 2).
const WALL_000: [Segment<f64>; 1] = [Segment::new([2.17, -1.0], [-0.83, 2.0])];
/// Laser noise (m, 1 sigma) of both models in the variance test.
const SIGMA: f64 = 0.01;
/// Corrections applied in the variance test.
const CORRECTIONS: usize = 50;

fn paper_model() -> LaserWallPaper<f64> {
    LaserWallPaper::new(
        LaserMount::paper_000(),
        WallLine::paper_000(A),
        SIGMA * SIGMA,
        SIGMA * SIGMA,
    )
}

fn exact_model() -> LaserRange<'static, f64> {
    LaserRange::new(LaserMount::paper_000(), &WALL_000, SIGMA * SIGMA)
}

/// Variance of the position along the unit direction `d` (m^2): `d^T P d`.
fn var_along(p: &Matrix3<f64>, d: Vector2<f64>) -> f64 {
    let d3 = Vector3::new(d[0], d[1], 0.0);
    (d3.transpose() * p * d3)[0]
}

fn along_wall() -> Vector2<f64> {
    Vector2::new(FRAC_1_SQRT_2, -FRAC_1_SQRT_2)
}

fn across_wall() -> Vector2<f64> {
    Vector2::new(FRAC_1_SQRT_2, FRAC_1_SQRT_2)
}

fn prior() -> Belief<f64, 3> {
    Belief::new(
        Vector3::zeros(),
        Matrix3::from_diagonal(&Vector3::new(0.01, 0.01, 0.001)),
    )
}

#[test]
fn models_at_the_000_test_pose() {
    let x = Vector3::zeros();
    let paper = paper_model();
    let exact = exact_model();
    let z = paper.h(&x).unwrap();
    assert!((z - Vector2::new(1.0, 0.0)).amax() < 1e-12, "{z}");
    let h = paper.jacobian(&x);
    let h_ref = SMatrix::<f64, 2, 3>::new(-1.0, 0.0, 0.0, 0.0, -1.0, -1.17);
    assert!((h - h_ref).amax() < 1e-12, "{h}");
    assert!((exact.range(&x).unwrap() - 1.0).abs() < 1e-12);
    let hx = exact.jacobian(&x);
    let hx_ref = SMatrix::<f64, 1, 3>::new(-1.0, -1.0, -1.17);
    assert!((hx - hx_ref).amax() < 1e-12, "{hx}");
    // The paper's sensor reading for a range of 1 m.
    assert_eq!(paper.z_from_range(1.0), Vector2::new(1.0, 0.0));
}

#[test]
fn paper_h_gains_information_along_the_wall_the_exact_model_does_not() {
    let ekf = Ekf::<f64>::default();
    let truth = Vector3::zeros();
    let paper = paper_model();
    let exact = exact_model();
    let z_paper = paper.h(&truth).unwrap();
    let z_exact = exact.h(&truth).unwrap();
    let b0 = prior();
    let v0 = var_along(&b0.p, along_wall());
    let c0 = var_along(&b0.p, across_wall());

    let (mut bp, mut be) = (b0, b0);
    println!(
        "variance along / across the wall (m^2), P0 = diag(0.01, 0.01, 0.001), sigma = {SIGMA} m:"
    );
    println!("  corrections | paper H: along    across    | exact range: along    across");
    for k in 1..=CORRECTIONS {
        bp = ekf.correct(&bp, &paper, &z_paper).unwrap().belief;
        be = ekf.correct(&be, &exact, &z_exact).unwrap().belief;
        if [1, 2, 5, 10, 20, 50].contains(&k) {
            println!(
                "  {k:>11} | {:>9.3e} {:>9.3e} | {:>9.3e} {:>9.3e}",
                var_along(&bp.p, along_wall()),
                var_along(&bp.p, across_wall()),
                var_along(&be.p, along_wall()),
                var_along(&be.p, across_wall()),
            );
        }
    }
    let (vp, ve) = (
        var_along(&bp.p, along_wall()),
        var_along(&be.p, along_wall()),
    );
    let (cp, ce) = (
        var_along(&bp.p, across_wall()),
        var_along(&be.p, across_wall()),
    );
    println!(
        "after {CORRECTIONS} corrections: along the wall paper {:.1} %, exact {:.1} % of the \
         initial {v0:.3e} m^2; across the wall paper {:.1} %, exact {:.1} %",
        100.0 * vp / v0,
        100.0 * ve / v0,
        100.0 * cp / c0,
        100.0 * ce / c0
    );
    // The measurement equals the prediction: the estimate does not move.
    assert!(bp.x.amax() < 1e-15 && be.x.amax() < 1e-15);
    // Paper H: claims information along the wall it cannot have.
    assert!(
        vp < 0.1 * v0,
        "paper: along-wall variance {vp} not below 10 % of {v0}"
    );
    // Exact model: none along the wall (d^T P d is invariant in exact
    // arithmetic, since H (d, 0) = 0 and P (d, 0) stays out of reach of H) ...
    assert!(
        ve > 0.9 * v0,
        "exact: along-wall variance {ve} fell below 90 % of {v0}"
    );
    assert!((ve - v0).abs() <= 1e-12 * v0);
    // ... while both learn across the wall.
    assert!(ce < 0.5 * c0 && cp < 0.5 * c0);
}

#[test]
fn no_measurement_when_the_beam_misses() {
    let ekf = Ekf::<f64>::default();
    let paper = paper_model();
    let exact = exact_model();
    let at = |x: f64, y: f64, th: f64| Vector3::new(x, y, th);

    // Hit: for reference.
    assert!(paper.h(&at(0.0, 0.0, 0.0)).is_some());
    assert!(exact.h(&at(0.0, 0.0, 0.0)).is_some());

    // Parallel: heading -45 deg, the beam runs along the wall.
    let parallel = at(0.0, 0.0, -FRAC_PI_4);
    assert_eq!(paper.h(&parallel), None);
    assert_eq!(exact.h(&parallel), None);
    // Within the tolerance of parallel, and just outside it (that hit is far
    // out of range, so widen the range to see it).
    let tol = paper.limits.parallel_tol;
    assert_eq!(paper.h(&at(0.0, 0.0, -FRAC_PI_4 + 0.5 * tol)), None);
    let mut far = paper;
    far.limits = BeamLimits::with_max_range(1e9);
    assert!(far.h(&at(0.0, 0.0, -FRAC_PI_4 + 4.0 * tol)).is_some());

    // Behind: heading pi, the wall is behind the sensor (gamma < 0).
    let behind = at(0.0, 0.0, PI);
    assert_eq!(paper.h(&behind), None);
    assert_eq!(exact.h(&behind), None);
    // The sensor on the far side of the wall, looking away from it.
    assert_eq!(paper.h(&at(2.0, 0.0, 0.0)), None);

    // Out of range: 11 m > the default 8 m; in range with a 20 m sensor.
    let far_pose = at(-10.0, 0.0, 0.0);
    assert_eq!(paper.h(&far_pose), None);
    assert_eq!(exact.h(&far_pose), None);
    let mut long = exact;
    long.limits = BeamLimits::with_max_range(20.0);
    assert!((long.range(&far_pose).unwrap() - 11.0).abs() < 1e-12);

    // Off the segment: a piece of the same wall that the beam misses. The
    // paper's model (an infinite line) still sees the wall.
    let piece = [Segment::new([1.07, 0.1], [0.67, 0.5])];
    let short = LaserRange::new(LaserMount::paper_000(), &piece, SIGMA * SIGMA);
    assert_eq!(short.h(&at(0.0, 0.0, 0.0)), None);
    assert!(paper.h(&at(0.0, 0.0, 0.0)).is_some());
    // ... and turned a little to the left the beam does hit it.
    assert!(short.h(&at(0.0, 0.0, 0.2)).is_some());

    // Through the filter: a typed error, and the belief is not consumed.
    let b = prior();
    let err = ekf
        .correct(&Belief::new(parallel, b.p), &paper, &Vector2::new(1.0, 0.0))
        .unwrap_err();
    assert_eq!(err, Error::NoMeasurement);
    let err = ekf
        .correct(&Belief::new(behind, b.p), &exact, &Vector1::new(1.0))
        .unwrap_err();
    assert_eq!(err, Error::NoMeasurement);
    let err = ekf.correct(&b, &short, &Vector1::new(1.0)).unwrap_err();
    assert_eq!(err, Error::NoMeasurement);
}

#[test]
fn ray_cast_returns_the_nearest_segment() {
    // Two walls across the beam: x = 0.7 and the 000 wall (hit at x = 1.17).
    let map = [
        WALL_000[0],
        Segment::new([0.7, -0.5], [0.7, 0.5]),
        // Behind the sensor: never hit.
        Segment::new([-0.5, -0.5], [-0.5, 0.5]),
    ];
    let m = LaserRange::new(LaserMount::paper_000(), &map, 1e-4);
    let x = Vector3::zeros();
    let hit = m.cast(&x).unwrap();
    assert_eq!(hit.segment, 1);
    assert!((hit.hit.range - 0.53).abs() < 1e-12);
    // Its Jacobian is that of the x = 0.7 wall: d gamma/dx = -1, dy = 0,
    // d gamma/dtheta = 0 (the sensor sweeps along the wall's normal... at
    // theta = 0 dp_s/dtheta = (0, 0.17) is parallel to the wall, and u' too).
    let h = m.jacobian(&x);
    assert!(
        (h - SMatrix::<f64, 1, 3>::new(-1.0, 0.0, 0.0)).amax() < 1e-12,
        "{h}"
    );
    // Looking above the short wall, the 000 wall is hit.
    let x = Vector3::new(0.0, 0.6, 0.0);
    let hit = m.cast(&x).unwrap();
    assert_eq!(hit.segment, 0);
    assert!((hit.hit.range - (A - 0.6 - 0.17)).abs() < 1e-12);
}

#[test]
fn sequential_equals_batch_for_the_paper_model() {
    let ekf = Ekf::<f64>::default();
    let paper = paper_model();
    let b = Belief::new(
        Vector3::new(0.02, 0.001, 0.01),
        Matrix3::new(0.01, 0.002, 0.0, 0.002, 0.01, 0.0005, 0.0, 0.0005, 0.001),
    );
    let z = Vector2::new(0.98, 0.0);
    let batch = ekf.correct(&b, &paper, &z).unwrap();
    let seq = ekf.correct_sequential(&b, &paper, &z).unwrap();
    assert!((batch.belief.x - seq.belief.x).amax() < 1e-12);
    assert!((batch.belief.p - seq.belief.p).amax() < 1e-12);
    assert!((batch.nis - seq.nis).abs() < 1e-9);
}

#[test]
fn skid_steer_kinematics() {
    let m = SkidSteer::<f64>::pioneer_3at(1e-4, 1e-4);
    let q0 = SVector::<f64, 2>::zeros();
    // Straight at 0.10 m/s for dT = 0.1 s.
    let x = m.f(&Vector3::zeros(), &TreadSpeeds::new(0.1, 0.1, 0.1), &q0);
    assert!((x - Vector3::new(0.01, 0.0, 0.0)).amax() < 1e-15);
    // Turn in place at 0.3 rad/s: V_R = -V_L = 0.3 D / 2 = 0.075 m/s.
    let turn = TreadSpeeds::new(-0.075, 0.075, 0.1);
    let x = m.f(&Vector3::zeros(), &turn, &q0);
    assert!((x - Vector3::new(0.0, 0.0, 0.03)).amax() < 1e-15);
    // Turning +47.5 deg takes 0.829 rad / 0.03 rad per step ~ 27.6 steps.
    let mut x = Vector3::zeros();
    for _ in 0..27 {
        x = m.f(&x, &turn, &q0);
    }
    assert!((x[2] - 0.81).abs() < 1e-12);
    // Theta is wrapped to (-pi, pi].
    let x = m.f(&Vector3::new(0.0, 0.0, PI - 0.01), &turn, &q0);
    assert!((x[2] - (-PI + 0.02)).abs() < 1e-12, "{}", x[2]);
    // Noise on the tread speeds: the mapped covariance grows with D^-2 in theta.
    let p = m.process_noise(&Vector3::zeros(), &turn);
    assert!((p[(2, 2)] - 2.0 * 1e-4 * (0.1f64 / 0.5).powi(2)).abs() < 1e-18);
}

#[test]
fn the_000_models_run_in_f32() {
    let ekf = Ekf::<f32>::default();
    let b = Belief::new(
        Vector3::<f32>::zeros(),
        Matrix3::from_diagonal(&Vector3::new(0.01f32, 0.01, 0.001)),
    );
    let motion = SkidSteer::<f32>::pioneer_3at(1e-4, 1e-4);
    let b = ekf
        .predict(&b, &motion, &TreadSpeeds::new(0.1f32, 0.1, 0.1))
        .unwrap();
    let wall = [Segment::new([2.17f32, -1.0], [-0.83, 2.0])];
    let exact = LaserRange::new(LaserMount::<f32>::paper_000(), &wall, 1e-4);
    let c = ekf.correct(&b, &exact, &Vector1::new(0.99f32)).unwrap();
    assert!(c.applied && c.belief.p[(0, 0)] < b.p[(0, 0)]);
    let paper = LaserWallPaper::new(
        LaserMount::<f32>::paper_000(),
        WallLine::paper_000(1.17f32),
        1e-4,
        1e-4,
    );
    let z = paper.z_from_range(0.99f32);
    let c = ekf.correct(&b, &paper, &z).unwrap();
    assert!(c.applied && c.belief.p[(1, 1)] < b.p[(1, 1)]);
}
