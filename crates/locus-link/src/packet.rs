//! The packets and their byte layout (protocol version 1; the tables are in
//! `docs/protocol.md`). Every multi-byte field is little-endian; every packet
//! starts with the 4-byte header `magic[2] version kind` and ends with the
//! CRC-32 (ISO-HDLC, the Ethernet/zlib CRC) of all the bytes before it.
//!
//! Encoding writes into a caller's buffer and decoding reads from a slice:
//! nothing allocates.

use crc::{CRC_32_ISO_HDLC, Crc};

use crate::error::Error;

/// The first two bytes of every packet: `"LK"`.
pub const MAGIC: [u8; 2] = *b"LK";
/// The protocol version this codec speaks.
pub const VERSION: u8 = 1;
/// Most laser beams one telemetry packet carries.
pub const MAX_BEAMS: usize = 16;
/// Length of a telemetry packet without beams (bytes); each beam adds 4.
pub const TELEMETRY_MIN_LEN: usize = 40;
/// Length of a command packet (bytes).
pub const COMMAND_LEN: usize = 24;
/// Largest packet (bytes): telemetry with [`MAX_BEAMS`] beams. A buffer of
/// this size holds any packet.
pub const MAX_PACKET: usize = TELEMETRY_MIN_LEN + 4 * MAX_BEAMS;
/// [`CommandPacket::ack`] when the host has applied no telemetry yet.
pub const NO_ACK: u32 = u32::MAX;

/// Smallest packet that can be checked: header, sequence and CRC (bytes).
const MIN_LEN: usize = 12;
/// Kind byte of a telemetry packet (robot to host).
const KIND_TELEMETRY: u8 = 1;
/// Kind byte of a command packet (host to robot).
const KIND_COMMAND: u8 = 2;
/// Telemetry flags: bit 0, IR pair reading present.
const FLAG_IR: u8 = 1;

/// The CRC-32 used on every packet (ISO-HDLC: polynomial 0x04C11DB7,
/// reflected, init and xor-out 0xFFFFFFFF; check value of `"123456789"` is
/// 0xCBF43926).
///
/// With the `small-crc` feature it is computed bit by bit (no table: 1 KiB
/// less flash, about eight times the work per byte) for flash-constrained
/// firmware; the values are the same.
#[cfg(not(feature = "small-crc"))]
const CRC: Crc<u32> = Crc::<u32>::new(&CRC_32_ISO_HDLC);
/// The CRC-32 used on every packet, bitwise (see above).
#[cfg(feature = "small-crc")]
const CRC: Crc<u32, crc::NoTable> = Crc::<u32, crc::NoTable>::new(&CRC_32_ISO_HDLC);

/// Robot to host: one sample of the robot's sensors.
///
/// Units: time in microseconds of the robot's own clock, encoder counts in
/// the robot's quadrature counts (the host knows the count quantum), IR and
/// laser distances in metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Telemetry {
    /// Sequence number: 0 for the first packet, +1 per packet sent,
    /// wrapping at 2^32.
    pub sequence: u32,
    /// Robot clock when the sample was taken (us).
    pub timestamp_us: u64,
    /// Cumulative encoder counts `[right, left]` since the robot started,
    /// wrapping modulo 2^32 (so a lost packet loses no travel: the next
    /// packet's difference covers it).
    pub counts: [u32; 2],
    /// IR pair distances `[d_s1, d_s2]` (m) when both sensors were in range.
    pub ir: Option<[f32; 2]>,
    /// Laser beam ranges (m); only the first `beam_count` are meaningful,
    /// the rest are zero.
    beams: [f32; MAX_BEAMS],
    /// Number of laser beams, `<= MAX_BEAMS`.
    beam_count: u8,
}

impl Telemetry {
    /// A telemetry packet with `sequence` and `timestamp_us`, zero counts,
    /// no IR reading and no beams.
    #[must_use]
    pub fn new(sequence: u32, timestamp_us: u64) -> Self {
        Self {
            sequence,
            timestamp_us,
            counts: [0, 0],
            ir: None,
            beams: [0.0; MAX_BEAMS],
            beam_count: 0,
        }
    }

