//! Replay on small hand-written Locus CSV logs: late lines, unknown ids,
//! configuration and log errors.

use std::path::Path;

use locus_logs::locus_csv;
use locus_replay::{Config, Error, Log, StartedFrom, Step, replay};

/// A robot driving at 0.2 m/s, turning at 0.1 rad/s, for 10 s at 50 Hz,
/// with sightings of three landmarks every 0.5 s (range and bearing from
/// the exact circular-arc pose, then perturbed deterministically); with
/// `late`, every second measurement line is listed three lines later.
fn text(late: bool) -> String {
    let mut s = String::from("landmark,1,3,0\nlandmark,2,0,3\nlandmark,3,-2,-2\nstart,0,0,0,0\n");
    let (v, w) = (0.2, 0.1);
    for i in 0..=500 {
        let t = f64::from(i) * 0.02;
        s.push_str(&format!("odometry,{t},{v},{w}\n"));
        s.push_str(&format!(
            "truth,{t},{},{},{}\n",
            v / w * (w * t).sin(),
            v / w * (1.0 - (w * t).cos()),
            w * t
        ));
    }
    let mut meas = Vec::new();
    for k in 1..20 {
        let t = f64::from(k) * 0.5;
        let (x, y, th) = (v / w * (w * t).sin(), v / w * (1.0 - (w * t).cos()), w * t);
        for (id, lx, ly) in [(1, 3.0, 0.0), (2, 0.0, 3.0), (3, -2.0, -2.0)] {
            let r = ((lx - x) * (lx - x) + (ly - y) * (ly - y)).sqrt();
            let b = (ly - y).atan2(lx - x) - th;
            let noise = 0.01 * (f64::from(k * 7 + id) * 1.3).sin();
            meas.push(format!(
                "measurement,{t},{id},{},{}\n",
                r + noise,
                b - noise
            ));
        }
    }
    // An id that is not in the map.
    meas.push("measurement,5.25,9,1,0\n".to_string());
    if late {
        // Every second sighting moved 3 lines later: listed after newer ones.
        for i in (0..meas.len() - 4).step_by(2) {
            meas.swap(i, i + 3);
        }
    }
    s.extend(meas);
    s
}

fn run(late: bool) -> (Vec<Step>, locus_replay::Report) {
    let log = Log::from_locus(
        "synthetic",
        locus_csv::parse(&text(late), Path::new("s.csv")).unwrap(),
    )
    .unwrap();
    let mut steps = Vec::new();
    let r = replay(&log, &Config::default(), |s| steps.push(*s)).unwrap();
    (steps, r)
}

#[test]
fn lines_listed_late_give_the_in_order_estimates() {
    let (a, ra) = run(false);
    let (b, rb) = run(true);
    assert_eq!(ra.late, 0);
    assert!(rb.late >= 20, "{} late", rb.late);
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!((x.belief.x - y.belief.x).abs().max() <= 1e-9);
        assert!((x.belief.p - y.belief.p).abs().max() <= 1e-9);
    }
    assert_eq!(ra.unknown_sightings, 1);
    assert_eq!(ra.applied, 57, "3 x 19 sightings, none gated");
    assert!(
        ra.summary.position_rmse < 0.05,
        "{}",
        ra.summary.position_rmse
    );
}

#[test]
fn bad_configurations_and_logs_are_errors() {
    let log = Log::from_locus(
        "s",
        locus_csv::parse(&text(false), Path::new("s.csv")).unwrap(),
    )
    .unwrap();
    let bad = Config {
        sigma_range: 0.0,
        ..Config::default()
    };
    assert!(matches!(
        replay(&log, &bad, |_| {}),
        Err(Error::InvalidConfig(_))
    ));
    // No start pose, no truth, and sightings of one landmark only: nothing
    // fixes the start.
    let mut no_start = log.clone();
    no_start.start = None;
    no_start.truth = Default::default();
    no_start.sightings.retain(|s| s.landmark == 1);
    let err = replay(&no_start, &Config::default(), |_| {}).unwrap_err();
    assert!(matches!(err, Error::NoStart { .. }), "{err}");
    assert!(err.to_string().contains("sightings fix none"), "{err}");
    let mut empty = log.clone();
    empty.odometry.clear();
    assert!(matches!(
        replay(&empty, &Config::default(), |_| {}),
        Err(Error::NoOdometry)
    ));
    let mut early = log;
    early.sightings[0].arrival = early.sightings[0].time - 0.1;
    assert!(matches!(
        replay(&early, &Config::default(), |_| {}),
        Err(Error::ArrivesBeforeTaken { index: 0, .. })
    ));
}

