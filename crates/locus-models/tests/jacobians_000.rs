//! Finite-difference checks of the analytic Jacobians of the paper-000 models,
//! at >= 1000 random valid points each (proptest, 2000 cases), through the
//! core's checker (`locus_core::jacobian_check`: central differences, relative
//! step 1e-5, mixed relative/absolute tolerance 1e-6).
//!
//! Valid domains tested:
//!
//! * `SkidSteer` (A, W): valid everywhere; poses in a 10 m box, headings in
//!   (-pi, pi], tread speeds within +-1.5 m/s, dT in [0.01, 0.5] s, effective
//!   track D in [0.2, 1.0] m.
//! * `LaserRange` (H): the range is differentiable where the nearest hit is
//!   strictly inside its segment, in front of the sensor, within range, the
//!   beam not parallel to the wall, and the nearest segment cannot switch. The
//!   finite differences move each pose coordinate by 1e-5 * max(1, |x_j|)
//!   (m, rad), so the tested domain keeps a margin: `|n.u| >= 0.1` (beam at
//!   least ~5.7 deg from grazing), range in [1 mm, max_range - 1 mm], hit
//!   at least 1 mm plus the stencil's reach along the wall (up to a few mm
//!   at long range and grazing incidence, see `stencil_reach`) from both
//!   ends of its segment, no end of another segment within that distance of
//!   the beam in front of the hit, and no other segment crossing the beam within 1 mm
//!   of the sensor or of the hit. The random scenes reach a little beyond
//!   that domain; points outside it are skipped and counted, and at least
//!   80 % (and at least 1000) must be checked.
//! * `LaserWallPaper`: its `h` equals a direct computation (the paper's
//!   `tan` formula of eq. 13 with the spec's fix, an independent line
//!   intersection, and the exact range model rotated into the sensor frame);
//!   its `H` (eq. 15) equals the finite-difference derivative of `h` with the
//!   hit point `(l, m)` held fixed, and is *not* the derivative of `h` itself
//!   (the paper's documented approximation): the hit point slides along the
//!   wall when the pose changes, which `H` ignores.

use core::f64::consts::PI;
use core::sync::atomic::{AtomicUsize, Ordering};

use locus_core::jacobian_check::{
    DEFAULT_STEP, DEFAULT_TOLERANCE, check_measurement_model, check_motion_model, compare,
    numeric_jacobian,
};
use locus_core::nalgebra::{SMatrix, SVector, Vector2, Vector3};
use locus_core::{MeasurementModel, MotionModel};
use locus_models::laser_wall::{
    BeamLimits, LaserMount, LaserRange, LaserWallPaper, Segment, WallLine, range_jacobian,
};
use locus_models::skid_steer::{SkidSteer, TreadSpeeds};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 2000,
        ..ProptestConfig::default()
    }
}

/// Config of the hand-driven runners (no regression files: their inputs are
/// not `proptest!` functions).
fn runner_config() -> Config {
    Config {
        cases: 2000,
        failure_persistence: None,
        ..Config::default()
    }
}

/// Margin of the tested domain of `LaserRange` (m), see the module doc.
const MARGIN: f64 = 1e-3;
/// Smallest `|n.u|` of the tested domain.
const MIN_INCIDENCE: f64 = 0.1;

fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn rot(v: &Vector2<f64>, ang: f64) -> Vector2<f64> {
    let (s, c) = ang.sin_cos();
    Vector2::new(c * v[0] - s * v[1], s * v[0] + c * v[1])
}

/// The intersection of the (two-sided) beam line `p_s + g u` with segment `seg`
/// extended by `MARGIN` at both ends: the signed range `g`, or `None` if the
/// lines are parallel or the intersection is off the extended segment.
fn beam_line_crossing(p_s: &Vector2<f64>, u: &Vector2<f64>, seg: &Segment<f64>) -> Option<f64> {
    let a = Vector2::from(seg.a);
    let d = Vector2::from(seg.b) - a;
    let len = d.norm();
    let den = cross(u, &d);
    if den.abs() < 1e-12 || len == 0.0 {
        return None;
    }
    // p_s + g u = a + t d  ->  g = cross(a - p_s, d)/cross(u, d), t = cross(a - p_s, u)/cross(u, d).
    let w = a - p_s;
    let g = cross(&w, &d) / den;
    let t = cross(&w, u) / den;
    (t * len >= -MARGIN && t * len <= len + MARGIN).then_some(g)
}

