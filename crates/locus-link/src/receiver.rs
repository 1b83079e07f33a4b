//! Receiver-side bookkeeping: every packet is classified as applied, lost
//! (a sequence gap), duplicate, late, corrupt or malformed, and counted. The
//! definitions (also in `docs/protocol.md`):
//!
//! - **applied**: decodes, and its sequence number is newer than every
//!   sequence applied before (or it is the first packet). The caller uses it.
//! - **lost**: the sequence numbers an applied packet skips over: when
//!   sequence `s` is applied after newest `n`, `s - n - 1` are added. Counted
//!   when the gap is seen, so a reordered packet that arrives after a newer
//!   one is counted once as lost (when skipped) and once as late (when it
//!   arrives); packets that never arrived number `lost - late`.
//! - **duplicate**: decodes, and its sequence number was received before
//!   (applied or late) within the last 64 sequence numbers.
//! - **late**: decodes, older than the newest applied, and not received
//!   before (or older than the 64-number window).
//! - **corrupt**: the CRC fails ([`Error::BadCrc`]).
//! - **malformed**: any other decode error (too short, bad magic, version,
//!   kind, length, reserved field, non-finite value).
//!
//! Sequence numbers compare modulo 2^32: `s` is newer than `n` when
//! `(s - n) mod 2^32` is in `1..2^31`. Only applied packets may change the
//! caller's state; every other class is dropped.

use crate::error::Error;
use crate::packet::{CommandPacket, Telemetry};

/// Width of the window of recently received sequence numbers (a bitmap).
const WINDOW: u32 = 64;

/// How a packet that decoded was classified.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Newer than every packet applied before: use it. `skipped` sequence
    /// numbers were jumped over (counted as lost; 0 without a gap).
    Applied {
        /// Sequence numbers between the previous applied packet and this
        /// one.
        skipped: u32,
    },
    /// Received before: drop it.
    Duplicate,
    /// Older than the newest applied and not received before: drop it.
    Late,
}

/// The receiver's counters (packets since the receiver was created).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counters {
    /// Packets applied.
    pub applied: u64,
    /// Sequence numbers skipped by applied packets.
    pub lost: u64,
    /// Packets received again.
    pub duplicate: u64,
    /// Packets older than the newest applied, first reception.
    pub late: u64,
    /// Packets whose CRC failed.
    pub corrupt: u64,
    /// Packets that failed any other decode check.
    pub malformed: u64,
}

/// Classifies and counts the packets of one direction of a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Receiver {
    /// Newest applied sequence number.
    newest: Option<u32>,
    /// Bit `k`: sequence `newest - k` was received.
    seen: u64,
    /// The counters.
    counters: Counters,
}

impl Receiver {
    /// A receiver that has seen nothing.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The counters so far.
    #[must_use]
    pub fn counters(&self) -> Counters {
        self.counters
    }

    /// Newest applied sequence number (`None` before the first).
    #[must_use]
    pub fn newest(&self) -> Option<u32> {
        self.newest
    }

    /// Classifies a packet that decoded, by its sequence number, and counts
    /// it.
    pub fn classify(&mut self, sequence: u32) -> Status {
        let Some(newest) = self.newest else {
            self.newest = Some(sequence);
            self.seen = 1;
            self.counters.applied += 1;
            return Status::Applied { skipped: 0 };
        };
        let ahead = sequence.wrapping_sub(newest);
        if ahead != 0 && ahead < 1 << 31 {
            let skipped = ahead - 1;
            self.seen = if ahead >= WINDOW {
                0
            } else {
                self.seen << ahead
            } | 1;
            self.newest = Some(sequence);
            self.counters.applied += 1;
            self.counters.lost += u64::from(skipped);
            return Status::Applied { skipped };
        }
        let behind = newest.wrapping_sub(sequence);
        if behind < WINDOW {
            let bit = 1u64 << behind;
            if self.seen & bit != 0 {
                self.counters.duplicate += 1;
                return Status::Duplicate;
            }
            self.seen |= bit;
        }
        self.counters.late += 1;
        Status::Late
    }

    /// Counts a packet that failed to decode: corrupt for a CRC error,
    /// malformed otherwise.
    pub fn reject(&mut self, error: &Error) {
        if error.is_corrupt() {
            self.counters.corrupt += 1;
        } else {
            self.counters.malformed += 1;
        }
    }

    /// Decodes telemetry and classifies it.
    ///
    /// # Errors
    /// The decode error (already counted as corrupt or malformed).
    pub fn receive_telemetry(&mut self, bytes: &[u8]) -> Result<(Telemetry, Status), Error> {
        match Telemetry::decode(bytes) {
            Ok(t) => Ok((t, self.classify(t.sequence))),
            Err(e) => {
                self.reject(&e);
                Err(e)
            }
        }
    }

    /// Decodes a command and classifies it.
    ///
    /// # Errors
    /// The decode error (already counted as corrupt or malformed).
    pub fn receive_command(&mut self, bytes: &[u8]) -> Result<(CommandPacket, Status), Error> {
        match CommandPacket::decode(bytes) {
            Ok(c) => Ok((c, self.classify(c.sequence))),
            Err(e) => {
                self.reject(&e);
                Err(e)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_class_is_counted() {
        let mut r = Receiver::new();
        assert_eq!(r.classify(10), Status::Applied { skipped: 0 });
        assert_eq!(r.classify(11), Status::Applied { skipped: 0 });
        assert_eq!(r.classify(11), Status::Duplicate);
        assert_eq!(r.classify(14), Status::Applied { skipped: 2 });
        assert_eq!(r.classify(12), Status::Late);
        assert_eq!(r.classify(12), Status::Duplicate);
        assert_eq!(r.classify(10), Status::Duplicate);
        r.reject(&Error::BadCrc {
            received: 0,
            computed: 1,
        });
        r.reject(&Error::BadMagic);
        assert_eq!(
            r.counters(),
            Counters {
                applied: 3,
                lost: 2,
                duplicate: 3,
                late: 1,
                corrupt: 1,
                malformed: 1,
            }
        );
    }

    #[test]
    fn sequence_wraps() {
        let mut r = Receiver::new();
        r.classify(u32::MAX - 1);
        assert_eq!(r.classify(1), Status::Applied { skipped: 2 });
        assert_eq!(r.classify(u32::MAX), Status::Late);
        // Far behind the window: late, not duplicate.
        assert_eq!(r.classify(u32::MAX - 1000), Status::Late);
    }
}
