//! Times the replay engine on an MRCLAM robot, for `scripts/replay_speed.sh`
//! (which runs it beside the pure-Python reference): loading the log, the
//! forward filter with evaluation, and the filter with the smoother, each
//! the best of several runs, in microseconds per event. Prints JSON.
//!
//! `cargo run --release -p locus-replay --example replay_speed -- DIR ROBOT`

use std::time::Instant;

use locus_logs::mrclam::Dataset;
use locus_replay::{Config, Log, replay};

fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

#[allow(clippy::cast_precision_loss)]
fn main() {
    let mut args = std::env::args().skip(1);
    let dir = args.next().expect("usage: replay_speed DIR ROBOT");
    let robot: u32 = args.next().map_or(3, |r| r.parse().expect("robot number"));
    let mut log = Log::default();
    let load = best_of(3, || {
        let dataset = Dataset::open(&dir).expect("dataset");
        log = Log::mrclam(&dataset, robot).expect("robot");
    });
    let events = (log.odometry.len() + log.sightings.len()) as f64;
    let log = &log;
    let run = |cfg: Config| {
        move || {
            let mut n = 0usize;
            replay(log, &cfg, |s| n += usize::from(s.truth.is_some())).expect("replay");
            assert!(n > 0);
        }
    };
    let filter = best_of(5, run(Config::default()));
    let smoothed = best_of(
        5,
        run(Config {
            smooth: true,
            ..Config::default()
        }),
    );
    println!(
        "{{\"robot\": {robot}, \"events\": {events}, \"load_s\": {load:.4}, \"load_us_per_event\": {:.3}, \"filter_us_per_event\": {:.3}, \"filter_smoother_us_per_event\": {:.3}}}",
        load / events * 1e6,
        filter / events * 1e6,
        smoothed / events * 1e6
    );
}