    /// The laser beam ranges (m).
    #[must_use]
    pub fn beams(&self) -> &[f32] {
        &self.beams[..usize::from(self.beam_count)]
    }

    /// Sets the laser beam ranges (m).
    ///
    /// # Errors
    /// [`Error::TooManyBeams`] for more than [`MAX_BEAMS`] ranges (the
    /// packet is unchanged).
    pub fn set_beams(&mut self, ranges: &[f32]) -> Result<(), Error> {
        if ranges.len() > MAX_BEAMS {
            return Err(Error::TooManyBeams {
                count: ranges.len(),
            });
        }
        self.beams = [0.0; MAX_BEAMS];
        self.beams[..ranges.len()].copy_from_slice(ranges);
        #[allow(clippy::cast_possible_truncation)] // <= MAX_BEAMS
        {
            self.beam_count = ranges.len() as u8;
        }
        Ok(())
    }

    /// Encoded length (bytes): `40 + 4 * beams`.
    #[must_use]
    pub fn encoded_len(&self) -> usize {
        TELEMETRY_MIN_LEN + 4 * usize::from(self.beam_count)
    }

    /// Writes the packet at the start of `buf` and returns its length.
    ///
    /// # Errors
    /// [`Error::BufferTooSmall`]; [`Error::NonFinite`] if a distance is NaN
    /// or infinite.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        let len = self.encoded_len();
        if buf.len() < len {
            return Err(Error::BufferTooSmall {
                needed: len,
                len: buf.len(),
            });
        }
        let ir = self.ir.unwrap_or([0.0, 0.0]);
        if !ir.iter().chain(self.beams()).all(|v| v.is_finite()) {
            return Err(Error::NonFinite);
        }
        let out = &mut buf[..len];
        header(out, KIND_TELEMETRY, self.sequence);
        out[8..16].copy_from_slice(&self.timestamp_us.to_le_bytes());
        out[16..20].copy_from_slice(&self.counts[0].to_le_bytes());
        out[20..24].copy_from_slice(&self.counts[1].to_le_bytes());
        out[24] = if self.ir.is_some() { FLAG_IR } else { 0 };
        out[25] = self.beam_count;
        out[26..28].copy_from_slice(&[0, 0]);
        out[28..32].copy_from_slice(&ir[0].to_le_bytes());
        out[32..36].copy_from_slice(&ir[1].to_le_bytes());
        for (i, b) in self.beams().iter().enumerate() {
            out[36 + 4 * i..40 + 4 * i].copy_from_slice(&b.to_le_bytes());
        }
        seal(out);
        Ok(len)
    }

    /// Decodes a telemetry packet (checks in the order of [`decode`]).
    ///
    /// # Errors
    /// Any decode error of [`decode`]; [`Error::BadKind`] for a command.
    pub fn decode(bytes: &[u8]) -> Result<Self, Error> {
        match decode(bytes)? {
            Packet::Telemetry(t) => Ok(t),
            Packet::Command(_) => Err(Error::BadKind { kind: KIND_COMMAND }),
        }
    }
}

/// Host to robot: wheel speed commands.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommandPacket {
    /// Sequence number: 0 for the first command, +1 per command sent,
    /// wrapping at 2^32.
    pub sequence: u32,
    /// Sequence number of the newest telemetry the host had applied when it
    /// computed this command ([`NO_ACK`] before the first). Lets the robot
    /// measure the round trip.
    pub ack: u32,
    /// Right wheel speed `V1` (m/s, forward positive).
    pub right: f32,
    /// Left wheel speed `V2` (m/s, forward positive).
    pub left: f32,
}