/// How far the hit point can slide along its wall within the checker's
/// stencil (m): the sensor moves by up to `h_x + h_y` plus its lever arm
/// times `h_theta`, the beam turns by `h_theta` and so sweeps `range *
/// h_theta` across the wall, and a wall met at incidence `|n.u|` stretches
/// both by `1/|n.u|`. At 8 m, a heading near pi and `|n.u|` = 0.1 this is
/// about 2.5 mm, more than `MARGIN`.
fn stencil_reach(model: &LaserRange<'_, f64>, x: &Vector3<f64>, range: f64, n_dot_u: f64) -> f64 {
    let h = |v: f64| DEFAULT_STEP * v.abs().max(1.0);
    let lever = model.mount.x_si.hypot(model.mount.y_si);
    (h(x[0]) + h(x[1]) + (lever + range) * h(x[2])) / n_dot_u.abs()
}

/// Whether `x` lies in the tested domain of `model` (see the module doc).
fn in_domain(model: &LaserRange<'_, f64>, x: &Vector3<f64>) -> bool {
    let Some(r) = model.cast(x) else {
        return false;
    };
    let hit = r.hit;
    if hit.n_dot_u.abs() < MIN_INCIDENCE
        || hit.range < MARGIN
        || hit.range > model.limits.max_range - MARGIN
    {
        return false;
    }
    let end_margin = MARGIN + stencil_reach(model, x, hit.range, hit.n_dot_u);
    let own = &model.map[r.segment];
    if (hit.point - Vector2::from(own.a)).norm() < end_margin
        || (hit.point - Vector2::from(own.b)).norm() < end_margin
    {
        return false;
    }
    let p_s = model.mount.sensor_position(x);
    let u = model.mount.beam_direction(x[2]);
    for (k, seg) in model.map.iter().enumerate() {
        if k == r.segment {
            continue;
        }
        // An end of another segment near the beam, in front of the hit: the
        // nearest segment may switch within the stencil.
        for e in [seg.a, seg.b] {
            let w = Vector2::from(e) - p_s;
            let along = w.dot(&u);
            if along > -MARGIN && along < hit.range + MARGIN && cross(&u, &w).abs() < end_margin {
                return false;
            }
        }
        // Another segment crossing the beam at the sensor or at the hit.
        if let Some(g) = beam_line_crossing(&p_s, &u, seg) {
            if g.abs() < MARGIN || (g - hit.range).abs() < MARGIN {
                return false;
            }
        }
    }
    true
}

/// A random pose, mounting and map: the first segment crosses the beam's line
/// at range `g0` (0.2-9 m) with the wall at `alpha` (0.05-3.09 rad) to the
/// beam, extending 0-2 m either side of the crossing; two clutter segments
/// (0.1-3 m long, anywhere in an 8 m box) may occlude it.
#[derive(Debug, Clone)]
struct Scene {
    x: Vector3<f64>,
    mount: LaserMount<f64>,
    map: [Segment<f64>; 3],
    /// The first segment's line: through the crossing `q`, direction `w`.
    q: Vector2<f64>,
    w: Vector2<f64>,
}

type Pose = (f64, f64, f64);
type Mount = (f64, f64, f64);
type Wall = (f64, f64, f64, f64);
type Clutter = (f64, f64, f64, f64);

