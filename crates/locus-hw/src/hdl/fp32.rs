//! Binary32 reference, test vectors and the Icarus Verilog runner of the
//! units under `hdl/fp/`.
//!
//! # Reference
//! [`add`], [`sub`], [`mul`] and [`div`] are Rust's `f32` operations on the
//! words' bits (round to nearest even, gradual underflow: x86-64 does not
//! flush subnormals), with one change, the hardware's NaN rule: every NaN
//! result is the canonical quiet NaN [`QNAN`] (`0x7FC0_0000`), whatever the
//! operands' payloads and signs.

use core::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

use super::{HdlError, TempDir};

/// The canonical quiet NaN, the only NaN the units produce.
pub const QNAN: u32 = 0x7FC0_0000;

fn canon(x: f32) -> u32 {
    if x.is_nan() { QNAN } else { x.to_bits() }
}

/// `a + b` on binary32 words (NaN results canonical).
pub fn add(a: u32, b: u32) -> u32 {
    canon(f32::from_bits(a) + f32::from_bits(b))
}

/// `a - b` on binary32 words (NaN results canonical).
pub fn sub(a: u32, b: u32) -> u32 {
    canon(f32::from_bits(a) - f32::from_bits(b))
}

/// `a * b` on binary32 words (NaN results canonical).
pub fn mul(a: u32, b: u32) -> u32 {
    canon(f32::from_bits(a) * f32::from_bits(b))
}

/// `a / b` on binary32 words (NaN results canonical).
pub fn div(a: u32, b: u32) -> u32 {
    canon(f32::from_bits(a) / f32::from_bits(b))
}

/// An operation under test.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// `fp_add` with `sub = 0`.
    Add,
    /// `fp_add` with `sub = 1`.
    Sub,
    /// `fp_mul`.
    Mul,
    /// `fp_div`.
    Div,
}

impl Op {
    /// The testbench's `+unit=` name.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Add | Self::Sub => "add",
            Self::Mul => "mul",
            Self::Div => "div",
        }
    }

    /// The vector's op field (the adder's `sub` input; 0 for mul and div).
    pub fn code(self) -> u32 {
        u32::from(self == Self::Sub)
    }

    /// The reference result.
    pub fn eval(self, a: u32, b: u32) -> u32 {
        match self {
            Self::Add => add(a, b),
            Self::Sub => sub(a, b),
            Self::Mul => mul(a, b),
            Self::Div => div(a, b),
        }
    }

    /// A vector with the reference result.
    pub fn vector(self, a: u32, b: u32) -> Vector {
        Vector {
            op: self.code(),
            a,
            b,
            y: self.eval(a, b),
        }
    }
}

/// One test vector: a line `op a b y` of the testbench's file (hex words).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Vector {
    /// 0: add (or mul, div), 1: subtract.
    pub op: u32,
    /// First operand.
    pub a: u32,
    /// Second operand.
    pub b: u32,
    /// Expected result.
    pub y: u32,
}

/// The special operands: signed zeros, the smallest and largest subnormals,
/// the smallest normal and its neighbours, 1, 1.5, 2 and neighbours of 1,
/// the largest finite and its neighbour, infinities, quiet and signalling
/// NaNs with payloads; each with both signs.
pub fn special_values() -> Vec<u32> {
    const POSITIVE: [u32; 20] = [
        0x0000_0000, // 0
        0x0000_0001, // smallest subnormal
        0x0000_0002,
        0x0040_0000, // a mid subnormal
        0x007F_FFFF, // largest subnormal
        0x0080_0000, // smallest normal, 2^-126
        0x0080_0001, // its successor
        0x0100_0000, // 2^-125
        0x3F80_0000, // 1
        0x3F7F_FFFF, // 1 - 2^-24
        0x3F80_0001, // 1 + 2^-23
        0x3FC0_0000, // 1.5
        0x4000_0000, // 2
        0x3400_0000, // 2^-23
        0x7F7F_FFFF, // largest finite
        0x7F7F_FFFE,
        0x7F80_0000, // infinity
        0x7FC0_0000, // canonical quiet NaN
        0x7FC1_2345, // quiet NaN with a payload
        0x7F80_0001, // signalling NaN
    ];
    let mut v: Vec<u32> = POSITIVE.to_vec();
    v.extend(POSITIVE.iter().map(|x| x | 0x8000_0000));
    v.push(0x7FA0_5A5A); // signalling NaN with a payload
    v
}

