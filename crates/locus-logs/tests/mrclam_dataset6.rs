//! Real-data check of the range-bearing model on MRCLAM dataset 6
//! (`../shared/data/mrclam/MRCLAM_Dataset6` from the workspace root).
//!
//! For each robot 1-5 and each landmark sighting, the ground-truth pose is
//! interpolated at the sighting's time (sightings outside the ground truth's
//! coverage, or between two samples more than 0.1 s apart, are skipped), the
//! `RangeBearing` model predicts the range and bearing with the sensor at the
//! robot's centre (the dataset's page: the camera "is conveniently placed to
//! align with the robot body frame"), and the residuals `z - h(X)` (bearing
//! wrapped) are summarised per robot.
//!
//! What the data README reports, and what is asserted:
//!
//! * range residual median within 0.05 m: asserted for robots 1, 2, 3, 5 and
//!   for all robots pooled. **Robot 4's median is about +0.067 m**, outside
//!   the README's bound; asserted within 0.08 m so that a change is noticed;
//! * heavy range tail, 1-4 % off by more than 0.5 m: asserted 0.5-6 % per
//!   robot, 1-4 % pooled;
//! * bearings tight, 0.01-0.02 rad: robust standard deviation (1.4826 MAD)
//!   asserted <= 0.03 rad per robot (the plain standard deviation is not
//!   tight for robots 3 and 5: a few gross bearing outliers);
//! * a small constant bearing bias on robot 4: its median bearing residual
//!   asserted beyond 0.01 rad in magnitude and at least 3x every other
//!   robot's.
//!
//! Barcodes: robot sightings and the unknown barcodes are separated; the
//! unknown ones must be among those the README lists (43, 34, 50, 52).

use std::path::PathBuf;
use std::time::Instant;

use locus_core::MeasurementModel;
use locus_core::nalgebra::{Vector2, Vector3};
use locus_logs::Error;
use locus_logs::mrclam::{self, Dataset, ROBOTS};
use locus_models::range_bearing::RangeBearing;

/// Largest spacing of the two ground-truth samples around a sighting, s.
const MAX_GAP: f64 = 0.1;

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/mrclam/MRCLAM_Dataset6")
}

