//! The host's loops over a transport: a run of laps ([`run_host`],
//! [`run_host_over`]) and a live session ([`run_host_live`]).

use core::net::SocketAddr;
use core::ops::ControlFlow;
use core::time::Duration;
use std::net::UdpSocket;
use std::time::Instant;

use locus_link::clock::ClockFit;
use locus_link::framing::FrameCounters;
use locus_link::{CommandPacket, Counters, MAX_PACKET, NO_ACK};

use super::{Host, HostConfig, HostStep, Outcome};
use crate::transport::{Transport, Udp};
use crate::{Error, at_least_1us};

/// What a host run did.
#[derive(Debug, Clone, PartialEq)]
pub struct HostReport {
    /// The telemetry receiver's counters (see [`Host::counters`]).
    pub counters: Counters,
    /// Estimate after each applied packet `(sequence, [x, y, theta])`.
    pub estimates: Vec<(u32, [f64; 3])>,
    /// The clock fit at the end (`robot = offset + (1 + drift) host`, host
    /// time in s since the handshake started).
    pub clock: Option<ClockFit>,
    /// Laps of the path completed.
    pub laps: usize,
    /// Whether the run is complete: every lap of
    /// [`HostConfig::laps`] was driven before the robot went quiet. A
    /// run that ends incomplete lost its robot (a dropped link, a stream
    /// without frame delimiters).
    pub complete: bool,
    /// Wall time without telemetry that ended the run (at least
    /// [`HostConfig::quiet`]).
    pub silence: Duration,
    /// Commands sent (handshake included).
    pub commands_sent: u64,
    /// IR corrections applied.
    pub corrections: u64,
    /// Filter errors (the packet's prediction or correction was skipped,
    /// the belief kept).
    pub filter_errors: u64,
    /// What the transport dropped before packets were formed (COBS frames
    /// on a byte stream; zero on UDP).
    pub framing: FrameCounters,
    /// Wall time from a telemetry packet's reception to its command's send
    /// (s), one per command sent after the handshake.
    pub latency: Vec<f64>,
}

/// Runs the host on `socket`, talking to the robot at `robot` over UDP
/// ([`run_host_over`] on [`Udp::to`]).
///
/// # Errors
/// As [`run_host_over`].
pub fn run_host(
    socket: &UdpSocket,
    robot: SocketAddr,
    cfg: &HostConfig,
    on_step: &mut impl FnMut(&HostStep),
) -> Result<HostReport, Error> {
    run_host_over(&mut Udp::to(socket, robot), cfg, on_step)
}

/// Runs the host over `link`, calling `on_step` after each applied
/// telemetry packet, until the robot has been quiet for
/// [`HostConfig::quiet`]: after the laps, or before them when the link is
/// lost ([`HostReport::complete`] false; what was received is reported
/// either way).
///
/// # Errors
/// [`Error::Timeout`] if no telemetry arrives within `handshake`; link
/// and configuration errors.
pub fn run_host_over(
    link: &mut impl Transport,
    cfg: &HostConfig,
    on_step: &mut impl FnMut(&HostStep),
) -> Result<HostReport, Error> {
    let mut host = Host::new(cfg)?;
    let mut buf = [0u8; 2048];
    let mut commands_sent = 0u64;
    let mut latency = Vec::new();
    let mut commands = Commands::default();

    let origin = Instant::now();
    let handshake_end = origin + cfg.handshake;
    let mut next_hello = origin;
    let mut last_rx: Option<Instant> = None;
    let silence = loop {
        let now = Instant::now();
        // Waiting for the first packet: resend the hello; else: quiet end.
        let wait = match last_rx {
            None => {
                if now >= handshake_end {
                    return Err(Error::Timeout("waiting for the robot's first telemetry"));
                }
                if now >= next_hello {
                    commands.send(link, NO_ACK, [0.0, 0.0])?;
                    commands_sent += 1;
                    next_hello = now + cfg.resend;
                }
                next_hello.min(handshake_end) - now
            }
            Some(t) => {
                let end = t + cfg.quiet;
                if now >= end {
                    break now - t;
                }
                end - now
            }
        };
        let Some(n) = link.recv(&mut buf, at_least_1us(wait))? else {
            continue;
        };
        let received = Instant::now();
        match host.receive(&buf[..n], (received - origin).as_secs_f64()) {
            Outcome::Undecodable => {
                last_rx.get_or_insert(received);
            }
            Outcome::Dropped(_) => {
                if last_rx.is_some() {
                    last_rx = Some(received);
                }
            }
            Outcome::Applied(step) => {
                last_rx = Some(received);
                if let Some(speeds) = step.command {
                    commands.send(link, step.sequence, speeds)?;
                    commands_sent += 1;
                    latency.push(received.elapsed().as_secs_f64());
                }
                on_step(&step);
            }
        }
    };
    Ok(HostReport {
        counters: host.counters(),
        clock: host.clock.estimate(),
        laps: host.laps,
        complete: host.done(),
        silence,
        commands_sent,
        corrections: host.corrections,
        filter_errors: host.filter_errors,
        framing: link.framing(),
        latency,
        estimates: host.estimates,
    })
}

