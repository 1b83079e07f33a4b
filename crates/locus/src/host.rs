//! `locus host`: the localisation and control loop for a robot speaking
//! the link protocol (`docs/protocol.md`). A robot that goes quiet before
//! the laps are done fails the run (after the table of what was received).

use std::net::{ToSocketAddrs, UdpSocket};

use anyhow::Context;
use clap::Args as ClapArgs;
use comfy_table::Table;
use locus_net::host::{HostStep, run_host, run_host_over};
use locus_net::transport::Serial;
use locus_simlink::host_config;

use crate::link_scenario::square_config;

/// Arguments of `locus host`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// The robot: a UDP address (`HOST:PORT`, or `udp:HOST:PORT`), or a
    /// serial device (`serial:/dev/ttyUSB0`; a Bluetooth SPP link is one
    /// too, e.g. `serial:/dev/rfcomm0`), over which packets travel as COBS
    /// frames (docs/protocol.md).
    #[arg(
        long,
        default_value = "127.0.0.1:7700",
        value_name = "ADDR|serial:DEVICE"
    )]
    robot: String,
    /// Local address to bind (UDP only).
    #[arg(long, default_value = "127.0.0.1:0")]
    bind: String,
    /// Serial line speed, bits per second (serial only): 50 to 4000000,
    /// the standard UART rates' span (0 would mean "hang up" to a serial
    /// line).
    #[arg(long, default_value_t = 115_200, value_parser = crate::args::baud)]
    baud: u32,
    /// `square` or a scenario file whose `scenario = "square"` (the robot's
    /// geometry, the filter's Q and R, the controller).
    #[arg(default_value = "square", value_name = "SCENARIO|FILE", value_parser = crate::args::ScenarioParser)]
    scenario: crate::args::ScenarioArg,
    /// Print every applied packet's estimate (robot time, x, y, theta).
    #[arg(long)]
    verbose: bool,
    /// Also serve the live estimate to Foxglove over its WebSocket
    /// protocol at this address (e.g. 127.0.0.1:8765; port 0 picks a free
    /// one, printed first): in Foxglove, Open connection, Foxglove
    /// WebSocket, `ws://ADDR`. docs/foxglove.md.
    #[arg(long, value_name = "ADDR")]
    foxglove: Option<core::net::SocketAddr>,
}

/// The robot's UDP address from `--robot` (`HOST:PORT` or
/// `udp:HOST:PORT`; `serial:DEVICE` is handled by the caller).
pub fn udp_robot(arg: &str) -> anyhow::Result<core::net::SocketAddr> {
    let text = arg.strip_prefix("udp:").unwrap_or(arg);
    text.to_socket_addrs()
        .with_context(|| format!("resolving {text} (--robot: HOST:PORT or serial:DEVICE)"))?
        .next()
        .with_context(|| format!("no address for {text}"))
}

/// Runs `locus host`.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let square = square_config(&args.scenario)?;
    let cfg = host_config(&square);
    let verbose = args.verbose;
    let live = match args.foxglove {
        Some(addr) => {
            let live = locus_serve::foxglove::Live::start(addr, crate::plot::ELLIPSE_SIGMA)
                .with_context(|| format!("--foxglove {addr}"))?;
            live.latch(&locus_serve::foxglove::arena(&cfg), 0.0)?;
            println!("Foxglove WebSocket on ws://{}/", live.local_addr());
            std::io::Write::flush(&mut std::io::stdout())?;
            Some(live)
        }
        None => None,
    };
    let mut on_step = |s: &HostStep| {
        if let Some(live) = &live {
            live.publish(&locus_serve::foxglove::frame_of(s));
        }
        if verbose {
            println!(
                "{:.2} s  x {:.4} m  y {:.4} m  theta {:.4} rad{}",
                s.robot_time,
                s.estimate[0],
                s.estimate[1],
                s.estimate[2],
                if s.skipped > 0 { "  (gap)" } else { "" }
            );
        }
    };
    let (peer, report) = if let Some(device) = args.robot.strip_prefix("serial:") {
        let mut link = Serial::open(device, args.baud)?;
        (
            format!("serial {device} at {} baud", args.baud),
            run_host_over(&mut link, &cfg, &mut on_step)?,
        )
    } else {
        let robot = udp_robot(&args.robot)?;
        let socket =
            UdpSocket::bind(&args.bind).with_context(|| format!("binding UDP {}", args.bind))?;
        (
            format!("robot {robot}"),
            run_host(&socket, robot, &cfg, &mut on_step)?,
        )
    };
    let c = report.counters;
    let mut lat: Vec<f64> = report.latency.clone();
    lat.sort_by(f64::total_cmp);
    let pct = |p: f64| {
        lat.get(((lat.len().saturating_sub(1)) as f64 * p).round() as usize)
            .map_or_else(|| "-".to_string(), |v| format!("{:.1}", v * 1e6))
    };
    println!("locus host: {peer}, {} laps", report.laps);
    let mut table = Table::new();
    table.load_preset(comfy_table::presets::ASCII_MARKDOWN);
    table.set_header(vec!["quantity", "value"]);
    for (k, v) in [
        (
            "packets applied / lost / duplicate / late [count]",
            format!("{} / {} / {} / {}", c.applied, c.lost, c.duplicate, c.late),
        ),
        (
            "packets corrupt / malformed [count]",
            format!("{} / {}", c.corrupt, c.malformed),
        ),
        (
            "packets suspect (sequence) / implausible (content) [count]",
            format!("{} / {}", c.suspect, c.implausible),
        ),
        ("resynchronisations [count]", c.resync.to_string()),
        (
            "serial frames dropped: malformed / oversize [count]",
            format!("{} / {}", report.framing.malformed, report.framing.oversize),
        ),
        (
            "filter errors (belief kept) [count]",
            report.filter_errors.to_string(),
        ),
        ("commands sent [count]", report.commands_sent.to_string()),
        (
            "IR corrections applied [count]",
            report.corrections.to_string(),
        ),
        (
            "receive-to-command p50 / p99 [us]",
            format!("{} / {}", pct(0.5), pct(0.99)),
        ),
        (
            "robot clock offset [s] / drift [ppm]",
            report.clock.map_or_else(
                || "-".to_string(),
                |f| format!("{:.6} / {:.1}", f.offset, f.drift * 1e6),
            ),
        ),
    ] {
        table.add_row(vec![k.to_string(), v]);
    }
    println!("{table}");
    if !report.complete {
        anyhow::bail!(
            "the robot went silent for {:.2} s before the run was complete ({} of {} laps): \
             {} packets received ({} applied), {} lost, {} serial frames dropped; \
             the run is incomplete (the table above is what was received)",
            report.silence.as_secs_f64(),
            report.laps,
            cfg.laps,
            c.received(),
            c.applied,
            c.lost,
            report.framing.dropped()
        );
    }
    Ok(())
}
