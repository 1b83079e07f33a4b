//! The floor of a batch run of paper 001's EKF step: the loop of
//! `locus.Filter.run` (the Python package) written in plain Rust, with the
//! same built-in models, Joseph form and results (pose, covariance, NIS,
//! applied: 14 numbers per step into four arrays), over the steps
//! `scripts/python_speed.py` times (a file of rows `d1, d2, ds1, ds2, wall`
//! as little-endian f64, NaN readings for a step without one; walls 0 to 3
//! for x+, x-, y+, y-). Prints the best of 7 runs in ns per step.
//!
//! Run: `cargo run --release -p locus-models --example batch_floor -- STEPS.bin`
//! (the speed script runs it).

#![allow(clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

use std::time::Instant;

use locus_core::nalgebra::{Matrix3, Vector3};
use locus_core::{Belief, CovarianceUpdate, Ekf};
use locus_models::{AxisWall, DiffDrive, IrPair, IrPairObservation, WheelTravel};

fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: batch_floor STEPS.bin");
    let raw = std::fs::read(&path).expect("reading the steps");
    let v: Vec<f64> = raw
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    let n = v.len() / 5;
    // The speed script's models (its cross-check run's constants).
    let drive = std::hint::black_box(DiffDrive::new(0.112, 2.6e-8, 8.3e-6));
    let ekf = std::hint::black_box(Ekf::new(CovarianceUpdate::Joseph));
    let pair = std::hint::black_box(IrPair {
        spacing: 0.1,
        lateral_offset: 0.03,
        forward_offset: 0.02,
    });
    let (mut poses, mut covs, mut nis, mut applied) = (
        vec![0.0; 3 * n],
        vec![0.0; 9 * n],
        vec![0.0; n],
        vec![0.0; n],
    );
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let mut b = Belief::new(
            Vector3::new(-0.84, -0.86, 0.03),
            Matrix3::from_diagonal(&Vector3::new(4e-4, 4e-4, 2.5e-3)),
        );
        let start = Instant::now();
        for i in 0..n {
            let r = &v[5 * i..5 * i + 5];
            b = ekf
                .predict(&b, &drive, &WheelTravel { d1: r[0], d2: r[1] })
                .expect("a finite step");
            let mut row = (f64::NAN, 0.0);
            if !r[2].is_nan() {
                #[allow(clippy::cast_possible_truncation)]
                let wall = match r[4] as i64 {
                    0 => AxisWall::x_plus(1.0),
                    1 => AxisWall::x_minus(1.0),
                    2 => AxisWall::y_plus(1.0),
                    _ => AxisWall::y_minus(1.0),
                };
                let o = IrPairObservation {
                    pair,
                    wall,
                    ds1: r[2],
                    ds2: r[3],
                    r11: 6.4e-5,
                    r22: 8.1e-5,
                };
                let c = ekf.correct(&b, &o, &o.z()).expect("a finite reading");
                b = c.belief;
                row = (c.nis, if c.applied { 1.0 } else { 0.0 });
            }
            poses[3 * i..3 * i + 3].copy_from_slice(b.x.as_slice());
            covs[9 * i..9 * i + 9].copy_from_slice(b.p.as_slice());
            nis[i] = row.0;
            applied[i] = row.1;
        }
        best = best.min(start.elapsed().as_secs_f64());
        std::hint::black_box((&poses, &covs, &nis, &applied));
    }
    #[allow(clippy::cast_precision_loss)]
    let per = best / n as f64 * 1e9;
    println!("{per:.1}");
}
