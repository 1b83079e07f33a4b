//! The localisation and control host for any robot that speaks the
//! protocol (`docs/protocol.md`).
//!
//! The filter is paper 001's [`Localiser`] on the link's 32-bit wrapping
//! encoder counts, built from a [`LocaliserConfig`] (wheelbase, encoder, IR
//! pair, `Q`, `R`, gate, initial belief); the IR pair is associated with
//! the arena walls the caller gives, and the path controller
//! ([`FollowPath::square`]) drives the laps. The host knows nothing of the
//! robot beyond the protocol: a simulator (`locus_sim::link_robot`) or a
//! real robot.
//!
//! # Loop
//! 1. Send a zero-speed command (ack [`NO_ACK`]) every `resend` until the
//!    first telemetry packet arrives.
//! 2. For each datagram from the robot's address: decode and classify it
//!    ([`Receiver`]). Dropped classes (duplicate, late, corrupt, malformed)
//!    only count. The first applied packet sets the reference encoder
//!    counts. Every later one: the count differences give the wheel
//!    travels since the last applied packet; with `g` sequence numbers
//!    skipped they are split into `g + 1` equal predictions (predicting
//!    through the gap, [`Localiser::counts`]); the IR reading, if any, is
//!    associated with a wall and corrects the filter behind its gate
//!    ([`Localiser::ir`]); the clock estimator gets
//!    (robot timestamp, receive time).
//! 3. The path controller maps the estimate to a body twist, turned into
//!    wheel speeds; a command packet carrying them and acknowledging the
//!    packet is sent. When the laps are done the host
//!    stops sending (the robot's watchdog stops the wheels) and keeps
//!    receiving and counting until the robot has been quiet for `quiet`.

use core::net::SocketAddr;
use core::time::Duration;
use std::net::UdpSocket;
use std::time::Instant;

use locus_control::{Controller, FollowPath, wheel_speeds};
use locus_link::clock::ClockFit;
use locus_link::{ClockEstimator, CommandPacket, Counters, MAX_PACKET, NO_ACK, Receiver, Status};
use locus_models::{Localiser, LocaliserConfig, Segment};

use crate::{Error, at_least_1us, is_timeout};

/// Buckets in the clock estimator's window.
const CLOCK_WINDOW: usize = 64;

/// Width of the link's encoder counts (bits): they wrap modulo `2^32`.
/// [`HostConfig::localiser`] must use it.
pub const COUNTER_BITS: u32 = 32;

/// Configuration of the host.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostConfig {
    /// The robot's geometry, encoder and IR pair, the filter's `Q`, `R`,
    /// gate and initial belief; `counter_bits` must be [`COUNTER_BITS`].
    pub localiser: LocaliserConfig<f64>,
    /// Whether the filter uses the IR readings (`false`: odometry only).
    pub use_ir: bool,
    /// The walls the IR pair is associated with (m, world frame): the
    /// square arena around the path.
    pub walls: [Segment<f64>; 4],
    /// The path controller's parameters.
    pub control: locus_control::Config,
    /// Laps of the square path to drive (>= 1).
    pub laps: usize,
    /// Interval of the handshake's zero-speed command. Default 50 ms.
    pub resend: Duration,
    /// Wall time to wait for the robot's first telemetry. Default 10 s.
    pub handshake: Duration,
    /// Wall time without telemetry after which the run ends (after the laps
    /// are done, or if the robot goes silent). Default 0.5 s.
    pub quiet: Duration,
    /// Bucket of the clock estimator's minimum-delay filter (s of host
    /// time); the window is 64 buckets. Default 0.05 s.
    pub clock_bucket: f64,
}

impl HostConfig {
    /// A host running `localiser` in the arena `walls`, with IR, the
    /// default path controller, 2 laps and the default timing.
    pub fn new(localiser: LocaliserConfig<f64>, walls: [Segment<f64>; 4]) -> Self {
        Self {
            localiser,
            use_ir: true,
            walls,
            control: locus_control::Config::default(),
            laps: 2,
            resend: Duration::from_millis(50),
            handshake: Duration::from_secs(10),
            quiet: Duration::from_millis(500),
            clock_bucket: 0.05,
        }
    }

