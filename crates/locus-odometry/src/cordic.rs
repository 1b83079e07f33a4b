//! CORDIC sine and cosine in rotation mode, on integers (paper 004,
//! section 4.1; spec section 5).
//!
//! # Algorithm
//!
//! With `n` iterations, `A_n = prod_{i<n} sqrt(1 + 2^-2i)` and a start
//! vector `x0 = 1/A_n`, `y0 = 0`, `z0 = angle`, for `i = 0..n-1`:
//!
//! ```text
//! d  = -1 if z < 0 else +1
//! x' = x - d y 2^-i      y' = y + d x 2^-i      z' = z - d atan(2^-i)
//! ```
//!
//! and then `x = cos(angle)`, `y = sin(angle)`. Only shifts, adds and a
//! table of `atan(2^-i)`. (`1/A_16 = 0.60725293510314`.)
//!
//! # Convergence and folding
//!
//! The iteration converges for `|angle| <= sum_i atan(2^-i)` = 99.88 deg.
//! Every angle is therefore **folded first**: `angle = q pi/2 + r` with
//! `q = round(angle / (pi/2))` and `|r| <= pi/4`; the kernel computes
//! `(sin r, cos r)` and the quadrant `q mod 4` is restored by swapping and
//! negating (`(s, c)`, `(c, -s)`, `(-s, -c)`, `(-c, s)` for `(sin, cos)`),
//! which costs nothing in hardware. Folding to `+-pi/4` (rather than the
//! +-99.88 deg the kernel could take) keeps the angle register within
//! `+-1` rad, which buys it one more fractional bit.
//!
//! # Fixed-point formats
//!
//! A `Cordic` has a register width `w` (8..=32 bits, two's complement) and
//! `F = w - 1` fractional bits, so every register is **Q1.F**, range
//! `[-1, 1)`, one LSB `= 2^-F`:
//!
//! * `x`, `y` (cosine, sine): Q1.F, **saturating** at `[-2^F, 2^F - 1]`.
//!   `cos 0 = 1` is returned as `2^F - 1` (error one LSB); the magnitude of
//!   `(x, y)` is `A_i / A_n <= 1` throughout, so saturation is only a
//!   guard against rounding at the top.
//! * `z` (residual angle): radians, Q1.F. After folding `|z| <= pi/4 < 1`.
//! * the angle **input** of [`Cordic::sin_cos_fixed`]: radians in the same
//!   scale (`2^F` per rad) but held in an `i64`, so any angle up to
//!   `2^(63-F)` rad can be given; folding uses a 62-bit `pi/2` and 128-bit
//!   products, so the fold adds no error beyond the input's own rounding.
//! * the outputs of [`Cordic::sin_cos_fixed`]: Q1.F in an `i64`, in
//!   `[-2^F, 2^F]` (a negated `-2^F` can reach `+2^F` after folding).
//! * the atan table: `round(atan(2^-i) 2^F)`, computed at construction by
//!   a `const fn` (a series, checked against libm in the tests), stored in
//!   a fixed `[i64; 32]`: no allocation, and a `Cordic` can be a `const`.
//!
//! The shifts `y 2^-i`, `x 2^-i` round to nearest (add `2^(i-1)`, then
//! shift right arithmetically: in hardware, the last bit shifted out is the
//! adder's carry-in). Truncating shifts instead bias every iteration the
//! same way and, on a 16-bit datapath, about double the error floor.
//!
//! # Accuracy
//!
//! The angle residual after `n` iterations is below `atan(2^-(n-1))`, so
//! the error falls by half per iteration until the register's LSB stops it:
//! on 16 bits the floor is about 1.5e-4 (reached at ~15 iterations; more
//! add nothing), on 32 bits it is far below the residual (1.2e-7 after 24
//! iterations). `tests/cordic.rs` prints the full table.
//!
//! ```
//! use locus_odometry::cordic::Cordic;
//!
//! let c = Cordic::PAPER; // 16-bit registers, 16 iterations
//! let (s, co) = c.sin_cos(core::f64::consts::FRAC_PI_6);
//! assert!((s - 0.5).abs() < 2.5e-4 && (co - 0.75f64.sqrt()).abs() < 2.5e-4);
//! // Any angle: folded into +-45 deg first.
//! let (s, _) = c.sin_cos(1000.0);
//! assert!((s - 1000f64.sin()).abs() < 2.5e-4);
//! ```

