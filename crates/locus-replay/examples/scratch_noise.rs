//! scratch
use locus_replay::log::NoiseRecords;
use locus_replay::{Config, Log};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let log = Log::locus_csv(std::path::Path::new(&args[1])).unwrap();
    let mut start = Config::default();
    start.calibration.std[2] = 0.05;
    start.calibration.std[3] = 0.05;
    let e = locus_replay::noise::estimate(&log, &start, &NoiseRecords::default(), false).unwrap();
    for r in &e.rounds {
        println!(
            "range {:.4} tau {:.2} (n {}) bearing {:.5} tau {:.2} q {:.6} {:.6} cal {:?}",
            r.range_spread,
            r.range_tau,
            r.ranges,
            r.bearing_spread,
            r.bearing_tau,
            r.config.q_v,
            r.config.q_omega,
            r.calibration
        );
    }
    println!(
        "drift q_v {} +- {} q_w {} +- {} fixes {}",
        e.drift.q_v, e.drift.q_v_se, e.drift.q_omega, e.drift.q_omega_se, e.drift.fixes
    );
    for i in &e.drift.intervals {
        println!("  {:?}", i);
    }
}
