//! Closed-loop tests of the path controller on a perfect unicycle.

use core::f64::consts::{FRAC_PI_2, PI};

use locus_control::{
    Config, Controller, Direction, FollowPath, Point, Pose, Routine, Segment, Twist, wheel_speeds,
    wrap_angle,
};
use proptest::prelude::*;

const DT: f64 = 0.01;

/// One exact step of a unicycle (arc integration).
fn step(pose: Pose, c: Twist, dt: f64) -> Pose {
    let dtheta = c.w * dt;
    let mid = pose.theta + dtheta / 2.0;
    Pose::new(
        pose.x + c.v * dt * mid.cos(),
        pose.y + c.v * dt * mid.sin(),
        pose.theta + dtheta,
    )
}

/// Runs `controller` from `pose` for at most `steps`, calling `visit` after each step;
/// returns the final pose and whether it reported done.
fn run(
    controller: &mut impl Controller,
    mut pose: Pose,
    steps: usize,
    mut visit: impl FnMut(usize, Pose, Twist),
) -> (Pose, bool) {
    for i in 0..steps {
        let c = controller.command(pose);
        assert!(c.v.is_finite() && c.w.is_finite());
        if c.done {
            return (pose, true);
        }
        pose = step(pose, c, DT);
        visit(i, pose, c);
    }
    (pose, false)
}

#[test]
fn follow_line_converges_from_offset_start() {
    let config = Config::default();
    let mut r = Routine::new(
        Segment::FollowLine {
            from: Point::new(0.0, 0.0),
            to: Point::new(3.0, 0.0),
        },
        config,
    );
    let mut max_late = 0.0_f64;
    let (end, done) = run(&mut r, Pose::new(0.0, 0.2, 0.5), 100_000, |i, p, c| {
        assert!(c.v.abs() <= config.v_ref + 1e-12 && c.w.abs() <= config.w_ref + 1e-12);
        if i as f64 * DT > 10.0 {
            max_late = max_late.max(p.y.abs());
        }
    });
    assert!(done);
    assert!(max_late < 0.01, "cross-track after transient {max_late}");
    assert!(end.x >= 3.0 && end.x < 3.01, "{end:?}");
    assert!(wrap_angle(end.theta).abs() < 0.05);
}

#[test]
fn follow_line_any_direction_left_and_right() {
    for &(from, to, start) in &[
        ((1.0, 1.0), (-1.0, -1.0), Pose::new(1.2, 0.9, 0.0)),
        ((0.0, 0.0), (0.0, -2.0), Pose::new(-0.3, 0.1, PI)),
    ] {
        let mut r = Routine::new(
            Segment::FollowLine {
                from: Point::new(from.0, from.1),
                to: Point::new(to.0, to.1),
            },
            Config::default(),
        );
        let (end, done) = run(&mut r, start, 100_000, |_, _, _| {});
        assert!(done);
        let d = ((end.x - to.0).powi(2) + (end.y - to.1).powi(2)).sqrt();
        assert!(d < 0.01, "{end:?}");
    }
}

#[test]
fn follow_circle_holds_radius_both_directions() {
    for direction in [Direction::Ccw, Direction::Cw] {
        let centre = Point::new(0.5, -0.2);
        let radius = 0.4;
        let mut r = Routine::new(
            Segment::FollowCircle {
                centre,
                radius,
                direction,
                arc: None,
            },
            Config::default(),
        );
        let mut max_err = 0.0_f64;
        let mut turn = 0.0;
        let start = Pose::new(0.5 + 0.5, -0.2, 0.0);
        let (_, done) = run(&mut r, start, 60_000, |i, p, c| {
            if i as f64 * DT > 20.0 {
                let rho = (p.x - centre.x).hypot(p.y - centre.y);
                max_err = max_err.max((rho - radius).abs());
                turn += c.w * DT;
            }
        });
        assert!(!done);
        assert!(max_err < 0.005, "{direction:?}: radius error {max_err}");
        assert!(turn * direction.sign() > 0.0, "{direction:?} turned {turn}");
    }
}

#[test]
fn follow_circle_stops_after_arc() {
    let mut r = Routine::new(
        Segment::FollowCircle {
            centre: Point::new(0.0, 0.0),
            radius: 0.5,
            direction: Direction::Ccw,
            arc: Some(FRAC_PI_2),
        },
        Config::default(),
    );
    let (end, done) = run(
        &mut r,
        Pose::new(0.5, 0.0, FRAC_PI_2),
        100_000,
        |_, _, _| {},
    );
    assert!(done);
    assert!(end.x.abs() < 0.01 && (end.y - 0.5).abs() < 0.01, "{end:?}");
    assert!(r.is_done());
    assert_eq!(r.command(end), Twist::DONE);
}

