//! Slip rejection of paper 004 (section 3.2; spec section 5) on a fixed
//! scenario, and a cross-check of the tricycle formulas against the EKF's
//! models (`locus_models::TricycleRear` / `TricycleFront`).
//!
//! Scenario, spec's \[assumed\] robot (rear R 0.05 m, front R 0.06 m,
//! D 0.40 m, L 0.45 m, every encoder 500 lines x4 = 2000 counts per
//! revolution, steering 0.18 deg per count):
//!
//! * 10 m straight along +x, then a 90 deg left arc of radius 2 m (of the
//!   rear-axle midpoint); true final pose (12 m, 2 m, 90 deg);
//! * 1 m/s sampled at 100 Hz: one odometry step per 1 cm of travel;
//! * slip: the rear-left wheel over-counts by 10 % over three 0.3 m bumps
//!   on the straight (at 2, 5 and 8 m); the front wheel over-counts by 15 %
//!   over a 1 m slippery patch on the arc (1 m into it, 1 m of the front
//!   wheel's own travel).
//!
//! Counts are generated from the true path: each wheel's travel (slip
//! included) is integrated exactly, the running total is turned into
//! counts and the integer part taken, so fractional remainders carry over
//! from step to step. The steering encoder reads the true steering angle
//! (atan(L / 2 m) = 12.68 deg on the arc) rounded to its 0.18 deg count.
//!
//! `cargo test -p locus-odometry --test slip -- --nocapture` prints the
//! tables.

use core::f64::consts::{FRAC_PI_2, PI};

use locus_core::{Pose, wrap_angle};
use locus_models::{FrontReading, RearCounts, TricycleFront, TricycleRear};
use locus_odometry::cordic::{Cordic, Libm, SinCos};
use locus_odometry::redundant::{Integration, Odometry, Reading, Selection, Tricycle, select};
use proptest::prelude::*;

/// Rear-axle travel per odometry step, m (1 m/s at 100 Hz).
const STEP: f64 = 0.01;
/// Length of the straight, m.
const STRAIGHT: f64 = 10.0;
/// Radius of the arc (rear-axle midpoint), m.
const RADIUS: f64 = 2.0;
/// End of the path: the straight plus a quarter circle, m.
const END: f64 = STRAIGHT + FRAC_PI_2 * RADIUS;
/// Rear-left bumps: start (m along the path), each 0.3 m of wheel travel.
const BUMPS: [f64; 3] = [2.0, 5.0, 8.0];
const BUMP_LEN: f64 = 0.3;
const BUMP_GAIN: f64 = 1.10;
/// Front slippery patch: start (m along the path), 1 m of front travel.
const PATCH_START: f64 = STRAIGHT + 1.0;
const PATCH_FRONT_LEN: f64 = 1.0;
const PATCH_GAIN: f64 = 1.15;

fn robot() -> Tricycle<f64> {
    Tricycle::assumed()
}

/// Curvature of the rear-axle path at `s`, 1/m (left positive).
fn curvature(s: f64) -> f64 {
    if s < STRAIGHT { 0.0 } else { 1.0 / RADIUS }
}

/// True steering angle at `s`: `tan(phi) = kappa L`.
fn steering(s: f64) -> f64 {
    (curvature(s) * robot().wheelbase).atan()
}

/// Front-wheel travel per metre of rear-axle travel, `1 / cos(phi)`.
fn front_ratio(s: f64) -> f64 {
    (1.0 + (curvature(s) * robot().wheelbase).powi(2)).sqrt()
}

