//! Speed of a whole replay: MRCLAM dataset 6, robot 3 (about 900 s of
//! odometry and sightings), read once outside the timing; the timed part
//! is [`locus_replay::replay`] with the default configuration, every step
//! handed to a sink that keeps the last position (so nothing is optimised
//! away); then the same with the Rauch-Tung-Striebel smoother. Ratios to
//! a pure-Python filter loop: `scripts/replay_speed.sh`.

use core::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use locus_logs::mrclam::Dataset;
use locus_replay::{Config, Log, replay};

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/mrclam/MRCLAM_Dataset6")
}

fn bench(c: &mut Criterion) {
    let dataset = Dataset::open(data_dir()).expect("MRCLAM dataset 6");
    let log = Log::mrclam(&dataset, 3).expect("robot 3");
    let cfg = Config::default();
    let mut group = c.benchmark_group("replay");
    group.sample_size(10);
    group.bench_function(
        format!(
            "MRCLAM 6 robot 3 ({:.0} s, {} odometry, {} sightings)",
            log.duration(),
            log.odometry.len(),
            log.sightings.len()
        ),
        |b| {
            b.iter(|| {
                let mut last = 0.0;
                let report = replay(black_box(&log), &cfg, |s| last = s.belief.x[0]).unwrap();
                black_box((report.steps, last))
            });
        },
    );
    let smoothed = Config {
        smooth: true,
        ..Config::default()
    };
    group.bench_function("MRCLAM 6 robot 3, filter and smoother", |b| {
        b.iter(|| {
            let mut last = 0.0;
            let report = replay(black_box(&log), &smoothed, |s| {
                last = s.smoothed.map_or(0.0, |p| p.x[0]);
            })
            .unwrap();
            black_box((report.steps, last))
        });
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