#[test]
fn go_xy_theta_reaches_target() {
    let config = Config::default();
    for &(x, y, theta, start) in &[
        (0.5, 0.3, 1.0, Pose::new(0.0, 0.0, 0.0)),
        (-0.4, 0.2, -2.5, Pose::new(0.1, -0.1, 3.0)),
        (0.0, 0.0, 0.0, Pose::new(0.0, 0.0, PI / 2.0)),
    ] {
        let mut r = Routine::new(Segment::GoXYTheta { x, y, theta }, config);
        let (end, done) = run(&mut r, start, 200_000, |_, _, _| {});
        assert!(done, "target ({x}, {y}, {theta})");
        assert!(
            (end.x - x).hypot(end.y - y) <= config.pos_tol * 2.0,
            "{end:?}"
        );
        assert!(
            wrap_angle(end.theta - theta).abs() <= config.heading_tol,
            "{end:?}"
        );
    }
}

#[test]
fn square_path_visits_corners_counter_clockwise() {
    let h = locus_control::SQUARE_HALF_SIDE;
    let corners = [(h, -h), (h, h), (-h, h), (-h, -h)];
    let mut path = FollowPath::square(Config::default());
    let start = Pose::new(-h, -h, 0.0);
    let mut next = 0;
    let mut max_off = 0.0_f64;
    let (end, done) = run(&mut path, start, 200_000, |_, p, _| {
        if next < 4 {
            let (cx, cy) = corners[next];
            if (p.x - cx).hypot(p.y - cy) < 0.03 {
                next += 1;
            }
        }
        // Distance from the square's outline never gets large.
        let off = (p.x.abs() - h).abs().min((p.y.abs() - h).abs());
        max_off = max_off.max(off);
    });
    assert!(done && path.is_done());
    assert_eq!(next, 4, "corners visited in order");
    assert!(max_off < 0.05, "left the square by {max_off}");
    assert!((end.x - start.x).hypot(end.y - start.y) < 0.03, "{end:?}");
}

#[test]
fn path_switches_in_same_step_and_empty_path_is_done() {
    let mut empty = FollowPath::<0>::new([], Config::default());
    assert_eq!(empty.command(Pose::default()), Twist::DONE);
    let seg = Segment::FollowLine {
        from: Point::new(0.0, 0.0),
        to: Point::new(1.0, 0.0),
    };
    let mut path = FollowPath::new([seg, seg], Config::default());
    // Past the end of the first: it finishes and the second (also done) too.
    assert_eq!(path.command(Pose::new(2.0, 0.0, 0.0)), Twist::DONE);
    assert_eq!(path.index(), 2);
    path.reset();
    assert_eq!(path.index(), 0);
    assert!(!path.command(Pose::new(0.5, 0.0, 0.0)).done);
}

#[test]
fn wheel_speed_formula() {
    let c = Twist {
        v: 0.1,
        w: 0.5,
        done: false,
    };
    let (v1, v2) = wheel_speeds(c, 0.12);
    assert!((v1 - 0.13).abs() < 1e-12);
    assert!((v2 - 0.07).abs() < 1e-12);
}

proptest! {
    #[test]
    fn wheel_speeds_invert(v in -1.0..1.0_f64, w in -5.0..5.0_f64, b in 0.05..0.5_f64) {
        let (v1, v2) = wheel_speeds(Twist { v, w, done: false }, b);
        prop_assert!(((v1 + v2) / 2.0 - v).abs() < 1e-12);
        prop_assert!(((v1 - v2) / b - w).abs() < 1e-9);
    }

    #[test]
    fn commands_are_saturated(x in -3.0..3.0_f64, y in -3.0..3.0_f64, t in -10.0..10.0_f64) {
        let config = Config::default();
        for seg in locus_control::square(0.85) {
            let c = Routine::new(seg, config).command(Pose::new(x, y, t));
            prop_assert!(c.v.abs() <= config.v_ref && c.w.abs() <= config.w_ref);
        }
    }
}

#[test]
fn degenerate_segments_finish_at_once() {
    let p = Point::new(0.3, 0.3);
    for seg in [
        Segment::FollowLine { from: p, to: p },
        Segment::FollowCircle {
            centre: p,
            radius: 0.0,
            direction: Direction::Cw,
            arc: None,
        },
    ] {
        assert_eq!(
            Routine::new(seg, Config::default()).command(Pose::default()),
            Twist::DONE
        );
    }
}

#[test]
fn non_finite_pose_gives_finite_command() {
    let mut r = Routine::new(
        Segment::GoXYTheta {
            x: 1.0,
            y: 0.0,
            theta: 0.0,
        },
        Config::default(),
    );
    let c = r.command(Pose::new(f64::NAN, 0.0, 0.0));
    assert!(c.v.is_finite() && c.w.is_finite());
}
