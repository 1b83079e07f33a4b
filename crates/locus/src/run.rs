//! `locus run [SCENARIO|FILE]`: a closed-loop scenario of the simulator
//! (built-in or a TOML scenario file, `locus_sim::scenario_file`), its
//! summary table, a per-step CSV log written as the run goes,
//! `metrics.json` and pictures (`crate::plot`); with `--runs N > 1`, a Monte Carlo over `N` seeds run in
//! parallel (`rayon`), its summary table, per-run metrics in `runs.csv` and
//! aggregate metrics in `metrics.json` (no step logs).
//!
//! Everything after the choice of the scenario is generic over the
//! scenario's record type ([`Record`]): [`execute`] takes a runner closure
//! of the shape of every `locus_sim` scenario runner
//! (`run_X(&cfg, seed, &mut sink) -> Result<Summary, Error>`). Adding a
//! scenario is one arm in [`run`]'s dispatch plus its [`Info`].

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use comfy_table::{Table, presets::UTF8_FULL};
use locus_core::wrap_angle;
use locus_models::laser_wall::Segment;
use locus_sim::closed_loop::{SquareConfig, run_square};
use locus_sim::hover::run_hover;
use locus_sim::scenario::{Record, Sample, Summary};
use locus_sim::scenario_file::{self, BUILTIN, ScenarioConfig};
use locus_sim::tricycle_slip::{TricycleSlipRecord, room, run_tricycle_slip};
use locus_sim::wall45::run_wall45;
use serde::Serialize;

use crate::metrics::{self, RunMetrics, Settings};
use crate::output::print_out;

/// The CSV writer is flushed every this many steps (and at the end), so a
/// killed run leaves a readable prefix: `log.csv` is always a prefix of the
/// complete log (header first), missing at most the last `FLUSH_EVERY` steps
/// plus one partial line without its newline.
const FLUSH_EVERY: usize = 100;

/// Arguments of `locus run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scenario to run: a built-in name, `square` (paper 001's arena with
    /// realistic noise: encoder quantisation, scale error, slip) or
    /// `square-ideal` (noise exactly as the filter's Q and R assume), or a
    /// scenario file `FILE.toml` whose `scenario = "square"` picks the kind
    /// and whose other keys override its defaults (see `--print-config`).
    #[arg(default_value = "square", value_name = "SCENARIO|FILE")]
    scenario: String,
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
    /// Do not draw the pictures of a single run. By default one run also
    /// writes `map`, `errors` and `covariance` as PNG and SVG into the
    /// output directory: walls with the true, estimated and odometry paths
    /// and 3-sigma covariance ellipses; x, y, heading errors with +-3 sigma
    /// bands; the variances over time (log scale).
    #[arg(long)]
    no_plots: bool,
    /// Level of the covariance ellipses on the map, in standard deviations
    /// (positive). The legend gives the probability a 2-D Gaussian falls inside,
    /// 1 - exp(-k^2/2): 39.3 % at 1 sigma (not 68.3 %), 68.3 % at 1.515,
    /// 98.9 % at 3.
    #[arg(long, default_value_t = crate::plot::ELLIPSE_SIGMA)]
    ellipse_sigma: f64,
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
    /// What the map's segments are, for the picture's legend (`walls`, or
    /// `landmarks` drawn as crosses).
    pub map_label: &'static str,
}

/// The square scenario's configuration with the command-line overrides.
fn square_config(args: &RunArgs, mut cfg: SquareConfig) -> Result<SquareConfig> {
    if let Some(laps) = args.laps {
        cfg.laps = usize::try_from(laps).context("--laps too large")?;
        #[allow(clippy::cast_precision_loss)]
        let needed = MAX_TIME_PER_LAP * laps as f64;
        cfg.max_time = cfg.max_time.max(needed);
    }
    Ok(cfg)
}

