//! The filter step never allocates: predict, correct (batch, sequential, with
//! gate) and the 11-step schedule run under allocation-counter's counting
//! global allocator, which counts the allocations of the measuring thread
//! only (the test harness's own threads cannot disturb the count).

mod common;

use locus_core::{ChiSquareGate, CovarianceUpdate, Ekf};

#[test]
fn predict_and_correct_do_not_allocate() {
    let mut r = common::rng(5);
    let inputs: Vec<_> = (0..1000)
        .map(|_| (common::random_travel(&mut r), common::random_ir(&mut r)))
        .collect();
    let model = common::random_model(&mut r);
    let start = common::random_belief(&mut r, 1e4);
    let gate = ChiSquareGate::new(0.999).unwrap();
    let filters = [
        Ekf::new(CovarianceUpdate::Joseph).with_gate(gate),
        Ekf::new(CovarianceUpdate::Plain),
        Ekf::new(CovarianceUpdate::ForcedSymmetric),
    ];

    // The counter is live: one allocation is seen as one.
    let control = allocation_counter::measure(|| {
        core::hint::black_box(Vec::<u8>::with_capacity(1));
    });
    assert_eq!(
        control.count_total, 1,
        "the counting allocator is not active"
    );
    let mut applied = 0usize;
    let info = allocation_counter::measure(|| {
        for ekf in &filters {
            let mut b = start;
            for (u, obs) in &inputs {
                b = ekf.predict(&b, &model, u).unwrap();
                let z = obs.z();
                let c = ekf.correct(&b, obs, &z).unwrap();
                let s = ekf.correct_sequential(&b, obs, &z).unwrap();
                let k = locus_core::schedule::correct_11_step(&b, obs, &z).unwrap();
                applied += usize::from(c.applied) + usize::from(s.applied);
                b = if c.applied { c.belief } else { k.belief() };
            }
            core::hint::black_box(b);
        }
    });
    assert!(applied > 0);
    assert_eq!(
        info.count_total, 0,
        "{} heap allocations in the filter loop",
        info.count_total
    );
}
