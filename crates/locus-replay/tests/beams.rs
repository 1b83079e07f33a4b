//! Range sensors against a map (issue 29): a simulated robot in a walled
//! room with a 36-beam range sensor, its scans replayed as the log's
//! `scan` records are. Each beam is one scalar correction against the range
//! cast in the map; the filter must track the robot within its own
//! uncertainty, and a reading far shorter than the map's (something not in
//! the map) must be skipped, not applied.

use locus_logs::locus_csv::LocusLog;
use locus_logs::mrclam::{Groundtruth, Odometry, TruthPose};
use locus_logs::{BeamSensor, Scans, SensorMount, Wall};
use locus_map::{Map, SegmentMap};
use locus_replay::policy::{Estimation, Overrides, Settled, settle};
use locus_replay::{Config, EventKind, GaussMarkov, Log, replay};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

const SIGMA: f64 = 0.02; // m, the beams' noise
const BEAMS: u32 = 36;

fn normal(rng: &mut StdRng) -> f64 {
    let u1: f64 = rng.random_range(f64::EPSILON..1.0);
    let u2: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (2.0 * core::f64::consts::PI * u2).cos()
}

/// A 10 m x 8 m room, a robot on a circle of radius 2 m about (5, 4) at
/// 0.3 m/s for 120 s with odometry at 20 Hz (white speed noise), a scan of
/// 36 beams (10 degrees apart, from the robot's centre) at 5 Hz, exact
/// truth. Every `obstacle`-th scan has its first chosen beam read 1 m short.
fn room_log(seed: u64, obstacle: Option<usize>) -> LocusLog {
    room_log_with(seed, obstacle, None)
}

/// [`room_log`] with every beam of a scan also off by a shared range bias,
/// a Gauss-Markov process `bias` (m, s) sampled exactly at the scans.
fn room_log_with(seed: u64, obstacle: Option<usize>, bias: Option<GaussMarkov<f64>>) -> LocusLog {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut b = 0.0;
    let corners = [[0.0, 0.0], [10.0, 0.0], [10.0, 8.0], [0.0, 8.0]];
    let walls: Vec<Wall> = (0..4)
        .map(|i| {
            let (a, b) = (corners[i], corners[(i + 1) % 4]);
            Wall {
                x1: a[0],
                y1: a[1],
                x2: b[0],
                y2: b[1],
            }
        })
        .collect();
    let map = SegmentMap::new(
        walls
            .iter()
            .map(|w| [w.x1, w.y1, w.x2, w.y2].into())
            .collect(),
    )
    .unwrap();
    let sensor = BeamSensor {
        id: 0,
        mount: SensorMount::default(),
        min_range: 0.05,
        max_range: 20.0,
        angle_0: -core::f64::consts::PI,
        angle_step: 2.0 * core::f64::consts::PI / f64::from(BEAMS),
        count: BEAMS,
    };
    let (v, w) = (0.3, 0.15);
    let pose = |t: f64| {
        let th = w * t;
        [5.0 + 2.0 * th.sin(), 4.0 - 2.0 * th.cos(), th]
    };
    let mut odometry = Vec::new();
    let mut truth = Vec::new();
    let mut scans = Scans::default();
    let mut n_scan = 0;
    for i in 0..=2400 {
        let t = f64::from(i) * 0.05;
        odometry.push(Odometry {
            time: t,
            v: v + 0.01 * normal(&mut rng),
            omega: w + 0.005 * normal(&mut rng),
        });
        let p = pose(t);
        truth.push(TruthPose {
            time: t,
            x: p[0],
            y: p[1],
            theta: p[2],
        });
        if i % 4 == 0 {
            if let Some(g) = bias {
                b = if n_scan == 0 {
                    g.sigma * normal(&mut rng)
                } else {
                    g.decay(0.2) * b + g.step_variance(0.2).sqrt() * normal(&mut rng)
                };
            }
            let mut ranges: Vec<f32> = (0..BEAMS)
                .map(|k| {
                    let hit = Map::Segments(map.clone())
                        .cast([p[0], p[1]], p[2] + sensor.angle(k), sensor.max_range)
                        .unwrap();
                    (hit.range + b + SIGMA * normal(&mut rng)) as f32
                })
                .collect();
            if obstacle.is_some_and(|o| n_scan % o == 0) {
                ranges[0] -= 1.0;
            }
            scans.push(t, 0, &ranges);
            n_scan += 1;
        }
    }
    let start = truth[0];
    LocusLog {
        start: Some(start),
        odometry,
        truth: Groundtruth::new(truth).unwrap(),
        walls,
        beam_sensors: vec![sensor],
        scans,
        ..LocusLog::default()
    }
}