/// Residual statistics of one robot.
#[derive(Debug, Clone, Default)]
struct Stats {
    robot: u32,
    sightings: usize,
    robot_sightings: usize,
    unknown: Vec<u32>,
    skipped: usize,
    range: Vec<f64>,
    bearing: Vec<f64>,
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Median absolute deviation (unscaled).
fn mad(v: &[f64]) -> f64 {
    let m = median(v);
    median(&v.iter().map(|x| (x - m).abs()).collect::<Vec<_>>())
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

fn std(v: &[f64]) -> f64 {
    let m = mean(v);
    (v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

fn tail_share(v: &[f64], bound: f64) -> f64 {
    v.iter().filter(|x| x.abs() > bound).count() as f64 / v.len() as f64
}

fn robot_stats(data: &Dataset, robot: u32) -> Stats {
    let truth = data.groundtruth(robot).expect("ground truth");
    let seen = data.sightings(robot).expect("measurements");
    // One model per sighting, sharing the sensor (at the centre) and noise.
    let base = RangeBearing::new(Vector2::zeros(), Vector2::zeros(), 0.1, 0.02);
    let mut st = Stats {
        robot,
        sightings: seen.landmarks.len(),
        robot_sightings: seen.robots.len(),
        unknown: seen.unknown.iter().map(|m| m.barcode).collect(),
        ..Stats::default()
    };
    for s in &seen.landmarks {
        let lm = data
            .landmark(s.subject)
            .expect("every landmark barcode has a position");
        let Some(pose) = truth.pose_at(s.time, MAX_GAP) else {
            st.skipped += 1;
            continue;
        };
        let model = base.with_landmark(Vector2::new(lm.x, lm.y));
        let x = Vector3::new(pose.x, pose.y, pose.theta);
        let z_hat = model.h(&x).expect("landmarks are far from the robots");
        let r = model.residual(&Vector2::new(s.range, s.bearing), &z_hat);
        st.range.push(r[0]);
        st.bearing.push(r[1]);
    }
    st
}

#[test]
fn range_bearing_residuals_on_mrclam_dataset6() {
    let start = Instant::now();
    let data = Dataset::open(data_dir())
        .unwrap_or_else(|e| panic!("MRCLAM dataset 6 must be at {}: {e}", data_dir().display()));
    assert_eq!(data.landmarks.len(), 15);
    assert_eq!(data.barcodes.entries().len(), 20);

    // The robots' logs are independent: read and process them in parallel.
    let stats: Vec<Stats> = std::thread::scope(|scope| {
        let handles: Vec<_> = ROBOTS
            .map(|robot| {
                let data = &data;
                scope.spawn(move || robot_stats(data, robot))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });

    println!(
        "MRCLAM dataset 6, range-bearing residuals z - h(X) at interpolated ground truth (gap <= {MAX_GAP} s), sensor at the centre"
    );
    println!(
        "robot | landmark sightings | used | skipped | robot sightings | unknown barcodes | range med [m] | range mean [m] | range MAD [m] | |dr| > 0.5 m | bearing med [rad] | bearing mean [rad] | bearing std [rad] | bearing robust std [rad]"
    );
    for s in &stats {
        println!(
            "{} | {} | {} | {} | {} | {:?} | {:+.4} | {:+.4} | {:.4} | {:.2} % | {:+.4} | {:+.4} | {:.4} | {:.4}",
            s.robot,
            s.sightings,
            s.range.len(),
            s.skipped,
            s.robot_sightings,
            s.unknown,
            median(&s.range),
            mean(&s.range),
            mad(&s.range),
            100.0 * tail_share(&s.range, 0.5),
            median(&s.bearing),
            mean(&s.bearing),
            std(&s.bearing),
            1.4826 * mad(&s.bearing),
        );
    }
    let pooled: Vec<f64> = stats.iter().flat_map(|s| s.range.iter().copied()).collect();
    println!(
        "all | {} used | range med {:+.4} m | |dr| > 0.5 m {:.2} %",
        pooled.len(),
        median(&pooled),
        100.0 * tail_share(&pooled, 0.5)
    );
    println!("elapsed {:.2} s", start.elapsed().as_secs_f64());

    for s in &stats {
        let r = s.robot;
        assert!(
            s.range.len() >= 1000,
            "robot {r}: only {} sightings used",
            s.range.len()
        );
        // Most sightings fall inside the ground truth's coverage.
        assert!(
            s.skipped * 5 < s.sightings,
            "robot {r}: {} skipped",
            s.skipped
        );
        let med = median(&s.range);
        let bound = if r == 4 { 0.08 } else { 0.05 };
        assert!(med.abs() <= bound, "robot {r}: range residual median {med}");
        let tail = tail_share(&s.range, 0.5);
        assert!(
            (0.005..=0.06).contains(&tail),
            "robot {r}: range tail {tail}"
        );
        let robust = 1.4826 * mad(&s.bearing);
        assert!(robust <= 0.03, "robot {r}: bearing robust std {robust}");
        assert!(
            s.unknown.iter().all(|b| [43, 34, 50, 52].contains(b)),
            "robot {r}: unknown barcodes {:?}",
            s.unknown
        );
        assert!(s.robot_sightings > 0, "robot {r} saw no other robot");
    }
    let pooled_med = median(&pooled);
    assert!(pooled_med.abs() <= 0.05, "pooled range median {pooled_med}");
    let pooled_tail = tail_share(&pooled, 0.5);
    assert!(
        (0.01..=0.04).contains(&pooled_tail),
        "pooled tail {pooled_tail}"
    );

    let bias = |robot: u32| median(&stats[robot as usize - 1].bearing).abs();
    let others = [1, 2, 3, 5].map(bias).into_iter().fold(0.0, f64::max);
    assert!(
        bias(4) > 0.01 && bias(4) >= 3.0 * others,
        "robot 4 bearing bias {} vs the others' largest {others}",
        bias(4)
    );
}

#[test]
fn a_corrupted_copy_of_a_real_xz_file_fails_its_check() {
    // The dataset's files carry a CRC64 per block: a flipped payload byte is
    // caught (by the decoder or by the check), not read as data.
    let src = data_dir().join("Robot1_Measurement.dat.xz");
    let mut bytes = std::fs::read(&src).unwrap_or_else(|e| panic!("{}: {e}", src.display()));
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mrclam_dataset6");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("Robot1_Measurement.dat.xz");
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(mrclam::read_measurements(&path).unwrap().len(), 1942);
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x01;
    std::fs::write(&path, &bytes).unwrap();
    let err = mrclam::read_measurements(&path).unwrap_err();
    assert!(matches!(err, Error::Decompress { .. }), "{err:?}");
}
