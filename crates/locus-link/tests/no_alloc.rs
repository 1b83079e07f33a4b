//! The codec, the receiver and the clock estimator never allocate (the
//! crate is `no_std` without `alloc`, so it cannot; this checks it at run
//! time under allocation-counter's counting global allocator, which counts
//! the allocations of the measuring thread only, so the test harness's own
//! threads cannot disturb the count).

use locus_link::{ClockEstimator, CommandPacket, MAX_PACKET, Receiver, Telemetry, decode};

#[test]
fn codec_receiver_and_clock_do_not_allocate() {
    let mut buf = [0u8; MAX_PACKET];
    let mut rx = Receiver::new();
    let mut clock = ClockEstimator::<16>::new(0.05);
    // The counter is live: one allocation is seen as one.
    let control = allocation_counter::measure(|| {
        core::hint::black_box(Vec::<u8>::with_capacity(1));
    });
    assert_eq!(
        control.count_total, 1,
        "the counting allocator is not active"
    );
    let mut applied = 0u32;
    let info = allocation_counter::measure(|| {
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
            let c = CommandPacket {
                sequence: k,
                ack: k,
                right: 0.1,
                left: 0.2,
            };
            let m = c.encode(&mut buf).unwrap();
            decode(&buf[..m]).unwrap();
            let _ = clock.estimate();
        }
    });
    assert_eq!(applied, 9_000);
    assert_eq!(rx.counters().corrupt, 1_000);
    assert_eq!(
        info.count_total, 0,
        "{} allocations in the link loop",
        info.count_total
    );
}
