//! The `tricycle-slip` scenario of seed 004 (spec section 5): the
//! slip-rejecting redundant odometry beats rear-only odometry; the EKF with
//! the laser beats both.
//!
//! `cargo test -p locus-sim --test tricycle_slip -- --nocapture` prints the
//! figures.

use locus_eval::Record;
use locus_sim::tricycle_slip::{
    SlipRejection, TricycleSlipConfig, TricycleSlipRecord, run_tricycle_slip,
};

/// Seeds of the comparison.
const RUNS: u64 = 20;

/// Per run: (final position error, RMS position error) in m of rear-only
/// odometry, slip-rejecting odometry and the EKF; and the final heading
/// errors (rad) in the same order.
#[allow(clippy::cast_precision_loss)]
fn errors(cfg: &TricycleSlipConfig, seed: u64) -> ([(f64, f64); 3], [f64; 3]) {
    let mut sq = [0.0f64; 3];
    let mut last = None;
    let mut n = 0usize;
    let summary = run_tricycle_slip(cfg, seed, &mut |r: &TricycleSlipRecord| {
        let (re, _) = r.rear_only_error();
        let (se, _) = r.slip_rejecting_error();
        let ee = r.sample().position_error_sq().sqrt();
        for (acc, e) in sq.iter_mut().zip([re, se, ee]) {
            *acc += e * e;
        }
        n += 1;
        last = Some(*r);
    })
    .expect("run");
    let r = last.expect("steps");
    assert_eq!(summary.steps, n);
    let rms = sq.map(|s| (s / n as f64).sqrt());
    let fin = [
        r.rear_only_error(),
        r.slip_rejecting_error(),
        (
            r.sample().position_error_sq().sqrt(),
            r.sample().heading_error,
        ),
    ];
    (
        [(fin[0].0, rms[0]), (fin[1].0, rms[1]), (fin[2].0, rms[2])],
        [fin[0].1, fin[1].1, fin[2].1],
    )
}

#[test]
fn slip_rejecting_odometry_beats_rear_only() {
    // On every seed, both slip-rejection rules end nearer the truth than the
    // rear-only odometry and have a smaller RMS position error over the run;
    // the EKF (rear odometry + laser) has a smaller RMS error than both.
    for rejection in [SlipRejection::ComponentMin, SlipRejection::ConsistentSet] {
        let cfg = TricycleSlipConfig {
            rejection,
            ..TricycleSlipConfig::default()
        };
        println!(
            "tricycle-slip, {rejection:?}: final |dp| (m), RMS |dp| (m), final dtheta (deg, truth - estimate)"
        );
        let mut sums = [0.0f64; 3];
        for seed in 0..RUNS {
            let (pos, head) = errors(&cfg, seed);
            println!(
                "  seed {seed:2}: rear-only {:.4} {:.4} {:+.2} | slip-rejecting {:.4} {:.4} {:+.2} | EKF {:.4} {:.4} {:+.2}",
                pos[0].0,
                pos[0].1,
                head[0].to_degrees(),
                pos[1].0,
                pos[1].1,
                head[1].to_degrees(),
                pos[2].0,
                pos[2].1,
                head[2].to_degrees()
            );
            for (s, p) in sums.iter_mut().zip(pos) {
                *s += p.1;
            }
            assert!(pos[1].0 < pos[0].0, "seed {seed}: final {pos:?}");
            assert!(pos[1].1 < pos[0].1, "seed {seed}: RMS {pos:?}");
            assert!(pos[2].1 < pos[1].1, "seed {seed}: EKF RMS {pos:?}");
        }
        #[allow(clippy::cast_precision_loss)]
        let n = RUNS as f64;
        println!(
            "  mean RMS |dp| over {RUNS} seeds: rear-only {:.3} m, slip-rejecting {:.3} m, EKF {:.4} m",
            sums[0] / n,
            sums[1] / n,
            sums[2] / n
        );
    }
}

#[test]
fn run_is_reproducible_and_logs_every_step() {
    let cfg = TricycleSlipConfig::default();
    let mut rows = Vec::new();
    let a = run_tricycle_slip(&cfg, 3, &mut |r: &TricycleSlipRecord| {
        rows.push(r.csv_row())
    })
    .expect("run");
    let b = run_tricycle_slip(&cfg, 3, &mut |_: &TricycleSlipRecord| {}).expect("run");
    assert_eq!(a.without_timing(), b.without_timing());
    // 10 m + pi m at 1 cm per step.
    assert_eq!(a.steps, 1000 + 315);
    assert_eq!(rows.len(), a.steps);
    let columns = TricycleSlipRecord::csv_header().split(',').count();
    assert!(rows.iter().all(|r| r.split(',').count() == columns));
    assert!(a.applied > 0);
}

#[test]
fn invalid_configuration_names_the_field() {
    let cfg = TricycleSlipConfig {
        laser_period: 0,
        ..TricycleSlipConfig::default()
    };
    let err = run_tricycle_slip(&cfg, 0, &mut |_: &TricycleSlipRecord| {}).expect_err("invalid");
    assert!(err.to_string().contains("laser_period"), "{err}");
    let err = toml::from_str::<TricycleSlipConfig>("bump_scael = 1.2\n").expect_err("unknown");
    assert!(err.to_string().contains("bump_scael"), "{err}");
    let cfg: TricycleSlipConfig =
        toml::from_str("rejection = \"consistent-set\"\nbump_count = 1\n").expect("parse");
    assert_eq!(cfg.rejection, SlipRejection::ConsistentSet);
    assert_eq!(cfg.bump_count, 1);
}
