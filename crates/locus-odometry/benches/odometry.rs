//! Odometry arithmetic, in ns, in one run: CORDIC sine/cosine (the paper's
//! 16-bit/16-iteration rotator and a 32-bit/24-iteration one) beside
//! `f64::sin_cos` and libm, and one tricycle step (rear, front, and with
//! each slip-rejection rule).
//!
//! `cargo bench -p locus-odometry --bench odometry`

use core::hint::black_box;
use core::time::Duration;

use criterion::Criterion;
use locus_core::Pose;
use locus_odometry::cordic::{Cordic, Libm};
use locus_odometry::redundant::{Integration, Odometry, Reading, Selection, Tricycle};

/// Paper 004: a sequential core, one iteration per clock, 16 iterations at
/// 50 MHz.
const PAPER_NS: f64 = 16.0 / 50.0e6 * 1.0e9;

fn trig(c: &mut Criterion) {
    println!(
        "reference: paper 004 FPGA CORDIC, 16 iterations x 1 clock at 50 MHz = {PAPER_NS:.0} ns \
         (text: \"less than 400 ns\")"
    );
    // 256 angles spread over +-pi (a fixed pseudo-random sequence), one per
    // call, so that neither the fold nor a branch predictor sees the same
    // angle twice in a row; most need the quadrant fold (|angle| > pi/4).
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let angles: Vec<f64> = (0..256)
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 * core::f64::consts::PI
                - core::f64::consts::PI
        })
        .collect();
    for (name, cordic) in [("16/16", Cordic::PAPER), ("32/24", Cordic::WIDE)] {
        let fixed: Vec<i64> = angles.iter().map(|&a| cordic.to_fixed(a)).collect();
        let mut k = 0usize;
        c.bench_function(&format!("sin_cos/cordic {name} (i64 in, i64 out)"), |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                black_box(&cordic).sin_cos_fixed(black_box(fixed[k]))
            })
        });
        c.bench_function(&format!("sin_cos/cordic {name} (f64 in, f64 out)"), |b| {
            b.iter(|| {
                k = (k + 1) & 255;
                black_box(&cordic).sin_cos(black_box(angles[k]))
            })
        });
    }
    let mut k = 0usize;
    c.bench_function("sin_cos/f64::sin_cos (std)", |b| {
        b.iter(|| {
            k = (k + 1) & 255;
            black_box(angles[k]).sin_cos()
        })
    });
    c.bench_function("sin_cos/libm::sincos", |b| {
        b.iter(|| {
            k = (k + 1) & 255;
            libm::sincos(black_box(angles[k]))
        })
    });
}

fn tricycle(c: &mut Criterion) {
    let t = Tricycle::<f64>::assumed();
    // 1 cm of a left arc of radius 2 m (steering 12.7 deg = 70 counts).
    let reading = Reading {
        n_l: 57,
        n_r: 70,
        n_f: 54,
        n_s: 70,
    };
    let pose = Pose::new(1.0, 2.0, 0.7);
    let cases = [
        ("rear only", Selection::Rear),
        ("front only", Selection::Front),
        ("component-wise min", Selection::ComponentMin),
        ("consistent set", Selection::ConsistentSet),
    ];
    for (name, selection) in cases {
        let odo = Odometry::new(t, selection, Integration::Euler, Libm, pose);
        c.bench_function(&format!("tricycle step/{name} (f64, libm)"), |b| {
            b.iter(|| {
                let mut o = black_box(odo);
                o.step(black_box(&reading))
            })
        });
    }
    let odo = Odometry::new(
        t,
        Selection::ComponentMin,
        Integration::Euler,
        Cordic::PAPER,
        pose,
    );
    c.bench_function(
        "tricycle step/component-wise min (f64, CORDIC 16/16)",
        |b| {
            b.iter(|| {
                let mut o = black_box(odo);
                o.step(black_box(&reading))
            })
        },
    );
    let t32 = Tricycle::<f32>::assumed();
    let odo = Odometry::new(
        t32,
        Selection::ComponentMin,
        Integration::Euler,
        Libm,
        Pose::new(1.0f32, 2.0, 0.7),
    );
    c.bench_function("tricycle step/component-wise min (f32, libm)", |b| {
        b.iter(|| {
            let mut o = black_box(odo);
            o.step(black_box(&reading))
        })
    });
}

fn main() {
    let mut c = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .configure_from_args();
    trig(&mut c);
    tricycle(&mut c);
    c.final_summary();
}
