//! What firmware implements to feed the decoder: a source of sampled channel
//! levels ([`EncoderSource`]), or of a hardware counter's value
//! ([`CountSource`], for MCUs whose timers decode quadrature themselves).
//!
//! Both traits are embedded-hal style: one required method, a fallible read
//! with the implementer's own error type, and blanket implementations for
//! `&mut S` so a driver can be lent rather than moved.
//!
//! ```
//! use locus_odometry::quadrature::{QuadratureDecoder, Transition};
//! use locus_odometry::counter::Counter;
//! use locus_odometry::source::EncoderSource;
//!
//! /// Two GPIO inputs, here scripted.
//! struct Pins<'a>(&'a [(bool, bool)]);
//!
//! impl EncoderSource for Pins<'_> {
//!     type Error = core::convert::Infallible;
//!     fn sample(&mut self) -> Result<(bool, bool), Self::Error> {
//!         let (first, rest) = self.0.split_first().expect("script long enough");
//!         self.0 = rest;
//!         Ok(*first)
//!     }
//! }
//!
//! let mut pins = Pins(&[(true, false), (true, true), (false, true)]);
//! let mut dec = QuadratureDecoder::new(false, false, Counter::paper());
//! for _ in 0..3 {
//!     let step = dec.poll(&mut pins).unwrap();
//!     assert!(matches!(step, Transition::Count(_)));
//! }
//! assert_eq!(dec.counter().value(), 3);
//! ```

/// A source of sampled quadrature levels `(A, B)`: two GPIO pins, a
/// port register, an FPGA status word.
///
/// `sample` is called once per sampling period by the code that drives a
/// [`QuadratureDecoder`](crate::quadrature::QuadratureDecoder). The sampling
/// rate must exceed the highest x4 edge rate (`4 N G v / (2 pi R)` edges/s at
/// speed `v`; also allow for phase and duty-cycle error, which bring edges
/// closer): two edges between samples read as an invalid transition.
pub trait EncoderSource {
    /// The error of a failed read (`core::convert::Infallible` for plain
    /// GPIO).
    type Error;

    /// Reads the current levels of channels A and B (`true` = high).
    fn sample(&mut self) -> Result<(bool, bool), Self::Error>;
}

impl<S: EncoderSource + ?Sized> EncoderSource for &mut S {
    type Error = S::Error;

    #[inline]
    fn sample(&mut self) -> Result<(bool, bool), Self::Error> {
        (**self).sample()
    }
}

/// A hardware up/down counter that decodes quadrature itself (an MCU timer in
/// encoder mode, the paper's FPGA 20-bit counter read over SPI).
///
/// The value wraps modulo `2^BITS`; take increments with
/// [`wrapping_diff`](crate::counter::wrapping_diff)`(now, before, Self::BITS)`,
/// which is exact as long as the counter moves by less than `2^(BITS-1)`
/// counts between two reads.
pub trait CountSource {
    /// The error of a failed read.
    type Error;

    /// The counter's width in bits, 1..=32 (20 in the paper, 16 or 32 for
    /// typical MCU timers).
    const BITS: u32;

    /// Reads the raw counter value, in `0..2^BITS` (counts, x4).
    fn count(&mut self) -> Result<u32, Self::Error>;
}

impl<S: CountSource + ?Sized> CountSource for &mut S {
    type Error = S::Error;
    const BITS: u32 = S::BITS;

    #[inline]
    fn count(&mut self) -> Result<u32, Self::Error> {
        (**self).count()
    }
}
