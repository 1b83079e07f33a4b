//! Framing of the link's packets on a byte stream (a UART on the robot, a
//! serial port on the host; a Bluetooth SPP link is a serial port too,
//! `/dev/rfcomm0` on Linux). UDP keeps packet boundaries; a byte stream does
//! not, so each packet travels as one **COBS frame** (Consistent Overhead
//! Byte Stuffing, Cheshire and Baker, 1999) between two `0x00` delimiters:
//!
//! ```text
//! 0x00  COBS(packet)  0x00
//! ```
//!
//! # Why COBS rather than SLIP
//! - **Bounded overhead**: COBS adds one byte per 254 bytes of packet (at
//!   most `ceil(n / 254)`, at least 1), whatever the content; SLIP doubles
//!   every byte that equals its delimiter or escape, so a packet of
//!   `0xC0`s is twice as long. A buffer of [`MAX_FRAME`] bytes holds any
//!   framed packet.
//! - **The delimiter never occurs inside a frame**: COBS removes every
//!   `0x00` from the packet, so a receiver that lost track resynchronises by
//!   scanning for the next `0x00`, and nothing inside a frame can look like
//!   its end.
//! - **No escape state**: in SLIP a lost or damaged escape byte changes the
//!   meaning of the byte after it, and that state is carried across the
//!   damage. A COBS decoder's only state is the length of the current block,
//!   and every delimiter resets it.
//!
//! # The leading delimiter
//! [`encode_frame`] writes a `0x00` before the frame as well as after it.
//! It costs one byte per frame and makes every frame survive arbitrary
//! garbage before it: whatever line noise, cut frame or power-up junk came
//! first, the leading `0x00` ends it. Without it, garbage that does not
//! end in `0x00` joins the next frame and takes it down with it (only that
//! one: the frame's own trailing delimiter ends the damage). The trailing
//! delimiter ends the frame as soon as it is sent, so the receiver never
//! waits for the next frame to see the end of this one. Between two frames
//! the receiver therefore sees `0x00 0x00`, an *empty frame*: not an error,
//! counted in [`FrameCounters::empty`] and skipped.
//!
//! # Who checks what
//! The framing checks only the COBS layer: a frame that is longer than the
//! decoder's buffer ([`FrameError::Oversize`]) or whose last code byte
//! points past the delimiter ([`FrameError::Malformed`]) is dropped and
//! counted here. Every other frame is handed out as bytes, unchecked; the
//! packet decoder ([`decode`](crate::decode), [`Receiver`](crate::Receiver))
//! then checks length, CRC and fields. So a frame whose bytes were flipped
//! on the line (but whose COBS structure survived) is counted by the
//! `Receiver` as *corrupt*, and a frame cut by a flipped-to-zero byte as
//! *malformed* or *corrupt*: one damaged byte costs at most the one packet
//! it falls in (and at most two frames: a byte that becomes `0x00` splits a
//! frame in two).
//!
//! # Why not the `cobs` crate
//! The encoder and the streaming decoder together are about 60 lines; the
//! decoder's resynchronisation rule and its per-reason counters
//! ([`FrameCounters`], with every received byte accounted for) are the part
//! that matters here, and a general crate's decoder does not report them.
//! Writing it keeps firmware free of another dependency. The encoder
//! produces the canonical form of the COBS article's examples (an
//! all-non-zero 254-byte block at the end is not followed by an empty
//! block), and the tests check those examples byte for byte.
//!
//! Nothing here allocates or panics, whatever bytes arrive.

use crate::error::{Error, FrameError};
use crate::packet::MAX_PACKET;

/// The frame delimiter. It never occurs inside a COBS-encoded frame.
pub const DELIMITER: u8 = 0x00;

/// Longest run of non-zero bytes one COBS block carries (its code byte is
/// `0xFF` and it implies no zero after it).
const MAX_RUN: usize = 254;

/// Largest framed length (bytes) of a packet of `packet_len` bytes: the
/// leading delimiter, the COBS code bytes (one per 254 bytes of packet, at
/// least one), the packet's bytes and the trailing delimiter. Reached by a
/// packet without zero bytes.
#[must_use]
pub const fn max_frame_len(packet_len: usize) -> usize {
    packet_len + 1 + packet_len.saturating_sub(1) / MAX_RUN + 2
}

/// Largest framed packet (bytes): [`MAX_PACKET`] plus 3 (two delimiters
/// and one code byte). A buffer of this size holds any framed packet.
pub const MAX_FRAME: usize = max_frame_len(MAX_PACKET);

/// Exact framed length (bytes) of `packet`, as [`encode_frame`] writes it
/// (at most [`max_frame_len`] of its length).
#[must_use]
pub fn frame_len(packet: &[u8]) -> usize {
    let mut run = 0;
    let mut extra = 0;
    for (i, &b) in packet.iter().enumerate() {
        if b == 0 {
            run = 0;
        } else {
            run += 1;
            if run == MAX_RUN && i + 1 < packet.len() {
                extra += 1;
                run = 0;
            }
        }
    }
    packet.len() + 1 + extra + 2
}

