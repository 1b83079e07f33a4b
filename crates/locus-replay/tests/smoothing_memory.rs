//! Issue 34, fault 4: `--smooth` held every step of the log until the
//! backward pass (about 0.9 KB an event: 8.5 GB for a 10^7-line log, which
//! aborted under a 6 GB limit). The smoother now works in segments from
//! checkpoints of the forward pass: it holds one segment's steps, a number
//! independent of the log's length, and its results are those of the
//! whole-log smoother to the bit.

use core::fmt::Write as _;
use std::path::Path;

use locus_logs::locus_csv;
use locus_replay::{Config, Log, Report, Step, replay_in_segments, smoothing_segment};

/// A robot circling at 0.2 m/s, 0.1 rad/s for `seconds` s with odometry at
/// 50 Hz, its ground truth, and sightings of three landmarks every 0.5 s
/// (perturbed deterministically, one in seven 4 m off so the gate and the
/// recovery act), landmark 2's listed after the next sightings, 0.5 s later
/// (applied by re-running the history). A 5 s silence in the middle makes the
/// history final at once.
fn text(seconds: u32) -> String {
    let mut s = String::from("landmark,1,3,0\nlandmark,2,0,3\nlandmark,3,-2,-2\nstart,0,0,0,0\n");
    let (v, w) = (0.2, 0.1);
    let pose = |t: f64| (v / w * (w * t).sin(), v / w * (1.0 - (w * t).cos()), w * t);
    let quiet = |t: f64| (f64::from(seconds / 2)..f64::from(seconds / 2) + 5.0).contains(&t);
    let mut late = String::new();
    for i in 0..=seconds * 50 {
        let t = f64::from(i) * 0.02;
        if quiet(t) {
            continue;
        }
        let (x, y, th) = pose(t);
        writeln!(s, "odometry,{t},{v},{w}\ntruth,{t},{x},{y},{th}").unwrap();
        if i % 25 == 0 && i > 0 {
            let before = core::mem::take(&mut late);
            for (id, lx, ly) in [(1u32, 3.0, 0.0), (2, 0.0, 3.0), (3, -2.0_f64, -2.0_f64)] {
                let k = i / 25 * 3 + id;
                let off = if k % 7 == 0 { 4.0 } else { 0.0 };
                let noise = 0.01 * (f64::from(k) * 1.3).sin();
                let r = (lx - x).hypot(ly - y) + noise + off;
                let b = (ly - y).atan2(lx - x) - th - noise;
                let line = format!("measurement,{t},{id},{r},{b}\n");
                if id == 2 {
                    late = line;
                } else {
                    s.push_str(&line);
                }
            }
            s.push_str(&before);
        }
    }
    s
}

fn log(seconds: u32) -> Log {
    Log::from_locus(
        "long",
        locus_csv::parse(&text(seconds), Path::new("long.csv")).unwrap(),
    )
    .unwrap()
}

/// The steps (each written out in full: `Debug` prints every `f64` so it
/// reads back to the same bits) and the report of a smoothed replay in
/// segments of `segment` steps.
fn smoothed(log: &Log, segment: usize) -> (Vec<String>, Report) {
    let cfg = Config {
        smooth: true,
        ..Config::default()
    };
    let mut steps = Vec::new();
    let report = replay_in_segments(log, &cfg, segment, |s: &Step| {
        let mut row = String::new();
        write!(row, "{s:?}").unwrap();
        steps.push(row);
    })
    .unwrap();
    (steps, report)
}

/// The report with what may differ between two runs of the same replay
/// set aside: the wall clock and the smoother's memory.
fn comparable(mut r: Report) -> String {
    r.summary = r.summary.without_timing();
    r.smoothed = r.smoothed.map(locus_eval::Summary::without_timing);
    r.smoothing_held = 0;
    r.smoothing_checkpoints = 0;
    format!("{r:?}")
}

#[test]
fn the_smoother_holds_one_segment_and_gives_the_whole_log_smoothers_results_to_the_bit() {
    let log = log(400);
    let (whole, whole_report) = smoothed(&log, usize::MAX);
    let n = whole.len();
    assert!(n > 20_000, "{n} steps");
    assert!(whole_report.late > 500, "{} late", whole_report.late);
    assert!(whole_report.gated > 100, "{} gated", whole_report.gated);
    // The whole-log smoother (one segment) holds every step.
    assert_eq!(whole_report.smoothing_held, n);
    assert_eq!(whole_report.smoothing_checkpoints, 0);
    // A run from a checkpoint makes at most one record's worth of steps
    // past its segment: the running filter's history, 1024 events.
    for segment in [1, 97, 1000, n - 1] {
        let (parts, report) = smoothed(&log, segment);
        assert!(
            report.smoothing_held <= segment + 1024,
            "segment {segment}: {} held",
            report.smoothing_held
        );
        assert!(
            report.smoothing_checkpoints <= n / segment,
            "segment {segment}: {} checkpoints",
            report.smoothing_checkpoints
        );
        assert_eq!(parts.len(), n, "segment {segment}");
        for (k, (a, b)) in parts.iter().zip(&whole).enumerate() {
            assert_eq!(a, b, "segment {segment}, step {k}");
        }
        assert_eq!(comparable(report), comparable(whole_report.clone()));
    }
    // Not smoothing holds nothing.
    let mut count = 0;
    let plain = replay_in_segments(&log, &Config::default(), 1, |_| count += 1).unwrap();
    assert_eq!((plain.smoothing_held, plain.smoothing_checkpoints), (0, 0));
    assert_eq!(count, n);
}

#[test]
fn the_default_segment_grows_as_the_square_root_of_the_log() {
    // A log of up to 2^17 events is one segment.
    assert_eq!(smoothing_segment(0), 1 << 17);
    assert_eq!(smoothing_segment(1 << 17), 1 << 17);
    // 10^7 events: still 2^17 (sqrt(1024 * 10^7) = 101 192), 1.3 % of
    // the log, 76 checkpoints; 10^9: 1 011 928 steps, 0.1 %.
    assert_eq!(smoothing_segment(10_000_000), 1 << 17);
    assert_eq!(smoothing_segment(1_000_000_000), 1_011_928);
    assert_eq!(smoothing_segment(usize::MAX), (usize::MAX).isqrt());
}