use crate::error::Error;

/// Largest iteration count, and size of the atan table.
pub const MAX_ITERATIONS: u32 = 32;
/// Narrowest register width, bits.
pub const MIN_WIDTH: u32 = 8;
/// Widest register width, bits (the registers live in `i64`s with
/// headroom for the un-saturated sums).
pub const MAX_WIDTH: u32 = 32;

/// `round(pi/2 2^62)`.
const HALF_PI_Q62: i128 = 7_244_019_458_077_122_842;
/// `round(2/pi 2^62)`.
const TWO_OVER_PI_Q62: i128 = 2_935_890_503_282_001_226;

/// A source of sine and cosine, for the odometry's `cos(theta)`,
/// `sin(theta)`, `cos(phi)`, `sin(phi)`: [`Libm`] (floating point) or a
/// [`Cordic`] (the paper's fixed-point datapath).
pub trait SinCos<T> {
    /// `(sin(angle), cos(angle))` of an angle in rad (any value; a
    /// non-finite angle gives NaNs).
    fn sin_cos(&self, angle: T) -> (T, T);
}

/// Sine and cosine from `libm` (correctly rounded to within an ulp or so).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Libm;

impl SinCos<f64> for Libm {
    #[inline]
    fn sin_cos(&self, angle: f64) -> (f64, f64) {
        libm::sincos(angle)
    }
}

impl SinCos<f32> for Libm {
    #[inline]
    fn sin_cos(&self, angle: f32) -> (f32, f32) {
        libm::sincosf(angle)
    }
}

/// A CORDIC rotator with a given register width and iteration count; see
/// the [module documentation](self) for the algorithm and the fixed-point
/// formats. Plain data (`Copy`, 272 bytes), buildable in a `const`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cordic {
    width: u32,
    iterations: u32,
    /// `round(atan(2^-i) 2^F)` for `i < iterations`, zeros after.
    atan: [i64; MAX_ITERATIONS as usize],
    /// `round(2^F / A_n)`.
    x0: i64,
}

impl Cordic {
    /// The paper's rotator: 16-bit registers, 16 iterations (one per
    /// clock: 16 cycles, 320 ns at 50 MHz). Error below 2.5e-4.
    pub const PAPER: Cordic = match Cordic::new(16, 16) {
        Ok(c) => c,
        Err(_) => panic!("16/16 is a valid CORDIC"),
    };

    /// A 32-bit rotator with 24 iterations: error below 1e-6.
    pub const WIDE: Cordic = match Cordic::new(32, 24) {
        Ok(c) => c,
        Err(_) => panic!("32/24 is a valid CORDIC"),
    };

    /// A rotator with `width`-bit registers (8..=32) and `iterations`
    /// iterations (1..=32; iterations past `width` only add rounding).
    /// Computes the atan table and `1/A_n` for the width; a `const fn`.
    ///
    /// Errors: [`Error::InvalidParameter`] for a width or an iteration
    /// count out of range.
    pub const fn new(width: u32, iterations: u32) -> Result<Self, Error> {
        if width < MIN_WIDTH || width > MAX_WIDTH {
            return Err(Error::InvalidParameter("CORDIC width must be 8..=32 bits"));
        }
        if iterations == 0 || iterations > MAX_ITERATIONS {
            return Err(Error::InvalidParameter("CORDIC iterations must be 1..=32"));
        }
        let scale = (1u64 << (width - 1)) as f64;
        let mut atan = [0i64; MAX_ITERATIONS as usize];
        let mut gain_sq = 1.0f64; // A_n^2 = prod (1 + 2^-2i)
        let mut i = 0u32;
        while i < iterations {
            atan[i as usize] = round_nonneg(atan_pow2(i) * scale);
            gain_sq *= 1.0 + pow2_neg(2 * i);
            i += 1;
        }
        let x0 = round_nonneg(scale / sqrt_const(gain_sq));
        Ok(Self {
            width,
            iterations,
            atan,
            x0,
        })
    }

    /// Register width `w`, bits.
    #[inline]
    pub const fn width(&self) -> u32 {
        self.width
    }

