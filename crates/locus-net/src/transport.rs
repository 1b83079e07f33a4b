//! How packets travel between robot and host: one [`Transport`] trait and
//! its implementations, so that the host and robot loops do not care
//! whether the link is UDP datagrams or a byte stream (a serial port, a
//! Bluetooth SPP link appearing as `/dev/rfcomm0`).
//!
//! - [`Udp`]: one packet per datagram (`docs/protocol.md`, "Transport:
//!   UDP").
//! - [`Serial`]: COBS frames on a byte stream (`docs/protocol.md`,
//!   "Transport: byte streams"), resynchronising after garbage, a cut
//!   frame or a lost byte, and counting what it drops.

use core::net::SocketAddr;
use core::time::Duration;
use std::net::UdpSocket;
use std::time::Instant;

use locus_link::framing::{FrameCounters, FrameDecoder, MAX_FRAME, encode_frame};
use serialport::SerialPort;

use crate::{Error, at_least_1us, is_timeout};

/// One end of a link: sends and receives whole packets.
pub trait Transport {
    /// Sends one packet to the peer.
    ///
    /// # Errors
    /// The link failed (or, on UDP, no peer is known yet).
    fn send(&mut self, packet: &[u8]) -> Result<(), Error>;

    /// Waits at most `timeout` (zero: takes only what has already arrived)
    /// for one packet from the peer and copies it into `buf`; `Ok(None)`
    /// if none came in time. A packet longer than `buf` is cut to it (the
    /// codec then rejects it).
    ///
    /// # Errors
    /// The link failed.
    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<Option<usize>, Error>;

    /// The packet received last was valid: answer its sender from now on.
    /// On UDP the robot learns the host's address this way; a
    /// point-to-point link has one peer and ignores it.
    fn follow_sender(&mut self) {}

    /// What the transport dropped before a packet was formed (frames on a
    /// byte stream); all zero for datagrams.
    fn framing(&self) -> FrameCounters {
        FrameCounters::default()
    }

    /// Waits until everything sent has left (a byte stream: the line's
    /// output queue has drained), so that a process ending right after its
    /// last packet does not discard it; a datagram is gone once sent.
    ///
    /// # Errors
    /// The link failed.
    fn drain(&mut self) -> Result<(), Error> {
        Ok(())
    }
}

/// UDP: one packet per datagram.
#[derive(Debug)]
pub struct Udp<'a> {
    socket: &'a UdpSocket,
    /// Where packets go, and (if `fixed`) the only source accepted.
    peer: Option<SocketAddr>,
    /// Whether `peer` is fixed (the host) or follows valid senders (the
    /// robot).
    fixed: bool,
    /// Source of the last datagram received.
    last_from: Option<SocketAddr>,
    /// The socket's blocking mode as last set.
    nonblocking: Option<bool>,
}

impl<'a> Udp<'a> {
    /// A link to `peer` on `socket`: packets go there, and datagrams from
    /// anywhere else are ignored (the host's side).
    pub fn to(socket: &'a UdpSocket, peer: SocketAddr) -> Self {
        Self {
            socket,
            peer: Some(peer),
            fixed: true,
            last_from: None,
            nonblocking: None,
        }
    }

    /// A link that answers whoever sent the last valid packet
    /// ([`Transport::follow_sender`]; the robot's side).
    pub fn listen(socket: &'a UdpSocket) -> Self {
        Self {
            socket,
            peer: None,
            fixed: false,
            last_from: None,
            nonblocking: None,
        }
    }

    /// The peer packets go to (`None` before the first valid packet of a
    /// listening link).
    pub fn peer(&self) -> Option<SocketAddr> {
        self.peer
    }

    fn set_nonblocking(&mut self, on: bool) -> Result<(), Error> {
        if self.nonblocking != Some(on) {
            self.socket.set_nonblocking(on)?;
            self.nonblocking = Some(on);
        }
        Ok(())
    }
}

impl Transport for Udp<'_> {
    fn send(&mut self, packet: &[u8]) -> Result<(), Error> {
        let peer = self
            .peer
            .ok_or(Error::Config("no peer to send to yet (UDP)"))?;
        self.socket.send_to(packet, peer)?;
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<Option<usize>, Error> {
        let deadline = Instant::now() + timeout;
        loop {
            if timeout.is_zero() {
                self.set_nonblocking(true)?;
            } else {
                let now = Instant::now();
                if now >= deadline {
                    return Ok(None);
                }
                self.set_nonblocking(false)?;
                self.socket
                    .set_read_timeout(Some(at_least_1us(deadline - now)))?;
            }
            match self.socket.recv_from(buf) {
                Ok((n, from)) => {
                    if self.fixed && Some(from) != self.peer {
                        continue;
                    }
                    self.last_from = Some(from);
                    return Ok(Some(n));
                }
                Err(e) if is_timeout(&e) => return Ok(None),
                // A packet sent before the peer bound its port comes back
                // as "connection refused" on some systems: not an error.
                Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {
                    if timeout.is_zero() {
                        return Ok(None);
                    }
                }
                Err(e) => return Err(e.into()),
            }
        }
    }

    fn follow_sender(&mut self) {
        if !self.fixed && self.last_from.is_some() {
            self.peer = self.last_from;
        }
    }
}

