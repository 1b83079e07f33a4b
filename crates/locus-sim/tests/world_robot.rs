//! World ray casts, exact ground-truth kinematics and slip zones.

use core::f64::consts::{FRAC_PI_2, PI, TAU};

use locus_core::wrap_angle;
use locus_models::laser_wall::LaserMount;
use locus_sim::robot::{
    DriveCommand, Kinematics, Pose, Robot, RobotError, Slip, SlipSchedule, TravelByWheel, Wheel,
};
use locus_sim::world::World;
use rand::SeedableRng;
use rand::rngs::StdRng;

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn square_arena_raycasts_hit_the_right_wall() {
    let w = World::square_arena();
    // From the origin: east hits x+ (index 1) at 1 m, south hits y- (0).
    let h = w.raycast([0.0, 0.0], 0.0, 8.0).unwrap();
    assert_eq!(h.wall_index, 1);
    assert!(close(h.range, 1.0, 1e-12));
    let h = w.raycast([0.0, 0.0], -FRAC_PI_2, 8.0).unwrap();
    assert_eq!(h.wall_index, 0);
    assert!(close(h.range, 1.0, 1e-12));
    // North from the origin: y+ spans x in [-0.15, 0.85], hit at 1 m.
    let h = w.raycast([0.0, 0.0], FRAC_PI_2, 8.0).unwrap();
    assert_eq!(h.wall_index, 2);
    // West: x- spans y in [-0.15, 0.85].
    let h = w.raycast([0.0, 0.0], PI, 8.0).unwrap();
    assert_eq!(h.wall_index, 3);
    // On the path (0.15 m from the walls), looking right (south) on side y-.
    let h = w.raycast([-0.5, -0.85], -FRAC_PI_2, 0.30).unwrap();
    assert_eq!(h.wall_index, 0);
    assert!(close(h.range, 0.15, 1e-12));
    assert!(close(h.point[0], -0.5, 1e-12) && close(h.point[1], -1.0, 1e-12));
    // Past the end of the y- wall (x > 0.15): no wall within range.
    assert!(w.raycast([0.5, -0.85], -FRAC_PI_2, 0.30).is_none());
    // Out of range.
    assert!(w.raycast([0.0, 0.0], 0.0, 0.9).is_none());
    // 45 degrees from the origin leaves through the corner gap: x+ ends at
    // y = 0.15 and y+ at x = 0.85.
    assert!(w.raycast([0.0, 0.0], PI / 4.0, 8.0).is_none());
    assert!(World::empty().raycast([0.0, 0.0], 0.3, 8.0).is_none());
}

#[test]
fn wall45_matches_paper_test_pose() {
    let w = World::wall45(1.17);
    let pose = Pose::new(0.0, 0.0, 0.0);
    let h = w
        .raycast_mount(&pose, &LaserMount::paper_000(), 8.0)
        .unwrap();
    assert_eq!(h.wall_index, 0);
    assert!(close(h.range, 1.0, 1e-12));
    // Looking away from the wall: nothing.
    assert!(w.raycast([0.0, 0.0], PI, 8.0).is_none());
}

fn diff_drive() -> Kinematics {
    Kinematics::DifferentialDrive {
        wheelbase: 0.112,
        wheel_radius: 0.028,
    }
}

#[test]
fn straight_line_is_exact() {
    let mut r = Robot::new(diff_drive(), Pose::new(0.1, -0.2, 0.3));
    let out = r
        .run(
            &DriveCommand::Wheels {
                left: 0.2,
                right: 0.2,
            },
            0.05,
            100,
            1,
        )
        .unwrap();
    let d = 0.2 * 0.05 * 100.0;
    assert!(close(r.pose.x, 0.1 + d * 0.3f64.cos(), 1e-12));
    assert!(close(r.pose.y, -0.2 + d * 0.3f64.sin(), 1e-12));
    assert!(close(r.pose.theta, 0.3, 1e-15));
    let sum: f64 = out.iter().map(|o| o.true_travel.left).sum();
    assert!(close(sum, d, 1e-12));
    assert_eq!(out[0].measured_travel, out[0].true_travel);
}

#[test]
fn full_circle_closes_on_itself() {
    // Wheel speeds giving w = 0.5 rad/s; 4*pi s is one full turn, in large
    // steps (exact arcs need no small dt).
    let k = diff_drive();
    let (vl, vr) = (0.1, 0.1 + 0.5 * 0.112);
    for n in [7, 40, 1000] {
        let mut r = Robot::new(k, Pose::new(0.3, 0.4, 1.0));
        let dt = 2.0 * TAU / f64::from(n);
        let out = r
            .run(
                &DriveCommand::Wheels {
                    left: vl,
                    right: vr,
                },
                dt,
                n as usize,
                1,
            )
            .unwrap();
        assert!(close(r.pose.x, 0.3, 1e-12), "n={n} x={}", r.pose.x);
        assert!(close(r.pose.y, 0.4, 1e-12), "n={n} y={}", r.pose.y);
        assert!(close(wrap_angle(r.pose.theta - 1.0), 0.0, 1e-12));
        // Halfway round: the opposite end of the diameter 2 v / w.
        let half = out[(n as usize) / 2 - 1].pose;
        if n % 2 == 0 {
            let diam = 2.0 * (0.5 * (vl + vr)) / 0.5;
            let dist = ((half.x - 0.3).powi(2) + (half.y - 0.4).powi(2)).sqrt();
            assert!(close(dist, diam, 1e-12), "n={n} dist={dist}");
        }
    }
}

