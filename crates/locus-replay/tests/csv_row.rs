//! `Step::csv_row` / `Step::write_csv_row` give, byte for byte, the row the
//! `format!`-based writer gave (kept here as the reference), for random
//! steps of every kind and outcome with any finite numbers, range-only
//! sightings and truths without heading.

use locus_core::Belief;
use locus_core::nalgebra::{Matrix3, Vector3};
use locus_logs::mrclam::TruthPose;
use locus_replay::{EventKind, Sighting, SightingOutcome, Step, Unusable};
use proptest::prelude::*;

/// The row as the `format!`/`to_string` writer built it.
fn reference_row(step: &Step) -> String {
    let (event, lm, r, b, nis, applied) = match step.kind {
        EventKind::Odometry { .. } => (
            "odometry",
            String::new(),
            String::new(),
            String::new(),
            ",".to_string(),
            String::new(),
        ),
        EventKind::Sighting {
            sighting, outcome, ..
        } => {
            // NIS and its dof (2, or 1 for a range-only sighting).
            let dof = if sighting.bearing.is_some() { 2 } else { 1 };
            let (nis, applied) = match outcome {
                SightingOutcome::Applied { nis, recovered, .. } => (
                    format!("{nis},{dof}"),
                    if recovered { "recovered" } else { "1" },
                ),
                SightingOutcome::Gated { nis } => (format!("{nis},{dof}"), "0"),
                SightingOutcome::NotInMap => (",".to_string(), "not-in-map"),
                SightingOutcome::NoMeasurement => (",".to_string(), "no-measurement"),
                SightingOutcome::Unusable(_) => (",".to_string(), "unusable"),
            };
            (
                "sighting",
                sighting.landmark.to_string(),
                sighting.range.to_string(),
                sighting.bearing.map_or_else(String::new, |b| b.to_string()),
                nis,
                applied.to_string(),
            )
        }
        EventKind::Scan {
            sensor, outcome, ..
        } => {
            let judged = outcome.applied + outcome.gated;
            let nis = if judged > 0 {
                format!("{},{judged}", outcome.nis)
            } else {
                ",".to_string()
            };
            (
                "scan",
                sensor.to_string(),
                String::new(),
                String::new(),
                nis,
                outcome.applied.to_string(),
            )
        }
    };
    let x = &step.belief.x;
    let p = &step.belief.p;
    let d = &step.dead_reckoning;
    let truth = step.truth.map_or_else(
        || ",,".to_string(),
        // A truth with no heading (theta NaN) leaves its field empty.
        |t| {
            let theta = if t.theta.is_nan() {
                String::new()
            } else {
                t.theta.to_string()
            };
            format!("{},{},{theta}", t.x, t.y)
        },
    );
    format!(
        "{},{},{},{event},{lm},{r},{b},{nis},{applied},{},{},{},{},{},{},{},{},{},{},{},{},{truth}",
        step.index,
        step.time,
        step.elapsed,
        x[0],
        x[1],
        x[2],
        p[(0, 0)],
        p[(0, 1)],
        p[(0, 2)],
        p[(1, 1)],
        p[(1, 2)],
        p[(2, 2)],
        d[0],
        d[1],
        d[2]
    )
}

/// Any finite f64 (sign, zeros, subnormals, every exponent), or one of
/// the figures a replay writes (UNIX times to the millisecond, metres,
/// small variances).
fn number() -> impl Strategy<Value = f64> {
    use proptest::num::f64::{NEGATIVE, NORMAL, POSITIVE, SUBNORMAL, ZERO};
    prop_oneof![
        3 => POSITIVE | NEGATIVE | NORMAL | SUBNORMAL | ZERO,
        1 => (1_248_000_000_000u64..1_249_000_000_000).prop_map(|ms| ms as f64 / 1000.0),
        1 => -20.0..20.0f64,
        1 => 1e-12..1e-2f64,
    ]
}

fn kind() -> impl Strategy<Value = EventKind> {
    let outcome = prop_oneof![
        (number(), any::<bool>()).prop_map(|(nis, recovered)| SightingOutcome::Applied {
            nis,
            recovered,
            weight: 1.0,
        }),
        number().prop_map(|nis| SightingOutcome::Gated { nis }),
        Just(SightingOutcome::NotInMap),
        Just(SightingOutcome::NoMeasurement),
        Just(SightingOutcome::Unusable(Unusable::RangeAbove {
            max: 1000.0
        })),
    ];
    let sighting = (
        number(),
        any::<u32>(),
        number(),
        proptest::option::of(number()),
    )
        .prop_map(|(time, landmark, range, bearing)| Sighting {
            time,
            arrival: time,
            landmark,
            range,
            bearing,
        });
    prop_oneof![
        (number(), number()).prop_map(|(v, omega)| EventKind::Odometry { v, omega }),
        (sighting, outcome).prop_map(|(sighting, outcome)| EventKind::Sighting {
            sighting,
            outcome,
            line: None,
        }),
    ]
}

fn step() -> impl Strategy<Value = Step> {
    let numbers = proptest::collection::vec(number(), 17);
    let heading = prop_oneof![3 => number(), 1 => Just(f64::NAN)];
    let truth = proptest::option::of(
        (number(), number(), number(), heading).prop_map(|(time, x, y, theta)| TruthPose {
            time,
            x,
            y,
            theta,
        }),
    );
    (any::<usize>(), kind(), numbers, truth).prop_map(|(index, kind, n, truth)| Step {
        index,
        time: n[0],
        elapsed: n[1],
        kind,
        belief: Belief::new(
            Vector3::new(n[2], n[3], n[4]),
            Matrix3::new(n[5], n[6], n[7], n[6], n[8], n[9], n[7], n[9], n[10]),
        ),
        calibration: [1.0, 1.0, 0.0, 0.0],
        smoothed: None,
        smoothed_calibration: None,
        dead_reckoning: [n[11], n[12], n[13]],
        truth,
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(20_000))]

    #[test]
    fn rows_are_those_of_the_format_writer(step in step(), head in "[a-z0-9,\n]{0,12}") {
        let want = reference_row(&step);
        prop_assert_eq!(&step.csv_row(), &want);
        // Appended after whatever the buffer holds.
        let mut out = head.clone();
        step.write_csv_row(&mut out);
        prop_assert_eq!(out, format!("{head}{want}"));
    }
}

#[test]
fn rows_have_the_header_s_columns() {
    let columns = Step::csv_header().split(',').count();
    let kinds = [
        EventKind::Odometry { v: 0.1, omega: 0.0 },
        EventKind::Sighting {
            sighting: Sighting {
                time: 1.0,
                arrival: 1.0,
                landmark: 7,
                range: 2.0,
                bearing: Some(-0.5),
            },
            outcome: SightingOutcome::NotInMap,
            line: Some(12),
        },
    ];
    for (kind, truth) in kinds.into_iter().zip([
        None,
        Some(TruthPose {
            time: 1.0,
            x: 1.0,
            y: 2.0,
            theta: 0.5,
        }),
    ]) {
        let step = Step {
            index: 3,
            time: 1.0,
            elapsed: 0.5,
            kind,
            belief: Belief::new(Vector3::zeros(), Matrix3::identity()),
            calibration: [1.0, 1.0, 0.0, 0.0],
            smoothed: None,
            smoothed_calibration: None,
            dead_reckoning: [0.0; 3],
            truth,
        };
        let row = step.csv_row();
        assert_eq!(row.split(',').count(), columns, "{row}");
        assert_eq!(row, reference_row(&step));
    }
}
