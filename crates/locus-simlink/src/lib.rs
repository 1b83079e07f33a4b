//! The `square` simulator as a robot endpoint of the link
//! (`docs/protocol.md`; the host is [`locus_net::host`]): `locus robot`.
//!
//! A crate of its own so that neither end depends on the other: the
//! simulator (`locus-sim`) knows nothing of the link's transports and the
//! host (`locus-net`) nothing of the simulator; this crate joins them.
//!
//! The robot is built exactly as [`locus_sim::closed_loop::run_square`]
//! builds it (same random draws in the same order from the same seed: true
//! start, slip bumps, then per step the right and left encoders and the IR
//! pair), so a run through the link with every command on time drives the
//! same robot as the in-process run. Only the realistic noise model is
//! simulated (the `square` scenario). [`host_config`] gives the host
//! configuration that matches the simulated robot.
//!
//! # Loop
//! 1. Wait (up to `handshake` of wall time) for a first valid command; its
//!    source becomes the host's address.
//! 2. Send telemetry 0: time 0, encoder counts 0, no readings.
//! 3. Every tick `k = 1, 2, ...` (robot time `k dt`, wall time
//!    `k dt / time_scale` after the handshake): apply the newest command
//!    received (watchdog: zero speeds if none for `watchdog` s of robot
//!    time), move the robot `dt`, advance the encoders, read the IR pair,
//!    send telemetry `k`. Commands are received while waiting for the tick.
//! 4. End after `idle_exit` s of robot time without a command, or at
//!    `max_time` of the scenario.

use core::time::Duration;
use std::net::UdpSocket;
use std::time::Instant;

use locus_link::{CommandPacket, MAX_PACKET, Receiver, Status, Telemetry};
use locus_net::host::HostConfig;
use locus_net::transport::{Transport, Udp};
use locus_net::{Error as LinkError, at_least_1us};
use locus_odometry::{Wheel as EncoderWheel, wrapping_diff};
use rand::SeedableRng;
use rand::rngs::StdRng;

use locus_sim::closed_loop::{Error as SimError, NoiseModel, SquareConfig};
use locus_sim::robot::{DriveCommand, Pose, Robot};
use locus_sim::sensors::{Encoder, IrPairSensor, SharpIr};
use locus_sim::world::World;

/// Errors of the robot endpoint.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The link failed: socket, encoding, timeout or an invalid endpoint
    /// setting.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The simulated robot or its configuration failed.
    #[error("simulator: {0}")]
    Sim(#[from] SimError),
}

impl From<std::io::Error> for Error {
    fn from(e: std::io::Error) -> Self {
        Self::Link(e.into())
    }
}

/// The host configuration for the robot `square` simulates: its localiser
/// on the link's 32-bit counts, the walls of [`World::square_arena`], its
/// path controller, laps and `use_ir`, with the host's default timing.
///
/// # Panics
/// Never: the square arena has four walls.
pub fn host_config(square: &SquareConfig) -> HostConfig {
    let walls = World::square_arena()
        .walls
        .try_into()
        .expect("the square arena has four walls");
    HostConfig {
        use_ir: square.use_ir,
        control: square.control,
        laps: square.laps,
        ..HostConfig::new(square.localiser(locus_net::host::COUNTER_BITS), walls)
    }
}

/// Width of the simulated encoders' wrapping counter (bits).
const ENCODER_BITS: u32 = locus_odometry::counter::PAPER_BITS;

/// Longest sleep between two polls of the socket while waiting for a tick.
const POLL: Duration = Duration::from_micros(50);

/// Configuration of the robot endpoint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotConfig {
    /// The scenario (robot, sensors, `dt`, `max_time`).
    pub square: SquareConfig,
    /// Seed of the simulation's random draws.
    pub seed: u64,
    /// Robot seconds per wall second (> 0; 1: real time).
    pub time_scale: f64,
    /// Robot time without a command after which the wheels stop (s).
    /// Default 0.2 s.
    pub watchdog: f64,
    /// Robot time without a command after which the run ends (s). Default
    /// 2 s.
    pub idle_exit: f64,
    /// Wall time to wait for the host's first command. Default 10 s.
    pub handshake: Duration,
    /// The wheels' top speed (m/s): a commanded speed beyond it is clamped
    /// to it (and counted), as a motor driver saturates. Default 1 m/s.
    pub max_wheel_speed: f64,
}

