//! The noise estimate (`locus_replay::noise`) on a simulated log whose noise
//! and odometry delay are known: robot 3 of MRCLAM dataset 6 re-simulated,
//! its logged velocities as commands that the simulated robot follows
//! `DELAY` seconds late with white velocity noise, and its sightings (same
//! times, same landmarks) taken from the simulated pose with white noise.
//! (The family of simulated robots unlike MRCLAM, `locus family`, measures
//! the estimate more widely.)

use std::path::PathBuf;

use locus_logs::mrclam::{Dataset, Groundtruth, TruthPose};
use locus_replay::log::NoiseRecords;
use locus_replay::noise::estimate;
use locus_replay::{Config, Log};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

const Q_V: f64 = 0.002; // m^2/s
const Q_OMEGA: f64 = 0.004; // rad^2/s
const SIGMA_RANGE: f64 = 0.1; // m
const SIGMA_BEARING: f64 = 0.01; // rad
const DELAY: f64 = 0.1; // s

/// A standard normal draw (Box-Muller).
fn normal(rng: &mut StdRng) -> f64 {
    let u1: f64 = rng.random_range(f64::EPSILON..1.0);
    let u2: f64 = rng.random_range(0.0..1.0);
    (-2.0 * u1.ln()).sqrt() * (2.0 * core::f64::consts::PI * u2).cos()
}

fn simulated() -> Log {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/mrclam/MRCLAM_Dataset6");
    let dataset = Dataset::open(dir).expect("MRCLAM dataset 6");
    let mut log = Log::mrclam(&dataset, 3).expect("robot 3");
    let mut rng = StdRng::seed_from_u64(7);
    let t0 = log.odometry[0].time;
    let start = log.truth.pose_at(t0, 0.25).expect("truth at start");
    // Integrate at 10 ms: the command in force DELAY s earlier, plus white
    // noise of PSD Q (variance Q / dt per step).
    let dt = 0.01;
    let end = log.odometry.last().unwrap().time + DELAY;
    let mut poses = Vec::new();
    let (mut x, mut y, mut th) = (start.x, start.y, start.theta);
    let mut t = t0;
    let mut k = 0;
    while t <= end {
        poses.push(TruthPose {
            time: t,
            x,
            y,
            theta: th,
        });
        while k + 1 < log.odometry.len() && log.odometry[k + 1].time + DELAY <= t {
            k += 1;
        }
        let (v, w) = if log.odometry[k].time + DELAY <= t {
            (log.odometry[k].v, log.odometry[k].omega)
        } else {
            (0.0, 0.0)
        };
        let v = v + normal(&mut rng) * (Q_V / dt).sqrt();
        let w = w + normal(&mut rng) * (Q_OMEGA / dt).sqrt();
        x += v * dt * th.cos();
        y += v * dt * th.sin();
        th = locus_core::wrap_angle(th + w * dt);
        t += dt;
    }
    log.truth = Groundtruth::new(poses).expect("time order");
    log.start = Some(start);
    let truth = log.truth.clone();
    let landmarks = log.landmarks.clone();
    log.sightings.retain_mut(|s| {
        let (Some(p), Some(l)) = (
            truth.pose_at(s.time, 0.02),
            landmarks.iter().find(|l| l.id == s.landmark),
        ) else {
            return false;
        };
        let (dx, dy) = (l.x - p.x, l.y - p.y);
        s.range = dx.hypot(dy) + SIGMA_RANGE * normal(&mut rng);
        s.bearing = Some(locus_core::wrap_angle(
            dy.atan2(dx) - p.theta + SIGMA_BEARING * normal(&mut rng),
        ));
        true
    });
    log
}