/// Every ordered pair of [`special_values`] for `op`.
pub fn special_vectors(op: Op) -> Vec<Vector> {
    let s = special_values();
    s.iter()
        .flat_map(|&a| s.iter().map(move |&b| op.vector(a, b)))
        .collect()
}

fn word(sign: u32, exp: u32, frac: u32) -> u32 {
    (sign & 1) << 31 | (exp & 0xFF) << 23 | (frac & 0x7F_FFFF)
}

/// A random exponent field clamped to the finite range [0, 254].
fn exp_near(r: &mut StdRng, centre: i32, spread: i32) -> u32 {
    (centre + r.random_range(-spread..=spread)).clamp(0, 254) as u32
}

/// `n` random vectors for `op`, reproducible from `seed`. Each vector draws
/// one of these classes (equally often):
/// 0. uniformly random bit patterns (about 0.8 % NaNs and infinities);
/// 1. operands with equal or nearby exponents (cancellation in add/sub);
/// 2. a subnormal operand;
/// 3. results near the underflow threshold and subnormal results, with a
///    power-of-two second operand in half of them (exact ties of
///    subnormal rounding);
/// 4. results near overflow (the largest finite and the rounding to
///    infinity);
/// 5. exact ties of normal rounding: add/sub with a half-ulp (or ulp-and-a-
///    half) second operand, mul by 1.5, 1.25 or 1.75 of a significand with
///    a set last bit, div by a power of two into the subnormal range.
pub fn random_vectors(op: Op, n: usize, seed: u64) -> Vec<Vector> {
    let mut r = StdRng::seed_from_u64(seed);
    let additive = matches!(op, Op::Add | Op::Sub);
    (0..n)
        .map(|_| {
            let (a, b) = match r.random_range(0..6u32) {
                0 => (r.random::<u32>(), r.random::<u32>()),
                1 => {
                    let a: u32 = r.random();
                    let ea = (a >> 23 & 0xFF) as i32;
                    let eb = exp_near(&mut r, ea.min(254), 2);
                    (a, word(r.random(), eb, r.random()))
                }
                2 => {
                    let sub = word(r.random(), 0, r.random::<u32>() >> r.random_range(0..23u32));
                    let other = if r.random_bool(0.5) {
                        word(r.random(), exp_near(&mut r, 127, 30), r.random())
                    } else {
                        r.random()
                    };
                    if r.random_bool(0.5) {
                        (sub, other)
                    } else {
                        (other, sub)
                    }
                }
                3 => {
                    let (ea, eb) = match op {
                        // Small operands: sums and differences near 2^-126.
                        Op::Add | Op::Sub => (exp_near(&mut r, 1, 2), exp_near(&mut r, 1, 2)),
                        // ea + eb - 127 near 0 (down to -25).
                        Op::Mul => {
                            let ea = exp_near(&mut r, 63, 62);
                            (
                                ea,
                                (127 - ea as i32 + r.random_range(-26..=2)).clamp(0, 254) as u32,
                            )
                        }
                        // ea - eb + 127 near 0.
                        Op::Div => {
                            let eb = exp_near(&mut r, 190, 64);
                            (
                                (eb as i32 - 127 + r.random_range(-26..=2)).clamp(0, 254) as u32,
                                eb,
                            )
                        }
                    };
                    let fb = if !additive && r.random_bool(0.5) {
                        0
                    } else {
                        r.random()
                    };
                    (word(r.random(), ea, r.random()), word(r.random(), eb, fb))
                }
                4 => {
                    let (ea, eb) = match op {
                        Op::Add | Op::Sub => (exp_near(&mut r, 253, 1), exp_near(&mut r, 253, 1)),
                        // ea + eb - 127 near 254.
                        Op::Mul => {
                            let ea = exp_near(&mut r, 190, 63);
                            (
                                ea,
                                (381 - ea as i32 + r.random_range(-2..=1)).clamp(0, 254) as u32,
                            )
                        }
                        // ea - eb + 127 near 254.
                        Op::Div => {
                            let eb = exp_near(&mut r, 63, 62);
                            (
                                (eb as i32 + 127 + r.random_range(-2..=1)).clamp(0, 254) as u32,
                                eb,
                            )
                        }
                    };
                    let fa = if r.random_bool(0.25) {
                        0x7F_FFFF
                    } else {
                        r.random()
                    };
                    (word(r.random(), ea, fa), word(r.random(), eb, r.random()))
                }
                _ => {
                    let a: u32 = r.random::<u32>() & 0x7F7F_FFFF | 1;
                    let a = if a >> 23 == 0 { a | 0x0080_0000 } else { a };
                    let ea = (a >> 23 & 0xFF) as i32;
                    let b = match op {
                        Op::Add | Op::Sub => {
                            let frac = [0, 0x40_0000][r.random_range(0..2usize)];
                            word(r.random(), (ea - 24).max(0) as u32, frac)
                        }
                        Op::Mul => {
                            let frac = [0x40_0000, 0x20_0000, 0x60_0000][r.random_range(0..3usize)];
                            word(r.random(), exp_near(&mut r, 127, 20), frac)
                        }
                        Op::Div => word(
                            r.random(),
                            (ea + 127 - r.random_range(-1..=24)).clamp(0, 254) as u32,
                            0,
                        ),
                    };
                    (a | (r.random::<u32>() & 0x8000_0000), b)
                }
            };
            op.vector(a, b)
        })
        .collect()
}

