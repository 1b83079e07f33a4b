//! Speed of the paper-001 closed loop on `square` (EKF at 100 Hz, no I/O):
//! one whole two-lap run per iteration; the printed real-time factor is the
//! simulated time over the measured time per run.
//!
//! `cargo bench -p locus-sim --bench closed_loop`

use core::hint::black_box;
use core::time::Duration;
use std::time::Instant;

use criterion::{Criterion, criterion_group, criterion_main};
use locus_sim::closed_loop::{SquareConfig, run_square};

fn closed_loop(c: &mut Criterion) {
    let cfg = SquareConfig::default();
    let summary = run_square(&cfg, 1, &mut |_| {}).expect("square runs");
    let mut group = c.benchmark_group("closed_loop");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    group.bench_function("square, 2 laps, 100 Hz, no I/O", |b| {
        b.iter(|| {
            run_square(black_box(&cfg), black_box(1), &mut |r| {
                black_box(r);
            })
        })
    });
    group.finish();
    // The real-time factor, from a few timed runs beside criterion's figure.
    let runs = 5;
    let start = Instant::now();
    for _ in 0..runs {
        black_box(run_square(&cfg, 1, &mut |r| {
            black_box(r);
        }))
        .expect("square runs");
    }
    let per_run = start.elapsed().as_secs_f64() / f64::from(runs);
    println!(
        "square: {} steps, {:.1} s simulated, {:.2} ms per run: {:.2} us per step, real-time factor {:.0}",
        summary.steps,
        summary.duration,
        per_run * 1e3,
        per_run * 1e6 / summary.steps as f64,
        summary.duration / per_run
    );
}

criterion_group!(benches, closed_loop);
criterion_main!(benches);