/// The [`Info`] of a square scenario.
fn square_info(name: &str, cfg: &SquareConfig) -> Info {
    Info {
        name: name.to_string(),
        title: "paper 001 closed loop",
        estimator: "EKF (odometry + IR)",
        measurement: "IR",
        dt: cfg.dt,
        laps: Some(cfg.laps),
        walls: locus_sim::World::square_arena().walls,
        map_label: "walls",
    }
}

/// The scenario named on the command line: its name (a built-in name, or
/// the file's stem) and configuration.
fn resolve(arg: &str) -> Result<(String, ScenarioConfig)> {
    if let Some(cfg) = ScenarioConfig::builtin(arg) {
        return Ok((arg.to_string(), cfg));
    }
    let path = Path::new(arg);
    if path.extension().is_some_and(|e| e == "toml") || path.is_file() {
        let cfg = scenario_file::load(path)?;
        let name = path
            .file_stem()
            .map_or_else(|| "file".to_string(), |s| s.to_string_lossy().into_owned());
        return Ok((name, cfg));
    }
    bail!(
        "unknown scenario `{arg}`; supported scenarios: {}, or a scenario file FILE.toml",
        BUILTIN.join(", ")
    )
}

/// Runs the scenario named in `args`, writing the log as it goes, then
/// prints the summary (or, with `--print-config`, prints its configuration).
pub fn run(args: &RunArgs) -> Result<()> {
    let (name, config) = resolve(&args.scenario)?;
    if args.print_config {
        let kind = if BUILTIN.contains(&args.scenario.as_str()) {
            args.scenario.as_str()
        } else {
            config.kind()
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
            execute(args, &info, &out, |seed, mut sink| {
                run_square(&cfg, seed, &mut sink)
            })
        }
        ScenarioConfig::Wall45(cfg) => {
            let info = Info {
                name,
                title: "paper 000 skid-steer robot, laser at the 45-degree wall (Table III path)",
                estimator: "EKF (odometry + laser)",
                measurement: "laser",
                dt: cfg.dt,
                laps: None,
                walls: locus_sim::World::wall45(cfg.wall_a).walls,
                map_label: "walls",
            };
            execute(args, &info, &out, |seed, mut sink| {
                run_wall45(&cfg, seed, &mut sink)
            })
        }
        ScenarioConfig::TricycleSlip(cfg) => {
            let info = Info {
                name,
                title: "paper 004 tricycle with wheel slip (odometry row: rear wheels only)",
                estimator: "EKF (rear odometry + laser)",
                measurement: "laser",
                dt: cfg.dt,
                laps: None,
                walls: room(cfg.room).walls,
                map_label: "walls",
            };
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
            let info = Info {
                name,
                title: "paper 002 body hovering before the camera (6-DOF; heading = attitude error)",
                estimator: "6-DOF estimator (camera marks)",
                measurement: "camera",
                dt: cfg.dt,
                laps: None,
                walls: Vec::new(),
                map_label: "walls",
            };
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
    fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    if args.runs > 1 {
        return monte_carlo(args, info, out, runner);
    }
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
        if !args.no_plots {
            samples.push(r.sample());
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

    let metrics_path = metrics::write(
        out,
        &RunMetrics {
            settings: Settings {
                seed: Some(args.seed),
                ..Settings::of(info)
            },
            summary,
            extra: (),
        },
    )?;

    let pictures = if args.no_plots {
        Vec::new()
    } else {
        let title = format!("locus run {}, seed {}", info.name, args.seed);
        crate::plot::write_all(
            out,
            &samples,
            (&info.walls, info.map_label),
            &title,
            args.ellipse_sigma,
        )?
    };

    let mut text = summary_text(args, info, &summary);
    text.push_str(&files_written(&csv_path, &metrics_path, &pictures, out));
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

/// A figure for the table: `scale * v` with `decimals`, or `n/a` when `v`
/// is NaN (a scenario without that estimator).
fn fig(v: f64, scale: f64, decimals: usize) -> String {
    if v.is_nan() {
        "n/a".to_string()
    } else {
        format!("{:.*}", decimals, scale * v)
    }
}

/// The single-run summary: first line and the two tables.
fn summary_text(args: &RunArgs, info: &Info, s: &Summary) -> String {
    let laps = info
        .laps
        .map_or_else(String::new, |_| format!(", {} laps", s.laps_completed));
    let mut text = format!(
        "locus run {}: {}, seed {}, {} steps of {} s ({:.1} s simulated{laps})\n",
        info.name, info.title, args.seed, s.steps, info.dt, s.sim_time
    );
    text.push_str(&summary_tables(info, s));
    text
}

/// The two tables of a single run's summary (estimators; filter checks),
/// shared with `locus replay`.
pub(crate) fn summary_tables(info: &Info, s: &Summary) -> String {
    let mut text = String::new();
    let mut table = Table::new();
    table.load_preset(UTF8_FULL).set_header(vec![
        "estimator",
        "position RMSE [cm]",
        "heading RMSE [deg]",
        "max position error [cm]",
    ]);
    let deg = 180.0 / core::f64::consts::PI;
    table.add_row(vec![
        info.estimator.to_string(),
        fig(s.ekf_position_rmse, 100.0, 2),
        fig(s.ekf_heading_rmse, deg, 2),
        fig(s.ekf_max_position_error, 100.0, 2),
    ]);
    table.add_row(vec![
        "odometry alone".to_string(),
        fig(s.odometry_position_rmse, 100.0, 2),
        fig(s.odometry_heading_rmse, deg, 2),
        fig(s.odometry_max_position_error, 100.0, 2),
    ]);
    text.push_str(&format!("{table}\n"));

    let mut filter = Table::new();
    filter
        .load_preset(UTF8_FULL)
        .set_header(vec!["filter check [unit]", "value"]);
    let dof = s.nees_dof;
    let rows = [
        (
            format!("mean NEES ({dof} dof, ideal {dof}) [-]"),
            fig(s.mean_nees, 1.0, 2),
        ),
        (
            format!("steps with NEES in 95 % chi-square({dof}) interval [%]"),
            fig(s.nees_in_interval, 100.0, 1),
        ),
        (
            format!(
                "{} readings / associated / applied [count]",
                info.measurement
            ),
            format!("{} / {} / {}", s.readings, s.associated, s.corrections),
        ),
        (
            "updates accepted by the gate [%]".to_string(),
            fig(s.acceptance, 100.0, 1),
        ),
        (
            "real-time factor [x]".to_string(),
            fig(s.real_time_factor, 1.0, 0),
        ),
    ];
    for (name, value) in rows {
        filter.add_row(vec![name, value]);
    }
    text.push_str(&format!("{filter}\n"));
    text
}

/// The spread of a metric over Monte Carlo runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
struct Spread {
    mean: f64,
    /// Sample standard deviation (n - 1; 0 for one value).
    std: f64,
    min: f64,
    max: f64,
}

impl Spread {
    /// The spread of `values`.
    #[allow(clippy::cast_precision_loss)]
    fn of(values: &[f64]) -> Self {
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = if values.len() > 1 {
            values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        Self {
            mean,
            std: var.sqrt(),
            min: values.iter().copied().fold(f64::INFINITY, f64::min),
            max: values.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }

    /// Mean, standard deviation, min and max, for a table row.
    fn figures(self) -> [f64; 4] {
        [self.mean, self.std, self.min, self.max]
    }
}

/// Reads one metric from a run's summary (SI).
type Getter = fn(&Summary) -> f64;

/// One Monte Carlo metric: JSON key (SI), table label, display scale and
/// how to read it from a summary.
struct Metric {
    key: &'static str,
    label: &'static str,
    scale: f64,
    get: Getter,
}

/// The metrics summarised over Monte Carlo runs.
const METRICS: [Metric; 6] = [
    Metric {
        key: "ekf_position_rmse_m",
        label: "EKF position RMSE [cm]",
        scale: 100.0,
        get: |s| s.ekf_position_rmse,
    },
    Metric {
        key: "ekf_heading_rmse_rad",
        label: "EKF heading RMSE [deg]",
        scale: 180.0 / core::f64::consts::PI,
        get: |s| s.ekf_heading_rmse,
    },
    Metric {
        key: "odometry_position_rmse_m",
        label: "odometry position RMSE [cm]",
        scale: 100.0,
        get: |s| s.odometry_position_rmse,
    },
    Metric {
        key: "odometry_heading_rmse_rad",
        label: "odometry heading RMSE [deg]",
        scale: 180.0 / core::f64::consts::PI,
        get: |s| s.odometry_heading_rmse,
    },
    Metric {
        key: "mean_nees",
        label: "mean NEES ({dof} dof, ideal {dof}) [-]",
        scale: 1.0,
        get: |s| s.mean_nees,
    },
    Metric {
        key: "acceptance_share",
        label: "updates accepted by the gate [%]",
        scale: 100.0,
        get: |s| s.acceptance,
    },
];

/// `--runs N > 1`: the scenario over seeds `seed..seed + N` in parallel,
/// without step logs; prints the Monte Carlo table, writes `runs.csv` and
/// `metrics.json`.
fn monte_carlo<R, E, F>(args: &RunArgs, info: &Info, out: &Path, runner: F) -> Result<()>
where
    R: Record,
    E: core::error::Error + Send + Sync + 'static,
    F: Fn(u64, &mut dyn FnMut(&R)) -> Result<Summary, E> + Sync,
{
    use indicatif::{ProgressBar, ProgressStyle};
    use rayon::prelude::*;

    let end = args
        .seed
        .checked_add(args.runs)
        .context("--seed + --runs overflows u64")?;
    let bar = ProgressBar::new(args.runs);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, eta {eta}")
            .context("progress bar template")?,
    );
    let started = std::time::Instant::now();
    let results: Vec<(u64, Result<Summary, E>)> = (args.seed..end)
        .into_par_iter()
        .map(|seed| {
            let r = runner(seed, &mut |_: &R| {});
            bar.inc(1);
            (seed, r)
        })
        .collect();
    bar.finish_and_clear();
    let wall_clock = started.elapsed().as_secs_f64();
    let mut runs = Vec::with_capacity(results.len());
    for (seed, r) in results {
        runs.push((
            seed,
            r.with_context(|| format!("{} run, seed {seed}", info.name))?,
        ));
    }

    let runs_path = out.join("runs.csv");
    fs::write(&runs_path, runs_csv(&runs))
        .with_context(|| format!("writing {}", runs_path.display()))?;
    let metrics_path = metrics::write(out, &monte_carlo_metrics(info, args.seed, &runs))?;

    let laps = info
        .laps
        .map_or_else(String::new, |l| format!(", {l} laps each"));
    let mut text = format!(
        "locus run {}: {}, Monte Carlo over {} runs (seeds {}..={}){laps}, {:.1} s wall clock\n",
        info.name,
        info.title,
        runs.len(),
        args.seed,
        end - 1,
        wall_clock
    );
    let mut table = Table::new();
    table.load_preset(UTF8_FULL).set_header(vec![
        "metric over runs [unit]",
        "mean",
        "std (n-1)",
        "min",
        "max",
    ]);
    let dof = runs.first().map_or(0, |(_, s)| s.nees_dof);
    for m in &METRICS {
        let values: Vec<f64> = runs.iter().map(|(_, s)| (m.get)(s)).collect();
        let label = m
            .label
            .replace("{dof}", &dof.to_string())
            .replace("{estimator}", info.estimator);
        let mut row = vec![label];
        row.extend(Spread::of(&values).figures().map(|v| fig(v, m.scale, 2)));
        table.add_row(row);
    }
    text.push_str(&format!("{table}\n"));
    text.push_str("no step logs with --runs > 1\n");
    text.push_str(&format!("runs: {}\n", runs_path.display()));
    text.push_str(&format!("metrics: {}\n", metrics_path.display()));
    print_out(&text)
}

/// A CSV field with 9 decimals, empty when not finite (no odometry).
fn csv_num(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.9}")
    } else {
        String::new()
    }
}

/// `runs.csv`: one row of summary metrics per run (SI units).
fn runs_csv(runs: &[(u64, Summary)]) -> String {
    let mut csv = String::from(
        "seed,steps,sim_time[s],laps_completed,ekf_position_rmse[m],ekf_heading_rmse[rad],\
         ekf_max_position_error[m],odometry_position_rmse[m],odometry_heading_rmse[rad],\
         odometry_max_position_error[m],mean_nees,nees_in_95_interval_share,ir_readings,\
         associated,corrections,acceptance_share,wall_clock[s]\n",
    );
    for (seed, s) in runs {
        let fields = [
            seed.to_string(),
            s.steps.to_string(),
            format!("{:.2}", s.sim_time),
            s.laps_completed.to_string(),
            format!("{:.9}", s.ekf_position_rmse),
            format!("{:.9}", s.ekf_heading_rmse),
            format!("{:.9}", s.ekf_max_position_error),
            csv_num(s.odometry_position_rmse),
            csv_num(s.odometry_heading_rmse),
            csv_num(s.odometry_max_position_error),
            format!("{:.6}", s.mean_nees),
            format!("{:.6}", s.nees_in_interval),
            s.readings.to_string(),
            s.associated.to_string(),
            s.corrections.to_string(),
            format!("{:.6}", s.acceptance),
            format!("{:.3}", s.wall_clock),
        ];
        csv.push_str(&fields.join(","));
        csv.push('\n');
    }
    csv
}

/// Aggregate `metrics.json` of a Monte Carlo: settings, then the
/// [`Spread`] over runs of each metric (SI).
#[derive(Serialize)]
struct MonteCarloMetrics<'a> {
    #[serde(flatten)]
    settings: Settings<'a>,
    #[serde(flatten, serialize_with = "serialize_in_order")]
    spreads: Vec<(&'static str, Spread)>,
}

/// Key-value pairs as a map, in their order.
fn serialize_in_order<S: serde::Serializer>(
    pairs: &[(&'static str, Spread)],
    serializer: S,
) -> Result<S::Ok, S::Error> {
    serializer.collect_map(pairs.iter().map(|(k, v)| (k, v)))
}

/// The [`MonteCarloMetrics`] of `runs` from `first_seed`.
fn monte_carlo_metrics<'a>(
    info: &'a Info,
    first_seed: u64,
    runs: &[(u64, Summary)],
) -> MonteCarloMetrics<'a> {
    let extra: [(&str, Getter); 2] = [
        ("ekf_max_position_error_m", |s| s.ekf_max_position_error),
        ("nees_in_95_interval_share", |s| s.nees_in_interval),
    ];
    let spreads = METRICS
        .iter()
        .map(|m| (m.key, m.get))
        .chain(extra.iter().copied())
        .map(|(key, get)| {
            let values: Vec<f64> = runs.iter().map(|(_, s)| get(s)).collect();
            (key, Spread::of(&values))
        })
        .collect();
    MonteCarloMetrics {
        settings: Settings {
            first_seed: Some(first_seed),
            runs: Some(runs.len()),
            ..Settings::of(info)
        },
        spreads,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_figure_is_printed_as_n_a() {
        assert_eq!(fig(f64::NAN, 100.0, 2), "n/a");
        assert_eq!(fig(0.0117, 100.0, 2), "1.17");
        assert_eq!(csv_num(f64::NAN), "");
    }
}
