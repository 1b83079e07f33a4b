//! NEES consistency of the EKF on `square-ideal`: with the
//! simulated noise exactly as the filter's `Q` and `R` assume, the N-run
//! average NEES of each time step lies inside the two-sided 95 % interval of
//! `chi-square(3N) / N` for at least 90 % of the steps.

use locus_core::chi2;
use locus_sim::closed_loop::{SquareConfig, StepRecord, run_square};

/// Monte-Carlo runs (seeds `0..RUNS`).
const RUNS: u64 = 100;

/// Per-step NEES of one run of `cfg` from `seed`.
fn nees_series(cfg: &SquareConfig, seed: u64) -> Vec<f64> {
    let mut series = Vec::new();
    run_square(cfg, seed, &mut |r: &StepRecord| series.push(r.nees)).expect("run");
    series
}

#[test]
#[allow(clippy::cast_precision_loss)]
fn average_nees_on_square_ideal_is_consistent() {
    let cfg = SquareConfig::ideal();
    let seeds: Vec<u64> = (0..RUNS).collect();
    let threads = std::thread::available_parallelism().map_or(4, usize::from);
    let chunk = seeds.len().div_ceil(threads);
    let runs: Vec<Vec<f64>> = std::thread::scope(|scope| {
        let handles: Vec<_> = seeds
            .chunks(chunk)
            .map(|chunk| {
                scope.spawn(|| {
                    chunk
                        .iter()
                        .map(|&seed| nees_series(&cfg, seed))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("worker"))
            .collect()
    });

    // Align the runs on the steps they all have (the lap time varies a little
    // with the noise).
    let steps = runs.iter().map(Vec::len).min().expect("runs");
    assert!(steps > 1000, "runs too short: {steps} steps");
    let n = runs.len() as f64;
    let dof = u32::try_from(3 * runs.len()).expect("dof");
    let lo = chi2::quantile(0.025, dof).expect("quantile") / n;
    let hi = chi2::quantile(0.975, dof).expect("quantile") / n;
    let mut inside = 0usize;
    let mut total = 0.0;
    for k in 0..steps {
        let avg = runs.iter().map(|r| r[k]).sum::<f64>() / n;
        total += avg;
        if (lo..=hi).contains(&avg) {
            inside += 1;
        }
    }
    let share = inside as f64 / steps as f64;
    println!(
        "square-ideal: {} runs, {steps} steps, average NEES {:.3}, \
         {:.1} % of steps in [{lo:.3}, {hi:.3}]",
        runs.len(),
        total / steps as f64,
        100.0 * share
    );
    assert!(share >= 0.90, "share {share} of steps inside [{lo}, {hi}]");
}
