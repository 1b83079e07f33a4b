//! The real data sets of issue 29 converted into Locus logs: laser_wall_1d
//! (AER1513) and the Intel lab (CARMEN log and relations), from
//! `../shared/data`. The figures printed here are those docs/log-format.md
//! quotes (`cargo test -p locus-logs --test beam_datasets -- --nocapture`).

use std::path::Path;

use locus_logs::scans::{NO_RETURN, Reading};
use locus_logs::se2::{dead_reckon, wrap};
use locus_logs::{aer1513, carmen, locus_csv, relations};

fn data(rel: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel)
}

#[test]
fn laser_wall_1d_converts_to_a_log_that_round_trips() {
    let d = aer1513::read(&data("laser_wall_1d/dataset1.txt")).unwrap();
    let log = &d.log;
    assert_eq!(log.odometry.len(), 12709);
    assert_eq!(log.scans.len(), 12709);
    assert_eq!(log.truth.poses().len(), 12709);
    assert!(!log.truth.has_heading());
    assert_eq!(log.walls.len(), 1);
    assert_eq!(log.beam_sensors[0].count, 1);
    assert!(log.noise.is_empty(), "the published noise is not a record");
    let (t0, t1) = (log.odometry[0].time, log.odometry.last().unwrap().time);
    assert!((t1 - t0 - 1270.8).abs() < 1e-9);
    // Every range within the sensor's limits.
    assert!(
        log.scans
            .iter()
            .all(|s| matches!(Reading::of(s.ranges[0]), Reading::Range(_)))
    );
    // Its baselines (the range alone, the linear Kalman filter given the
    // published noise) against the README's figures: locus_replay::rail,
    // tested in crates/locus-replay/tests/beams.rs.
    eprintln!(
        "laser_wall_1d: {} lines, {t0} s to {t1} s, wall at {} m",
        log.odometry.len(),
        d.wall_x
    );
    let text = locus_csv::write(log);
    assert_eq!(&locus_csv::parse(&text, Path::new("w.csv")).unwrap(), log);
}

#[test]
fn intel_lab_converts_and_its_odometry_dead_reckons_the_raw_motion() {
    let c = carmen::read(&data("intel_lab/intel-corrected.log.gz")).unwrap();
    let log = &c.log;
    assert_eq!(log.scans.len(), 910);
    assert_eq!(log.scans.ranges_len(), 910 * 180);
    assert_eq!(log.truth.poses().len(), 910);
    assert!(log.truth.has_heading());
    let sensor = log.beam_sensors[0];
    assert_eq!((sensor.count, sensor.mount.x), (180, 0.0));
    assert_eq!(c.raw_motion.len(), 909);
    assert_eq!(c.timeless_segments, 0);
    let no_return = log
        .scans
        .iter()
        .flat_map(|s| s.ranges)
        .filter(|r| **r == NO_RETURN)
        .count();
    // Times non-decreasing: scans, truth and odometry.
    let times = log.scans.times();
    assert!(times.windows(2).all(|w| w[0] <= w[1]));
    assert!(log.odometry.windows(2).all(|w| w[0].time <= w[1].time));
    // Dead reckoning from each scan to the next gives the raw motion.
    let mut worst: f64 = 0.0;
    let mut from = 0;
    for (k, want) in c.raw_motion.iter().enumerate() {
        let (a, b) = (times[k], times[k + 1]);
        while from < log.odometry.len() && log.odometry[from].time < a {
            from += 1;
        }
        let start = from.saturating_sub(1);
        let end = log.odometry.partition_point(|o| o.time <= b);
        let got = dead_reckon(&log.odometry[start..end], a, b);
        let e = [got[0] - want[0], got[1] - want[1], wrap(got[2] - want[2])];
        let e = e.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(
            e < 1e-6,
            "segment {k} ({a} s to {b} s): {got:?} against {want:?}"
        );
        worst = worst.max(e);
    }
    let turns = log
        .odometry
        .iter()
        .filter(|o| o.v == 0.0 && o.omega != 0.0)
        .count();
    // Records faster than the replay's limits (4 pi rad/s, 10 m/s): only
    // where the retiming left a segment shorter than carmen::MIN_DT.
    let fast: Vec<f64> = log
        .odometry
        .windows(2)
        .filter(|w| w[0].omega.abs() > 4.0 * core::f64::consts::PI || w[0].v.abs() > 10.0)
        .map(|w| w[1].time - w[0].time)
        .collect();
    assert!(fast.iter().all(|dt| *dt < carmen::MIN_DT), "{fast:?}");
    assert!(fast.len() < 20, "{}", fast.len());
    let fast = fast.len();
    let top_v = log.odometry.iter().fold(0.0_f64, |m, o| m.max(o.v.abs()));
    eprintln!(
        "intel_lab: {} scans from {} s to {} s, {no_return} no-return readings of {}; \
         {} odometry records ({turns} turns in place, {fast} above 4 pi rad/s or 10 m/s, top |v| {top_v:.3} m/s); \
         {} stamps retimed, by at most {:.4} s; dead reckoning against raw motion: worst {worst:.1e}",
        log.scans.len(),
        times[0],
        times[909],
        log.scans.ranges_len(),
        log.odometry.len(),
        c.retimed,
        c.largest_retime
    );
    assert_eq!(no_return, 4172);
    let text = locus_csv::write(log);
    assert_eq!(
        &locus_csv::parse(&text, Path::new("intel.csv")).unwrap(),
        log
    );
}

#[test]
fn intel_relations_fall_on_the_scans_at_the_stated_offset() {
    let c = carmen::read(&data("intel_lab/intel-corrected.log.gz")).unwrap();
    let r = relations::read(
        &data("intel_lab/intel.relations.xz"),
        relations::INTEL_OFFSET,
    )
    .unwrap();
    assert_eq!(r.len(), 2984);
    let mut counts = Vec::new();
    for tol in [1e-3, 5e-3, 1e-2] {
        let both = relations::on_scans(&r, &c.scan_stamps, tol)
            .iter()
            .filter(|m| m.is_some())
            .count();
        counts.push((tol, both));
    }
    // The residuals of the ends matched within 5 ms: centred on 0 if the
    // offset is right (the stamps have 2 to 4 decimals).
    let matched = relations::on_scans(&r, &c.scan_stamps, 5e-3);
    let mut residuals: Vec<f64> = r
        .iter()
        .zip(&matched)
        .filter_map(|(r, m)| m.map(|(i, j)| [r.t1 - c.scan_stamps[i], r.t2 - c.scan_stamps[j]]))
        .flatten()
        .collect();
    residuals.sort_by(f64::total_cmp);
    let median = residuals[residuals.len() / 2];
    eprintln!(
        "intel relations: {} relations; both ends on a scan within 1 ms / 5 ms / 10 ms: {:?}; \
         median residual of the matched ends {:.3} ms",
        r.len(),
        counts.iter().map(|c| c.1).collect::<Vec<_>>(),
        median * 1e3
    );
    assert_eq!(counts[1].1, 119);
    assert!(median.abs() < 1e-3, "{median}");
}