fn replayed(log: &Log, cfg: &Config) -> (locus_replay::Report, usize) {
    let mut scans = 0;
    let r = replay(log, cfg, |s| {
        if let EventKind::Scan { .. } = s.kind {
            scans += 1;
        }
    })
    .expect("replay");
    (r, scans)
}

/// With the noise it was simulated with, the filter tracks the robot to a
/// few centimetres and is honest: each position error inside its own
/// 3 sigma at least 95 % of the time (99.7 % for a consistent Gaussian).
#[test]
fn a_room_scan_by_scan_is_tracked_within_its_own_uncertainty() {
    let log = Log::from_locus("room", room_log(1, None)).unwrap();
    let cfg = Config {
        q_v: 0.01 * 0.01 * 0.05,
        q_omega: 0.005 * 0.005 * 0.05,
        beams: locus_replay::Beams {
            sigma: SIGMA,
            ..Default::default()
        },
        ..Config::default()
    };
    let (r, scans) = replayed(&log, &cfg);
    let s = r.summary;
    println!(
        "position RMSE {:.4} m, heading {:.4} rad, 3 sigma x/y {:?}, NEES {:.2}; beams {:?}",
        s.position_rmse, s.heading_rmse, s.within_3_sigma, s.mean_nees, r.beams
    );
    assert_eq!(scans, 601);
    assert_eq!(r.scans, 601);
    // 30 of the 36 beams a scan (the default), every one sees a wall.
    assert_eq!(r.beams.chosen, 601 * 30);
    assert!(r.beams.applied > 601 * 25, "{:?}", r.beams);
    assert!(s.position_rmse < 0.03, "{}", s.position_rmse);
    assert!(
        s.within_3_sigma[0] >= 0.95 && s.within_3_sigma[1] >= 0.95,
        "{s:?}"
    );
    assert!(s.mean_nees < 4.5, "{}", s.mean_nees);
}

/// A beam reading 1 m short of the wall (a person between the sensor and
/// the wall) is skipped as short, not applied.
#[test]
fn readings_far_shorter_than_the_map_are_skipped() {
    let log = Log::from_locus("room", room_log(2, Some(3))).unwrap();
    let cfg = Config {
        beams: locus_replay::Beams {
            sigma: SIGMA,
            ..Default::default()
        },
        ..Config::default()
    };
    let (r, _) = replayed(&log, &cfg);
    // One scan in three has one beam 1 m short: 201 of them.
    assert!(r.beams.short >= 195, "{:?}", r.beams);
    assert!(
        r.summary.position_rmse < 0.05,
        "{}",
        r.summary.position_rmse
    );
}

/// A log exported and read back keeps its walls, beam sensor and scans.
#[test]
fn a_log_with_beams_survives_its_export() {
    let log = Log::from_locus("room", room_log(3, None)).unwrap();
    let text = locus_logs::locus_csv::write(&log.to_locus());
    let back = locus_logs::locus_csv::parse(&text, std::path::Path::new("room.csv")).unwrap();
    let back = Log::from_locus("room", back).unwrap();
    assert_eq!(back.beam_sensors, log.beam_sensors);
    assert_eq!(back.scans, log.scans);
    assert!(back.map == log.map, "walls kept");
}

/// With no noise given, the policy estimates the beams' noise from the log
/// itself: on white range noise of 2 cm, within 25 % of it, with no range
/// bias to speak of, and the replay with the estimate stays honest.
#[test]
fn the_beams_noise_is_estimated_from_the_log() {
    let log = Log::from_locus("room", room_log(4, None)).unwrap();
    let settled = no_flags(&log);
    let bias = settled.range_bias.expect("a log with scans");
    println!("range bias {bias:?}");
    // White beams: the search finds a bias too small to matter, and not
    // significant.
    let search = bias.search.expect("searched");
    assert!(bias.bias.sigma < 0.1 * SIGMA, "{bias:?}");
    assert!(!search.significant(), "{search:?}");
    let sigma = settled.config.beams.sigma;
    let (r, _) = replayed(&log, &settled.config);
    let s = r.summary;
    println!(
        "sigma_beam {sigma:.4} m (simulated {SIGMA}), q_v {:.2e}, q_omega {:.2e}; RMSE {:.4} m, 3 sigma {:?}, NEES {:.2}",
        settled.config.q_v, settled.config.q_omega, s.position_rmse, s.within_3_sigma, s.mean_nees
    );
    assert!((sigma / SIGMA - 1.0).abs() < 0.25, "{sigma}");
    assert!(
        s.within_3_sigma[0] >= 0.9 && s.within_3_sigma[1] >= 0.9,
        "{s:?}"
    );
}