    /// Iteration count `n` (one per clock in the paper's sequential core).
    #[inline]
    pub const fn iterations(&self) -> u32 {
        self.iterations
    }

    /// Fractional bits `F = w - 1` of every register (Q1.F).
    #[inline]
    pub const fn frac_bits(&self) -> u32 {
        self.width - 1
    }

    /// The fixed-point value of 1.0, `2^F` (one rad for angles). Not
    /// representable in a `w`-bit register itself (max `2^F - 1`).
    #[inline]
    pub const fn one(&self) -> i64 {
        1i64 << (self.width - 1)
    }

    /// The start value `x0 = round(2^F / A_n)` (Q1.F).
    #[inline]
    pub const fn x0(&self) -> i64 {
        self.x0
    }

    /// `1/A_n` as stored, `x0 / 2^F` (0.60725... for n >= 12).
    #[inline]
    pub fn inverse_gain(&self) -> f64 {
        self.x0 as f64 / self.one() as f64
    }

    /// The atan table, `round(atan(2^-i) 2^F)` for `i < n` (Q1.F rad).
    #[inline]
    pub fn atan_table(&self) -> &[i64] {
        &self.atan[..self.iterations as usize]
    }

    /// The largest angle the un-folded iteration converges for with this
    /// table, `sum atan(2^-i)` (rad): 1.7433 rad = 99.88 deg for n >= 16.
    /// Informative: [`Cordic::sin_cos_fixed`] folds first.
    pub fn convergence_limit(&self) -> f64 {
        let sum: i64 = self.atan_table().iter().sum();
        sum as f64 / self.one() as f64
    }

    /// An angle (rad) in the input format: `round(angle 2^F)`, saturating
    /// at the `i64` range (`+-2^(63-F)` rad). `angle` must be finite.
    #[inline]
    pub fn to_fixed(&self, angle: f64) -> i64 {
        libm::round(angle * self.one() as f64) as i64
    }

    /// A Q1.F value as `f64`: `v / 2^F`.
    #[inline]
    pub fn from_fixed(&self, v: i64) -> f64 {
        // 2^-F is exact: a multiplication, not a division.
        v as f64 * (1.0 / self.one() as f64)
    }

