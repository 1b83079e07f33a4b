//! `locus serve`: the teaching UI in the browser (crate `locus-serve`).

use core::net::SocketAddr;

use anyhow::{Context, Result};
use clap::Args as ClapArgs;
use locus_sim::scenario_file::ScenarioConfig;

use crate::args::{ScenarioArg, ScenarioParser};

/// Arguments of `locus serve`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Scenario each session starts from: `square`, `square-ideal`, or a
    /// TOML scenario file with `scenario = "square"` (the page can switch
    /// between the two built-ins and load the guide's steps a to f).
    #[arg(default_value = "square", value_name = "SCENARIO|FILE", value_parser = ScenarioParser)]
    scenario: ScenarioArg,
    /// Address to listen on. The default is the loopback interface only:
    /// anyone who can reach the port can drive the simulation, so give
    /// another address (e.g. 0.0.0.0:8080) only on a network you trust.
    #[arg(long, default_value = "127.0.0.1:8080")]
    addr: SocketAddr,
    /// Seed of every session's simulation (Reset replays it).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Most concurrent sessions (browser tabs); more are refused with 503.
    #[arg(long, default_value_t = 64)]
    max_sessions: usize,
    /// Attach the page to a robot instead of the simulation: a UDP address
    /// (`HOST:PORT` or `udp:HOST:PORT`) or a serial device
    /// (`serial:/dev/rfcomm0`), as `locus host --robot`. The host localises
    /// it with SCENARIO's robot, filter and controller; it starts stopped
    /// (Start on the page drives the path).
    #[arg(long, value_name = "ADDR|serial:DEVICE")]
    robot: Option<String>,
    /// Local address of the host's UDP socket (with `--robot ADDR`).
    #[arg(long, default_value = "127.0.0.1:0")]
    bind: SocketAddr,
    /// Serial line speed, bits per second (with `--robot serial:DEVICE`):
    /// 50 to 4000000, the standard UART rates' span (0 would mean "hang
    /// up" to a serial line).
    #[arg(long, default_value_t = 115_200, value_parser = crate::args::baud)]
    baud: u32,
    /// Also serve the robot's live estimate to Foxglove over its WebSocket
    /// protocol at this address (with `--robot`; e.g. 127.0.0.1:8765, port
    /// 0 picks a free one): in Foxglove, Open connection, Foxglove
    /// WebSocket, `ws://ADDR`. docs/foxglove.md.
    #[arg(long, value_name = "ADDR", requires = "robot")]
    foxglove: Option<SocketAddr>,
}

/// The square-kind configuration of `arg` (a built-in or a file) and its
/// name.
fn scenario(arg: &ScenarioArg) -> Result<(String, locus_sim::SquareConfig)> {
    let (name, cfg) = (arg.to_string(), arg.config()?);
    match cfg {
        ScenarioConfig::Square(c) => Ok((name, c)),
        other => Err(locus_serve::Error::Scenario(other.kind().to_string()).into()),
    }
}

/// Runs the server until interrupted.
pub fn run(args: &Args) -> Result<()> {
    let (name, cfg) = scenario(&args.scenario)?;
    let mut config = locus_serve::Config::new(&name, cfg)?;
    config.seed = args.seed;
    config.limits.max_sessions = args.max_sessions;
    let robot = match &args.robot {
        None => None,
        Some(arg) => {
            let link = if let Some(device) = arg.strip_prefix("serial:") {
                locus_serve::robot::Link::serial(device, args.baud)?
            } else {
                let robot = crate::host::udp_robot(arg)?;
                locus_serve::robot::Link::udp(args.bind, robot)
                    .with_context(|| format!("binding UDP {}", args.bind))?
            };
            let mut host = locus_simlink::host_config(&cfg);
            // A live session: the path repeats until the page stops it.
            host.laps = usize::MAX;
            let live = args
                .foxglove
                .map(|addr| {
                    locus_serve::foxglove::Live::start(addr, crate::plot::ELLIPSE_SIGMA)
                        .with_context(|| format!("--foxglove {addr}"))
                })
                .transpose()?;
            let foxglove = live.as_ref().map(locus_serve::foxglove::Live::local_addr);
            let attached =
                locus_serve::robot::Attached::start_with(link, &host, cfg.dt, config.tick, live)?;
            Some((attached, foxglove))
        }
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .context("starting the async runtime")?;
    runtime.block_on(async {
        let listener = tokio::net::TcpListener::bind(args.addr)
            .await
            .with_context(|| format!("binding {}", args.addr))?;
        let addr = listener.local_addr()?;
        match (&args.robot, &robot) {
            (Some(robot), Some((_, foxglove))) => {
                println!(
                    "Locus teaching UI on http://{addr}/ attached to the robot at {robot} (its filter and controller from {name}; stopped until Start); Ctrl-C stops it"
                );
                if let Some(f) = foxglove {
                    println!("Foxglove WebSocket on ws://{f}/ (the robot's live estimate)");
                }
            }
            _ => println!(
                "Locus teaching UI on http://{addr}/ (scenario {name}, seed {}); Ctrl-C stops it",
                args.seed
            ),
        }
        if !addr.ip().is_loopback() {
            println!(
                "warning: listening on {}: reachable from the network",
                addr.ip()
            );
        }
        match robot {
            Some((robot, _)) => locus_serve::serve_with_robot(listener, config, robot).await?,
            None => locus_serve::serve(listener, config).await?,
        }
        Ok(())
    })
}
