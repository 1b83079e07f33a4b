//! The firmware as a robot on the Locus link (`docs/protocol.md`), over a
//! byte stream: each step's telemetry goes out as a COBS frame
//! ([`encode_frame`]), and wheel commands come in byte by byte through a
//! [`FrameDecoder`] and the protocol's [`Receiver`]. No allocation, no I/O:
//! the firmware binary (`locus-fw-link`) moves the bytes over its UART.
//!
//! What a step sends is what `locus_simlink` (the simulated robot
//! endpoint) sends: telemetry `k` after step `k` (telemetry 0 before the
//! first step: time 0, counts 0, no reading), sequence `k`, robot time
//! `k dt`, the encoder counts and the IR pair's reading when both sensors
//! read. The decoders' 20-bit wrapping counts become the link's 32-bit
//! cumulative counts by adding each step's wrapping difference
//! ([`wrapping_diff`]) to a wrapping `u32` ([`LinkRobot::extend`]), as a
//! robot whose counter is narrower than the protocol's must.
//!
//! The robot has no motors: a command is counted (the receiver's counters)
//! and its acknowledgement paces the stream ([`acknowledges`]), nothing
//! else.

use locus_link::framing::{FrameCounters, FrameDecoder, MAX_FRAME, encode_frame};
use locus_link::{CommandPacket, Counters, MAX_PACKET, NO_ACK, Receiver, Status, Telemetry};
use locus_odometry::counter::PAPER_BITS;
use locus_odometry::wrapping_diff;

/// Robot time between two telemetry packets (us): the filter's 10 ms step.
pub const STEP_US: u64 = 10_000;

/// The robot end of the link: the count extension, the telemetry framing
/// and the command decoding with its counters.
#[derive(Debug, Clone)]
pub struct LinkRobot {
    /// The decoders' last 20-bit counts `[right, left]`.
    last: [u32; 2],
    /// The link's cumulative counts `[right, left]`, wrapping modulo 2^32.
    counts: [u32; 2],
    /// COBS frames of the commands (a command is 24 bytes; the buffer
    /// holds any packet, so an oversize frame is one the protocol cannot
    /// carry).
    decoder: FrameDecoder<MAX_PACKET>,
    /// Sequence bookkeeping of the commands.
    receiver: Receiver,
    /// Telemetry packets framed.
    sent: u64,
}

impl Default for LinkRobot {
    fn default() -> Self {
        Self::new()
    }
}

impl LinkRobot {
    /// A robot end whose decoders start at count 0 (as
    /// [`crate::Firmware::new`]'s do), with cumulative counts 0.
    #[must_use]
    pub fn new() -> Self {
        Self {
            last: [0, 0],
            counts: [0, 0],
            decoder: FrameDecoder::new(),
            receiver: Receiver::new(),
            sent: 0,
        }
    }

    /// Extends the decoders' 20-bit wrapping counts `now` (`[right, left]`)
    /// to the link's 32-bit cumulative counts: adds the wrapping difference
    /// since the last call (in `[-2^19, 2^19)`: a wheel must not turn more
    /// than 2^19 counts between two calls, some 5800 turns here) and
    /// returns the new counts.
    pub fn extend(&mut self, now: [u32; 2]) -> [u32; 2] {
        for ((count, last), now) in self.counts.iter_mut().zip(&mut self.last).zip(now) {
            *count = count.wrapping_add_signed(wrapping_diff(now, *last, PAPER_BITS));
            *last = now;
        }
        self.counts
    }

    /// The link's cumulative counts `[right, left]` so far.
    #[must_use]
    pub fn counts(&self) -> [u32; 2] {
        self.counts
    }

    /// Telemetry `sequence` (robot time `sequence * STEP_US`), with the
    /// decoders' 20-bit counts `now` extended ([`extend`](Self::extend))
    /// and the IR reading `ir` (m), framed into `out`; returns the frame's
    /// length (43 bytes: 40 of packet, 1 of COBS overhead, the leading and
    /// the closing delimiter).
    ///
    /// # Errors
    /// [`locus_link::Error::NonFinite`] for a NaN or infinite reading (the
    /// counts are extended all the same).
    #[inline(never)]
    pub fn telemetry_frame(
        &mut self,
        sequence: u32,
        now: [u32; 2],
        ir: Option<[f32; 2]>,
        out: &mut [u8; MAX_FRAME],
    ) -> Result<usize, locus_link::Error> {
        let mut t = Telemetry::new(sequence, u64::from(sequence) * STEP_US);
        t.counts = self.extend(now);
        t.ir = ir;
        let mut packet = [0u8; MAX_PACKET];
        let n = t.encode(&mut packet)?;
        let len = encode_frame(&packet[..n], out)?;
        self.sent += 1;
        Ok(len)
    }

    /// One byte received from the host. Returns the command a frame ending
    /// here carried, if it was valid and new by its sequence number
    /// ([`Status::Applied`]); everything else (a dropped frame, a corrupt,
    /// malformed, duplicate, late or suspect packet) is only counted.
    #[inline(never)]
    pub fn push(&mut self, byte: u8) -> Option<CommandPacket> {
        let Some(Ok(frame)) = self.decoder.push(byte) else {
            return None;
        };
        match self.receiver.receive_command(frame) {
            Ok((c, Status::Applied { .. })) => Some(c),
            _ => None,
        }
    }

    /// The command receiver's counters (applied, lost, duplicate, late,
    /// corrupt, malformed, suspect).
    #[must_use]
    pub fn commands(&self) -> Counters {
        self.receiver.counters()
    }

    /// What the COBS decoder dropped before packets were formed.
    #[must_use]
    pub fn framing(&self) -> FrameCounters {
        self.decoder.counters()
    }

    /// Telemetry packets framed.
    #[must_use]
    pub fn sent(&self) -> u64 {
        self.sent
    }
}

/// Whether a command acknowledging telemetry `ack` answers telemetry `k`
/// or a later one: `ack` is `k` or up to 2^31 - 1 ahead (wrapping), and not
/// [`NO_ACK`] (the host's handshake commands, sent before it applied any
/// telemetry).
#[must_use]
pub fn acknowledges(ack: u32, k: u32) -> bool {
    ack != NO_ACK && ack.wrapping_sub(k) < 1 << 31
}