/// Writes `vectors` in the testbench's format, one `op a b y` line each.
pub fn write_vectors(path: &Path, vectors: &[Vector]) -> Result<(), HdlError> {
    let io = |source| HdlError::Io {
        context: format!("writing {}", path.display()),
        source,
    };
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    let mut line = String::with_capacity(32);
    for v in vectors {
        line.clear();
        // Writing into a String cannot fail.
        let _ = writeln!(line, "{:x} {:08x} {:08x} {:08x}", v.op, v.a, v.b, v.y);
        out.write_all(line.as_bytes()).map_err(io)?;
    }
    out.flush().map_err(io)
}

/// The testbench's verdict.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SimReport {
    /// Vectors simulated.
    pub vectors: u64,
    /// Outputs that differ from the expected word.
    pub mismatches: u64,
    /// The first mismatches as the testbench printed them.
    pub mismatch_lines: Vec<String>,
}

/// Simulates `vectors` on `op`'s unit with Icarus Verilog: compiles
/// `hdl/tb/tb_fp.v` and the three units and runs them in a temporary
/// directory ([`super::simulate`]), then parses the summary line.
///
/// # Errors
/// [`HdlError`]: the simulator is missing or fails, or prints no summary.
pub fn simulate(op: Op, vectors: &[Vector]) -> Result<SimReport, HdlError> {
    let dir = TempDir::new(op.unit())?;
    let vec_path = dir.path().join("vectors.txt");
    write_vectors(&vec_path, vectors)?;
    let text = super::simulate(
        &dir,
        &["tb/tb_fp.v", "fp/fp_add.v", "fp/fp_mul.v", "fp/fp_div.v"],
        &[
            format!("+vectors={}", vec_path.display()),
            format!("+unit={}", op.unit()),
        ],
    )?;
    parse_summary(&text).ok_or(HdlError::NoSummary(text))
}

fn parse_summary(text: &str) -> Option<SimReport> {
    let (vectors, mismatches) = text.lines().find_map(|l| {
        let w: Vec<&str> = l.split_whitespace().collect();
        match w.as_slice() {
            ["vectors", n, "mismatches", m] => Some((n.parse().ok()?, m.parse().ok()?)),
            _ => None,
        }
    })?;
    let mismatch_lines = text
        .lines()
        .filter(|l| l.starts_with("mismatch "))
        .map(str::to_owned)
        .collect();
    Some(SimReport {
        vectors,
        mismatches,
        mismatch_lines,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_nan_rule_and_signed_zeros() {
        assert_eq!(add(0x7F80_0000, 0xFF80_0000), QNAN);
        assert_eq!(mul(0xFFC1_2345, 0x3F80_0000), QNAN);
        assert_eq!(add(0x3F80_0000, 0xBF80_0000), 0);
        assert_eq!(add(0x8000_0000, 0x8000_0000), 0x8000_0000);
        assert_eq!(div(0xBF80_0000, 0), 0xFF80_0000);
        // No flush to zero: the smallest subnormal survives.
        assert_eq!(mul(0x0000_0002, 0x3F00_0000), 1);
    }

    #[test]
    fn summary_is_parsed() {
        let r = parse_summary(
            "mismatch vector 3: op 0 a 1 b 2 got 3 expected 4\nvectors 10 mismatches 1\n",
        );
        assert_eq!(
            r.map(|r| (r.vectors, r.mismatches, r.mismatch_lines.len())),
            Some((10, 1, 1))
        );
        assert!(parse_summary("nothing").is_none());
    }
}
