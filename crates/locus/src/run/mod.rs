//! `locus run [SCENARIO|FILE]`: a closed-loop scenario of the simulator
//! (built-in or a TOML scenario file, `locus_sim::scenario_file`), its
//! summary table (`crate::table`), a per-step CSV log written as the run
//! goes, `metrics.json` (`crate::metrics`) and pictures (`crate::plot`);
//! with `--runs N > 1`, a Monte Carlo over `N` seeds ([`monte_carlo`]).
//!
//! Everything after the choice of the scenario is generic over the
//! scenario's record type ([`Record`]): [`execute`] takes a runner closure
//! of the shape of every `locus_sim` scenario runner
//! (`run_X(&cfg, seed, &mut sink) -> Result<Summary, Error>`). Adding a
//! scenario is one arm in [`run`]'s dispatch plus its [`Info`].

mod monte_carlo;

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;
use locus_core::wrap_angle;
use locus_eval::results::Results;
use locus_eval::{Record, Sample, Summary};
use locus_models::laser_wall::Segment;
use std::sync::Mutex;

use locus_sim::beam_log::{RunLog, SquareLog, Wall45Log};
use locus_sim::closed_loop::{SquareConfig, StepRecord, run_square};
use locus_sim::hover::run_hover;
use locus_sim::scenario_file::ScenarioConfig;
use locus_sim::tricycle_slip::{TricycleSlipRecord, room, run_tricycle_slip};
use locus_sim::wall45::{Wall45Config, Wall45Record, run_wall45};

pub(crate) use self::monte_carlo::seeds;
use crate::args::ScenarioArg;
use crate::metrics::{self, Metrics, Simulation, SimulationSection, Source};
use crate::output::print_out;
use crate::plot::PictureArgs;

/// The CSV writer is flushed every this many steps (and at the end), so a
/// killed run leaves a readable prefix: `log.csv` is always a prefix of the
/// complete log (header first), missing at most the last `FLUSH_EVERY` steps
/// plus one partial line without its newline.
const FLUSH_EVERY: usize = 100;

/// Arguments of `locus run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scenario to run: a built-in name (listed below), or a scenario
    /// file `FILE.toml` whose `scenario = "square"` picks the kind and
    /// whose other keys override its defaults (see `--print-config`).
    #[arg(default_value = "square", value_name = "SCENARIO|FILE", value_parser = crate::args::ScenarioParser)]
    scenario: ScenarioArg,
    /// Print the scenario's complete configuration as a TOML scenario file
    /// (a template: every key, SI units) and exit without running.
    #[arg(long)]
    print_config: bool,
    /// Seed of the random numbers (a run is reproducible from its seed).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Laps of the square path to drive [laps, >= 1] (default: the
    /// scenario's, 2). The simulated-time limit grows with it (300 s per lap,
    /// at least the scenario's 600 s).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    laps: Option<u64>,
    /// Monte Carlo runs [count, >= 1] over the seeds SEED..SEED+RUNS-1, in
    /// parallel. With more than one run no step log is written: per-run
    /// metrics go to `runs.csv`, their mean/spread to `metrics.json`.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    runs: u64,
    /// Output directory (created if missing). Default:
    /// `out/run-<SCENARIO>`. One run writes `log.csv` (flushed every 100
    /// steps, so a killed run leaves a readable prefix whose last line at
    /// most is partial) and `metrics.json`; several runs write `runs.csv`
    /// and `metrics.json`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Also write the run as a Locus log (docs/log-format.md, v4) to
    /// this file: the walls, each range sensor as a beam sensor (paper
    /// 001's two IR sensors, paper 000's laser) with its readings as scan
    /// records, the odometry the filter used as speed and turn rate, the
    /// truth, the start and the filter's noise; `locus replay csv FILE`
    /// replays it (docs/replay.md, "A simulated run as a log"). For
    /// `square`, `square-ideal` and `wall45`, one run.
    #[arg(long, value_name = "FILE", conflicts_with = "runs")]
    export_log: Option<PathBuf>,
    /// Pictures of a single run.
    #[command(flatten)]
    pictures: PictureArgs,
    /// Foxglove output of a single run.
    #[command(flatten)]
    foxglove: crate::foxglove::McapArgs,
}

/// Simulated-time limit per lap when `--laps` is given (s).
const MAX_TIME_PER_LAP: f64 = 300.0;