    /// `(sin, cos)` of an angle given in rad with `F` fractional bits (any
    /// `i64`), both Q1.F in `[-2^F, 2^F]`. Integer arithmetic only: the
    /// fold into `+-pi/4` (128-bit products with 62-bit constants, no
    /// division), then `n` shift-add iterations on `w`-bit saturating
    /// registers.
    pub fn sin_cos_fixed(&self, angle: i64) -> (i64, i64) {
        let (r, quadrant) = self.fold(angle);
        let (s, c) = self.rotate(r);
        match quadrant {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    }

    /// `(sin, cos)` of `angle` (rad, any finite value) through the integer
    /// datapath: quantise to `F` bits, [`Cordic::sin_cos_fixed`], back to
    /// `f64`. A non-finite angle gives `(NaN, NaN)`. Angles beyond
    /// `2^(62-F)` rad (2^47 rad at 16 bits, 2^31 rad at 32) are first
    /// reduced modulo `f64`'s 2 pi by `libm::remainder`, whose error grows
    /// as `|angle| x 2.4e-16 / (2 pi)` rad: negligible below ~1e9 rad, and
    /// meaningless (though still a unit vector) for astronomically large
    /// angles, where an `f64` has no sub-radian resolution anyway.
    pub fn sin_cos(&self, angle: f64) -> (f64, f64) {
        if !angle.is_finite() {
            return (f64::NAN, f64::NAN);
        }
        let limit = (1u64 << (62 - self.frac_bits())) as f64;
        let a = if libm::fabs(angle) < limit {
            angle
        } else {
            libm::remainder(angle, core::f64::consts::TAU)
        };
        let (s, c) = self.sin_cos_fixed(self.to_fixed(a));
        let lsb = 1.0 / self.one() as f64; // 2^-F, exact
        (s as f64 * lsb, c as f64 * lsb)
    }

    /// Folds an angle (Q_F rad) into `r` (Q1.F, `|r| <= pi/4` + a few LSB)
    /// and the quadrant `q mod 4`, with `angle = q pi/2 + r`.
    #[inline]
    fn fold(&self, angle: i64) -> (i64, u32) {
        let f = self.frac_bits();
        // Fast path: already within +-0.78 rad (< pi/4 at every width).
        let quarter = (self.one() / 100) * 78;
        if (-quarter..=quarter).contains(&angle) {
            return (angle, 0);
        }
        // q = round(angle 2/pi): angle (Q_F, < 2^63) times 2/pi (Q62) is
        // Q(F+62), below 2^125.
        let q = (i128::from(angle) * TWO_OVER_PI_Q62 + (1i128 << (f + 61))) >> (f + 62);
        // r = angle - q pi/2 in Q62 (|angle| < 2^(63+62-F) <= 2^118).
        let shift = 62 - f;
        let r_ext = (i128::from(angle) << shift) - q * HALF_PI_Q62;
        let r = ((r_ext + (1i128 << (shift - 1))) >> shift) as i64;
        (r, (q & 3) as u32)
    }

    /// The shift-add iterations on `|z| < 1` rad (Q1.F): `(sin z, cos z)`.
    #[inline]
    fn rotate(&self, z0: i64) -> (i64, i64) {
        let hi = self.one() - 1;
        let lo = -self.one();
        let mut x = self.x0;
        let mut y = 0i64;
        let mut z = z0;
        for i in 0..self.iterations {
            let xs = shr_round(x, i);
            let ys = shr_round(y, i);
            let a = self.atan[i as usize];
            // d = -1 if z < 0 else +1, applied as a conditional negation
            // (`(v ^ m) - m` is `-v` for m = -1 and `v` for m = 0): no
            // data-dependent branch, as in the hardware's add/subtract.
            let m = z >> 63;
            x = ((x - ((ys ^ m) - m)).max(lo)).min(hi);
            y = ((y + ((xs ^ m) - m)).max(lo)).min(hi);
            z -= (a ^ m) - m;
        }
        (y, x)
    }
}

impl Default for Cordic {
    /// [`Cordic::PAPER`].
    fn default() -> Self {
        Self::PAPER
    }
}

impl SinCos<f64> for Cordic {
    #[inline]
    fn sin_cos(&self, angle: f64) -> (f64, f64) {
        Cordic::sin_cos(self, angle)
    }
}

impl SinCos<f32> for Cordic {
    #[inline]
    fn sin_cos(&self, angle: f32) -> (f32, f32) {
        let (s, c) = Cordic::sin_cos(self, f64::from(angle));
        (s as f32, c as f32)
    }
}

/// `v 2^-i` rounded to nearest (ties up); `i <= 31`.
#[inline(always)]
fn shr_round(v: i64, i: u32) -> i64 {
    if i == 0 {
        v
    } else {
        (v + (1i64 << (i - 1))) >> i
    }
}

/// `2^-k` for `k <= 63`.
const fn pow2_neg(k: u32) -> f64 {
    1.0 / (1u64 << k) as f64
}

/// `round(v)` (ties away from zero) for `0 <= v < 2^62`, in a `const fn`.
/// Not `(v + 0.5) as i64`: that rounds 0.49999999999999994 up.
const fn round_nonneg(v: f64) -> i64 {
    let t = v as i64;
    // `v - t` is exact for v < 2^62.
    if v - t as f64 >= 0.5 { t + 1 } else { t }
}

/// `sqrt(v)` for `1 <= v < 4` by Newton's iteration, in a `const fn`.
const fn sqrt_const(v: f64) -> f64 {
    let mut y = 1.5;
    let mut k = 0;
    while k < 64 {
        let next = 0.5 * (y + v / y);
        if next == y {
            break;
        }
        y = next;
        k += 1;
    }
    y
}

/// `atan(2^-i)` in a `const fn`: pi/4 for `i = 0`, otherwise the series
/// `x - x^3/3 + x^5/5 - ...` with `x = 2^-i <= 1/2` (terms fall by 4 or
/// more each, so 40 terms reach below 2^-80 x).
const fn atan_pow2(i: u32) -> f64 {
    if i == 0 {
        return core::f64::consts::FRAC_PI_4;
    }
    let x = pow2_neg(i);
    let x2 = x * x;
    // Sum from the smallest term up for accuracy.
    let terms = 40;
    let mut powers = [0.0f64; 40];
    let mut p = x;
    let mut k = 0;
    while k < terms {
        powers[k] = p;
        p *= x2;
        k += 1;
    }
    let mut sum = 0.0;
    let mut k = terms;
    while k > 0 {
        k -= 1;
        let term = powers[k] / (2 * k + 1) as f64;
        if k % 2 == 0 {
            sum += term;
        } else {
            sum -= term;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    #[test]
    fn tables_match_libm() {
        for w in MIN_WIDTH..=MAX_WIDTH {
            let c = Cordic::new(w, MAX_ITERATIONS).unwrap();
            let scale = (1u64 << (w - 1)) as f64;
            for (i, &a) in c.atan_table().iter().enumerate() {
                let want = libm::round(libm::atan(libm::ldexp(1.0, -(i as i32))) * scale) as i64;
                assert_eq!(a, want, "w {w} i {i}");
            }
            let mut k = 1.0;
            for i in 0..MAX_ITERATIONS {
                k /= libm::sqrt(1.0 + libm::ldexp(1.0, -2 * i as i32));
            }
            assert_eq!(c.x0(), libm::round(k * scale) as i64, "w {w}");
        }
        assert!((Cordic::new(32, 16).unwrap().inverse_gain() - 0.60725293510314).abs() < 1e-9);
    }

    #[test]
    fn convergence_limit_is_99_88_deg() {
        let deg = Cordic::WIDE.convergence_limit().to_degrees();
        assert!((deg - 99.88).abs() < 0.005, "{deg}");
    }

    #[test]
    fn invalid_configurations() {
        assert!(Cordic::new(7, 16).is_err());
        assert!(Cordic::new(33, 16).is_err());
        assert!(Cordic::new(16, 0).is_err());
        assert!(Cordic::new(16, 33).is_err());
        assert!(Cordic::new(8, 1).is_ok());
    }

    #[test]
    fn fold_quadrants_and_far_angles() {
        let c = Cordic::WIDE;
        for k in -8i32..=8 {
            for &off in &[-0.7, -0.3, 0.0, 0.2, FRAC_PI_4, 0.78] {
                let a = f64::from(k) * FRAC_PI_2 + off;
                let (s, co) = c.sin_cos(a);
                assert!((s - libm::sin(a)).abs() < 1e-6, "{a}");
                assert!((co - libm::cos(a)).abs() < 1e-6, "{a}");
            }
        }
        // Large angles: the fold uses a 62-bit pi/2.
        for &a in &[1.0e3, -2.5e4, 1.0e6, 4.0e9, -1.0e12] {
            let (s, co) = Cordic::PAPER.sin_cos(a);
            assert!((s - libm::sin(a)).abs() < 2.5e-4, "{a}");
            assert!((co - libm::cos(a)).abs() < 2.5e-4, "{a}");
        }
        // Beyond 2^31 rad the 32-bit input is reduced modulo 2 pi in f64
        // first (error ~ angle x 4e-17).
        for &a in &[4.0e9, -3.0e9] {
            let (s, co) = c.sin_cos(a);
            assert!((s - libm::sin(a)).abs() < 1e-6, "{a}");
            assert!((co - libm::cos(a)).abs() < 1e-6, "{a}");
        }
        // Absurd angles still give a unit vector.
        let (s, co) = c.sin_cos(1.0e300);
        assert!((s * s + co * co - 1.0).abs() < 1e-6);
        let (s, co) = c.sin_cos(f64::NAN);
        assert!(s.is_nan() && co.is_nan());
        // pi exactly, both signs.
        let (s, co) = c.sin_cos(PI);
        assert!(s.abs() < 1e-6 && (co + 1.0).abs() < 1e-6);
        let (s, co) = c.sin_cos(-PI);
        assert!(s.abs() < 1e-6 && (co + 1.0).abs() < 1e-6);
    }

    #[test]
    fn fixed_extremes_do_not_overflow() {
        for w in [8, 16, 24, 32] {
            let c = Cordic::new(w, 32).unwrap();
            for a in [i64::MIN, i64::MIN + 1, -1, 0, 1, i64::MAX] {
                let (s, co) = c.sin_cos_fixed(a);
                assert!(s.abs() <= c.one() && co.abs() <= c.one());
            }
        }
    }
}