/// What [`run_host_live`] tells its caller each time round its loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveTick {
    /// Host time now (s since the loop began; the clock of
    /// [`Host::receive`] and [`Host::set_teleop`]).
    pub host_time: f64,
    /// The packet applied since the previous call, if one was.
    pub step: Option<HostStep>,
    /// Wall time from that packet's reception to its command's send (s).
    pub latency: Option<f64>,
    /// Commands sent so far (zero-speed hellos included).
    pub commands_sent: u64,
    /// What the transport dropped before packets were formed (COBS frames
    /// on a byte stream; zero on UDP).
    pub framing: FrameCounters,
    /// Whether no packet has been applied for `quiet` (or none yet): the
    /// host is sending zero-speed hellos every `resend` until the robot
    /// answers again.
    pub silent: bool,
}

/// Runs the host over `link` for as long as `each` says
/// ([`ControlFlow::Continue`]), for a live session (`locus serve --robot`)
/// rather than a run of laps: no handshake timeout and no quiet end; while
/// the robot is silent (at the start, or for `quiet` after its last
/// applied packet: a robot that restarted) the host sends a zero-speed
/// hello every `resend`.
///
/// `each` is called once before anything is sent (to configure the host:
/// [`Host::set_stopped`] and the other setters), after every applied
/// packet (whose command has then been sent), and at least every `poll`
/// otherwise; what it sets takes effect from the next packet. It runs on
/// the loop's thread, between packets, so it must not block.
///
/// # Errors
/// Link errors (the socket or serial device failed) and an invalid
/// configuration.
pub fn run_host_live(
    link: &mut impl Transport,
    cfg: &HostConfig,
    poll: Duration,
    mut each: impl FnMut(&mut Host, &LiveTick) -> ControlFlow<()>,
) -> Result<(), Error> {
    let mut host = Host::new(cfg)?;
    let mut buf = [0u8; 2048];
    let mut commands = Commands::default();
    let mut commands_sent = 0u64;
    let origin = Instant::now();
    let mut tick = LiveTick {
        host_time: 0.0,
        step: None,
        latency: None,
        commands_sent,
        framing: link.framing(),
        silent: true,
    };
    if each(&mut host, &tick).is_break() {
        return Ok(());
    }
    let mut next_hello = origin;
    let mut last_applied: Option<Instant> = None;
    loop {
        let now = Instant::now();
        let silent = last_applied.is_none_or(|t| now.duration_since(t) >= cfg.quiet);
        if silent && now >= next_hello {
            commands.send(link, NO_ACK, [0.0, 0.0])?;
            commands_sent += 1;
            next_hello = now + cfg.resend;
        }
        let wait = if silent {
            next_hello.saturating_duration_since(now).min(poll)
        } else {
            poll
        };
        tick.step = None;
        tick.latency = None;
        if let Some(n) = link.recv(&mut buf, at_least_1us(wait))? {
            let received = Instant::now();
            if let Outcome::Applied(step) =
                host.receive(&buf[..n], (received - origin).as_secs_f64())
            {
                last_applied = Some(received);
                if let Some(speeds) = step.command {
                    commands.send(link, step.sequence, speeds)?;
                    commands_sent += 1;
                    tick.latency = Some(received.elapsed().as_secs_f64());
                }
                tick.step = Some(step);
            }
        }
        let now = Instant::now();
        tick.host_time = (now - origin).as_secs_f64();
        tick.commands_sent = commands_sent;
        tick.framing = link.framing();
        tick.silent = last_applied.is_none_or(|t| now.duration_since(t) >= cfg.quiet);
        if each(&mut host, &tick).is_break() {
            return Ok(());
        }
    }
}

/// The host's outgoing command packets, numbered from 0.
#[derive(Debug, Default)]
struct Commands {
    sequence: u32,
}

impl Commands {
    /// Sends wheel speeds `[right, left]` (m/s) acknowledging telemetry
    /// `ack`.
    fn send(
        &mut self,
        link: &mut impl Transport,
        ack: u32,
        [right, left]: [f32; 2],
    ) -> Result<(), Error> {
        let mut out = [0u8; MAX_PACKET];
        let c = CommandPacket {
            sequence: self.sequence,
            ack,
            right,
            left,
        };
        let n = c.encode(&mut out).map_err(Error::Encode)?;
        link.send(&out[..n])?;
        self.sequence = self.sequence.wrapping_add(1);
        Ok(())
    }
}
