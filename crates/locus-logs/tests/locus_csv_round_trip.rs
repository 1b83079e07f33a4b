//! `locus_csv::parse(write(log)) == log` for random logs: every record kind
//! (range-bearing and range-only sightings, truth with or without heading),
//! with or without a sensor line and each noise record, numbers anywhere in
//! the finite range (subnormals, huge and tiny exponents, -0.0).

use std::path::Path;

use locus_logs::locus_csv::{self, LandmarkMeasurement, LocusLog, MapLandmark};
use locus_logs::mrclam::{Groundtruth, Odometry, TruthPose};
use locus_logs::{NoiseRecords, SensorMount};
use proptest::prelude::*;

/// Any finite f64, sign included.
fn finite() -> impl Strategy<Value = f64> {
    use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
    POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO
}

/// Any finite f64 that is > 0.
fn positive() -> impl Strategy<Value = f64> {
    use proptest::num::f64::{NORMAL, POSITIVE, SUBNORMAL};
    POSITIVE | NORMAL | SUBNORMAL
}

fn pose() -> impl Strategy<Value = TruthPose> {
    (finite(), finite(), finite(), finite()).prop_map(|(time, x, y, theta)| TruthPose {
        time,
        x,
        y,
        theta,
    })
}

fn log() -> impl Strategy<Value = LocusLog> {
    let sensor = proptest::option::of(
        (finite(), finite(), finite()).prop_map(|(x, y, yaw)| SensorMount { x, y, yaw }),
    );
    let noise = [0; 4]
        .map(|_| proptest::option::of(positive()))
        .prop_map(|[a, b, c, d]| NoiseRecords {
            q_v: a,
            q_omega: b,
            sigma_range: c,
            sigma_bearing: d,
        });
    let landmarks = proptest::collection::btree_map(any::<u32>(), (finite(), finite()), 0..5)
        .prop_map(|m| {
            m.into_iter()
                .map(|(id, (x, y))| MapLandmark { id, x, y })
                .collect::<Vec<_>>()
        });
    let odometry = proptest::collection::vec((finite(), finite(), finite()), 0..8).prop_map(|v| {
        let mut o: Vec<_> = v
            .into_iter()
            .map(|(time, v, omega)| Odometry { time, v, omega })
            .collect();
        o.sort_by(|a, b| a.time.total_cmp(&b.time));
        o
    });
    let measurement = (
        finite(),
        any::<u32>(),
        finite(),
        proptest::option::of(finite()),
    )
        .prop_map(|(time, id, r, bearing)| LandmarkMeasurement {
            time,
            id,
            range: r.abs(),
            bearing,
        });
    // With a heading, or positions only (version 3).
    let truth =
        (proptest::collection::vec(pose(), 0..8), any::<bool>()).prop_map(|(mut v, heading)| {
            v.sort_by(|a, b| a.time.total_cmp(&b.time));
            if heading {
                Groundtruth::new(v).expect("sorted")
            } else {
                Groundtruth::positions(v).expect("sorted")
            }
        });
    (
        sensor,
        noise,
        landmarks,
        proptest::option::of(pose()),
        odometry,
        proptest::collection::vec(measurement, 0..8),
        truth,
    )
        .prop_map(
            |(sensor, noise, landmarks, start, odometry, measurements, truth)| LocusLog {
                sensor,
                noise,
                landmarks,
                start,
                odometry,
                measurements,
                truth,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn write_then_parse_gives_the_log_back(log in log()) {
        let text = locus_csv::write(&log);
        let back = locus_csv::parse(&text, Path::new("r.csv")).expect("written logs parse");
        // Bitwise, so that -0.0 and 0.0 are told apart.
        prop_assert_eq!(format!("{back:?}"), format!("{log:?}"));
        prop_assert_eq!(back, log);
    }
}