fn scene_strategy() -> impl Strategy<Value = Scene> {
    let pose = (-1.0..1.0f64, -1.0..1.0f64, -PI..PI);
    let mount = (-0.3..0.3f64, -0.3..0.3f64, -PI..PI);
    // Range to the wall, wall angle to the beam, extents on both sides of the
    // hit. Deliberately a little wider than the tested domain (ranges beyond
    // the 8 m maximum, grazing beams, hits near an end) so that the domain
    // test is exercised: those points are skipped and counted.
    let wall = (0.2..9.0f64, 0.05..(PI - 0.05), 0.0..2.0f64, 0.0..2.0f64);
    let clutter = (-4.0..4.0f64, -4.0..4.0f64, -PI..PI, 0.1..3.0f64);
    (pose, mount, wall, clutter.clone(), clutter).prop_map(
        |(pose, mount, wall, c1, c2): (Pose, Mount, Wall, Clutter, Clutter)| {
            let x = Vector3::new(pose.0, pose.1, pose.2);
            let mount = LaserMount::new(mount.0, mount.1, mount.2);
            let p_s = mount.sensor_position(&x);
            let u = mount.beam_direction(x[2]);
            let q = p_s + u * wall.0;
            let w = rot(&u, wall.1);
            let a = q - w * wall.2;
            let b = q + w * wall.3;
            let clutter = |c: Clutter| {
                let d = Vector2::new(c.2.cos(), c.2.sin()) * (0.5 * c.3);
                Segment::new([c.0 - d[0], c.1 - d[1]], [c.0 + d[0], c.1 + d[1]])
            };
            Scene {
                x,
                mount,
                map: [
                    Segment::new([a[0], a[1]], [b[0], b[1]]),
                    clutter(c1),
                    clutter(c2),
                ],
                q,
                w,
            }
        },
    )
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn skid_steer_a_and_w_match_finite_differences(
        x in -5.0..5.0f64, y in -5.0..5.0f64, th in -PI..PI,
        v_l in -1.5..1.5f64, v_r in -1.5..1.5f64, dt in 0.01..0.5f64, d in 0.2..1.0f64,
    ) {
        let model = SkidSteer::new(d, 1e-4, 2e-4);
        let res = check_motion_model(
            &model, &Vector3::new(x, y, th), &TreadSpeeds::new(v_l, v_r, dt),
            DEFAULT_STEP, DEFAULT_TOLERANCE,
        );
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    /// H of the paper model equals the derivative of eq. 14 with (l, m) held
    /// fixed (the helper below writes eq. 14 afresh from the spec).
    #[test]
    fn paper_h_jacobian_is_the_derivative_with_the_hit_point_held_fixed(scene in scene_strategy()) {
        let model = paper_model(&scene);
        let Some(hit) = model.hit(&scene.x) else {
            return Err(TestCaseError::fail("the constructed wall must be hit"));
        };
        let (l, m) = (hit.point[0], hit.point[1]);
        let fixed = |x: &SVector<f64, 3>| Some(h_fixed_hit_point(&scene.mount, x, l, m));
        let num = numeric_jacobian(fixed, |a, b| a - b, &scene.x, DEFAULT_STEP).unwrap();
        let res = compare("H (l, m fixed)", &model.jacobian(&scene.x), &num, DEFAULT_TOLERANCE);
        prop_assert!(res.is_ok(), "{}", res.unwrap_err());
    }

    /// The paper's h equals direct computations of the hit point in the
    /// sensor frame.
    #[test]
    fn paper_h_matches_a_direct_computation(scene in scene_strategy()) {
        let model = paper_model(&scene);
        let z = model.h(&scene.x).expect("the constructed wall must be hit");
        // 1. Independent intersection (Cramer's rule on p_s + g u = a + t d),
        //    then world -> robot frame -> sensor frame.
        let p_s = scene.mount.sensor_position(&scene.x);
        let u = scene.mount.beam_direction(scene.x[2]);
        let (a, d) = (scene.q, scene.w);
        let g = cross(&(a - p_s), &d) / cross(&u, &d);
        let hit = p_s + u * g;
        let direct = h_fixed_hit_point(&scene.mount, &scene.x, hit[0], hit[1]);
        prop_assert!((z - direct).amax() <= 1e-9 * (1.0 + g), "h {z} vs direct {direct}");
        // 2. It is the range reading in the sensor frame: gamma [cos beta, sin beta].
        let from_range = model.z_from_range(g);
        prop_assert!((z - from_range).amax() <= 1e-9 * (1.0 + g), "h {z} vs z_from_range {from_range}");
        // 3. And the exact range model on the same (long) wall, rotated.
        let long = [Segment::new([(a - d * 1e3)[0], (a - d * 1e3)[1]], [(a + d * 1e3)[0], (a + d * 1e3)[1]])];
        let mut exact = LaserRange::new(scene.mount, &long, 1e-4);
        exact.limits = model.limits;
        let gamma = exact.range(&scene.x).expect("the long wall must be hit");
        prop_assert!((z - model.z_from_range(gamma)).amax() <= 1e-9 * (1.0 + g));
    }
}

/// The paper model on the first wall of a scene, as an infinite line, with a
/// 100 m range so that every constructed crossing (0.2-9 m) is a hit.
fn paper_model(scene: &Scene) -> LaserWallPaper<f64> {
    let wall = WallLine::new([-scene.w[1], scene.w[0]], [scene.q[0], scene.q[1]]);
    let mut model = LaserWallPaper::new(scene.mount, wall, 1e-4, 1e-4);
    model.limits = BeamLimits::with_max_range(100.0);
    model
}

/// Eq. 14 for a fixed hit point (l, m) (m, world frame), written from the spec.
fn h_fixed_hit_point(
    mount: &LaserMount<f64>,
    x: &SVector<f64, 3>,
    l: f64,
    m: f64,
) -> SVector<f64, 2> {
    let (s, c) = x[2].sin_cos();
    Vector2::new(
        (l - x[0]) * c + (m - x[1]) * s - mount.x_si,
        (m - x[1]) * c - (l - x[0]) * s - mount.y_si,
    )
}

#[test]
fn laser_range_h_matches_finite_differences() {
    let total = AtomicUsize::new(0);
    let checked = AtomicUsize::new(0);
    let occluded = AtomicUsize::new(0);
    let mut runner = TestRunner::new(runner_config());
    runner
        .run(&scene_strategy(), |scene| {
            total.fetch_add(1, Ordering::Relaxed);
            let model = LaserRange::new(scene.mount, &scene.map, 1e-4);
            if !in_domain(&model, &scene.x) {
                return Ok(());
            }
            match check_measurement_model(&model, &scene.x, DEFAULT_STEP, DEFAULT_TOLERANCE) {
                Ok(true) => {
                    checked.fetch_add(1, Ordering::Relaxed);
                    if model.cast(&scene.x).map(|r| r.segment) != Some(0) {
                        occluded.fetch_add(1, Ordering::Relaxed);
                    }
                    Ok(())
                }
                Ok(false) => Err(TestCaseError::fail(format!(
                    "no measurement at a perturbed point inside the tested domain: {scene:?}"
                ))),
                Err(e) => Err(TestCaseError::fail(format!("{e} at {scene:?}"))),
            }
        })
        .unwrap();
    let (total, checked, occluded) = (
        total.into_inner(),
        checked.into_inner(),
        occluded.into_inner(),
    );
    println!(
        "LaserRange H: {checked} of {total} random points checked ({} skipped outside the tested \
         domain); {occluded} of the checked hits were on an occluding clutter segment",
        total - checked
    );
    assert!(checked >= 1000, "only {checked} points checked");
    assert!(
        checked * 10 >= total * 8,
        "too many points skipped: {checked} of {total} checked"
    );
}

#[test]
fn paper_h_jacobian_is_not_the_derivative_of_h() {
    // The paper's H holds (l, m) fixed; the true derivative of its h is
    // [cos beta, sin beta]^T d gamma/dX (h = gamma [cos beta, sin beta]).
    // They differ by R(theta)^T d(l, m)/dX, whose position block is the
    // projection onto the wall along the beam (norm >= 1): never small.
    let total = AtomicUsize::new(0);
    let differs = AtomicUsize::new(0);
    let min_gap_micro = AtomicUsize::new(usize::MAX);
    let mut runner = TestRunner::new(runner_config());
    runner
        .run(&scene_strategy(), |scene| {
            total.fetch_add(1, Ordering::Relaxed);
            let model = paper_model(&scene);
            let x = scene.x;
            let num = numeric_jacobian(|xx| model.h(xx), |a, b| a - b, &x, DEFAULT_STEP)
                .ok_or_else(|| TestCaseError::fail("no measurement near a constructed hit"))?;
            let h_paper = model.jacobian(&x);
            // The checker flags the paper's H ...
            let res = check_measurement_model(&model, &x, DEFAULT_STEP, DEFAULT_TOLERANCE);
            prop_assert!(
                res.is_err(),
                "paper H agreed with finite differences at {scene:?}"
            );
            // ... by a wide margin ...
            let gap = (h_paper - num).norm();
            prop_assert!(gap >= 0.5, "gap only {gap} at {scene:?}");
            min_gap_micro.fetch_min((gap * 1e6) as usize, Ordering::Relaxed);
            // ... while the finite differences are the exact range derivative
            // rotated into the sensor frame.
            let hit = model.hit(&x).unwrap();
            let dg = range_jacobian(&scene.mount, &x, &hit);
            let (s, c) = scene.mount.beta.sin_cos();
            let exact: SMatrix<f64, 2, 3> = Vector2::new(c, s) * dg;
            let res = compare("dh/dX (exact)", &exact, &num, DEFAULT_TOLERANCE);
            prop_assert!(res.is_ok(), "{}", res.unwrap_err());
            differs.fetch_add(1, Ordering::Relaxed);
            Ok(())
        })
        .unwrap();
    let (total, differs) = (total.into_inner(), differs.into_inner());
    println!(
        "paper H vs finite differences of h: differs at {differs} of {total} points, \
         smallest ||H - dh/dX||_F = {:.3}",
        min_gap_micro.into_inner() as f64 * 1e-6
    );
    assert_eq!(differs, total);
    assert!(total >= 1000);
}

#[test]
fn paper_tan_formula_agrees_with_the_normal_form_on_the_000_wall() {
    // Eq. 13 as the paper writes it (with the spec's [fix]: the robot's own
    // x, y included), on the wall x + y = a, away from its singularities
    // (phi = +-90 deg, and phi = -45 deg where the beam is parallel).
    let a = 1.17;
    let model = LaserWallPaper::new(LaserMount::paper_000(), WallLine::paper_000(a), 1e-4, 1e-4);
    let mut runner = TestRunner::new(runner_config());
    let compared = AtomicUsize::new(0);
    runner
        .run(
            &(
                -1.0..1.0f64,
                -1.0..1.0f64,
                -PI..PI,
                -0.2..0.2f64,
                -0.2..0.2f64,
                -1.0..1.0f64,
            ),
            |(x, y, th, xsi, ysi, beta)| {
                let mut model = model;
                model.mount = LaserMount::new(xsi, ysi, beta);
                let xv = Vector3::new(x, y, th);
                let phi = th + beta;
                let t = phi.tan();
                if phi.cos().abs() < 0.1 || (1.0 + t).abs() < 0.1 {
                    return Ok(());
                }
                let Some(z) = model.h(&xv) else {
                    return Ok(());
                };
                let p_s = model.mount.sensor_position(&xv);
                let l = (a - p_s[1] + p_s[0] * t) / (1.0 + t);
                let m = a - l;
                let direct = h_fixed_hit_point(&model.mount, &xv, l, m);
                prop_assert!((z - direct).amax() <= 1e-9, "h {z} vs tan formula {direct}");
                compared.fetch_add(1, Ordering::Relaxed);
                Ok(())
            },
        )
        .unwrap();
    let compared = compared.into_inner();
    println!("paper tan formula (eq. 13): compared at {compared} of 2000 points");
    assert!(compared >= 500, "only {compared} points compared");
}

#[test]
fn skid_steer_jacobians_at_the_000_test_values() {
    // dT = 0.1 s, D = 0.5 m: spot values of A and W against the spec's matrices.
    let model = SkidSteer::<f64>::pioneer_3at(1e-4, 1e-4);
    let x = Vector3::new(0.2, 0.1, 0.5);
    let u = TreadSpeeds::new(0.08, 0.12, 0.1);
    let (v, dt, d) = (0.1, 0.1, 0.5);
    let a = model.jacobian_state(&x, &u);
    let w = model.jacobian_noise(&x, &u);
    let (s, c) = 0.5f64.sin_cos();
    let a_ref =
        SMatrix::<f64, 3, 3>::new(1.0, 0.0, -dt * v * s, 0.0, 1.0, dt * v * c, 0.0, 0.0, 1.0);
    let w_ref = SMatrix::<f64, 3, 2>::new(
        dt / 2.0 * c,
        dt / 2.0 * c,
        dt / 2.0 * s,
        dt / 2.0 * s,
        -dt / d,
        dt / d,
    );
    assert!((a - a_ref).amax() < 1e-15);
    assert!((w - w_ref).amax() < 1e-15);
    let f = model.f(&x, &u, &SVector::zeros());
    assert!((f[2] - (0.5 + dt * 0.04 / d)).abs() < 1e-15);
}

#[test]
fn the_checker_catches_a_wrong_range_jacobian() {
    // The exact range Jacobian without the `gamma n.u'` term of d gamma/dtheta
    // (the beam's rotation) must fail the check, at the 000 test pose.
    struct Wrong<'a>(LaserRange<'a, f64>);
    impl MeasurementModel<f64, 3, 1> for Wrong<'_> {
        fn evaluate(
            &self,
            x: &SVector<f64, 3>,
            jacobian: Option<&mut SMatrix<f64, 1, 3>>,
        ) -> Option<SVector<f64, 1>> {
            if let Some(j) = jacobian {
                let hit = self.0.cast(x).unwrap().hit;
                let n = hit.normal;
                let dps = self.0.mount.sensor_position_dtheta(x[2]);
                *j = self.0.jacobian(x);
                j[2] = -n.dot(&dps) / hit.n_dot_u;
            }
            self.0.h(x)
        }
        fn noise(&self, x: &SVector<f64, 3>) -> SMatrix<f64, 1, 1> {
            self.0.noise(x)
        }
    }
    let map = [Segment::new([2.17, -1.0], [-0.83, 2.0])];
    let right = LaserRange::new(LaserMount::paper_000(), &map, 1e-4);
    let x = Vector3::zeros();
    assert_eq!(
        check_measurement_model(&right, &x, DEFAULT_STEP, DEFAULT_TOLERANCE),
        Ok(true)
    );
    let err =
        check_measurement_model(&Wrong(right), &x, DEFAULT_STEP, DEFAULT_TOLERANCE).unwrap_err();
    assert_eq!((err.jacobian, err.row, err.col), ("H", 0, 2));
    assert!((err.analytic + 0.17).abs() < 1e-12 && (err.numeric + 1.17).abs() < 1e-6);
}
