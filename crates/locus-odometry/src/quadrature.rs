//! x4 quadrature decoding from sampled channel levels (paper 004, section
//! 2.1; spec section 5).
//!
//! Channels A and B are square waves a quarter period apart. Every edge of
//! either channel is one count, so an encoder of N lines gives `4 N` counts
//! per shaft revolution. Numbering the four states in the forward order
//!
//! ```text
//! (A, B):  00 -> 10 -> 11 -> 01 -> 00     phase 0 -> 1 -> 2 -> 3 -> 0
//! ```
//!
//! the difference of phases between two samples, modulo 4, decides:
//! 0 = no edge, 1 = one edge forward, 3 = one edge in reverse, 2 = both
//! channels changed, an **invalid transition**: counted as an error, never as
//! a count. **Forward** means A leads B (A rises first) and counts up.
//!
//! After an invalid transition the decoder adopts the new levels (they are the
//! best knowledge of where the shaft is). So a one-sample glitch on both
//! channels (`s, !s, s`) gives two invalid transitions and no net count, and
//! two real edges missed between samples (sampling too slow) lose two counts
//! but are flagged. A glitch on both channels in a sample where one channel
//! also has a real edge looks like a single-channel change, a valid
//! transition, and cannot be detected by any decoder.
//!
//! ```
//! use locus_odometry::counter::Counter;
//! use locus_odometry::quadrature::{Direction, QuadratureDecoder, Transition};
//!
//! let mut dec = QuadratureDecoder::new(false, false, Counter::paper());
//! assert_eq!(dec.update(true, false), Transition::Count(Direction::Forward));
//! assert_eq!(dec.update(false, true), Transition::Invalid); // both changed
//! assert_eq!(dec.update(false, false), Transition::Count(Direction::Forward));
//! assert_eq!(dec.update(true, false), Transition::Count(Direction::Forward));
//! assert_eq!(dec.counter().value(), 3);
//! assert_eq!(dec.invalid_transitions(), 1);
//! ```

use crate::counter::Counter;
use crate::error::Error;
use crate::source::EncoderSource;

/// The direction of one count.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Channel A leads channel B; counts up.
    Forward,
    /// Channel B leads channel A; counts down.
    Reverse,
}

impl Direction {
    /// +1 for [`Direction::Forward`], -1 for [`Direction::Reverse`] (counts).
    #[inline]
    pub const fn sign(self) -> i32 {
        match self {
            Direction::Forward => 1,
            Direction::Reverse => -1,
        }
    }
}

/// What one new sample of the channels meant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Transition {
    /// Neither channel changed.
    Hold,
    /// Exactly one channel changed: one count in this direction.
    Count(Direction),
    /// Both channels changed: an error, not a count.
    Invalid,
}

/// The phase (0..4) of the levels `(a, b)` in the forward order
/// 00, 10, 11, 01.
#[inline]
const fn phase(a: bool, b: bool) -> u8 {
    // Index (a << 1 | b): 00 -> 0, 01 -> 3, 10 -> 1, 11 -> 2.
    const PHASE: [u8; 4] = [0, 3, 1, 2];
    PHASE[((a as usize) << 1) | b as usize]
}

/// Decodes one transition between two samples of the levels `(A, B)`:
/// `Ok(None)` if nothing changed, `Ok(Some(direction))` for one edge.
///
/// # Errors
/// [`Error::InvalidTransition`] if both channels changed.
#[inline]
pub const fn decode(
    previous: (bool, bool),
    current: (bool, bool),
) -> Result<Option<Direction>, Error> {
    match phase(current.0, current.1).wrapping_sub(phase(previous.0, previous.1)) & 3 {
        0 => Ok(None),
        1 => Ok(Some(Direction::Forward)),
        3 => Ok(Some(Direction::Reverse)),
        _ => Err(Error::InvalidTransition),
    }
}

/// A stateful x4 decoder: the last sampled levels, the up/down
/// [`Counter`] it drives, and the number of invalid transitions seen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct QuadratureDecoder {
    phase: u8,
    counter: Counter,
    invalid: u32,
}

impl QuadratureDecoder {
    /// A decoder whose channels currently read `(a, b)`, driving `counter`
    /// (whose value is kept as the starting position).
    pub const fn new(a: bool, b: bool, counter: Counter) -> Self {
        Self {
            phase: phase(a, b),
            counter,
            invalid: 0,
        }
    }

    /// Takes one new sample of the levels and returns what it meant; a
    /// [`Transition::Count`] has already been applied to the counter, a
    /// [`Transition::Invalid`] to the error count.
    #[inline]
    pub fn update(&mut self, a: bool, b: bool) -> Transition {
        let now = phase(a, b);
        let delta = now.wrapping_sub(self.phase) & 3;
        self.phase = now;
        match delta {
            0 => Transition::Hold,
            1 => {
                self.counter.step(Direction::Forward);
                Transition::Count(Direction::Forward)
            }
            3 => {
                self.counter.step(Direction::Reverse);
                Transition::Count(Direction::Reverse)
            }
            _ => {
                self.invalid = self.invalid.saturating_add(1);
                Transition::Invalid
            }
        }
    }

    /// Samples `source` once and decodes it, as [`update`](Self::update).
    ///
    /// # Errors
    /// The source's error; the decoder is then unchanged.
    #[inline]
    pub fn poll<S: EncoderSource>(&mut self, source: &mut S) -> Result<Transition, S::Error> {
        let (a, b) = source.sample()?;
        Ok(self.update(a, b))
    }

    /// The counter (its value is the position, counts modulo `2^bits`).
    #[inline]
    pub const fn counter(&self) -> &Counter {
        &self.counter
    }

    /// The counter, mutably (to set or reset the position).
    #[inline]
    pub fn counter_mut(&mut self) -> &mut Counter {
        &mut self.counter
    }

    /// The number of invalid transitions seen since construction or the last
    /// [`clear_invalid_transitions`](Self::clear_invalid_transitions)
    /// (saturates at `u32::MAX`).
    #[inline]
    pub const fn invalid_transitions(&self) -> u32 {
        self.invalid
    }

    /// Sets the invalid-transition count to 0.
    #[inline]
    pub fn clear_invalid_transitions(&mut self) {
        self.invalid = 0;
    }

    /// The last sampled levels `(A, B)`.
    #[inline]
    pub const fn levels(&self) -> (bool, bool) {
        match self.phase {
            0 => (false, false),
            1 => (true, false),
            2 => (true, true),
            _ => (false, true),
        }
    }
}
