//! `locus robot`: the `square` simulator as a robot endpoint on UDP
//! (protocol: `docs/protocol.md`).

use core::time::Duration;
use std::net::UdpSocket;

use anyhow::Context;
use clap::Args as ClapArgs;
use locus_net::transport::Serial;
use locus_simlink::{RobotConfig, run_robot, run_robot_over};

use crate::link_scenario::square_config;

/// Arguments of `locus robot`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Address to listen on for the host's commands over UDP (telemetry
    /// goes back to the sender of the newest command).
    #[arg(long, default_value = "127.0.0.1:7700")]
    udp: String,
    /// Talk over this serial device instead of UDP (`/dev/ttyS1`, one end
    /// of a pseudo-terminal pair...), packets as COBS frames
    /// (docs/protocol.md).
    #[arg(long, conflicts_with = "udp", value_name = "DEVICE")]
    serial: Option<String>,
    /// Serial line speed, bits per second (with --serial): 50 to 4000000,
    /// the standard UART rates' span (0 would mean "hang up" to a serial
    /// line).
    #[arg(long, default_value_t = 115_200, value_parser = crate::args::baud)]
    baud: u32,
    /// `square` or a scenario file whose `scenario = "square"`.
    #[arg(default_value = "square", value_name = "SCENARIO|FILE", value_parser = crate::args::ScenarioParser)]
    scenario: crate::args::ScenarioArg,
    /// Seed of the simulation's random numbers.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Robot seconds per wall second (> 0; > 1 runs faster than real time).
    #[arg(long, default_value_t = 1.0)]
    time_scale: f64,
    /// Robot time without a command after which the wheels stop (s, > 0).
    #[arg(long, default_value_t = 0.2)]
    watchdog: f64,
    /// Robot time without a command after which the run ends (s, at least
    /// the watchdog).
    #[arg(long, default_value_t = 2.0)]
    idle_exit: f64,
    /// Wall time to wait for the host's first command (s, >= 0).
    #[arg(long, default_value_t = 60.0)]
    handshake: f64,
    /// The wheels' top speed (m/s, > 0): faster commanded speeds are
    /// clamped to it and counted.
    #[arg(long, default_value_t = 1.0)]
    max_wheel_speed: f64,
}

/// Runs `locus robot`.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let square = square_config(&args.scenario)?;
    let handshake = if args.handshake.is_finite() {
        Duration::try_from_secs_f64(args.handshake).ok()
    } else {
        None
    }
    .context("--handshake must be a finite, non-negative number of seconds")?;
    let cfg = RobotConfig {
        square,
        seed: args.seed,
        time_scale: args.time_scale,
        watchdog: args.watchdog,
        idle_exit: args.idle_exit,
        handshake,
        max_wheel_speed: args.max_wheel_speed,
    };
    // Every flag is checked before the socket is bound.
    cfg.validate().context("locus robot: invalid setting")?;
    let r = if let Some(device) = &args.serial {
        let mut link = Serial::open(device, args.baud)?;
        eprintln!(
            "locus robot: {} on serial {device} at {} baud (time scale {}); waiting for a host",
            args.scenario, args.baud, args.time_scale
        );
        run_robot_over(&mut link, &cfg)?
    } else {
        let socket =
            UdpSocket::bind(&args.udp).with_context(|| format!("binding UDP {}", args.udp))?;
        eprintln!(
            "locus robot: {} listening on {} (time scale {}); waiting for a host",
            args.scenario,
            socket.local_addr()?,
            args.time_scale
        );
        run_robot(&socket, &cfg)?
    };
    let c = r.commands;
    println!(
        "locus robot: {} ticks ({:.2} s robot time), {} telemetry packets sent; commands applied {} / lost {} / duplicate {} / late {} / corrupt {} / malformed {} / suspect {}; frames dropped {}; clamped {}; on time {:.1} %; watchdog stops {}",
        r.ticks,
        r.sim_time,
        r.sent,
        c.applied,
        c.lost,
        c.duplicate,
        c.late,
        c.corrupt,
        c.malformed,
        c.suspect,
        r.framing.dropped(),
        r.clamped,
        100.0 * r.on_time as f64 / r.ticks.max(1) as f64,
        r.watchdog_stops
    );
    Ok(())
}