/// The innovation likelihood that `locus tune` maximises prefers a range
/// and bearing noise near the log's (about 0.007 m and rad RMS here) to
/// one 25x too large or 10x too small.
#[test]
fn the_innovation_likelihood_prefers_the_right_noise() {
    let log = Log::from_locus(
        "s",
        locus_csv::parse(&text(false), Path::new("s.csv")).unwrap(),
    )
    .unwrap();
    let nll = |sigma: f64| {
        let cfg = Config {
            sigma_range: sigma,
            sigma_bearing: sigma,
            gate: None,
            ..Config::default()
        };
        replay(&log, &cfg, |_| {}).unwrap().innovation_nll
    };
    let (right, large, small) = (nll(0.01), nll(0.25), nll(0.001));
    println!("innovation NLL: sigma 0.01 {right:.1}, 0.25 {large:.1}, 0.001 {small:.1}");
    assert!(right < large && right < small);
}

/// Issue 20: a sighting with range 1e154 (finite, so a valid field)
/// aborted the replay ("S is not positive definite") or, ungated and
/// Gaussian, threw the estimate 1e154 m away. It is refused as unusable;
/// the estimate is that of the log without it, whatever the gate and the
/// weighting.
#[test]
fn a_sighting_the_filter_cannot_use_is_refused_and_the_belief_kept() {
    let clean = Log::from_locus(
        "s",
        locus_csv::parse(&text(false), Path::new("s.csv")).unwrap(),
    )
    .unwrap();
    let mut hostile = clean.clone();
    let mut bad = hostile.sightings[12];
    bad.time -= 0.01;
    bad.range = 1e154;
    hostile.sightings.insert(13, bad);
    for (gate, robust_dof) in [(Some(0.99), Some(4.0)), (None, Some(4.0)), (None, None)] {
        let cfg = Config {
            gate,
            robust_dof,
            ..Config::default()
        };
        let a = replay(&clean, &cfg, |_| {}).unwrap();
        let mut refused = Vec::new();
        let b = replay(&hostile, &cfg, |s| {
            if let locus_replay::EventKind::Sighting {
                outcome: locus_replay::SightingOutcome::Unusable(why),
                ..
            } = s.kind
            {
                refused.push(why);
            }
        })
        .unwrap();
        assert_eq!(b.unusable, 1, "{gate:?} {robust_dof:?}");
        assert_eq!(b.applied, a.applied, "{gate:?} {robust_dof:?}");
        assert_eq!(
            refused,
            [locus_replay::Unusable::RangeAbove { max: 1000.0 }]
        );
        let d = (a.final_belief.x - b.final_belief.x).abs().max();
        // The refused event splits one prediction in two: rounding only.
        assert!(d < 1e-6, "{gate:?} {robust_dof:?}: final pose off by {d}");
    }
    // Within the range bound, the correction's own failure refuses it:
    // with the bound lifted, the Student-t reweighting of an innovation of
    // 1e154 m fails (its noise overflows), typed, not as an abort.
    let cfg = Config {
        gate: None,
        max_range: f64::MAX,
        ..Config::default()
    };
    let mut refused = Vec::new();
    let b = replay(&hostile, &cfg, |s| {
        if let locus_replay::EventKind::Sighting {
            outcome: locus_replay::SightingOutcome::Unusable(why),
            ..
        } = s.kind
        {
            refused.push(why);
        }
    })
    .unwrap();
    assert_eq!(b.unusable, 1);
    assert!(
        matches!(refused[..], [locus_replay::Unusable::Filter(_)]),
        "{refused:?}"
    );
}

/// A log with no start pose and no ground truth (a user's own robot) starts
/// where its first sightings put it, and localises as well as from the
/// true start.
#[test]
fn a_log_with_no_start_and_no_truth_starts_where_its_sightings_put_it() {
    let known = Log::from_locus(
        "s",
        locus_csv::parse(&text(false), Path::new("s.csv")).unwrap(),
    )
    .unwrap();
    let stripped: String = text(false)
        .lines()
        .filter(|l| !l.starts_with("start,") && !l.starts_with("truth,"))
        .map(|l| format!("{l}\n"))
        .collect();
    let log = Log::from_locus(
        "s",
        locus_csv::parse(&stripped, Path::new("s.csv")).unwrap(),
    )
    .unwrap();
    assert!(log.start.is_none() && log.truth.poses().is_empty());
    let mut last = None;
    let r = replay(&log, &Config::default(), |s| last = Some(*s)).unwrap();
    let StartedFrom::Sightings(fix) = r.started_from else {
        panic!("{:?}", r.started_from);
    };
    // The robot starts at the origin, heading along x.
    assert!(fix.pose.norm() < 0.05, "{}", fix.pose);
    assert_eq!(fix.landmarks, 3);
    assert!(r.summary.position_rmse.is_nan(), "no truth: n/a");
    let mut last_known = None;
    replay(&known, &Config::default(), |s| last_known = Some(*s)).unwrap();
    let (a, b) = (last.unwrap().belief.x, last_known.unwrap().belief.x);
    assert!((a - b).norm() < 1e-3, "{a} against {b}");
}