/// What the summary table and the files say about a scenario, besides its
/// per-run [`Summary`].
#[derive(Debug, Clone)]
pub struct Info {
    /// Scenario name as given on the command line (e.g. `square`).
    pub name: String,
    /// What runs, for the first line of the output (e.g. `paper 001 closed
    /// loop`).
    pub title: &'static str,
    /// Label of the filter's row in the table (e.g. `EKF (odometry + IR)`).
    pub estimator: &'static str,
    /// Name of the measurements in the counts row (e.g. `IR`).
    pub measurement: &'static str,
    /// Filter step (s).
    pub dt: f64,
    /// Laps to drive, for scenarios that drive laps.
    pub laps: Option<usize>,
    /// The map's walls (m, world frame), for the pictures.
    pub walls: Vec<Segment<f64>>,
}

/// The square scenario's configuration with the command-line overrides.
fn square_config(args: &RunArgs, mut cfg: SquareConfig) -> Result<SquareConfig> {
    if let Some(laps) = args.laps {
        cfg.laps = usize::try_from(laps).context("--laps too large")?;
        #[allow(clippy::cast_precision_loss)]
        let needed = MAX_TIME_PER_LAP * laps as f64;
        cfg.max_time = cfg.max_time.max(needed);
        // The longer time limit must still make a run of bounded steps.
        cfg.validate()
            .with_context(|| format!("--laps {laps} (at most {MAX_TIME_PER_LAP} s per lap)"))?;
    }
    Ok(cfg)
}

