//! `locus guide` (paper 001's steps a-f, criteria of spec section 3 as
//! revised on 2026-12-01) over a fixed set of 22 seeds, none left out:
//! 1 (the default of `locus guide`), 101, 201, ..., 2101.
//!
//! **Criterion: steps a to e pass on every seed; step f passes on at least
//! 20 of the 22 seeds.** The test prints the rate it measured.
//!
//! Each guide seed `s` runs every step over the seeds `s..s + 10` and
//! step f's NEES test over `s..s + 100`; the seeds are 100 apart, so the
//! guides share no run and their outcomes are independent draws.
//!
//! Why f alone has an allowance. Steps a to e compare means of ten runs
//! with thresholds far from them: a correct filter meets them on every
//! seed, so one failure is a fault. Step f also asks for a NEES test,
//! which is itself a statistical test: the share of steps whose 100-run
//! average NEES lies in the 95 % interval of `chi-square(300) / 100`
//! (2.54 to 3.50) must be at least 90 %. The steps of a run are
//! correlated, so that share varies from one seed set to the next, and a
//! correct filter falls below 90 % on some seeds: over the 50 disjoint
//! guide seeds 1, 101, ..., 4901, f failed on 1 (docs/guide.md). Taking
//! that rate, p = 0.02 per seed, the number of failures among 22 seeds is
//! binomial(22, p): P(more than 2) = 1 - P(0) - P(1) - P(2) = 1 - 0.641 -
//! 0.288 - 0.062 = 0.01. So a correct filter passes f on at least 20 of
//! the 22 seeds with probability 0.99 (0.90 even at p = 0.05, 2.5 times
//! the rate seen), should a change of the simulator's random draws give
//! new seed sets.
//!
//! The test can still fail. A filter whose covariance were wrong by a
//! factor of 2 would have a mean NEES of 1.5 or 6 instead of 3, outside
//! that interval at nearly every step, and f would fail on every seed; a
//! step of a to e that breaks fails on its first seed.

use rayon::prelude::*;

use locus_sim::guide::run_guide;

/// The fixed seeds: the default seed of `locus guide` and 21 others, 100
/// apart.
const SEEDS: [u64; 22] = {
    let mut seeds = [0; 22];
    let mut k = 0;
    while k < seeds.len() {
        seeds[k] = 1 + 100 * k as u64;
        k += 1;
    }
    seeds
};

/// Step f must pass on at least this many of [`SEEDS`] (module doc).
const F_AT_LEAST: usize = 20;

#[test]
fn the_guide_passes_a_to_e_on_every_seed_and_f_on_20_of_22() {
    // The guide runs each step's seeds on all cores; the guides themselves
    // run in parallel too.
    let guides: Vec<_> = SEEDS
        .par_iter()
        .map(|&seed| (seed, run_guide(seed).expect("guide")))
        .collect();
    let mut failures = Vec::new();
    let mut f_failures = Vec::new();
    for (seed, steps) in &guides {
        let letters: String = steps.iter().map(|s| s.step).collect();
        assert_eq!(letters, "abcdef", "seed {seed}");
        for s in steps.iter().filter(|s| !s.passed) {
            let line = format!(
                "seed {seed}, step {}: {} ({})",
                s.step, s.measured, s.criterion
            );
            if s.step == 'f' {
                f_failures.push(line);
            } else {
                failures.push(line);
            }
        }
    }
    let f_passed = SEEDS.len() - f_failures.len();
    println!(
        "step f passed on {f_passed} of {} seeds ({:.0} %), criterion at least {F_AT_LEAST}",
        SEEDS.len(),
        100.0 * f_passed as f64 / SEEDS.len() as f64
    );
    for line in &f_failures {
        println!("{line}");
    }
    assert!(
        failures.is_empty(),
        "steps a to e must pass on every seed:\n{}",
        failures.join("\n")
    );
    assert!(
        f_passed >= F_AT_LEAST,
        "step f passed on {f_passed} of {} seeds, fewer than {F_AT_LEAST}:\n{}",
        SEEDS.len(),
        f_failures.join("\n")
    );
}
