//! `SquareSim`, the stepping form of the square closed loop: the same run
//! as `run_square`, live parameter changes, teleoperation, correction
//! details.

use locus_sim::closed_loop::Error;
use locus_sim::{LiveParams, SquareConfig, SquareSim, StepRecord, Teleop, run_square};

fn one_lap() -> SquareConfig {
    SquareConfig {
        laps: 1,
        ..SquareConfig::default()
    }
}

#[test]
fn stepping_gives_the_records_of_run_square() {
    let cfg = one_lap();
    let mut expected: Vec<StepRecord> = Vec::new();
    run_square(&cfg, 7, &mut |r: &StepRecord| expected.push(*r)).unwrap();
    let mut sim = SquareSim::new(&cfg, 7).unwrap().with_details(true);
    let mut got = Vec::new();
    let mut details = 0;
    while let Some(s) = sim.step(None).unwrap() {
        details += usize::from(s.correction.is_some());
        got.push(s.record);
    }
    assert_eq!(got, expected);
    assert!(sim.is_finished());
    assert_eq!(sim.laps(), 1);
    assert!(details > 100, "only {details} corrections detailed");
    assert!(sim.step(None).unwrap().is_none());
}

#[test]
fn correction_detail_is_consistent_with_the_record() {
    let mut sim = SquareSim::new(&one_lap(), 3).unwrap().with_details(true);
    let mut checked = 0;
    while let Some(s) = sim.step(None).unwrap() {
        let Some(d) = s.correction else { continue };
        assert_eq!(Some(d.innovation), s.record.innovation);
        assert_eq!(Some(d.nis), s.record.nis);
        assert_eq!(d.applied, s.record.applied);
        assert_eq!(d.x_post, s.record.ekf);
        // NIS = y^T S^-1 y from the reported S.
        let [[a, b], [c, e]] = d.s;
        let det = a * e - b * c;
        let y = d.innovation;
        let nis = (y[0] * (e * y[0] - b * y[1]) + y[1] * (a * y[1] - c * y[0])) / det;
        assert!(
            (nis - d.nis).abs() <= 1e-6 * d.nis.max(1.0),
            "{nis} vs {}",
            d.nis
        );
        // The gate decision matches the threshold.
        let threshold = d.gate_threshold.expect("the square has a 99 % gate");
        assert_eq!(d.applied, d.nis <= threshold);
        checked += 1;
    }
    assert!(checked > 100);
}

#[test]
fn live_r_changes_the_gain_and_a_bad_value_is_refused() {
    let cfg = one_lap();
    let gain_with = |r: f64| {
        let mut sim = SquareSim::new(&cfg, 5).unwrap();
        let live = LiveParams {
            r11: r,
            r22: r,
            ..LiveParams::of(&cfg)
        };
        sim.set_live(&live).unwrap();
        let (mut sum, mut n) = (0.0, 0.0);
        while let Some(s) = sim.step(None).unwrap() {
            if let Some(g) = s.record.gain.filter(|_| s.record.applied) {
                sum += g[0];
                n += 1.0;
            }
        }
        sum / n
    };
    let (small, large) = (gain_with(1e-6), gain_with(1e-2));
    assert!(
        small > 5.0 * large,
        "gain with small R {small}, large R {large}"
    );

    let mut sim = SquareSim::new(&cfg, 5).unwrap();
    let bad = LiveParams {
        q11: f64::NAN,
        ..LiveParams::of(&cfg)
    };
    assert!(matches!(
        sim.set_live(&bad),
        Err(Error::OutOfRange { field: "q11", .. })
    ));
    assert_eq!(sim.config().q11, cfg.q11);
}

#[test]
fn teleoperation_drives_the_robot() {
    let mut sim = SquareSim::new(&one_lap(), 1).unwrap();
    let start = sim.truth();
    for _ in 0..100 {
        let s = sim.step(Some(Teleop { v: 0.0, w: 1.0 })).unwrap().unwrap();
        assert!(s.teleop);
        assert!((s.wheel_speeds.0 + s.wheel_speeds.1).abs() < 1e-12);
    }
    // 1 s at 1 rad/s: turned by about 1 rad, in place.
    let end = sim.truth();
    let turned = locus_core::wrap_angle(end.theta - start.theta);
    assert!((turned - 1.0).abs() < 0.1, "turned {turned} rad");
    assert!((end.x - start.x).hypot(end.y - start.y) < 0.01);
}