/// The settings of a replay with no flags.
fn no_flags(log: &Log) -> Settled {
    settle(
        log,
        &Config::default(),
        &Overrides {
            estimation: Estimation::Noise,
            ..Overrides::default()
        },
    )
    .expect("settle")
}

/// A range error shared by a scan's beams and persisting from scan to scan
/// (a Gauss-Markov bias of 3 cm and 5 s beside the white 2 cm) is found as
/// the range bias with no flags, near the values simulated, and the replay
/// with it is honest. Taken as white instead (the bias held, the beams'
/// noise widened for its correlation), the same log's filter is honest
/// too but far less accurate.
#[test]
fn a_persistent_range_error_is_found_as_a_bias() {
    let simulated = GaussMarkov {
        sigma: 0.03,
        tau: 5.0,
    };
    let log = Log::from_locus("room", room_log_with(7, None, Some(simulated))).unwrap();
    let settled = no_flags(&log);
    let bias = settled.range_bias.expect("a log with scans");
    let (r, _) = replayed(&log, &settled.config);
    let s = r.summary;
    let held = Config {
        beams: locus_replay::Beams {
            bias: locus_replay::Beams::HELD_BIAS,
            ..settled.config.beams
        },
        ..settled.config
    };
    let white = settle(
        &log,
        &held,
        &Overrides {
            estimation: Estimation::Noise,
            beam_bias: Some(locus_replay::Beams::HELD_BIAS),
            ..Overrides::default()
        },
    )
    .expect("settle");
    let (rw, _) = replayed(&log, &white.config);
    println!(
        "found {:?} (sigma_beam {:.4}); RMSE {:.4} m, 3 sigma {:?}, NEES {:.2}; \
         white: sigma_beam {:.4}, RMSE {:.4} m, 3 sigma {:?}, NEES {:.2}",
        bias.bias,
        settled.config.beams.sigma,
        s.position_rmse,
        s.within_3_sigma,
        s.mean_nees,
        white.config.beams.sigma,
        rw.summary.position_rmse,
        rw.summary.within_3_sigma,
        rw.summary.mean_nees
    );
    assert!(!bias.held, "{bias:?}");
    // 120 s hold about 12 independent stretches of a 5 s process, so each
    // value is known to some 20-50 % (seeds 7, 8, 9: sigma 0.046, 0.042,
    // 0.036 m; tau 8.5, 7.3, 4.5 s: sigma and tau trade along a ridge of
    // the likelihood, on which seed 7's (0.037 m, 5.9 s) and (0.051 m,
    // 10.7 s) differ by under 1 nat of 60 000).
    assert!(
        (0.6..1.6).contains(&(bias.bias.sigma / simulated.sigma)),
        "{bias:?}"
    );
    assert!(
        (0.4..2.5).contains(&(bias.bias.tau / simulated.tau)),
        "{bias:?}"
    );
    assert!(
        s.within_3_sigma[0] >= 0.9 && s.within_3_sigma[1] >= 0.9,
        "{s:?}"
    );
    assert!(
        rw.summary.position_rmse > 1.5 * s.position_rmse,
        "{:?}",
        rw.summary
    );
}

/// The truth's clock is measured from the sensors: a simulated log's
/// truth, exact, is compared at its stamps; the same truth stamped 0.1 s
/// late is found 0.1 s late and compared there.
#[test]
fn the_truth_clock_is_measured_from_the_sensors() {
    use locus_replay::truth_clock::{STEP, measure};
    let mut log = Log::from_locus("room", room_log(4, None)).unwrap();
    let cfg = Config::default();
    let exact = measure(&log, &cfg).expect("truth and scans");
    println!("exact truth: {exact:?}");
    assert!(!exact.applied, "{exact:?}");
    assert!(exact.offset.abs() <= STEP, "{exact:?}");
    log.truth = log.truth.shifted(0.1);
    let late = measure(&log, &cfg).expect("truth and scans");
    println!("truth 0.1 s late: {late:?}");
    assert!(late.applied, "{late:?}");
    assert!((late.offset - 0.1).abs() <= STEP, "{late:?}");
}