    /// Checks the values the host relies on.
    ///
    /// # Errors
    /// [`Error::Config`] naming the first invalid value.
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let l = &self.localiser;
        let c = &self.control;
        let checks = [
            (self.laps > 0, "laps must be >= 1"),
            (
                l.counter_bits == COUNTER_BITS,
                "localiser.counter_bits must be 32 (the link's counts)",
            ),
            (
                [
                    c.v_ref,
                    c.w_ref,
                    c.k_cross,
                    c.k_heading,
                    c.k_pos,
                    c.pos_tol,
                    c.heading_tol,
                ]
                .into_iter()
                .all(pos),
                "control values must be finite and > 0",
            ),
            (
                pos(self.clock_bucket),
                "clock_bucket must be finite and > 0 s",
            ),
        ];
        if let Some((_, what)) = checks.into_iter().find(|(ok, _)| !ok) {
            return Err(Error::Config(what));
        }
        l.validate().map_err(|e| match e {
            locus_core::Error::InvalidParameter(what) => Error::Config(what),
            _ => Error::Config("invalid localiser configuration"),
        })
    }
}

/// The host's state after one applied telemetry packet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostStep {
    /// Sequence of the packet.
    pub sequence: u32,
    /// Robot timestamp of the packet (s).
    pub robot_time: f64,
    /// Sequence numbers skipped before it (predicted through).
    pub skipped: u32,
    /// EKF estimate `[x, y, theta]` (m, m, rad) after the packet.
    pub estimate: [f64; 3],
    /// EKF covariance diagonal (m^2, m^2, rad^2).
    pub variance: [f64; 3],
    /// IR reading `[d_s1, d_s2]` (m), if any.
    pub ir: Option<[f32; 2]>,
    /// Whether an IR correction was applied (associated and gated in).
    pub corrected: bool,
    /// Wheel speeds sent `[right, left]` (m/s); `None` once the path is
    /// done.
    pub command: Option<[f32; 2]>,
}

/// What a host run did.
#[derive(Debug, Clone, PartialEq)]
pub struct HostReport {
    /// The telemetry receiver's counters.
    pub counters: Counters,
    /// Estimate after each applied packet `(sequence, [x, y, theta])`.
    pub estimates: Vec<(u32, [f64; 3])>,
    /// The clock fit at the end (`robot = offset + (1 + drift) host`, host
    /// time in s since the handshake started).
    pub clock: Option<ClockFit>,
    /// Laps of the path completed.
    pub laps: usize,
    /// Commands sent (handshake included).
    pub commands_sent: u64,
    /// IR corrections applied.
    pub corrections: u64,
    /// Wall time from a telemetry packet's reception to its command's send
    /// (s), one per command sent after the handshake.
    pub latency: Vec<f64>,
}

