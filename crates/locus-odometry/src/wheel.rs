//! Encoder counts to distance (paper 004, section 2.1; spec section 5).
//!
//! An incremental encoder with `N` **lines** per encoder-shaft revolution,
//! decoded x4 (a count on every edge of both channels), turns `G`
//! encoder-shaft revolutions per wheel revolution on a wheel of radius `R`.
//! One wheel revolution is therefore `4 N G` counts, and `C` counts are
//!
//! ```text
//! P  = pi C R / (2 N G)     distance rolled, m
//! dP = pi R / (2 N G)       quantisation step (one count), m
//! ```
//!
//! Note the two meanings of "N" in the spec: here (and in the paper's
//! eq. for `P`) `N` is lines per encoder revolution; in the tricycle formulas
//! of [`redundant`](crate::redundant) `N` is counts per wheel revolution,
//! [`Wheel::counts_per_rev`] `= 4 N G`. The code names them `lines` and
//! `counts_per_rev` so they cannot be confused.
//!
//! The arithmetic is generic over [`Real`] (`f32` for an MCU with a
//! single-precision FPU, `f64` on a PC); counts are integers (`i32`, the
//! difference of two readings of the wrapping 20-bit counter).
//!
//! ```
//! use locus_odometry::wheel::Wheel;
//!
//! let w = Wheel::<f64>::assumed(); // 500 lines, G = 1, R = 0.05 m
//! assert_eq!(w.counts_per_rev(), 2000.0);
//! assert!((w.quantum() - core::f64::consts::PI * 0.05 / 1000.0).abs() < 1e-18);
//! assert!((w.distance(2000) - 2.0 * core::f64::consts::PI * 0.05).abs() < 1e-15);
//! ```

use locus_core::{Scalar, cast};

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// The floating-point types the odometry arithmetic runs in: `f32` and
/// `f64` (sealed). Locus's one scalar, [`locus_core::Scalar`] (nalgebra's
/// `RealField`: `abs`, `floor`, `is_finite`, ... and the arithmetic, all
/// `no_std` through `libm`), plus the constants and the integer
/// conversions the odometry needs. Sines and cosines are not used from
/// here: they come from a [`SinCos`](crate::cordic::SinCos) source (libm or
/// CORDIC). An `f64` constant becomes a `T` by [`locus_core::cast`].
pub trait Real: Scalar + sealed::Sealed {
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 1/2.
    const HALF: Self;
    /// pi.
    const PI: Self;
    /// 2 pi.
    const TWO_PI: Self;

    /// From a signed integer (a count): exact for `f64`; for `f32`, exact
    /// up to `2^24` in magnitude (rounded to nearest beyond).
    fn from_int(v: i32) -> Self;
    /// From an unsigned integer (exact for `f64`; `f32` up to `2^24`).
    fn from_uint(v: u32) -> Self;
    /// To `f64` (exact).
    fn to_f64(self) -> f64;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const HALF: Self = 0.5;
    const PI: Self = core::f32::consts::PI;
    const TWO_PI: Self = core::f32::consts::TAU;

    #[inline]
    fn from_int(v: i32) -> Self {
        v as f32
    }
    #[inline]
    fn from_uint(v: u32) -> Self {
        v as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const HALF: Self = 0.5;
    const PI: Self = core::f64::consts::PI;
    const TWO_PI: Self = core::f64::consts::TAU;

    #[inline]
    fn from_int(v: i32) -> Self {
        f64::from(v)
    }
    #[inline]
    fn from_uint(v: u32) -> Self {
        f64::from(v)
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
}

/// An encoder on a wheel: lines `N`, encoder-shaft revolutions per wheel
/// revolution `G`, wheel radius `R`, with x4 quadrature decoding.
///
/// Valid domain: `lines > 0`, `gear > 0` and `radius > 0`, all finite
/// ([`Wheel::validate`]); the conversions do not check it (a zero gives
/// infinities, as the formula does).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wheel<T> {
    /// Encoder lines per encoder-shaft revolution `N` (> 0). \[assumed\] 500.
    pub lines: u32,
    /// Encoder-shaft revolutions per wheel revolution `G` (> 0; need not
    /// be an integer: a 3.7:1 gearbox with the encoder on the motor has
    /// `G = 3.7`). \[assumed\] 1.
    pub gear: T,
    /// Wheel radius `R`, m (> 0). \[assumed\] 0.05 m.
    pub radius: T,
}

impl<T: Real> Wheel<T> {
    /// A wheel with `lines` encoder lines, gear `G` (encoder revolutions
    /// per wheel revolution) and radius `R` (m).
    #[inline]
    pub fn new(lines: u32, gear: T, radius: T) -> Self {
        Self {
            lines,
            gear,
            radius,
        }
    }