/// Frames `packet` into `out`: `0x00`, the COBS encoding of `packet`,
/// `0x00`. Returns the number of bytes written ([`frame_len`]). Any
/// content and length is accepted (zeros included; an empty packet frames
/// as `00 01 00`); a receiver's [`FrameDecoder`] drops frames longer than
/// its buffer.
///
/// # Errors
/// [`Error::BufferTooSmall`] if `out` is shorter than [`frame_len`]
/// (nothing is written). A buffer of [`MAX_FRAME`] bytes always suffices
/// for a packet of at most [`MAX_PACKET`] bytes.
pub fn encode_frame(packet: &[u8], out: &mut [u8]) -> Result<usize, Error> {
    let needed = frame_len(packet);
    if out.len() < needed {
        return Err(Error::BufferTooSmall {
            needed,
            len: out.len(),
        });
    }
    out[0] = DELIMITER;
    // `code_at` is the current block's code byte, written when the block
    // ends; `code` is 1 + the non-zero bytes in the block so far.
    let mut code_at = 1;
    let mut code: u8 = 1;
    let mut w = 2;
    for (i, &b) in packet.iter().enumerate() {
        if b == 0 {
            out[code_at] = code;
            code_at = w;
            w += 1;
            code = 1;
        } else {
            out[w] = b;
            w += 1;
            code += 1;
            // A full block implies no zero; start the next one only if
            // more bytes follow (the canonical form).
            if code == 0xFF && i + 1 < packet.len() {
                out[code_at] = code;
                code_at = w;
                w += 1;
                code = 1;
            }
        }
    }
    out[code_at] = code;
    out[w] = DELIMITER;
    Ok(w + 1)
}

/// What a [`FrameDecoder`] has seen since it was created. Every byte
/// pushed is counted exactly once:
/// `bytes pushed = frame_bytes + discarded + empty + pending()`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FrameCounters {
    /// Frames decoded and handed out (good COBS; their content is for the
    /// packet decoder to judge).
    pub frames: u64,
    /// Bytes of the decoded frames as received: COBS bytes and the closing
    /// delimiter.
    pub frame_bytes: u64,
    /// Frames dropped because they decode to more bytes than the buffer
    /// ([`FrameError::Oversize`]).
    pub oversize: u64,
    /// Frames dropped because the delimiter came inside a COBS block
    /// ([`FrameError::Malformed`]).
    pub malformed: u64,
    /// Empty frames: a delimiter right after a delimiter (or as the first
    /// byte). Not an error: the sender's leading delimiter makes one
    /// between every two frames; skipped, one byte each.
    pub empty: u64,
    /// Bytes discarded: those of dropped frames (with their closing
    /// delimiter) and those before the decoder's first delimiter (with
    /// that delimiter, unless it was the very first byte: then it is an
    /// empty frame).
    pub discarded: u64,
}

impl FrameCounters {
    /// Frames dropped by the framing layer: oversize plus malformed.
    #[must_use]
    pub fn dropped(&self) -> u64 {
        self.oversize + self.malformed
    }
}

/// Streaming COBS decoder with a fixed buffer of `N` bytes (by default
/// [`MAX_PACKET`], the largest packet). Feed it the received bytes, one at
/// a time ([`push`](Self::push)) or as slices ([`feed`](Self::feed),
/// [`feed_all`](Self::feed_all)); each delimiter that ends a non-empty
/// frame yields the decoded bytes or the reason it was dropped.
///
/// **Resynchronisation**: the decoder starts out of step (the line may be
/// opened in the middle of a frame) and discards everything up to the first
/// `0x00`. On an error (oversize, malformed) it drops the frame and
/// discards up to the next `0x00`. Every `0x00` starts a new frame, so one
/// damaged or lost byte can never affect a frame after the next delimiter.
///
/// A decoded frame borrows the decoder's buffer; it is valid until the next
/// byte is pushed.
#[derive(Debug, Clone)]
pub struct FrameDecoder<const N: usize = MAX_PACKET> {
    /// Decoded bytes of the current frame (the first `len`).
    buf: [u8; N],
    /// Decoded bytes in `buf`.
    len: usize,
    /// Bytes still to come in the current COBS block; 0 when the next
    /// non-zero byte is a code byte.
    left: u8,
    /// Code byte of the current block, 0 before a frame's first block. A
    /// block with a code below 0xFF implies a zero after it, written when
    /// the next block starts (the last block's is not part of the packet).
    code: u8,
    /// Bytes of the current frame received so far, delimiter excluded.
    received: u64,
    /// Discarding up to the next delimiter (at start and after an error).
    discarding: bool,
    /// The counters.
    counters: FrameCounters,
}

