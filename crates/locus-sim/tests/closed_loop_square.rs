//! The paper-001 closed loop on the `square` scenario.

use locus_sim::closed_loop::{SquareConfig, StepRecord, run_square};

#[test]
fn ekf_beats_odometry_and_the_seed_reproduces_the_run() {
    let cfg = SquareConfig::default();
    let mut records = 0usize;
    let mut applied = 0usize;
    let a = run_square(&cfg, 7, &mut |r: &StepRecord| {
        records += 1;
        applied += usize::from(r.applied);
    })
    .expect("run");
    assert_eq!(records, a.steps);
    assert_eq!(applied, a.applied);
    assert_eq!(a.laps_completed, cfg.laps);
    assert!(a.applied > 100, "{a:?}");
    assert!(
        a.position_rmse < 0.25 * a.odometry_position_rmse,
        "EKF {} m vs odometry {} m",
        a.position_rmse,
        a.odometry_position_rmse
    );
    assert!(a.position_rmse < 0.05, "{a:?}");
    // Roughly consistent: mean NEES near its 3 dof, most steps inside the
    // 95 % interval.
    assert!((1.0..6.0).contains(&a.mean_nees), "{a:?}");
    assert!(a.nees_in_interval > 0.8, "{a:?}");
    let b = run_square(&cfg, 7, &mut |_: &StepRecord| {}).expect("run");
    assert_eq!(a.without_timing(), b.without_timing());
    let c = run_square(&cfg, 8, &mut |_: &StepRecord| {}).expect("run");
    assert_ne!(a.without_timing(), c.without_timing());
}

#[test]
fn the_ekf_stays_localised_on_several_seeds() {
    let cfg = SquareConfig::default();
    for seed in 1..=5 {
        let s = run_square(&cfg, seed, &mut |_: &StepRecord| {}).expect("run");
        assert!(
            s.position_rmse < 0.03 && s.position_rmse < 0.2 * s.odometry_position_rmse,
            "seed {seed}: {s:?}"
        );
    }
}

#[test]
fn an_invalid_configuration_is_rejected() {
    let cfg = SquareConfig {
        dt: 0.0,
        ..SquareConfig::default()
    };
    let err = run_square(&cfg, 1, &mut |_: &StepRecord| {}).unwrap_err();
    assert!(err.to_string().contains("dt"), "{err}");
}