impl RobotConfig {
    /// Checks every timing and limit value.
    ///
    /// # Errors
    /// [`locus_net::Error::Config`] (as [`Error::Link`]) naming the first
    /// invalid value; the scenario's own errors.
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let checks = [
            (pos(self.time_scale), "time_scale must be finite and > 0"),
            (pos(self.watchdog), "watchdog must be finite and > 0 s"),
            (pos(self.idle_exit), "idle_exit must be finite and > 0 s"),
            (
                self.idle_exit >= self.watchdog,
                "idle_exit must be at least the watchdog (s)",
            ),
            (
                pos(self.max_wheel_speed),
                "max_wheel_speed must be finite and > 0 m/s",
            ),
        ];
        if let Some((_, what)) = checks.into_iter().find(|(ok, _)| !ok) {
            return Err(LinkError::Config(what).into());
        }
        self.square.validate()?;
        Ok(())
    }
}

impl Default for RobotConfig {
    fn default() -> Self {
        Self {
            square: SquareConfig::default(),
            seed: 1,
            time_scale: 1.0,
            watchdog: 0.2,
            idle_exit: 2.0,
            handshake: Duration::from_secs(10),
            max_wheel_speed: 1.0,
        }
    }
}

/// What a robot run did.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotReport {
    /// True pose after each telemetry packet `(sequence, pose)` (sequence
    /// 0: the start).
    pub truth: Vec<(u32, Pose<f64>)>,
    /// Telemetry packets sent.
    pub sent: u64,
    /// The command receiver's counters.
    pub commands: locus_link::Counters,
    /// What the transport dropped before commands were formed (COBS frames
    /// on a byte stream; zero on UDP).
    pub framing: locus_link::framing::FrameCounters,
    /// Times the watchdog stopped the wheels.
    pub watchdog_stops: u64,
    /// Commands applied with a wheel speed beyond `max_wheel_speed`
    /// (clamped to it).
    pub clamped: u64,
    /// Ticks whose command answered the previous telemetry packet (ack
    /// `k - 1` at tick `k`): the lockstep share is `on_time / ticks`.
    pub on_time: u64,
    /// Ticks simulated (after telemetry 0).
    pub ticks: u64,
    /// Robot time simulated (s).
    pub sim_time: f64,
}

/// Everything simulated, built as `run_square` builds it.
struct Sim {
    robot: Robot,
    enc: [Encoder; 2],
    last: [u32; 2],
    counts: [u32; 2],
    ir: IrPairSensor,
    world: World,
    rng: StdRng,
    right_scale: f64,
}

impl Sim {
    fn new(cfg: &SquareConfig, seed: u64) -> Result<Self, SimError> {
        cfg.validate()?;
        if cfg.noise != NoiseModel::Realistic {
            return Err(SimError::Config(
                "the robot endpoint simulates the realistic noise model only",
            ));
        }
        let mut rng = StdRng::seed_from_u64(seed);
        let (robot, _) = cfg.true_robot(&mut rng);
        let wheel = EncoderWheel::new(cfg.encoder_lines, cfg.encoder_gear, cfg.wheel_radius);
        let enc = [Encoder::new(wheel)?, Encoder::new(wheel)?];
        let last = [enc[0].read(), enc[1].read()];
        let pair = locus_models::IrPair::centred(cfg.ir_spacing);
        let ir = IrPairSensor::new(pair, SharpIr::assumed(cfg.ir_sigma)?)?;
        Ok(Self {
            robot,
            enc,
            last,
            counts: [0, 0],
            ir,
            world: World::square_arena(),
            rng,
            right_scale: 1.0 + cfg.right_scale_error,
        })
    }

    /// One step under wheel speeds `(right, left)` (m/s): the new pose and
    /// the IR reading (m).
    fn step(
        &mut self,
        right: f64,
        left: f64,
        dt: f64,
    ) -> Result<(Pose<f64>, Option<[f32; 2]>), Error> {
        let out = self
            .robot
            .step(&DriveCommand::Wheels { left, right }, dt)
            .map_err(SimError::from)?;
        self.enc[0]
            .advance(out.measured_travel.right * self.right_scale, &mut self.rng)
            .map_err(SimError::from)?;
        self.enc[1]
            .advance(out.measured_travel.left, &mut self.rng)
            .map_err(SimError::from)?;
        for i in 0..2 {
            let now = self.enc[i].read();
            // The firmware extends the 20-bit counter to the protocol's
            // wrapping 32-bit count.
            self.counts[i] =
                self.counts[i].wrapping_add_signed(wrapping_diff(now, self.last[i], ENCODER_BITS));
            self.last[i] = now;
        }
        let p = out.pose;
        let reading = self
            .ir
            .read(&self.world.walls, [p.x, p.y, p.theta], &mut self.rng)
            .map_err(SimError::from)?;
        #[allow(clippy::cast_possible_truncation)] // the wire carries f32
        let reading = reading.map(|(a, b)| [a as f32, b as f32]);
        Ok((p, reading))
    }
}

