//! `locus`: EKF localisation for wheeled robots, from the command line.
//!
//! The binary is thin: argument parsing, printing and files. The maths lives in
//! `locus-core` (the filter) and `locus-models` (the papers' models).

mod args;
mod demo;
mod doa;
mod family;
mod font;
mod foxglove;
mod guide;
mod host;
mod hw;
mod hw_pnr;
mod hw_rtl;
mod link_scenario;
mod map;
mod metrics;
mod output;
mod plot;
mod replay;
mod reproduce;
mod robot;
mod run;
mod serve;
mod table;
mod tune;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Locus: where is my robot? Extended Kalman Filter localisation of wheeled
/// robots from wheel odometry and range sensors.
#[derive(Parser, Debug)]
#[command(name = "locus", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the paper-001 EKF along one wall of the square arena and compare it
    /// with odometry alone: one leg, open loop, in a few lines of the library
    /// API (`locus run` is the full closed loop).
    Demo(demo::DemoArgs),
    /// Run a closed-loop scenario of the simulator (robot, sensors, filter
    /// against odometry alone), built-in (listed in `locus run --help`) or
    /// from a TOML scenario file: prints a summary table and writes `log.csv` (as the run goes),
    /// `metrics.json` and pictures (map, errors, covariance as PNG and SVG);
    /// with `--runs N`, a Monte Carlo over N seeds in parallel (table,
    /// `runs.csv`, `metrics.json`, no step log).
    Run(run::RunArgs),
    /// Paper 001's guided experiment, steps a) to f): odometry only, noise-free
    /// IR with tiny R, noisy IR with tiny R, tiny Q, huge Q, tuned Q and R.
    /// Each step runs the `square` scenario on 10 seeds and is judged on a
    /// measurable criterion (spec section 3); prints a table with PASS/FAIL
    /// and exits non-zero if a step fails.
    Guide(guide::GuideArgs),
    /// Reproduce a table of the papers beside Locus's Monte Carlo results:
    /// `table3` is paper 000's Table III (skid-steer robot, laser at the
    /// 45-degree wall), with the paper's measurement Jacobian and with the
    /// exact one.
    Reproduce(reproduce::ReproduceArgs),
    /// Domain of attraction of paper 002's observer over a (v_g, alpha)
    /// grid: CSV, heatmaps, `--shard I/N` slices and `doa merge`.
    Doa(doa::Args),
    /// Cycle-level model of papers 000/003's FPGA correction core: cycles,
    /// time and operators per correction, over 1..9 datapaths.
    Hw(hw::Args),
    /// The simulator as a robot on UDP (paper 001's link): sends encoder
    /// counts and IR readings at the sensor rate, applies the wheel speeds
    /// it receives, stops when they stop (watchdog). Protocol:
    /// docs/protocol.md.
    Robot(robot::Args),
    /// The localisation and control host for a robot speaking the link
    /// protocol: EKF, path controller, wheel commands; reports lost,
    /// duplicate, late, corrupt and malformed packets and the robot's clock.
    Host(host::Args),
    /// Replay a recorded log through the EKF: `replay mrclam DIR --robot N`
    /// (UTIAS MRCLAM), `replay librsf FILE` (libRSF text, e.g. Indoor UWB)
    /// or `replay csv FILE` (Locus's CSV log format,
    /// docs/log-format.md; `.xz` read directly). Late sightings are applied
    /// at their own time. Prints the summary against ground truth beside
    /// odometry alone, writes `log.csv`, `metrics.json` and pictures.
    Replay(Box<replay::Args>),
    /// Build an occupancy grid from scans taken at known poses (log-odds
    /// mapping), to localise in afterwards: from a Locus CSV log with beam
    /// sensors, scans and ground truth with heading (each scan at the
    /// truth interpolated at its time), or from a CARMEN log's corrected
    /// poses (`--carmen`). Writes ROS map_server's `map.yaml` and
    /// `map.pgm` and a picture `map.png` (grid and path), and prints a
    /// summary. docs/maps.md.
    Map(map::Args),
    /// Settings for a fleet: the noise levels and the odometry delay tuned
    /// on some logs (an MRCLAM dataset's robots, or Locus CSV logs), by
    /// default the medians of what `locus replay` estimates from each log
    /// with no flags (--objective for the others), and every log's errors
    /// against its ground truth with the built-in and the tuned values.
    Tune(tune::Args),
    /// The simulated family of robots (locus_sim::family) as a benchmark
    /// of the replay: each member's log replayed as `locus replay csv FILE`
    /// does with no flags, beside an honest reference given the true noise,
    /// delay and calibration. Prints position and heading RMSE, 3-sigma
    /// shares, mean NEES and each noise level used against its truth;
    /// writes family.csv and family.md (and the logs with --out). Exit code
    /// 0 whatever the figures.
    Family(family::Args),
    /// The teaching UI in the browser (paper 001's interface): an HTTP and
    /// WebSocket server on 127.0.0.1:8080 (--addr to change) running the
    /// square closed loop per browser tab; the page shows the arena, the
    /// covariance ellipse, live plots, Q/R/gain controls, the guide's steps
    /// a) to f), one correction step by step, and exports the log as CSV.
    Serve(serve::Args),
}

/// Stack of each rayon worker, bytes.
const REPLAY_STACK: usize = 64 << 20;

fn main() -> ExitCode {
    // `locus hw | head -1`: a `println!` on the closed pipe ends quietly.
    output::quiet_broken_pipe();
    // Replays run on rayon's workers, and a replay estimating its noise
    // runs replays in parallel in turn (nested, on the same stacks): the
    // running filter's history is a large value, so the workers get
    // stacks of 64 MiB (reserved, not committed) rather than 2 MiB.
    // Failing to set it (a pool already built) only keeps the default.
    let _ = rayon::ThreadPoolBuilder::new()
        .stack_size(REPLAY_STACK)
        .build_global();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Run(args) => run::run(&args),
        Command::Guide(args) => guide::run(&args),
        Command::Reproduce(args) => reproduce::run(&args),
        Command::Doa(args) => doa::run(&args),
        Command::Hw(args) => hw::run(&args),
        Command::Robot(args) => robot::run(&args),
        Command::Host(args) => host::run(&args),
        Command::Replay(args) => replay::run(&args),
        Command::Map(args) => map::run(&args),
        Command::Tune(args) => tune::run(&args),
        Command::Family(args) => family::run(&args),
        Command::Serve(args) => serve::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // `locus run | head`: the reader has gone; nothing left to say.
        Err(err) if output::is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            for cause in err.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::FAILURE
        }
    }
}