    /// The spec's \[assumed\] wheel: N = 500 lines, G = 1, R = 0.05 m
    /// (2000 counts per revolution, 0.157 mm per count).
    #[inline]
    pub fn assumed() -> Self {
        Self::new(500, T::ONE, cast(0.05))
    }

    /// `Ok(())` if `lines > 0` and `gear`, `radius` are finite and `> 0`;
    /// otherwise [`Error::InvalidParameter`](crate::error::Error::InvalidParameter)
    /// naming the field.
    pub fn validate(&self) -> Result<(), crate::error::Error> {
        use crate::error::Error::InvalidParameter;
        if self.lines == 0 {
            return Err(InvalidParameter("wheel lines must be > 0"));
        }
        if !(self.gear.is_finite() && self.gear > T::ZERO) {
            return Err(InvalidParameter("wheel gear must be finite and > 0"));
        }
        if !(self.radius.is_finite() && self.radius > T::ZERO) {
            return Err(InvalidParameter("wheel radius must be finite and > 0"));
        }
        Ok(())
    }

    /// Counts per wheel revolution with x4 decoding, `4 N G` (counts).
    /// This is the tricycle formulas' `N`.
    #[inline]
    pub fn counts_per_rev(&self) -> T {
        T::from_uint(4) * T::from_uint(self.lines) * self.gear
    }

    /// The quantisation step `dP = pi R / (2 N G)`: distance rolled per
    /// count, m. The position error of a reading is within one step.
    #[inline]
    pub fn quantum(&self) -> T {
        T::PI * self.radius / (T::from_uint(2) * T::from_uint(self.lines) * self.gear)
    }

    /// Distance rolled for `counts` counts, `P = pi C R / (2 N G)`, m
    /// (signed: negative counts are backwards).
    #[inline]
    pub fn distance(&self, counts: i32) -> T {
        T::from_int(counts) * self.quantum()
    }

    /// The (fractional) number of counts for a distance rolled (m), the
    /// inverse of [`Wheel::distance`]: `distance / dP`. A simulator takes
    /// the integer part of the running total.
    #[inline]
    pub fn counts_for(&self, distance: T) -> T {
        distance / self.quantum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;

    #[test]
    fn paper_formulas() {
        let w = Wheel::new(500, 3.0, 0.07);
        // P = pi C R / (2 N G), dP = pi R / (2 N G).
        assert!((w.quantum() - PI * 0.07 / (2.0 * 500.0 * 3.0)).abs() < 1e-18);
        assert!((w.distance(-1234) - PI * -1234.0 * 0.07 / 3000.0).abs() < 1e-15);
        assert_eq!(w.counts_per_rev(), 6000.0);
        // One wheel revolution is 2 pi R.
        assert!((w.distance(6000) - 2.0 * PI * 0.07).abs() < 1e-15);
        assert!((w.counts_for(w.distance(777)) - 777.0).abs() < 1e-9);
        let f = Wheel::<f32>::assumed();
        assert!((f.distance(2000) - core::f32::consts::TAU * 0.05).abs() < 1e-6);
    }

    #[test]
    fn validation() {
        assert!(Wheel::<f64>::assumed().validate().is_ok());
        assert!(Wheel::new(0, 1.0, 0.05).validate().is_err());
        assert!(Wheel::new(500, 0.0, 0.05).validate().is_err());
        assert!(Wheel::new(500, 1.0, f64::NAN).validate().is_err());
        assert!(Wheel::new(500, 1.0, -0.05).validate().is_err());
    }
}