impl CommandPacket {
    /// Writes the packet ([`COMMAND_LEN`] bytes) at the start of `buf`.
    ///
    /// # Errors
    /// [`Error::BufferTooSmall`]; [`Error::NonFinite`] for a NaN or
    /// infinite speed.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, Error> {
        if buf.len() < COMMAND_LEN {
            return Err(Error::BufferTooSmall {
                needed: COMMAND_LEN,
                len: buf.len(),
            });
        }
        if !(self.right.is_finite() && self.left.is_finite()) {
            return Err(Error::NonFinite);
        }
        let out = &mut buf[..COMMAND_LEN];
        header(out, KIND_COMMAND, self.sequence);
        out[8..12].copy_from_slice(&self.ack.to_le_bytes());
        out[12..16].copy_from_slice(&self.right.to_le_bytes());
        out[16..20].copy_from_slice(&self.left.to_le_bytes());
        seal(out);
        Ok(COMMAND_LEN)
    }

    /// Decodes a command packet (checks in the order of [`decode`]). A
    /// telemetry packet is [`Error::BadKind`] once its CRC, magic and
    /// version passed, without checking its body: the robot's decoder then
    /// carries no telemetry decoding (flash on a microcontroller).
    ///
    /// # Errors
    /// Any decode error of [`decode`] for a command; [`Error::BadKind`] for
    /// telemetry.
    pub fn decode(bytes: &[u8]) -> Result<Self, Error> {
        let (kind, sequence) = check(bytes)?;
        match kind {
            KIND_COMMAND => decode_command(bytes, sequence),
            kind => Err(Error::BadKind { kind }),
        }
    }
}

/// A decoded packet of either direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Packet {
    /// Robot to host.
    Telemetry(Telemetry),
    /// Host to robot.
    Command(CommandPacket),
}

/// Decodes one packet. The checks run in this order, and the first that
/// fails is the error: length at least 12 (header, sequence, CRC) ([`Error::TooShort`]), CRC
/// ([`Error::BadCrc`]), magic, version, kind, the exact length of that kind
/// ([`Error::BadLength`], [`Error::TooManyBeams`]), reserved fields zero,
/// values finite. Every input either decodes or returns an error; nothing
/// panics.
///
/// # Errors
/// As listed above.
pub fn decode(bytes: &[u8]) -> Result<Packet, Error> {
    let (kind, sequence) = check(bytes)?;
    match kind {
        KIND_TELEMETRY => decode_telemetry(bytes, sequence).map(Packet::Telemetry),
        KIND_COMMAND => decode_command(bytes, sequence).map(Packet::Command),
        kind => Err(Error::BadKind { kind }),
    }
}

/// The checks every packet passes first: length at least 12, CRC, magic,
/// version. Returns the kind byte and the sequence number.
fn check(bytes: &[u8]) -> Result<(u8, u32), Error> {
    let len = bytes.len();
    if len < MIN_LEN {
        return Err(Error::TooShort { len });
    }
    let (body, tail) = bytes.split_at(len - 4);
    let received = u32::from_le_bytes([tail[0], tail[1], tail[2], tail[3]]);
    let computed = crc32(body);
    if received != computed {
        return Err(Error::BadCrc { received, computed });
    }
    if body[0..2] != MAGIC {
        return Err(Error::BadMagic);
    }
    if body[2] != VERSION {
        return Err(Error::BadVersion { version: body[2] });
    }
    Ok((body[3], u32_at(body, 4)))
}

/// The command body of a packet whose CRC, magic, version and kind passed.
fn decode_command(bytes: &[u8], sequence: u32) -> Result<CommandPacket, Error> {
    let len = bytes.len();
    if len != COMMAND_LEN {
        return Err(Error::BadLength {
            expected: COMMAND_LEN,
            len,
        });
    }
    let c = CommandPacket {
        sequence,
        ack: u32_at(bytes, 8),
        right: f32_at(bytes, 12),
        left: f32_at(bytes, 16),
    };
    if c.right.is_finite() && c.left.is_finite() {
        Ok(c)
    } else {
        Err(Error::NonFinite)
    }
}

