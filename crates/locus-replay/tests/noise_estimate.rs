//! The noise estimate (`locus_replay::noise`) on a simulated log whose noise
//! and odometry delay are known: robot 3 of MRCLAM dataset 6 re-simulated,
//! its logged velocities as commands that the simulated robot follows
//! `DELAY` seconds late with white velocity noise, and its sightings (same
//! times, same landmarks) taken from the simulated pose with white noise.

use std::path::PathBuf;

use locus_logs::mrclam::{Dataset, Groundtruth, TruthPose};
use locus_replay::noise::{Q_FACTORS, estimate};
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

#[test]
fn recovers_the_noise_and_delay_a_log_was_simulated_with() {
    let log = simulated();
    // The estimate scales both process noises by one factor, keeping the
    // start's ratio: start from the simulation's ratio (2).
    let start = Config {
        q_v: 0.01,
        q_omega: 0.02,
        ..Config::default()
    };
    let e = estimate(&log, &start).expect("estimate");
    let c = e.config;
    for r in &e.rounds {
        println!(
            "round: range {:.4} m (tau {:.2}), bearing {:.5} rad (tau {:.2})",
            r.range_spread, r.range_tau, r.bearing_spread, r.bearing_tau
        );
    }
    println!("delays (s, NLL): {:?}", e.delays);
    println!("Q factors (factor, NLL): {:?}", e.q_factors);
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
    // The process noise is searched on a grid of factors about 2x apart:
    // within one step of the truth.
    let ratio = c.q_v / Q_V;
    assert!(
        ratio > 0.4 && ratio < 2.5,
        "q_v {} (grid {:?})",
        c.q_v,
        Q_FACTORS
    );
    assert!((c.q_omega / c.q_v - Q_OMEGA / Q_V).abs() < 1e-9);
}
