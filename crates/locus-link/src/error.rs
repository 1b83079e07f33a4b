//! Typed errors of the codec and of the byte-stream framing: small
//! `#[non_exhaustive]` enums, usable without `std` (`Display` and
//! [`core::error::Error`]).

use core::fmt;

/// Why a packet could not be encoded or decoded. New variants may be added
/// without a breaking change.
///
/// A receiver counts [`Error::BadCrc`] as *corrupt* and every other decode
/// error as *malformed* (see [`Error::is_corrupt`] and `docs/protocol.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// Encoding: the output buffer holds `len` bytes, the packet needs
    /// `needed`.
    BufferTooSmall {
        /// Bytes the packet needs.
        needed: usize,
        /// Bytes the buffer holds.
        len: usize,
    },
    /// Decoding: fewer bytes than the smallest packet (12: header,
    /// sequence number and CRC).
    TooShort {
        /// Bytes received.
        len: usize,
    },
    /// Decoding: the CRC-32 of the packet does not match its last four
    /// bytes (the packet was damaged in transit or truncated).
    BadCrc {
        /// The CRC carried by the packet.
        received: u32,
        /// The CRC computed over the packet's bytes.
        computed: u32,
    },
    /// Decoding: the first two bytes are not [`MAGIC`](crate::MAGIC).
    BadMagic,
    /// Decoding: a protocol version this codec does not speak.
    BadVersion {
        /// The version byte received.
        version: u8,
    },
    /// Decoding: an unknown packet kind, or a kind other than the one asked
    /// for.
    BadKind {
        /// The kind byte received.
        kind: u8,
    },
    /// Decoding: the length does not match the kind (and, for telemetry,
    /// the beam count).
    BadLength {
        /// Length the header implies (bytes).
        expected: usize,
        /// Length received (bytes).
        len: usize,
    },
    /// More laser beams than [`MAX_BEAMS`](crate::MAX_BEAMS).
    TooManyBeams {
        /// The beam count asked for or received.
        count: usize,
    },
    /// A reserved bit or field is not zero (or an absent reading is not
    /// encoded as zero).
    Reserved,
    /// A measurement or command is NaN or infinite.
    NonFinite,
}

impl Error {
    /// `true` for [`Error::BadCrc`]: the receiver counts the packet as
    /// corrupt. Every other decode error is counted as malformed.
    #[must_use]
    pub fn is_corrupt(&self) -> bool {
        matches!(self, Error::BadCrc { .. })
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::BufferTooSmall { needed, len } => {
                write!(
                    f,
                    "buffer of {len} bytes too small for a {needed}-byte packet"
                )
            }
            Error::TooShort { len } => write!(f, "packet of {len} bytes is too short"),
            Error::BadCrc { received, computed } => write!(
                f,
                "CRC mismatch: packet carries {received:#010x}, computed {computed:#010x}"
            ),
            Error::BadMagic => f.write_str("bad magic bytes"),
            Error::BadVersion { version } => write!(f, "unsupported protocol version {version}"),
            Error::BadKind { kind } => write!(f, "unexpected packet kind {kind}"),
            Error::BadLength { expected, len } => {
                write!(f, "packet length {len} bytes, header implies {expected}")
            }
            Error::TooManyBeams { count } => write!(f, "{count} laser beams (at most 16)"),
            Error::Reserved => f.write_str("reserved field not zero"),
            Error::NonFinite => f.write_str("non-finite value"),
        }
    }
}

impl core::error::Error for Error {}

/// Why the byte-stream framing ([`FrameDecoder`](crate::FrameDecoder))
/// dropped a frame. The decoder has already counted it
/// ([`FrameCounters`](crate::FrameCounters)) and discards the rest of the
/// frame up to the next delimiter. New variants may be added without a
/// breaking change.
///
/// Framing errors are about the COBS layer only; a frame that decodes but
/// whose bytes were damaged is caught by the packet decoder's CRC
/// ([`Error::BadCrc`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum FrameError {
    /// The frame decodes to more bytes than the decoder's buffer holds
    /// (a lost delimiter merged frames, or line noise without a 0x00).
    Oversize {
        /// The decoder's buffer (bytes).
        capacity: usize,
    },
    /// The delimiter arrived inside a COBS block: the last code byte
    /// pointed past the end of the frame (a cut frame, a lost byte, or a
    /// damaged code byte).
    Malformed,
}

impl fmt::Display for FrameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FrameError::Oversize { capacity } => {
                write!(f, "frame longer than the {capacity}-byte buffer")
            }
            FrameError::Malformed => f.write_str("COBS code points past the frame delimiter"),
        }
    }
}

impl core::error::Error for FrameError {}
