//! The Verilog binary32 units under `hdl/fp/`, simulated with Icarus
//! Verilog, against Rust's `f32` (canonical NaN): every pair of special
//! values plus 10^6 seeded random vectors per operation, and a check that a
//! wrong expected word is reported.
//!
//! Icarus runs about 30-65 us per vector here (div slowest: 8 stages), so
//! the file takes about 90 s on two cores (each operation about 26-64 s).

use std::time::Instant;

use locus_hw::hdl::fp32::{self, Op, Vector};

const RANDOM: usize = 1_000_000;

fn check(op: Op, seed: u64) {
    let mut vectors = fp32::special_vectors(op);
    let specials = vectors.len();
    vectors.extend(fp32::random_vectors(op, RANDOM, seed));
    let t = Instant::now();
    let report = fp32::simulate(op, &vectors).unwrap_or_else(|e| panic!("{e}"));
    println!(
        "{op:?}: {} vectors ({specials} special pairs + {RANDOM} random), {} mismatches, {:.1} s",
        report.vectors,
        report.mismatches,
        t.elapsed().as_secs_f64()
    );
    for l in &report.mismatch_lines {
        println!("  {l}");
    }
    assert_eq!(report.vectors, vectors.len() as u64);
    assert_eq!(report.mismatches, 0, "{op:?}: {:?}", report.mismatch_lines);
}

#[test]
fn add_matches_f32() {
    check(Op::Add, 1);
}

#[test]
fn sub_matches_f32() {
    check(Op::Sub, 2);
}

#[test]
fn mul_matches_f32() {
    check(Op::Mul, 3);
}

#[test]
fn div_matches_f32() {
    check(Op::Div, 4);
}

/// One corrupted expected word among correct ones: the testbench must
/// report exactly that vector (so a passing run means the outputs were
/// compared).
#[test]
fn corrupted_expected_word_is_reported() {
    for op in [Op::Add, Op::Mul, Op::Div] {
        let mut vectors: Vec<Vector> = fp32::random_vectors(op, 40, 9);
        vectors[17].y ^= 1;
        let report = fp32::simulate(op, &vectors).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            (report.vectors, report.mismatches),
            (40, 1),
            "{op:?}: {report:?}"
        );
        let line = &report.mismatch_lines[0];
        assert!(line.starts_with("mismatch vector 17:"), "{op:?}: {line}");
        let v = vectors[17];
        assert!(
            line.contains(&format!("a {:08x} b {:08x}", v.a, v.b)),
            "{op:?}: {line}"
        );
        assert!(
            line.ends_with(&format!("expected {:08x}", v.y)),
            "{op:?}: {line}"
        );
    }
}