/// Runs the robot endpoint on `socket` over UDP until the host goes quiet
/// ([`run_robot_over`] on [`Udp::listen`]: telemetry goes to the sender of
/// the newest valid command).
///
/// # Errors
/// As [`run_robot_over`].
pub fn run_robot(socket: &UdpSocket, cfg: &RobotConfig) -> Result<RobotReport, Error> {
    run_robot_over(&mut Udp::listen(socket), cfg)
}

/// Runs the robot endpoint over `link` until the host goes quiet.
///
/// # Errors
/// [`locus_net::Error::Timeout`] (as [`Error::Link`]) if no host command
/// arrives within `handshake`; link, configuration and simulator errors.
#[allow(clippy::cast_precision_loss, clippy::cast_possible_truncation)]
#[allow(clippy::cast_sign_loss, clippy::too_many_lines)]
pub fn run_robot_over(link: &mut impl Transport, cfg: &RobotConfig) -> Result<RobotReport, Error> {
    cfg.validate()?;
    let dt = cfg.square.dt;
    let mut sim = Sim::new(&cfg.square, cfg.seed)?;
    let mut receiver = Receiver::new();
    let mut buf = [0u8; 2048];
    let mut out = [0u8; MAX_PACKET];

    // 1. Handshake: the first valid command names the host.
    let deadline = Instant::now() + cfg.handshake;
    let mut command: CommandPacket = loop {
        let now = Instant::now();
        if now >= deadline {
            return Err(LinkError::Timeout("waiting for the host's first command").into());
        }
        if let Some(n) = link.recv(&mut buf, at_least_1us(deadline - now))? {
            if let Ok((c, Status::Applied { .. })) = receiver.receive_command(&buf[..n]) {
                link.follow_sender();
                break clamp(c, cfg.max_wheel_speed);
            }
        }
    };

    let mut report = RobotReport {
        truth: vec![(0, sim.robot.pose)],
        sent: 0,
        commands: receiver.counters(),
        framing: link.framing(),
        watchdog_stops: 0,
        clamped: 0,
        on_time: 0,
        ticks: 0,
        sim_time: 0.0,
    };
    // 2. Telemetry 0.
    let n = Telemetry::new(0, 0)
        .encode(&mut out)
        .map_err(LinkError::Encode)?;
    link.send(&out[..n])?;
    report.sent += 1;

    let start = Instant::now();
    let mut last_command_time = 0.0;
    let mut stopped = false;
    let max_ticks = (cfg.square.max_time / dt).ceil() as u64;
    for k in 1..=max_ticks {
        // Receive commands until this tick's wall deadline.
        let due = start + Duration::from_secs_f64(k as f64 * dt / cfg.time_scale);
        let robot_time_prev = (k - 1) as f64 * dt;
        loop {
            if let Some(n) = link.recv(&mut buf, Duration::ZERO)? {
                if let Ok((c, Status::Applied { .. })) = receiver.receive_command(&buf[..n]) {
                    command = clamp(c, cfg.max_wheel_speed);
                    report.clamped += u64::from(command != c);
                    link.follow_sender();
                    last_command_time = robot_time_prev;
                }
                continue;
            }
            let now = Instant::now();
            if now >= due {
                break;
            }
            // A socket read timeout rounds up to the kernel's tick (1-10
            // ms): poll, sleeping in short steps (high-resolution timers).
            std::thread::sleep((due - now).min(POLL));
        }
        let idle = robot_time_prev - last_command_time;
        if idle >= cfg.idle_exit {
            break;
        }
        let (right, left) = if idle >= cfg.watchdog {
            if !stopped {
                report.watchdog_stops += 1;
                stopped = true;
            }
            (0.0, 0.0)
        } else {
            stopped = false;
            (f64::from(command.right), f64::from(command.left))
        };
        if command.ack == (k - 1) as u32 {
            report.on_time += 1;
        }
        let (pose, ir) = sim.step(right, left, dt)?;
        let seq = k as u32;
        let mut t = Telemetry::new(seq, (k as f64 * dt * 1e6).round() as u64);
        t.counts = sim.counts;
        t.ir = ir;
        let n = t.encode(&mut out).map_err(LinkError::Encode)?;
        link.send(&out[..n])?;
        report.sent += 1;
        report.ticks = k;
        report.sim_time = k as f64 * dt;
        report.truth.push((seq, pose));
    }
    report.commands = receiver.counters();
    report.framing = link.framing();
    // The last telemetry must reach the host before the process ends.
    link.drain()?;
    Ok(report)
}

/// `c` with both wheel speeds clamped to `[-max, max]` (m/s).
#[allow(clippy::cast_possible_truncation)]
fn clamp(c: CommandPacket, max: f64) -> CommandPacket {
    let max = max as f32;
    CommandPacket {
        right: c.right.clamp(-max, max),
        left: c.left.clamp(-max, max),
        ..c
    }
}
