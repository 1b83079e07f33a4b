//! The filter step never allocates: predict, correct (batch, sequential, with
//! gate) and the 11-step schedule run under a counting global allocator.
#![allow(unsafe_code)] // a GlobalAlloc impl is unsafe by definition

mod common;

use core::alloc::{GlobalAlloc, Layout};
use core::sync::atomic::{AtomicUsize, Ordering};
use std::alloc::System;

use locus_core::{ChiSquareGate, CovarianceUpdate, Ekf};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

// One test in this binary, so no other test thread allocates meanwhile.
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

    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut applied = 0usize;
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
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert!(applied > 0);
    assert_eq!(
        after - before,
        0,
        "{} heap allocations in the filter loop",
        after - before
    );
}