/// Runs the host on `socket`, talking to the robot at `robot`, calling
/// `on_step` after each applied telemetry packet.
///
/// # Errors
/// [`Error::Timeout`] if no telemetry arrives within `handshake`; socket,
/// configuration and filter errors.
#[allow(clippy::cast_possible_truncation, clippy::too_many_lines)]
pub fn run_host(
    socket: &UdpSocket,
    robot: SocketAddr,
    cfg: &HostConfig,
    on_step: &mut impl FnMut(&HostStep),
) -> Result<HostReport, Error> {
    cfg.validate()?;
    let mut localiser: Localiser<f64> = cfg.localiser.localiser()?;
    let mut controller = FollowPath::square(cfg.control);
    let mut receiver = Receiver::new();
    let mut clock = ClockEstimator::<CLOCK_WINDOW>::new(cfg.clock_bucket);
    let mut buf = [0u8; 2048];
    let mut out = [0u8; MAX_PACKET];
    let mut report = HostReport {
        counters: Counters::default(),
        estimates: Vec::new(),
        clock: None,
        laps: 0,
        commands_sent: 0,
        corrections: 0,
        latency: Vec::new(),
    };
    let mut sequence = 0u32;
    let mut send = |socket: &UdpSocket, ack: u32, right: f32, left: f32| -> Result<(), Error> {
        let c = CommandPacket {
            sequence,
            ack,
            right,
            left,
        };
        let n = c.encode(&mut out).map_err(Error::Encode)?;
        socket.send_to(&out[..n], robot)?;
        sequence = sequence.wrapping_add(1);
        Ok(())
    };

    let origin = Instant::now();
    let handshake_end = origin + cfg.handshake;
    let mut next_hello = origin;
    let mut last_rx: Option<Instant> = None;
    let mut done = false;
    loop {
        let now = Instant::now();
        // Waiting for the first packet: resend the hello; else: quiet end.
        let wait = match last_rx {
            None => {
                if now >= handshake_end {
                    return Err(Error::Timeout("waiting for the robot's first telemetry"));
                }
                if now >= next_hello {
                    send(socket, NO_ACK, 0.0, 0.0)?;
                    report.commands_sent += 1;
                    next_hello = now + cfg.resend;
                }
                next_hello.min(handshake_end) - now
            }
            Some(t) => {
                let end = t + cfg.quiet;
                if now >= end {
                    break;
                }
                end - now
            }
        };
        socket.set_read_timeout(Some(at_least_1us(wait)))?;
        let (n, from) = match socket.recv_from(&mut buf) {
            Ok(r) => r,
            Err(e) if is_timeout(&e) => continue,
            // A hello sent before the robot bound its port comes back as
            // "connection refused" on some systems: keep trying.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => continue,
            Err(e) => return Err(e.into()),
        };
        let received = Instant::now();
        if from != robot {
            continue;
        }
        let Ok((t, status)) = receiver.receive_telemetry(&buf[..n]) else {
            last_rx.get_or_insert(received);
            continue;
        };
        if last_rx.is_none() && !matches!(status, Status::Applied { .. }) {
            continue;
        }
        last_rx = Some(received);
        let Status::Applied { skipped } = status else {
            continue;
        };
        let robot_time = t.timestamp_us as f64 * 1e-6;
        clock.push(robot_time, (received - origin).as_secs_f64());
        // Predicting through the gap; the first applied packet only sets
        // the reference counts (and its reading is not used).
        let predicted = localiser
            .counts(t.counts, skipped.saturating_add(1))?
            .is_some();
        let corrected = match t.ir.filter(|_| predicted && cfg.use_ir) {
            Some([ds1, ds2]) => localiser
                .ir(&cfg.walls, [f64::from(ds1), f64::from(ds2)])?
                .applied(),
            None => false,
        };
        report.corrections += u64::from(corrected);
        let x = localiser.belief().x;
        report.estimates.push((t.sequence, [x[0], x[1], x[2]]));

        let mut sent = None;
        if !done {
            let est = locus_control::Pose::new(x[0], x[1], x[2]);
            let mut twist = controller.command(est);
            if twist.done {
                report.laps += 1;
                if report.laps >= cfg.laps {
                    done = true;
                } else {
                    controller.reset();
                    twist = controller.command(est);
                }
            }
            if !done {
                let (v1, v2) = wheel_speeds(twist, cfg.localiser.wheelbase);
                let (right, left) = (v1 as f32, v2 as f32);
                send(socket, t.sequence, right, left)?;
                report.commands_sent += 1;
                report.latency.push(received.elapsed().as_secs_f64());
                sent = Some([right, left]);
            }
        }
        let p = localiser.belief().p;
        on_step(&HostStep {
            sequence: t.sequence,
            robot_time,
            skipped,
            estimate: [x[0], x[1], x[2]],
            variance: [p[(0, 0)], p[(1, 1)], p[(2, 2)]],
            ir: t.ir,
            corrected,
            command: sent,
        });
    }
    report.counters = receiver.counters();
    report.clock = clock.estimate();
    Ok(report)
}