impl<const N: usize> Default for FrameDecoder<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> FrameDecoder<N> {
    /// A decoder that discards up to the first delimiter.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            buf: [0; N],
            len: 0,
            left: 0,
            code: 0,
            received: 0,
            discarding: true,
            counters: FrameCounters {
                frames: 0,
                frame_bytes: 0,
                oversize: 0,
                malformed: 0,
                empty: 0,
                discarded: 0,
            },
        }
    }

    /// The counters so far.
    #[must_use]
    pub fn counters(&self) -> FrameCounters {
        self.counters
    }

    /// Bytes of the current frame received but not yet decided (0 while
    /// discarding: those are already counted in `discarded`).
    #[must_use]
    pub fn pending(&self) -> u64 {
        if self.discarding { 0 } else { self.received }
    }

    /// Pushes one received byte. Returns `None` until a delimiter ends a
    /// non-empty frame that was not already dropped, or a frame is found
    /// oversize; then the decoded frame or the reason it was dropped
    /// (already counted). Empty frames and discarded bytes yield nothing.
    pub fn push(&mut self, byte: u8) -> Option<Result<&[u8], FrameError>> {
        let event = self.step(byte)?;
        Some(event.map(|len| &self.buf[..len]))
    }

    /// Pushes bytes from the start of `bytes` up to and including the first
    /// that yields an event (see [`push`](Self::push)). Returns how many
    /// bytes were used and the event; call again with the rest.
    pub fn feed(&mut self, bytes: &[u8]) -> (usize, Option<Result<&[u8], FrameError>>) {
        for (i, &b) in bytes.iter().enumerate() {
            if let Some(event) = self.step(b) {
                return (i + 1, Some(event.map(|len| &self.buf[..len])));
            }
        }
        (bytes.len(), None)
    }

    /// Pushes all of `bytes`, calling `on_frame` with every event in order.
    pub fn feed_all(&mut self, bytes: &[u8], mut on_frame: impl FnMut(Result<&[u8], FrameError>)) {
        let mut rest = bytes;
        while !rest.is_empty() {
            let (used, event) = self.feed(rest);
            if let Some(event) = event {
                on_frame(event);
            }
            rest = &rest[used..];
        }
    }

    /// One byte; an event carries the decoded length (`<= N`).
    fn step(&mut self, byte: u8) -> Option<Result<usize, FrameError>> {
        if byte == DELIMITER {
            return self.end_of_frame();
        }
        self.received += 1;
        if self.discarding {
            self.counters.discarded += 1;
            return None;
        }
        let fits = if self.left == 0 {
            let implied_zero = self.code != 0 && self.code != 0xFF;
            self.code = byte;
            self.left = byte - 1;
            !implied_zero || self.put(0)
        } else {
            self.left -= 1;
            self.put(byte)
        };
        if fits {
            return None;
        }
        self.counters.oversize += 1;
        self.counters.discarded += self.received;
        self.discarding = true;
        Some(Err(FrameError::Oversize { capacity: N }))
    }

    /// Appends a decoded byte; `false` if the buffer is full.
    fn put(&mut self, byte: u8) -> bool {
        match self.buf.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
                true
            }
            None => false,
        }
    }

    /// A delimiter: decide the frame and start the next.
    fn end_of_frame(&mut self) -> Option<Result<usize, FrameError>> {
        let (received, len, left, discarding) =
            (self.received, self.len, self.left, self.discarding);
        self.received = 0;
        self.len = 0;
        self.left = 0;
        self.code = 0;
        self.discarding = false;
        if received == 0 {
            self.counters.empty += 1;
            None
        } else if discarding {
            self.counters.discarded += 1;
            None
        } else if left != 0 {
            self.counters.malformed += 1;
            self.counters.discarded += received + 1;
            Some(Err(FrameError::Malformed))
        } else {
            self.counters.frames += 1;
            self.counters.frame_bytes += received + 1;
            Some(Ok(len))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::CommandPacket;

    /// The worked example of `docs/protocol.md`, byte for byte.
    #[test]
    fn worked_example_of_the_protocol_page() {
        let c = CommandPacket {
            sequence: 1,
            ack: 0,
            right: 0.5,
            left: 0.5,
        };
        let mut packet = [0u8; 24];
        c.encode(&mut packet).unwrap();
        assert_eq!(
            packet,
            [
                0x4c, 0x4b, 0x01, 0x02, 0x01, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
                0x00, 0x3f, 0x00, 0x00, 0x00, 0x3f, 0xa9, 0xc4, 0xf5, 0x0e,
            ]
        );
        let mut frame = [0u8; MAX_FRAME];
        let n = encode_frame(&packet, &mut frame).unwrap();
        assert_eq!(
            frame[..n],
            [
                0x00, 0x06, 0x4c, 0x4b, 0x01, 0x02, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01,
                0x01, 0x01, 0x02, 0x3f, 0x01, 0x01, 0x06, 0x3f, 0xa9, 0xc4, 0xf5, 0x0e, 0x00,
            ]
        );
        let mut d = FrameDecoder::<MAX_PACKET>::new();
        let mut got = None;
        d.feed_all(&frame[..n], |f| got = Some(f.map(CommandPacket::decode)));
        assert_eq!(got, Some(Ok(Ok(c))));
    }
}
