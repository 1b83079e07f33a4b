//! Every record of a log is accounted for (issue 34): each measurement is
//! a reading that is applied, gated, skipped for a named reason or refused
//! for a named reason; each odometry record is applied or refused as
//! implausible. Checked over arbitrary v2 logs, absurd values included,
//! and the replay never fails on a record's value.

use core::fmt::Write as _;
use std::path::Path;

use locus_logs::locus_csv;
use locus_replay::{Config, Log, replay, replay_in_segments};
use proptest::prelude::*;

/// A value of any size a CSV field may hold: ordinary, tiny, huge, signed.
fn any_value() -> impl Strategy<Value = f64> {
    prop_oneof![
        6 => -3.0..3.0_f64,
        1 => prop::sample::select(vec![0.0, 1e-300, 1e6, -1e6, 1e154, 1e308, -1e308]),
    ]
}

/// A v2 log: three landmarks, a start, odometry in time order (some
/// records absurd), measurements of known and unknown ids at ordinary,
/// late and absurd times, with any range and bearing.
fn any_log() -> impl Strategy<Value = String> {
    (
        prop::collection::vec((0.001..0.5_f64, any_value(), any_value()), 1..60),
        prop::collection::vec(
            (
                0.0..40.0_f64,
                0u32..5,
                prop_oneof![3 => 0.0..6.0_f64, 1 => prop::sample::select(vec![1e154, 1e308])],
                any_value(),
            ),
            0..60,
        ),
        prop::option::of(prop::sample::select(vec![1e6, 1e308])),
    )
        .prop_map(|(odometry, measurements, last_time)| {
            let mut s =
                String::from("landmark,1,3,0\nlandmark,2,0,3\nlandmark,3,-2,-2\nstart,0,0,0,0\n");
            let mut t = 0.0;
            for (dt, v, w) in odometry {
                writeln!(s, "odometry,{t},{v},{w}").unwrap();
                t += dt;
            }
            if let Some(last) = last_time {
                writeln!(s, "odometry,{last},0.1,0").unwrap();
            }
            for (time, id, range, bearing) in measurements {
                writeln!(s, "measurement,{time},{id},{range},{bearing}").unwrap();
            }
            s
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn every_reading_and_odometry_record_is_accounted_for(text in any_log()) {
        let (csv, lines) = locus_csv::parse_with_lines(&text, Path::new("any.csv")).unwrap();
        let measurements = csv.measurements.len();
        let odometry = csv.odometry.len();
        let log = Log::from_locus_lines("any.csv", csv, lines).unwrap();
        let r = replay(&log, &Config::default(), |_| {});
        let r = match r {
            Ok(r) => r,
            Err(e) => return Err(TestCaseError::fail(format!("replay failed: {e}"))),
        };
        // Readings: applied, gated, skipped (not in the map, no predicted
        // measurement, unknown id, too late) or refused (unusable,
        // implausible time).
        prop_assert_eq!(
            measurements,
            r.sightings + r.too_late + r.implausible_time + r.unknown_sightings,
            "{:?}", r
        );
        prop_assert_eq!(
            r.sightings,
            r.applied + r.gated + r.not_in_map + r.no_measurement + r.unusable,
            "{:?}", r
        );
        // The summary tallies every event, compared with the truth or not.
        prop_assert_eq!(r.summary.steps, r.steps);
        prop_assert_eq!(r.summary.compared, r.compared);
        prop_assert_eq!(r.summary.readings, r.sightings);
        prop_assert_eq!(r.summary.associated, r.applied + r.gated);
        prop_assert_eq!(r.summary.applied, r.applied);
        prop_assert_eq!(odometry, r.odometry + r.implausible_odometry);
        // The belief stays finite whatever the values.
        prop_assert!(r.final_belief.x.iter().all(|v| v.is_finite()), "{:?}", r.final_belief);
        // The smoother's segments re-run the forward pass from checkpoints:
        // the counts are the forward pass's, once.
        let smoothed = Config { smooth: true, ..Config::default() };
        let s = match replay_in_segments(&log, &smoothed, 7, |_| {}) {
            Ok(s) => s,
            Err(e) => return Err(TestCaseError::fail(format!("smoothed replay failed: {e}"))),
        };
        prop_assert_eq!(
            (s.sightings, s.applied, s.gated, s.too_late, s.unusable, s.no_measurement),
            (r.sightings, r.applied, r.gated, r.too_late, r.unusable, r.no_measurement)
        );
        prop_assert_eq!((s.odometry, s.implausible_odometry), (r.odometry, r.implausible_odometry));
        // The smoother's summary counts the same events as the filter's.
        let (f, m) = (s.summary, s.smoothed.expect("smoothed"));
        prop_assert_eq!(
            (m.steps, m.readings, m.associated, m.applied),
            (f.steps, f.readings, f.associated, f.applied)
        );
    }
}