/// Bytes read from a serial port at a time.
const READ_CHUNK: usize = 256;

/// Longest wait for room in the line's output buffer: a frame takes under
/// 5 ms at 115 200 baud, so a line that cannot take one in this time is
/// stuck, and the send fails.
const WRITE_TIMEOUT: Duration = Duration::from_secs(1);

/// A byte stream (a serial port; a Bluetooth SPP link is one too): each
/// packet travels as a COBS frame between `0x00` delimiters
/// ([`locus_link::framing`]). Garbage, a cut frame or a lost byte cost at
/// most the frames they touch; the decoder's counters say what was
/// dropped, and a frame whose bytes were damaged reaches the packet decoder,
/// which counts it as corrupt.
pub struct Serial {
    port: Box<dyn SerialPort>,
    decoder: FrameDecoder,
    /// Bytes read but not yet fed to the decoder: `rx[pos..len]`.
    rx: [u8; READ_CHUNK],
    pos: usize,
    len: usize,
}

impl core::fmt::Debug for Serial {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Serial")
            .field("framing", &self.decoder.counters())
            .finish_non_exhaustive()
    }
}

impl Serial {
    /// Opens the serial device `path` (`/dev/ttyUSB0`, `/dev/rfcomm0`, a
    /// pseudo-terminal) at `baud` bits per second, 8 data bits, no parity,
    /// one stop bit, no flow control.
    ///
    /// # Errors
    /// [`Error::Serial`] naming the device.
    pub fn open(path: &str, baud: u32) -> Result<Self, Error> {
        let port = serialport::new(path, baud)
            .timeout(Duration::from_millis(10))
            .open()
            .map_err(|source| Error::Serial {
                device: path.to_string(),
                source,
            })?;
        Ok(Self::new(port))
    }

    /// A framed link over an already opened port (for instance one end of
    /// a pseudo-terminal pair).
    pub fn new(port: Box<dyn SerialPort>) -> Self {
        Self {
            port,
            decoder: FrameDecoder::new(),
            rx: [0; READ_CHUNK],
            pos: 0,
            len: 0,
        }
    }
}

impl Transport for Serial {
    fn send(&mut self, packet: &[u8]) -> Result<(), Error> {
        let mut frame = [0u8; MAX_FRAME];
        let n = encode_frame(packet, &mut frame).map_err(Error::Encode)?;
        // The port's one timeout also bounds writes: a read may have left
        // it near zero, and a write then fails as soon as the line's
        // buffer is momentarily full.
        self.port
            .set_timeout(WRITE_TIMEOUT)
            .map_err(|e| Error::Io(e.into()))?;
        // No flush: on a tty it waits until the line has sent every byte
        // (tcdrain); the kernel sends the frame on its own.
        self.port.write_all(&frame[..n])?;
        Ok(())
    }

    fn recv(&mut self, buf: &mut [u8], timeout: Duration) -> Result<Option<usize>, Error> {
        let deadline = Instant::now() + timeout;
        loop {
            while self.pos < self.len {
                let (used, event) = self.decoder.feed(&self.rx[self.pos..self.len]);
                self.pos += used;
                // A dropped frame is already counted by the decoder.
                if let Some(Ok(frame)) = event {
                    let n = frame.len().min(buf.len());
                    buf[..n].copy_from_slice(&frame[..n]);
                    return Ok(Some(n));
                }
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() && !timeout.is_zero() {
                return Ok(None);
            }
            self.port
                .set_timeout(left)
                .map_err(|e| Error::Io(e.into()))?;
            match self.port.read(&mut self.rx) {
                Ok(n) => {
                    self.pos = 0;
                    self.len = n;
                    if n == 0 && timeout.is_zero() {
                        return Ok(None);
                    }
                }
                Err(e) if is_timeout(&e) => return Ok(None),
                Err(e) => return Err(e.into()),
            }
        }
    }

    fn framing(&self) -> FrameCounters {
        self.decoder.counters()
    }

    fn drain(&mut self) -> Result<(), Error> {
        self.port
            .set_timeout(WRITE_TIMEOUT)
            .map_err(|e| Error::Io(e.into()))?;
        // tcdrain: returns once a UART has sent every byte written (a pty
        // returns at once: it has no transmit queue).
        self.port.flush()?;
        Ok(())
    }
}