/// The estimate starts from [`Config::default`] (MRCLAM's values: `q_v` =
/// `q_omega` = 0.002, a ratio `q_omega / q_v` of 1; range 1 m, bearing
/// 0.01 rad; no delay), while the log was simulated with `q_v` 0.002 m^2/s
/// and `q_omega` 0.004 rad^2/s, a ratio of 2: the starting ratio is wrong,
/// and the test asserts that both process noise values are recovered (each
/// within two of its standard errors, and their ratio nearer 2 than 1), as
/// are the measurement noise (within 20 %) and the delay (within 0.05 s).
#[test]
fn recovers_the_noise_and_delay_a_log_was_simulated_with() {
    let log = simulated();
    // From the MRCLAM defaults: the ratio of q_omega to q_v is wrong.
    let start = Config::default();
    let e = estimate(&log, &start, &NoiseRecords::default(), false).expect("estimate");
    let c = e.config;
    for r in &e.rounds {
        println!(
            "round: range {:.4} m (tau {:.2}), bearing {:.5} rad (tau {:.2})",
            r.range_spread, r.range_tau, r.bearing_spread, r.bearing_tau
        );
    }
    println!("delays (s, NLL): {:?}", e.delays);
    println!(
        "drift: q_v {:.5} +- {:.5}, q_omega {:.5} +- {:.5} ({} fixes)",
        e.drift.q_v, e.drift.q_v_se, e.drift.q_omega, e.drift.q_omega_se, e.drift.fixes
    );
    println!("q factors tried (factor, NLL): {:?}", e.q_factors);
    println!(
        "estimated: q_v {:.5} m^2/s, q_omega {:.5} rad^2/s, range {:.4} m, bearing {:.5} rad, delay {:.2} s (simulated {Q_V}, {Q_OMEGA}, {SIGMA_RANGE}, {SIGMA_BEARING}, {DELAY})",
        c.q_v, c.q_omega, c.sigma_range, c.sigma_bearing, c.odometry_delay
    );
    assert!((c.odometry_delay - DELAY).abs() <= 0.05 + 1e-12, "delay");
    assert!(
        (c.sigma_range / SIGMA_RANGE - 1.0).abs() < 0.2,
        "range noise"
    );
    assert!(
        (c.sigma_bearing / SIGMA_BEARING - 1.0).abs() < 0.2,
        "bearing noise"
    );
    // The process noise, from the drift between pose fixes where it tells
    // the value, else from the likelihood, comes with its standard error:
    // the truth lies within two of it.
    for (name, value, se, truth) in [
        ("q_v", c.q_v, e.q_se(0), Q_V),
        ("q_omega", c.q_omega, e.q_se(1), Q_OMEGA),
    ] {
        assert!(
            se > 0.0 && (value - truth).abs() <= 2.0 * se,
            "{name}: {value} +- {se}, truth {truth}"
        );
    }
    // And the ratio moved from the start's 1 to the log's 2: nearer 2 than
    // 1 on a log scale (above sqrt 2), which a q_omega left at its start
    // would not be.
    let ratio = c.q_omega / c.q_v;
    assert!(
        ratio > core::f64::consts::SQRT_2,
        "q_omega / q_v = {ratio}: still nearer the start's 1 than the log's {}",
        Q_OMEGA / Q_V
    );
}

/// The policy's noise estimate settles the bearing bias from the log: on the
/// simulated robot 3 whose bearings all read 0.04 rad high (a sensor mounted
/// off-axis), the whole log tells the bias, the replay estimates it and
/// ends within 3 of its standard deviations of 0.04 rad.
#[test]
fn a_bearing_offset_the_motion_reveals_is_estimated() {
    use locus_replay::policy::{Estimation, Overrides, settle};
    const OFFSET: f64 = 0.04;
    let mut log = simulated();
    for s in &mut log.sightings {
        s.bearing = s.bearing.map(|b| locus_core::wrap_angle(b + OFFSET));
    }
    let overrides = Overrides {
        estimation: Estimation::Noise,
        ..Overrides::default()
    };
    let settled = settle(&log, &Config::default(), &overrides).expect("settle");
    let bias = settled.biases[1];
    println!("{bias:?}");
    assert!(!bias.held, "{bias:?}");
    let r = locus_replay::replay(&log, &settled.config, |_| {}).expect("replay");
    let (b, sd) = r.calibration[3];
    println!("bearing bias {b:.4} +- {sd:.4} rad (simulated {OFFSET})");
    assert!((b - OFFSET).abs() <= 3.0 * sd && sd < 0.01, "{b} +- {sd}");
}

/// A robot that stands still cannot tell a bearing offset from its heading:
/// the policy holds the bias at 0 and says so.
#[test]
fn a_bearing_offset_a_robot_standing_still_cannot_tell_is_held() {
    use locus_replay::policy::{Estimation, Overrides, settle};
    let mut log = simulated();
    let pose = TruthPose {
        time: 0.0,
        x: 1.0,
        y: 0.5,
        theta: 0.3,
    };
    let mut rng = StdRng::seed_from_u64(3);
    log.odometry = (0..1200)
        .map(|k| locus_logs::mrclam::Odometry {
            time: f64::from(k) * 0.1,
            v: 0.0,
            omega: 0.0,
        })
        .collect();
    log.truth = Groundtruth::new(vec![
        pose,
        TruthPose {
            time: 120.0,
            ..pose
        },
    ])
    .expect("truth");
    log.start = Some(pose);
    log.sightings = (0..240)
        .flat_map(|k| {
            let t = f64::from(k) * 0.5 + 0.05;
            log.landmarks
                .iter()
                .filter(|l| (l.x - pose.x).hypot(l.y - pose.y) < 6.0)
                .map(|l| (l.id, l.x - pose.x, l.y - pose.y))
                .collect::<Vec<_>>()
                .into_iter()
                .map(move |(id, dx, dy)| (t, id, dx, dy))
        })
        .map(|(t, id, dx, dy)| locus_replay::Sighting {
            time: t,
            arrival: t,
            landmark: id,
            range: dx.hypot(dy) + SIGMA_RANGE * normal(&mut rng),
            bearing: Some(locus_core::wrap_angle(
                dy.atan2(dx) - pose.theta + 0.04 + SIGMA_BEARING * normal(&mut rng),
            )),
        })
        .collect();
    log.lines.measurements.clear();
    let overrides = Overrides {
        estimation: Estimation::Noise,
        ..Overrides::default()
    };
    let settled = settle(&log, &Config::default(), &overrides).expect("settle");
    let bias = settled.biases[1];
    println!("{bias:?}");
    assert!(bias.held, "{bias:?}");
    let r = locus_replay::replay(&log, &settled.config, |_| {}).expect("replay");
    assert!(r.calibration[3].0.abs() < 1e-9 && r.calibration[3].1 <= 1e-6);
}
