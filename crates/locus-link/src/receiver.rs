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
//! - **suspect**: decodes, but its sequence number is more than
//!   [`MAX_JUMP`] ahead of or behind the newest applied: no sender skips so
//!   many, so the number itself is not trusted (a bit flip the CRC missed, a
//!   forged or replayed packet, a sender that restarted). It costs O(1) and
//!   moves nothing. [`RESYNC_AFTER`] suspect packets in a row, each numbered
//!   one after the other, are a sender that restarted or jumped for good:
//!   the last of them is applied as if it were the first packet (counted in
//!   `applied` and in `resync`), so the link is never locked out.
//! - **implausible**: applied by sequence, but the caller found its content
//!   impossible (for instance a wheel travel the robot's top speed cannot
//!   explain) and refused it ([`Receiver::refuse_applied`]).
//!
//! Every packet lands in exactly one of applied, duplicate, late, corrupt,
//! malformed, suspect and implausible; lost and resync count events, not
//! packets.
//!
//! Sequence numbers compare modulo 2^32: `s` is newer than `n` when
//! `(s - n) mod 2^32` is in `1..=MAX_JUMP`. Only applied packets may change
//! the caller's state; every other class is dropped.

use crate::error::Error;
use crate::packet::{CommandPacket, Telemetry};

/// Width of the window of recently received sequence numbers (a bitmap).
const WINDOW: u32 = 64;

/// Largest plausible sequence jump (numbers) between the newest applied
/// packet and a new one, either way: 1024 packets are 10 s of telemetry at
/// 100 Hz. A jump beyond it is suspect.
pub const MAX_JUMP: u32 = 1024;

/// Suspect packets in a row, numbered one after the other, after which the
/// receiver re-anchors on them (a sender that restarted its numbering).
pub const RESYNC_AFTER: u32 = 8;

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
    /// Sequence number beyond [`MAX_JUMP`] of the newest: drop it.
    Suspect,
    /// The last of [`RESYNC_AFTER`] consecutive suspect packets: the
    /// receiver re-anchored on it. Use it as the first packet of a new
    /// stream (reference values only: nothing is known of the gap).
    Resynchronised,
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
    /// Packets whose sequence number jumped beyond [`MAX_JUMP`].
    pub suspect: u64,
    /// Applied packets the caller refused for their content
    /// ([`Receiver::refuse_applied`]).
    pub implausible: u64,
    /// Times the receiver re-anchored on a run of suspect packets.
    pub resync: u64,
}

impl Counters {
    /// Packets received: the sum of the per-packet classes (applied,
    /// duplicate, late, corrupt, malformed, suspect, implausible).
    #[must_use]
    pub fn received(&self) -> u64 {
        self.applied
            + self.duplicate
            + self.late
            + self.corrupt
            + self.malformed
            + self.suspect
            + self.implausible
    }
}

/// Classifies and counts the packets of one direction of a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Receiver {
    /// Newest applied sequence number.
    newest: Option<u32>,
    /// Bit `k`: sequence `newest - k` was received.
    seen: u64,
    /// The newest suspect packet's sequence and how many suspect packets
    /// in a row, numbered one after the other, ended with it.
    suspects: Option<(u32, u32)>,
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
            return self.anchor(sequence, Status::Applied { skipped: 0 });
        };
        let ahead = sequence.wrapping_sub(newest);
        if ahead != 0 && ahead <= MAX_JUMP {
            let skipped = ahead - 1;
            self.seen = if ahead >= WINDOW {
                0
            } else {
                self.seen << ahead
            } | 1;
            self.newest = Some(sequence);
            self.suspects = None;
            self.counters.applied += 1;
            self.counters.lost += u64::from(skipped);
            return Status::Applied { skipped };
        }
        let behind = newest.wrapping_sub(sequence);
        if behind > MAX_JUMP {
            let run = match self.suspects {
                Some((last, run)) if sequence == last.wrapping_add(1) => run + 1,
                _ => 1,
            };
            if run >= RESYNC_AFTER {
                self.counters.resync += 1;
                return self.anchor(sequence, Status::Resynchronised);
            }
            self.suspects = Some((sequence, run));
            self.counters.suspect += 1;
            return Status::Suspect;
        }
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

    /// Applies `sequence` as the first of a stream and returns `status`.
    fn anchor(&mut self, sequence: u32, status: Status) -> Status {
        self.newest = Some(sequence);
        self.seen = 1;
        self.suspects = None;
        self.counters.applied += 1;
        status
    }

    /// The caller refused the packet it was just given as applied, for its
    /// content: it is recounted from applied to implausible (its sequence
    /// number stays received, so a copy of it is a duplicate).
    pub fn refuse_applied(&mut self) {
        self.counters.applied = self.counters.applied.saturating_sub(1);
        self.counters.implausible += 1;
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
                ..Counters::default()
            }
        );
        assert_eq!(r.counters().received(), 9);
    }

    #[test]
    fn a_jump_beyond_the_window_is_suspect_and_costs_nothing() {
        let mut r = Receiver::new();
        r.classify(10);
        assert_eq!(
            r.classify(10 + MAX_JUMP),
            Status::Applied {
                skipped: MAX_JUMP - 1
            }
        );
        let newest = 10 + MAX_JUMP;
        // 2^31 - 1 ahead: once counted as 2^31 - 2 lost and applied.
        assert_eq!(
            r.classify(newest.wrapping_add((1 << 31) - 1)),
            Status::Suspect
        );
        assert_eq!(
            r.classify(newest.wrapping_add(MAX_JUMP + 1)),
            Status::Suspect
        );
        assert_eq!(
            r.classify(newest.wrapping_sub(MAX_JUMP + 1)),
            Status::Suspect
        );
        assert_eq!(r.newest(), Some(newest));
        assert_eq!(r.classify(newest + 1), Status::Applied { skipped: 0 });
        let c = r.counters();
        assert_eq!(
            (c.suspect, c.lost, c.applied),
            (3, u64::from(MAX_JUMP - 1), 3)
        );
    }

    #[test]
    fn a_restarted_sender_is_followed_after_a_run_of_suspects() {
        let mut r = Receiver::new();
        for s in 5000..5010 {
            r.classify(s);
        }
        // The sender restarts at 0: suspect until RESYNC_AFTER in a row.
        for s in 0..RESYNC_AFTER - 1 {
            assert_eq!(r.classify(s), Status::Suspect);
        }
        assert_eq!(r.classify(RESYNC_AFTER - 1), Status::Resynchronised);
        assert_eq!(r.classify(RESYNC_AFTER), Status::Applied { skipped: 0 });
        // Scattered suspects never re-anchor.
        for k in 0..100u32 {
            assert_eq!(r.classify((1 << 30) + k * 7919), Status::Suspect);
        }
        let c = r.counters();
        assert_eq!(
            (c.resync, c.applied, c.suspect),
            (1, 12, u64::from(RESYNC_AFTER - 1) + 100)
        );
    }

    #[test]
    fn a_refused_packet_moves_from_applied_to_implausible() {
        let mut r = Receiver::new();
        r.classify(1);
        r.classify(2);
        r.refuse_applied();
        assert_eq!(r.classify(2), Status::Duplicate);
        let c = r.counters();
        assert_eq!(
            (c.applied, c.implausible, c.duplicate, c.received()),
            (1, 1, 1, 3)
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