#[test]
fn tricycle_and_skid_steer_arcs() {
    // Tricycle at constant steering: circle of radius L / tan(phi) about the
    // rear axle midpoint; rear wheels' travel differs by w D dt.
    let (l, d, phi, s) = (0.45, 0.40, 0.3, 0.5);
    let k = Kinematics::Tricycle {
        wheelbase: l,
        rear_track: d,
    };
    let w = s * f64::sin(phi) / l;
    let period = TAU / w;
    let mut r = Robot::new(k, Pose::default());
    let out = r
        .run(
            &DriveCommand::Steered {
                speed: s,
                steering: phi,
            },
            period / 50.0,
            25,
            1,
        )
        .unwrap();
    let radius = l / phi.tan();
    assert!(close(r.pose.x, 0.0, 1e-12) && close(r.pose.y, 2.0 * radius, 1e-12));
    let o = out[0];
    assert!(close(
        o.true_travel.right - o.true_travel.left,
        w * d * period / 50.0,
        1e-12
    ));
    assert!(close(o.true_travel.front, s * period / 50.0, 1e-15));
    // Skid steer spinning in place.
    let k = Kinematics::SkidSteer {
        effective_track: 0.5,
    };
    let (p, t) = k
        .step(
            &Pose::default(),
            &DriveCommand::Wheels {
                left: -0.25,
                right: 0.25,
            },
            1.0,
        )
        .unwrap();
    assert!(close(p.theta, 1.0, 1e-15) && p.x == 0.0 && p.y == 0.0);
    assert_eq!(
        t,
        TravelByWheel {
            left: -0.25,
            right: 0.25,
            front: 0.0
        }
    );
    // Mismatched command and bad dt are errors that leave the robot alone.
    let mut r = Robot::new(k, Pose::default());
    assert!(matches!(
        r.step(
            &DriveCommand::Steered {
                speed: 1.0,
                steering: 0.0
            },
            0.1
        ),
        Err(RobotError::CommandMismatch { .. })
    ));
    assert!(
        r.step(
            &DriveCommand::Wheels {
                left: 1.0,
                right: 1.0
            },
            f64::NAN
        )
        .is_err()
    );
    assert_eq!(r.pose, Pose::default());
    assert_eq!(r.odometer, TravelByWheel::default());
}

#[test]
fn slip_scales_only_the_affected_wheel_inside_the_zone() {
    // Rear-left over-counts 10 % over three 0.3 m bumps starting at 1.0 m,
    // 0.5 m apart: extra = 0.1 * 0.9 m = 0.09 m on the left only.
    let slip = SlipSchedule::bumps(Wheel::Left, 1.0, 0.3, 0.5, 3, 1.1);
    let mut r = Robot::new(diff_drive(), Pose::default()).with_slip(slip);
    // 0.07 m steps: zone edges fall inside steps (partial overlap).
    let out = r
        .run(
            &DriveCommand::Wheels {
                left: 0.7,
                right: 0.7,
            },
            0.1,
            50,
            1,
        )
        .unwrap();
    let (mut tl, mut ml, mut tr, mut mr) = (0.0, 0.0, 0.0, 0.0);
    for (i, o) in out.iter().enumerate() {
        let s0 = 0.07 * i as f64;
        let s1 = s0 + 0.07;
        let in_zone = [(1.0, 1.3), (1.5, 1.8), (2.0, 2.3)]
            .iter()
            .any(|&(a, b)| s1 > a + 1e-12 && s0 < b - 1e-12);
        if in_zone {
            assert!(o.measured_travel.left > o.true_travel.left, "step {i}");
        } else {
            assert!(
                close(o.measured_travel.left, o.true_travel.left, 1e-15),
                "step {i}"
            );
        }
        assert_eq!(o.measured_travel.right, o.true_travel.right);
        assert!(o.measured_travel.left <= 1.1 * o.true_travel.left + 1e-15);
        tl += o.true_travel.left;
        ml += o.measured_travel.left;
        tr += o.true_travel.right;
        mr += o.measured_travel.right;
    }
    assert!(close(tl, 3.5, 1e-12));
    assert!(close(ml - tl, 0.09, 1e-12), "extra = {}", ml - tl);
    assert_eq!(mr, tr);
    // Driving backwards, slip over-counts in the direction of motion.
    let zone = Slip {
        wheel: Wheel::Right,
        start: 0.0,
        end: 10.0,
        scale: 1.5,
    };
    let mut r =
        Robot::new(diff_drive(), Pose::default()).with_slip(SlipSchedule { zones: vec![zone] });
    let o = r
        .step(
            &DriveCommand::Wheels {
                left: -0.2,
                right: -0.2,
            },
            1.0,
        )
        .unwrap();
    assert!(close(o.measured_travel.right, -0.3, 1e-15));
    assert_eq!(o.measured_travel.left, -0.2);
}

#[test]
fn random_bumps_are_seeded() {
    let make = |seed| {
        let mut rng = StdRng::seed_from_u64(seed);
        SlipSchedule::random_bumps(
            &mut rng,
            Wheel::Left,
            (0.0, 5.0),
            4,
            (0.1, 0.3),
            (1.05, 1.2),
        )
    };
    let a = make(7);
    assert_eq!(a, make(7));
    assert_ne!(a, make(8));
    assert_eq!(a.zones.len(), 4);
    for z in &a.zones {
        assert!((0.0..5.0).contains(&z.start));
        assert!(z.end - z.start >= 0.1 && z.end - z.start < 0.3);
        assert!((1.05..1.2).contains(&z.scale));
    }
}
