//! The clock estimator tracks a robot clock with 0.5 s offset and 100 ppm
//! drift to within 1 ms, with up to 0.5 ms of random one-way delay (buckets
//! of 1 s, a 64 s window).

use locus_link::ClockEstimator;

/// A small deterministic generator (xorshift64*), uniform in [0, 1).
struct Uniform(u64);

impl Uniform {
    #[allow(clippy::cast_precision_loss)]
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn tracks_offset_and_drift_within_1_ms() {
    let (offset, drift) = (0.5, 100e-6);
    let mut est = ClockEstimator::<64>::new(1.0);
    let mut u = Uniform(0x9E37_79B9_7F4A_7C15);
    let mut worst: f64 = 0.0;
    // 100 Hz for 1000 s of host time, starting late in the day (large
    // absolute times).
    for k in 0..100_000u32 {
        let host_send = 40_000.0 + f64::from(k) * 0.01;
        let robot = offset + (1.0 + drift) * host_send;
        let host_rx = host_send + 0.5e-3 * u.next();
        est.push(robot, host_rx);
        if k >= 100 {
            // Robot time now, against the truth at this host time.
            let now = host_rx;
            let truth = offset + (1.0 + drift) * now;
            let err = (est.robot_time(now).unwrap() - truth).abs();
            worst = worst.max(err);
        }
    }
    let fit = est.estimate().unwrap();
    println!(
        "worst robot-time error {:.3} ms; fit offset {:.6} s, drift {:.2} ppm",
        worst * 1e3,
        fit.offset,
        fit.drift * 1e6
    );
    assert!(worst < 1e-3, "worst error {worst} s");
    assert!((fit.drift - drift).abs() < 10e-6, "drift {}", fit.drift);
    // The offset at host time 0 extrapolates 40 000 s back: the drift's
    // error dominates it; check it at the window instead.
    let last = 40_000.0 + 999.99;
    assert!((fit.robot_time(last) - (offset + (1.0 + drift) * last)).abs() < 1e-3);
}

#[test]
fn no_estimate_before_two_distinct_times() {
    let mut est = ClockEstimator::<8>::new(0.0);
    assert!(est.estimate().is_none());
    est.push(1.0, 2.0);
    assert!(est.estimate().is_none());
    est.push(1.5, 2.0);
    assert!(est.estimate().is_none());
    est.push(2.0, 3.0);
    let fit = est.estimate().unwrap();
    assert!(fit.drift.is_finite());
}
