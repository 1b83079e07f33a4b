//! The codec, the receiver and the clock estimator never allocate (the
//! crate is `no_std` without `alloc`, so it cannot; this checks it at run
//! time under a counting global allocator).
#![allow(unsafe_code)] // a GlobalAlloc impl is unsafe by definition

use core::alloc::{GlobalAlloc, Layout};
use core::sync::atomic::{AtomicUsize, Ordering};
use std::alloc::System;

use locus_link::{ClockEstimator, Command, MAX_PACKET, Receiver, Telemetry, decode};

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
fn codec_receiver_and_clock_do_not_allocate() {
    let mut buf = [0u8; MAX_PACKET];
    let mut rx = Receiver::new();
    let mut clock = ClockEstimator::<16>::new(0.05);
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut applied = 0u32;
    for k in 0..10_000u32 {
        let mut t = Telemetry::new(k, u64::from(k) * 10_000);
        t.counts = [k.wrapping_mul(7), k.wrapping_mul(5)];
        t.ir = (k % 2 == 0).then_some([0.1, 0.2]);
        t.set_beams(&[1.0, 2.0, 3.0][..(k % 4) as usize]).unwrap();
        let n = t.encode(&mut buf).unwrap();
        if k % 10 == 3 {
            buf[5] ^= 1; // corrupt
        }
        if rx.receive_telemetry(&buf[..n]).is_ok() {
            applied += 1;
            clock.push(f64::from(k) * 0.01, f64::from(k) * 0.01 + 0.5);
        }
        let c = Command {
            sequence: k,
            ack: k,
            right: 0.1,
            left: 0.2,
        };
        let m = c.encode(&mut buf).unwrap();
        decode(&buf[..m]).unwrap();
        let _ = clock.estimate();
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert_eq!(applied, 9_000);
    assert_eq!(rx.counters().corrupt, 1_000);
    assert_eq!(after, before, "{} allocations", after - before);
}
