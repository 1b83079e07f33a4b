//! A wrapping up/down counter of configurable width, and wrap-safe
//! differences of counter readings (spec section 5: "Up/down counter of 20
//! bits (wraps; differences must be taken modulo 2^20)").
//!
//! The counter never saturates: it counts modulo `2^bits`, as the paper's
//! FPGA counter and MCU timers do. A position increment is the *signed*
//! difference of two readings modulo `2^bits`, mapped into
//! `[-2^(bits-1), 2^(bits-1))`: exact whenever the true motion between the
//! two readings is in that range (at 20 bits, +-524 287 counts: 262 wheel
//! revolutions, 82 m with the \[assumed\] N = 500, G = 1, R = 0.05 m).
//!
//! ```
//! use locus_odometry::counter::{Counter, wrapping_diff};
//!
//! let mut c = Counter::paper(); // 20 bits
//! c.set(0xF_FFFE);
//! let before = c.value();
//! c.add(5); // wraps through 2^20
//! assert_eq!(c.value(), 3);
//! assert_eq!(c.since(before), 5);
//! assert_eq!(wrapping_diff(before, c.value(), 20), -5);
//! ```

use crate::error::Error;
use crate::quadrature::Direction;

/// The counter width of paper 004's FPGA, in bits.
pub const PAPER_BITS: u32 = 20;

/// The signed difference `later - earlier` of two `bits`-bit counter readings,
/// modulo `2^bits`, in `[-2^(bits-1), 2^(bits-1))` (counts).
///
/// Bits of the readings above `bits` are ignored. `bits` must be in 1..=32
/// (checked by a debug assertion; other values give an unspecified result).
#[inline]
pub fn wrapping_diff(later: u32, earlier: u32, bits: u32) -> i32 {
    debug_assert!(
        (1..=32).contains(&bits),
        "counter width must be 1..=32 bits"
    );
    let unused = 32 - bits;
    // Shift the `bits`-bit difference to the top of the word and back with an
    // arithmetic shift: this sign-extends it (two's complement modulo 2^bits).
    ((later.wrapping_sub(earlier) << unused) as i32) >> unused
}

/// An up/down counter of `bits` bits (1..=32) that wraps modulo `2^bits`.
///
/// Values are counts (x4 quadrature edges, see
/// [`QuadratureDecoder`](crate::quadrature::QuadratureDecoder)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Counter {
    value: u32,
    bits: u32,
}

impl Counter {
    /// A counter of `bits` bits, starting at 0.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] unless `1 <= bits <= 32`.
    pub const fn new(bits: u32) -> Result<Self, Error> {
        if bits == 0 || bits > 32 {
            return Err(Error::InvalidParameter("counter width must be 1..=32 bits"));
        }
        Ok(Self { value: 0, bits })
    }

    /// The paper's 20-bit counter, starting at 0.
    pub const fn paper() -> Self {
        Self {
            value: 0,
            bits: PAPER_BITS,
        }
    }

    /// The counter's width, bits.
    #[inline]
    pub const fn bits(&self) -> u32 {
        self.bits
    }

    /// The mask of the valid bits, `2^bits - 1`.
    #[inline]
    pub const fn mask(&self) -> u32 {
        u32::MAX >> (32 - self.bits)
    }

    /// The current value, counts, in `0..2^bits`.
    #[inline]
    pub const fn value(&self) -> u32 {
        self.value
    }

    /// Sets the value (counts); bits above the width are dropped.
    #[inline]
    pub fn set(&mut self, value: u32) {
        self.value = value & self.mask();
    }

    /// Sets the value to 0 (the paper's "reset after reading").
    #[inline]
    pub fn reset(&mut self) {
        self.value = 0;
    }

    /// Adds a signed number of counts, wrapping modulo `2^bits`.
    #[inline]
    pub fn add(&mut self, delta: i32) {
        self.value = self.value.wrapping_add_signed(delta) & self.mask();
    }

    /// Counts one edge: up for [`Direction::Forward`], down for
    /// [`Direction::Reverse`].
    #[inline]
    pub fn step(&mut self, direction: Direction) {
        self.add(direction.sign());
    }

    /// The signed number of counts since an earlier reading of this counter,
    /// `value - earlier` modulo `2^bits`, in `[-2^(bits-1), 2^(bits-1))`.
    #[inline]
    pub fn since(&self, earlier: u32) -> i32 {
        wrapping_diff(self.value, earlier, self.bits)
    }
}

impl Default for Counter {
    /// [`Counter::paper`]: 20 bits, starting at 0.
    fn default() -> Self {
        Self::paper()
    }
}