/// laser_wall_1d (paper 000's laser to a wall, Vicon truth) replayed with
/// no flags (issue 29): its truth is found about 70 ms late against the
/// laser and compared there; the range error that persists for seconds is
/// found as the range bias; the filter and the smoother are then each
/// inside their 3 sigma at least 90 % of the time, and no worse than the
/// range alone, judged at the same instants (the estimate after each
/// scan; `instants.rs`). (Measured: filter 6.54 mm, smoother 6.40 mm, the
/// range alone 6.60 mm. A causal filter cannot do much better than follow
/// the range here: the range error persists for about 4 s, over which the
/// odometry's own walk grows to about a centimetre.)
#[test]
fn laser_wall_replayed_with_no_flags_is_honest() {
    let path = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/laser_wall_1d/dataset1.txt"
    ));
    let read = locus_logs::aer1513::read(path).expect("laser_wall_1d");
    let mut log = Log::from_locus("dataset1.txt", read.log).unwrap();
    let base = Config {
        smooth: true,
        ..Config::default()
    };
    let clock = locus_replay::truth_clock::settle(&mut log, &base, None).expect("truth");
    let settled = settle(
        &log,
        &base,
        &Overrides {
            estimation: Estimation::Noise,
            ..Overrides::default()
        },
    )
    .expect("settle");
    let r = replay(&log, &settled.config, |_| {}).expect("replay");
    let smoothed = r.smoothed.expect("smoothed");
    let [range, kf] = locus_replay::rail::baselines(
        &log,
        read.wall_x,
        read.r_var,
        read.v_var,
        base.truth_max_gap,
    );
    println!(
        "{clock}\nrange bias {:?}, sigma_beam {:.4}, q_v {:.2e}\nfilter RMSE {:.5} m, 3 sigma {:?}\n\
         smoother RMSE {:.5} m, 3 sigma {:?}\nrange alone {:.5} m; linear KF {:.5} m, {:.3}",
        settled.range_bias,
        settled.config.beams.sigma,
        settled.config.q_v,
        r.summary.position_rmse,
        r.summary.within_3_sigma,
        smoothed.position_rmse,
        smoothed.within_3_sigma,
        range.rmse,
        kf.rmse,
        kf.within_3_sigma
    );
    assert!(
        clock.applied && (0.05..=0.09).contains(&clock.offset),
        "{clock:?}"
    );
    assert!(!settled.range_bias.expect("scans").held);
    for (name, s, bound) in [
        ("filter", r.summary, range.rmse),
        ("smoother", smoothed, range.rmse),
    ] {
        assert!(s.position_rmse <= bound, "{name}: {s:?} against {range:?}");
        assert!(s.within_3_sigma[0] >= 0.9, "{name}: {s:?}");
    }
}

/// The laser_wall_1d baselines reproduce the figures the data's README
/// gives (measured there by its own script): the range alone 0.0192 m, the
/// linear Kalman filter given the published noise 0.0253 m with 66 % of
/// steps inside its 3 sigma.
#[test]
fn the_laser_wall_baselines_match_the_published_figures() {
    let path = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/laser_wall_1d/dataset1.txt"
    ));
    let read = locus_logs::aer1513::read(path).expect("laser_wall_1d");
    let log = Log::from_locus("dataset1.txt", read.log).unwrap();
    let [range, kf] = locus_replay::rail::baselines(
        &log,
        read.wall_x,
        read.r_var,
        read.v_var,
        locus_replay::Config::default().truth_max_gap,
    );
    println!("range alone {range:?}\nlinear KF {kf:?}");
    assert_eq!(range.compared, 12709);
    assert!((range.rmse - 0.0192).abs() < 0.00005, "{range:?}");
    assert!((kf.rmse - 0.0253).abs() < 0.00005, "{kf:?}");
    assert!((kf.within_3_sigma - 0.66).abs() < 0.01, "{kf:?}");
}