impl Info {
    /// A simulated scenario named `name` with filter step `dt` in the map
    /// `walls`, without laps; `(title, estimator, measurement)` as the
    /// fields of those names.
    fn scenario(
        name: String,
        dt: f64,
        walls: Vec<Segment<f64>>,
        (title, estimator, measurement): (&'static str, &'static str, &'static str),
    ) -> Self {
        Self {
            name,
            title,
            estimator,
            measurement,
            dt,
            laps: None,
            walls,
        }
    }
}

/// The [`Info`] of a square scenario.
fn square_info(name: &str, cfg: &SquareConfig) -> Info {
    Info {
        laps: Some(cfg.laps),
        ..Info::scenario(
            name.to_string(),
            cfg.dt,
            locus_sim::World::square_arena().walls,
            ("paper 001 closed loop", "EKF (odometry + IR)", "IR"),
        )
    }
}

/// The [`Info`] of a `wall45` scenario.
fn wall45_info(name: String, cfg: &Wall45Config) -> Info {
    Info::scenario(
        name,
        cfg.dt,
        locus_sim::World::wall45(cfg.wall_a).walls,
        (
            "paper 000 skid-steer robot, laser at the 45-degree wall (Table III path)",
            "EKF (odometry + laser)",
            "laser",
        ),
    )
}

/// [`execute`] of the one run `--export-log` allows, with each step's
/// record also pushed into `log`, which is then written to `path`.
fn execute_exporting<L, E, F>(
    args: &RunArgs,
    info: &Info,
    out: &Path,
    path: &Path,
    log: L,
    runner: F,
) -> Result<()>
where
    L: RunLog + Send,
    L::Record: Record,
    E: core::error::Error + Send + Sync + 'static,
    F: Fn(u64, &mut dyn FnMut(&L::Record)) -> Result<Summary, E> + Sync,
{
    let log = Mutex::new(log);
    execute(args, info, out, |seed, sink| {
        runner(seed, &mut |r: &L::Record| {
            if let Ok(mut log) = log.lock() {
                log.push(r);
            }
            sink(r);
        })
    })?;
    let log = log
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a run panicked"))?;
    export_log(path, &log.finish())
}

/// Writes `log` to `path` in the Locus log format and says so.
fn export_log(path: &Path, log: &locus_logs::locus_csv::LocusLog) -> Result<()> {
    std::fs::write(path, locus_logs::locus_csv::write(log))
        .with_context(|| format!("writing {}", path.display()))?;
    print_out(&format!(
        "Locus log (beam records): {} ({} odometry, {} scans; replay: locus replay csv {})\n",
        path.display(),
        log.odometry.len(),
        log.scans.len(),
        path.display()
    ))
}

/// The scenario named on the command line: its name (a built-in name, or
/// the file's stem) and configuration.
fn resolve(arg: &ScenarioArg) -> Result<(String, ScenarioConfig)> {
    let name = match arg {
        ScenarioArg::Builtin(s) => s.to_string(),
        ScenarioArg::File(path) => path
            .file_stem()
            .map_or_else(|| "file".to_string(), |s| s.to_string_lossy().into_owned()),
    };
    Ok((name, arg.config()?))
}

/// Runs the scenario named in `args`, writing the log as it goes, then
/// prints the summary (or, with `--print-config`, prints its configuration).
pub fn run(args: &RunArgs) -> Result<()> {
    let (name, config) = resolve(&args.scenario)?;
    if args.print_config {
        let kind = match args.scenario {
            ScenarioArg::Builtin(s) => s.name(),
            ScenarioArg::File(_) => config.kind(),
        };
        return print_out(&config.to_toml(kind)?);
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/run-{name}")));
    // One arm per scenario kind: its command-line overrides, its Info and
    // its runner.
    match config {
        ScenarioConfig::Square(base) => {
            let cfg = square_config(args, base)?;
            let info = square_info(&name, &cfg);
            let run =
                |seed, mut sink: &mut dyn FnMut(&StepRecord)| run_square(&cfg, seed, &mut sink);
            match &args.export_log {
                None => execute(args, &info, &out, run),
                Some(path) => {
                    let log = SquareLog::new(&cfg, args.seed)?;
                    execute_exporting(args, &info, &out, path, log, run)
                }
            }
        }
        ScenarioConfig::Wall45(cfg) => {
            let info = wall45_info(name, &cfg);
            let run =
                |seed, mut sink: &mut dyn FnMut(&Wall45Record)| run_wall45(&cfg, seed, &mut sink);
            match &args.export_log {
                None => execute(args, &info, &out, run),
                Some(path) => {
                    let log = Wall45Log::new(&cfg, args.seed)?;
                    execute_exporting(args, &info, &out, path, log, run)
                }
            }
        }
        _ if args.export_log.is_some() => anyhow::bail!(
            "--export-log: only the square, square-ideal and wall45 scenarios can be written as a log"
        ),
        ScenarioConfig::TricycleSlip(cfg) => {
            let info = Info::scenario(
                name,
                cfg.dt,
                room(cfg.room).walls,
                (
                    "paper 004 tricycle with wheel slip (odometry row: rear wheels only)",
                    "EKF (rear odometry + laser)",
                    "laser",
                ),
            );
            // The slip-rejecting odometry's errors (the table's odometry row
            // is the rear-only one), for the line printed after the table.
            let slip_rejecting = std::sync::Mutex::new((0.0_f64, 0.0_f64, 0_usize));
            execute(args, &info, &out, |seed, sink| {
                run_tricycle_slip(&cfg, seed, &mut |r: &TricycleSlipRecord| {
                    let t = &r.sample;
                    let e2 = (t.truth[0] - r.slip_rejecting[0]).powi(2)
                        + (t.truth[1] - r.slip_rejecting[1]).powi(2);
                    let eth = wrap_angle(t.truth_heading - r.slip_rejecting[2]);
                    if let Ok(mut acc) = slip_rejecting.lock() {
                        acc.0 += e2;
                        acc.1 += eth * eth;
                        acc.2 += 1;
                    }
                    sink(r);
                })
            })?;
            let (e2, eth2, n) = *slip_rejecting
                .lock()
                .map_err(|_| anyhow::anyhow!("a run panicked"))?;
            if args.runs == 1 && n > 0 {
                #[allow(clippy::cast_precision_loss)]
                let n = n as f64;
                print_out(&format!(
                    "slip-rejecting odometry alone (paper 004): position RMSE {:.2} cm, heading RMSE {:.2} deg (the table's odometry row is rear-only)\n",
                    100.0 * (e2 / n).sqrt(),
                    (eth2 / n).sqrt().to_degrees()
                ))?;
            }
            Ok(())
        }
        ScenarioConfig::Hover(cfg) => {
            let info = Info::scenario(
                name,
                cfg.dt,
                Vec::new(),
                (
                    "paper 002 body hovering before the camera (6-DOF; heading = attitude error)",
                    "6-DOF estimator (camera marks)",
                    "camera",
                ),
            );
            execute(args, &info, &out, |seed, mut sink| {
                run_hover(&cfg, seed, &mut sink)
            })
        }
    }
}

/// Runs a scenario given as a runner closure `(seed, sink) -> summary`:
/// one run (log, metrics, table) or, with `--runs N > 1`, a Monte Carlo.
///
/// # Errors
/// Files that cannot be written, a failed run, standard output closed.
pub fn execute<R, E, F>(args: &RunArgs, info: &Info, out: &Path, runner: F) -> Result<()>
where
    R: Record,
    E: core::error::Error + Send + Sync + 'static,
    F: Fn(u64, &mut dyn FnMut(&R)) -> Result<Summary, E> + Sync,
{
    // Whatever `out` holds from an earlier run goes first: a run killed
    // midway leaves only its own partial outputs.
    crate::output::prepare_run_dir(out)?;
    if args.runs > 1 {
        anyhow::ensure!(
            args.foxglove.mcap.is_none(),
            "--mcap writes a single run: leave out --runs {} or --mcap",
            args.runs
        );
        return monte_carlo::monte_carlo(args, info, out, runner);
    }
    let mut recorder = match &args.foxglove.mcap {
        Some(path) => {
            let walls = info
                .walls
                .iter()
                .map(|w| [w.a[0], w.a[1], w.b[0], w.b[1]])
                .collect();
            let scene = crate::foxglove::scene(walls, &[], None);
            Some(crate::foxglove::Recorder::create(
                path,
                scene,
                args.pictures.ellipse_sigma,
            )?)
        }
        None => None,
    };
    let csv_path = out.join("log.csv");
    let file =
        File::create(&csv_path).with_context(|| format!("creating {}", csv_path.display()))?;
    let mut csv = BufWriter::new(file);
    writeln!(csv, "{}", R::csv_header())
        .and_then(|()| csv.flush())
        .with_context(|| format!("writing {}", csv_path.display()))?;

    let mut io_error: Option<std::io::Error> = None;
    let mut steps = 0usize;
    let mut samples: Vec<Sample> = Vec::new();
    let mut sink = |r: &R| {
        steps += 1;
        if !args.pictures.no_plots || recorder.is_some() {
            let sample = r.sample();
            if let Some(rec) = &mut recorder {
                rec.push(&crate::foxglove::frame_of_sample(&sample));
            }
            if !args.pictures.no_plots {
                samples.push(sample);
            }
        }
        if io_error.is_some() {
            return;
        }
        let mut res = writeln!(csv, "{}", r.csv_row());
        if res.is_ok() && steps % FLUSH_EVERY == 0 {
            res = csv.flush();
        }
        if let Err(e) = res {
            io_error = Some(e);
        }
    };
    let result = runner(args.seed, &mut sink);
    // Flush what was logged even if the run failed.
    let flushed = csv.flush();
    if let Some(e) = io_error {
        return Err(e).with_context(|| format!("writing {}", csv_path.display()));
    }
    flushed.with_context(|| format!("writing {}", csv_path.display()))?;
    let summary = result.with_context(|| format!("{} run", info.name))?;

    let section = SimulationSection {
        simulation: Simulation {
            seed: Some(args.seed),
            laps_completed: info.laps.map(|_| summary.laps_completed),
            ..Simulation::of(info)
        },
    };
    let metrics_path = metrics::write(
        out,
        &Metrics::new(
            Source::Simulation,
            &info.name,
            Results::of(&summary),
            section,
        ),
    )?;

    let pictures = if args.pictures.no_plots {
        Vec::new()
    } else {
        let title = format!("locus run {}, seed {}", info.name, args.seed);
        crate::plot::write_all(
            out,
            &samples,
            crate::plot::Map::Walls(&info.walls),
            &title,
            args.pictures.ellipse_sigma,
        )?
    };

    let mut text = summary_text(args, info, &summary);
    let mcap = recorder
        .map(|rec| rec.finish(&text, "locus run"))
        .transpose()?;
    text.push_str(&files_written(&csv_path, &metrics_path, &pictures, out));
    if let Some(w) = &mcap {
        text.push_str(&crate::foxglove::written(w));
    }
    print_out(&text)
}

/// The lines naming the files a single run wrote: the log, the metrics and
/// the pictures (if any) in `out`.
pub(crate) fn files_written(
    csv_path: &Path,
    metrics_path: &Path,
    pictures: &[PathBuf],
    out: &Path,
) -> String {
    let mut text = format!(
        "log: {}\nmetrics: {}\n",
        csv_path.display(),
        metrics_path.display()
    );
    if !pictures.is_empty() {
        let names: Vec<String> = pictures
            .iter()
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect();
        text.push_str(&format!(
            "pictures: {} in {}\n",
            names.join(", "),
            out.display()
        ));
    }
    text
}

/// The single-run summary: first line and the two tables.
fn summary_text(args: &RunArgs, info: &Info, s: &Summary) -> String {
    let laps = info
        .laps
        .map_or_else(String::new, |_| format!(", {} laps", s.laps_completed));
    let mut text = format!(
        "locus run {}: {}, seed {}, {} steps of {} s ({:.1} s simulated{laps})\n",
        info.name, info.title, args.seed, s.steps, info.dt, s.duration
    );
    text.push_str(&crate::table::summary(
        (info.estimator, info.measurement),
        s,
    ));
    text
}
