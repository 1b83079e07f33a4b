//! `locus guide` (paper 001's steps a-f) on the default seed and 20 others.
//!
//! Steps a-d and f meet their criteria on all 21 seeds. Step e meets its
//! gain criterion (the filter jumps to each measurement) but not the
//! spec's "RMSE within 20 % of c's": with Q large enough for a position
//! gain >= 0.9, e's RMSE is 70-155 % above c's (measured, see the README).
//! The test pins that: if e ever came within 20 % of c, the README is
//! wrong.

use locus_sim::guide::run_guide;

#[test]
fn the_guide_steps_meet_their_criteria_on_21_seeds() {
    let seeds: Vec<u64> = core::iter::once(1).chain(1001..1021).collect();
    for seed in seeds {
        let steps = run_guide(seed).expect("guide");
        let letters: String = steps.iter().map(|s| s.step).collect();
        assert_eq!(letters, "abcdef");
        for s in &steps {
            if s.step == 'e' {
                assert!(!s.passed, "seed {seed}: e now passes: {}", s.measured);
                let gain: f64 = s
                    .measured
                    .strip_prefix("mean position gain ")
                    .and_then(|r| r.split(';').next())
                    .and_then(|g| g.parse().ok())
                    .expect("gain figure");
                assert!(gain >= 0.9, "seed {seed}: {}", s.measured);
            } else {
                assert!(
                    s.passed,
                    "seed {seed}, step {}: {} ({})",
                    s.step, s.measured, s.criterion
                );
            }
        }
    }
}