fn patch_end() -> f64 {
    PATCH_START + PATCH_FRONT_LEN / front_ratio(PATCH_START)
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum W {
    RearLeft,
    RearRight,
    Front,
}

/// Counted travel of a wheel per metre of rear-axle travel at `s`: the
/// true ratio (wheel path / axle path) times the over-count, if any.
fn rate(w: W, s: f64, slip: bool) -> f64 {
    let half_track = 0.5 * robot().track;
    let k = curvature(s);
    match w {
        W::RearLeft => {
            let bump = slip && BUMPS.iter().any(|&b| s >= b && s < b + BUMP_LEN);
            (1.0 - k * half_track) * if bump { BUMP_GAIN } else { 1.0 }
        }
        W::RearRight => 1.0 + k * half_track,
        W::Front => {
            let patch = slip && s >= PATCH_START && s < patch_end();
            front_ratio(s) * if patch { PATCH_GAIN } else { 1.0 }
        }
    }
}

/// Counted travel of a wheel while the axle goes from `s0` to `s1`: the
/// rates are piecewise constant, so split at every breakpoint and sum.
fn travel(w: W, s0: f64, s1: f64, slip: bool) -> f64 {
    let mut cuts = vec![s0, s1, STRAIGHT, PATCH_START, patch_end()];
    for b in BUMPS {
        cuts.extend([b, b + BUMP_LEN]);
    }
    cuts.retain(|&c| c >= s0 && c <= s1);
    cuts.sort_by(f64::total_cmp);
    cuts.windows(2)
        .map(|p| (p[1] - p[0]) * rate(w, 0.5 * (p[0] + p[1]), slip))
        .sum()
}

/// The encoder readings of every step along the path.
fn readings(slip: bool) -> Vec<Reading> {
    let t = robot();
    let wheels = [
        (W::RearLeft, t.rear),
        (W::RearRight, t.rear),
        (W::Front, t.front),
    ];
    let mut total = [0.0f64; 3]; // counted travel so far, m
    let mut counted = [0i64; 3]; // counts so far
    let mut out = Vec::new();
    let mut k = 0u32;
    loop {
        let s0 = f64::from(k) * STEP;
        if s0 >= END - 1e-12 {
            break;
        }
        let s1 = (f64::from(k + 1) * STEP).min(END);
        let mut n = [0i32; 3];
        for (i, (w, wheel)) in wheels.iter().enumerate() {
            total[i] += travel(*w, s0, s1, slip);
            let c = wheel.counts_for(total[i]).floor() as i64;
            n[i] = (c - counted[i]) as i32;
            counted[i] = c;
        }
        let n_s = (steering(0.5 * (s0 + s1)) / t.steering.quantum()).round() as i32;
        out.push(Reading {
            n_l: n[0],
            n_r: n[1],
            n_f: n[2],
            n_s,
        });
        k += 1;
    }
    out
}

/// Final position error (m) and heading error (deg) of dead reckoning.
fn run<S: SinCos<f64> + Copy>(
    readings: &[Reading],
    selection: Selection,
    integration: Integration,
    trig: S,
) -> (f64, f64) {
    let mut odo = Odometry::new(robot(), selection, integration, trig, Pose::default());
    for r in readings {
        odo.step(r);
    }
    let p = odo.pose();
    let pos = (p.x - (STRAIGHT + RADIUS)).hypot(p.y - RADIUS);
    let head = wrap_angle(p.theta - FRAC_PI_2).to_degrees();
    (pos, head)
}

const SELECTIONS: [(&str, Selection); 4] = [
    ("rear only", Selection::Rear),
    ("front only", Selection::Front),
    ("component-wise min", Selection::ComponentMin),
    ("consistent set", Selection::ConsistentSet),
];

#[test]
fn slip_rejection_scenario() {
    let slip = readings(true);
    let clean = readings(false);
    assert_eq!(slip.len(), clean.len());
    // Sanity of the generator: total counts against the path lengths.
    let t = robot();
    let sum = |rs: &[Reading], f: fn(&Reading) -> i32| rs.iter().map(f).sum::<i32>();
    let left_clean = t.rear.distance(sum(&clean, |r| r.n_l));
    let left_true = STRAIGHT + FRAC_PI_2 * (RADIUS - 0.5 * t.track);
    assert!((left_clean - left_true).abs() <= t.rear.quantum());
    let left_slip = t.rear.distance(sum(&slip, |r| r.n_l));
    let extra = 3.0 * BUMP_LEN * (BUMP_GAIN - 1.0);
    assert!((left_slip - left_true - extra).abs() <= 2.0 * t.rear.quantum());
    let front_slip = t.front.distance(sum(&slip, |r| r.n_f));
    let front_true = STRAIGHT + FRAC_PI_2 * RADIUS * front_ratio(END);
    let extra = PATCH_FRONT_LEN * (PATCH_GAIN - 1.0);
    assert!((front_slip - front_true - extra).abs() <= 2.0 * t.front.quantum());

    println!(
        "Slip scenario: 10 m straight + 90 deg left arc R 2 m ({} steps of 1 cm); \
         rear-left +10 % on 3 x 0.3 m bumps, front +15 % on a 1 m patch on the arc.",
        slip.len()
    );
    println!("Final pose error: position |dp| (m), heading dtheta (deg, + = too far left).");
    let configs: [(&str, Integration, Option<Cordic>); 3] = [
        ("libm, midpoint", Integration::Midpoint, None),
        ("libm, Euler (paper)", Integration::Euler, None),
        (
            "CORDIC 16/16, midpoint",
            Integration::Midpoint,
            Some(Cordic::PAPER),
        ),
    ];
    println!(
        "{:<24} {:<20} | {:>9} {:>9} | {:>9} {:>9}",
        "sin/cos, heading", "odometry", "slip: m", "deg", "no slip: m", "deg"
    );
    let mut slip_errors = Vec::new();
    for (cname, integration, cordic) in configs {
        for (name, selection) in SELECTIONS {
            let go = |rs: &[Reading]| match cordic {
                Some(c) => run(rs, selection, integration, c),
                None => run(rs, selection, integration, Libm),
            };
            let (ps, hs) = go(&slip);
            let (pc, hc) = go(&clean);
            println!("{cname:<24} {name:<20} | {ps:>9.4} {hs:>+9.3} | {pc:>10.4} {hc:>+9.3}");
            if cname == "libm, midpoint" {
                slip_errors.push((name, ps, hs.abs(), pc, hc.abs()));
            }
        }
        println!();
    }

    // Under slip the better slip-rejecting variant (by position error)
    // beats both single sources, in position and in heading.
    let [rear, front, cmin, consistent] = slip_errors[..] else {
        unreachable!()
    };
    let best = if cmin.1 <= consistent.1 {
        cmin
    } else {
        consistent
    };
    for single in [rear, front] {
        assert!(
            best.1 < single.1 && best.2 < single.2,
            "{} ({:.4} m, {:.3} deg) does not beat {} ({:.4} m, {:.3} deg)",
            best.0,
            best.1,
            best.2,
            single.0,
            single.1,
            single.2
        );
    }
    // The single sources do see the slip.
    assert!(rear.1 > 0.5 && front.1 > 0.1, "{rear:?} {front:?}");
}

/// The cost of the minimum rule without slip: per step it takes the smaller
/// of two quantised values, so the path comes out short on average.
#[test]
fn minimum_rule_is_biased_low_without_slip() {
    let clean = readings(false);
    let t = robot();
    let mut odo = Odometry::new(
        t,
        Selection::ComponentMin,
        Integration::Midpoint,
        Libm,
        Pose::default(),
    );
    let (mut chosen, mut rear_len, mut front_len) = (0.0, 0.0, 0.0);
    for r in &clean {
        let (rear, front) = odo.increments(r);
        rear_len += rear.path_length_sq().sqrt();
        front_len += front.path_length_sq().sqrt();
        let inc = odo.step(r);
        chosen += inc.path_length_sq().sqrt();
        assert_eq!(inc, select(Selection::ComponentMin, &rear, &front));
    }
    println!(
        "No slip, path length: true {END:.4} m, rear {rear_len:.4}, front {front_len:.4}, \
         component-wise min {chosen:.4} ({:+.4} m)",
        chosen - END
    );
    assert!((rear_len - END).abs() < 2e-3 && (front_len - END).abs() < 2e-3);
    assert!(chosen < rear_len.min(front_len));
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 4000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// The odometry's rear formulas equal `locus_models::TricycleRear::increments`.
    #[test]
    fn rear_matches_locus_models(n_l in -20_000i32..20_000, n_r in -20_000i32..20_000) {
        let m = robot().rear_motion(n_l, n_r);
        let (ds, dth) = TricycleRear::<f64>::assumed().increments(&RearCounts::from_counts(n_l, n_r));
        prop_assert!((m.ds - ds).abs() <= 1e-12 * (1.0 + ds.abs()), "{} {}", m.ds, ds);
        prop_assert!((m.dtheta - dth).abs() <= 1e-12 * (1.0 + dth.abs()), "{} {}", m.dtheta, dth);
    }

    /// The front formulas equal `locus_models::TricycleFront::increments`,
    /// including the clamping of steering readings beyond +-40 deg.
    #[test]
    fn front_matches_locus_models(n_f in -20_000i32..20_000, phi in -1.5f64..1.5) {
        let m = robot().front_motion(n_f, phi, &Libm);
        let (ds, dth) = TricycleFront::<f64>::assumed().increments(&FrontReading::from_count(n_f, phi));
        prop_assert!((m.ds - ds).abs() <= 1e-12 * (1.0 + ds.abs()), "{} {}", m.ds, ds);
        prop_assert!((m.dtheta - dth).abs() <= 1e-12 * (1.0 + dth.abs()), "{} {}", m.dtheta, dth);
    }

    /// The same through the steering encoder: a count beyond the limit is
    /// clamped, `checked_angle` rejects it, and the model agrees.
    #[test]
    fn steering_counts_clamp(n_f in -5_000i32..5_000, n_s in -400i32..400) {
        let t = robot();
        let m = t.front_motion_counts(n_f, n_s, &Libm);
        let raw = t.steering.raw_angle(n_s);
        let (ds, dth) = TricycleFront::<f64>::assumed().increments(&FrontReading::from_count(n_f, raw));
        prop_assert!((m.ds - ds).abs() <= 1e-12 * (1.0 + ds.abs()));
        prop_assert!((m.dtheta - dth).abs() <= 1e-12 * (1.0 + dth.abs()));
        let limit = 40f64.to_radians();
        prop_assert_eq!(t.steering.checked_angle(n_s).is_ok(), raw.abs() <= limit);
        prop_assert!(t.steering.angle(n_s).abs() <= limit);
    }

    /// Euler increments are the paper's eq. 1-2 and 4-5 (with the spec's
    /// y fix): `(ds cos(theta), ds sin(theta))`.
    #[test]
    fn euler_increment(theta in -PI..PI, n_f in -500i32..500, n_s in -200i32..200) {
        let t = robot();
        let m = t.front_motion_counts(n_f, n_s, &Libm);
        let inc = m.increment(theta, Integration::Euler, &Libm);
        let phi = t.steering.angle(n_s);
        let ds_f = t.front.distance(n_f);
        prop_assert!((inc.dx - ds_f * phi.cos() * theta.cos()).abs() < 1e-15);
        prop_assert!((inc.dy - ds_f * phi.cos() * theta.sin()).abs() < 1e-15);
        prop_assert!((inc.dtheta - ds_f * phi.sin() / 0.45).abs() < 1e-15);
    }
}