/// The telemetry body of a packet whose CRC, magic, version and kind passed.
fn decode_telemetry(bytes: &[u8], sequence: u32) -> Result<Telemetry, Error> {
    let len = bytes.len();
    if len < TELEMETRY_MIN_LEN {
        return Err(Error::BadLength {
            expected: TELEMETRY_MIN_LEN,
            len,
        });
    }
    let count = usize::from(bytes[25]);
    if count > MAX_BEAMS {
        return Err(Error::TooManyBeams { count });
    }
    let expected = TELEMETRY_MIN_LEN + 4 * count;
    if len != expected {
        return Err(Error::BadLength { expected, len });
    }
    let flags = bytes[24];
    if flags & !FLAG_IR != 0 || bytes[26] != 0 || bytes[27] != 0 {
        return Err(Error::Reserved);
    }
    let ir_raw = [f32_at(bytes, 28), f32_at(bytes, 32)];
    let ir = if flags & FLAG_IR != 0 {
        Some(ir_raw)
    } else if u32_at(bytes, 28) == 0 && u32_at(bytes, 32) == 0 {
        None
    } else {
        return Err(Error::Reserved);
    };
    let mut t = Telemetry::new(sequence, u64_at(bytes, 8));
    t.counts = [u32_at(bytes, 16), u32_at(bytes, 20)];
    t.ir = ir;
    for i in 0..count {
        t.beams[i] = f32_at(bytes, 36 + 4 * i);
    }
    #[allow(clippy::cast_possible_truncation)] // <= MAX_BEAMS
    {
        t.beam_count = count as u8;
    }
    if !ir_raw.iter().chain(t.beams()).all(|v| v.is_finite()) {
        return Err(Error::NonFinite);
    }
    Ok(t)
}

/// The CRC-32 of `bytes` ([`CRC`]). Out of line with `small-crc`, so that a
/// firmware that both encodes and decodes carries one copy of the bitwise
/// loop.
#[cfg_attr(feature = "small-crc", inline(never))]
fn crc32(bytes: &[u8]) -> u32 {
    CRC.checksum(bytes)
}

/// Writes magic, version, `kind` and `sequence` (bytes 0..8).
fn header(out: &mut [u8], kind: u8, sequence: u32) {
    out[0..2].copy_from_slice(&MAGIC);
    out[2] = VERSION;
    out[3] = kind;
    out[4..8].copy_from_slice(&sequence.to_le_bytes());
}

/// Writes the CRC of all but the last four bytes into the last four.
fn seal(out: &mut [u8]) {
    let n = out.len() - 4;
    let crc = crc32(&out[..n]);
    out[n..].copy_from_slice(&crc.to_le_bytes());
}

/// Little-endian `u32` at `at` (the caller has checked the length).
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// Little-endian `u64` at `at` (the caller has checked the length).
fn u64_at(b: &[u8], at: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[at..at + 8]);
    u64::from_le_bytes(a)
}

/// Little-endian `f32` at `at` (the caller has checked the length).
fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_bits(u32_at(b, at))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_check_value() {
        assert_eq!(CRC.checksum(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn layout_of_a_command() {
        let c = CommandPacket {
            sequence: 0x0102_0304,
            ack: 5,
            right: 1.0,
            left: -1.0,
        };
        let mut buf = [0u8; COMMAND_LEN];
        assert_eq!(c.encode(&mut buf), Ok(COMMAND_LEN));
        assert_eq!(&buf[..8], &[b'L', b'K', 1, 2, 4, 3, 2, 1]);
        assert_eq!(&buf[8..12], &[5, 0, 0, 0]);
        assert_eq!(&buf[12..16], &1.0f32.to_le_bytes());
        assert_eq!(&buf[16..20], &(-1.0f32).to_le_bytes());
        assert_eq!(u32_at(&buf, 20), CRC.checksum(&buf[..20]));
    }

    #[test]
    fn the_command_decoder_refuses_telemetry_by_kind_without_reading_its_body() {
        let mut buf = [0u8; MAX_PACKET];
        let n = Telemetry::new(7, 70).encode(&mut buf).unwrap();
        assert_eq!(
            CommandPacket::decode(&buf[..n]),
            Err(Error::BadKind {
                kind: KIND_TELEMETRY
            })
        );
        // A reserved byte set, resealed: `decode` reads the body and says
        // so; the command decoder stops at the kind.
        buf[26] = 1;
        seal(&mut buf[..n]);
        assert_eq!(decode(&buf[..n]), Err(Error::Reserved));
        assert_eq!(
            CommandPacket::decode(&buf[..n]),
            Err(Error::BadKind {
                kind: KIND_TELEMETRY
            })
        );
    }
}
