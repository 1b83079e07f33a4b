//! `locus run [SCENARIO]`: a closed-loop scenario of the simulator, its
//! summary table, a per-step CSV log written as the run goes, and
//! `metrics.json`; with `--runs N > 1`, a Monte Carlo over `N` seeds run in
//! parallel (`rayon`), its summary table, per-run metrics in `runs.csv` and
//! aggregate metrics in `metrics.json` (no step logs).
//!
//! Only `square` (paper 001: controller, encoders, IR pair, EKF on the 1 m
//! arena, see `locus_sim::closed_loop`) exists so far.

use std::fs::{self, File};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use comfy_table::{Table, presets::UTF8_FULL};
use locus_sim::closed_loop::{SquareConfig, StepRecord, Summary, run_square};

/// The scenarios `locus run` knows: `square` (paper 001's arena with
/// realistic noise: encoder quantisation, scale error, slip) and
/// `square-ideal` (the same with noise exactly as the filter's Q and R
/// assume: no slip, no quantisation, no gate).
pub const SCENARIOS: [&str; 2] = ["square", "square-ideal"];

/// The CSV writer is flushed every this many steps (and at the end), so a
/// killed run leaves a readable prefix: `log.csv` is always a prefix of the
/// complete log (header first), missing at most the last `FLUSH_EVERY` steps
/// plus one partial line without its newline.
const FLUSH_EVERY: usize = 100;

/// Arguments of `locus run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scenario to run: `square` (paper 001, realistic noise) or
    /// `square-ideal` (noise exactly as the filter assumes).
    #[arg(default_value = "square")]
    scenario: String,
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
}

/// Simulated-time limit per lap when `--laps` is given (s).
const MAX_TIME_PER_LAP: f64 = 300.0;

/// The scenario's configuration with the command-line overrides.
fn config(args: &RunArgs) -> Result<SquareConfig> {
    let mut cfg = match args.scenario.as_str() {
        "square-ideal" => SquareConfig::ideal(),
        _ => SquareConfig::default(),
    };
    if let Some(laps) = args.laps {
        cfg.laps = usize::try_from(laps).context("--laps too large")?;
        #[allow(clippy::cast_precision_loss)]
        let needed = MAX_TIME_PER_LAP * laps as f64;
        cfg.max_time = cfg.max_time.max(needed);
    }
    Ok(cfg)
}

/// Runs the scenario, writing the log as it goes, then prints the summary.
pub fn run(args: &RunArgs) -> Result<()> {
    if !SCENARIOS.contains(&args.scenario.as_str()) {
        bail!(
            "unknown scenario `{}`; supported scenarios: {}",
            args.scenario,
            SCENARIOS.join(", ")
        );
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/run-{}", args.scenario)));
    fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    let cfg = config(args)?;
    if args.runs > 1 {
        return monte_carlo(args, &cfg, &out);
    }
    let csv_path = out.join("log.csv");
    let file =
        File::create(&csv_path).with_context(|| format!("creating {}", csv_path.display()))?;
    let mut csv = BufWriter::new(file);
    writeln!(csv, "{}", StepRecord::csv_header())
        .and_then(|()| csv.flush())
        .with_context(|| format!("writing {}", csv_path.display()))?;

    let mut io_error: Option<std::io::Error> = None;
    let mut sink = |r: &StepRecord| {
        if io_error.is_some() {
            return;
        }
        let mut res = writeln!(csv, "{}", r.csv_row());
        if res.is_ok() && (r.step + 1) % FLUSH_EVERY == 0 {
            res = csv.flush();
        }
        if let Err(e) = res {
            io_error = Some(e);
        }
    };
    let result = run_square(&cfg, args.seed, &mut sink);
    // Flush what was logged even if the run failed.
    let flushed = csv.flush();
    if let Some(e) = io_error {
        return Err(e).with_context(|| format!("writing {}", csv_path.display()));
    }
    flushed.with_context(|| format!("writing {}", csv_path.display()))?;
    let summary = result.context("square run")?;

    let metrics_path = out.join("metrics.json");
    fs::write(
        &metrics_path,
        metrics_json(&args.scenario, args.seed, &cfg, &summary),
    )
    .with_context(|| format!("writing {}", metrics_path.display()))?;

    print_summary(args, &cfg, &summary, &csv_path, &metrics_path);
    Ok(())
}

fn print_summary(
    args: &RunArgs,
    cfg: &SquareConfig,
    s: &Summary,
    csv_path: &Path,
    metrics_path: &Path,
) {
    println!(
        "locus run {}: paper 001 closed loop, seed {}, {} steps of {} s ({:.1} s simulated, {} laps)",
        args.scenario, args.seed, s.steps, cfg.dt, s.sim_time, s.laps_completed
    );
    let mut table = Table::new();
    table.load_preset(UTF8_FULL).set_header(vec![
        "estimator",
        "position RMSE [cm]",
        "heading RMSE [deg]",
        "max position error [cm]",
    ]);
    table.add_row(vec![
        "EKF (odometry + IR)".to_string(),
        format!("{:.2}", 100.0 * s.ekf_position_rmse),
        format!("{:.2}", s.ekf_heading_rmse.to_degrees()),
        format!("{:.2}", 100.0 * s.ekf_max_position_error),
    ]);
    table.add_row(vec![
        "odometry alone".to_string(),
        format!("{:.2}", 100.0 * s.odometry_position_rmse),
        format!("{:.2}", s.odometry_heading_rmse.to_degrees()),
        format!("{:.2}", 100.0 * s.odometry_max_position_error),
    ]);
    println!("{table}");

    let mut filter = Table::new();
    filter
        .load_preset(UTF8_FULL)
        .set_header(vec!["filter check [unit]", "value"]);
    let rows = [
        (
            "mean NEES (3 dof, ideal 3) [-]",
            format!("{:.2}", s.mean_nees),
        ),
        (
            "steps with NEES in 95 % chi-square(3) interval [%]",
            format!("{:.1}", 100.0 * s.nees_in_interval),
        ),
        (
            "IR readings / associated / applied [count]",
            format!("{} / {} / {}", s.readings, s.associated, s.corrections),
        ),
        (
            "updates accepted by the gate [%]",
            format!("{:.1}", 100.0 * s.acceptance),
        ),
        ("real-time factor [x]", format!("{:.0}", s.real_time_factor)),
    ];
    for (name, value) in rows {
        filter.add_row(vec![name.to_string(), value]);
    }
    println!("{filter}");
    println!("log: {}", csv_path.display());
    println!("metrics: {}", metrics_path.display());
}

/// A JSON number, or `null` when not finite.
fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "null".to_string()
    }
}

/// `metrics.json`: the scenario, seed, main settings and the summary (SI).
fn metrics_json(scenario: &str, seed: u64, cfg: &SquareConfig, s: &Summary) -> String {
    let fields: Vec<(&str, String)> = vec![
        ("scenario", format!("\"{scenario}\"")),
        ("seed", seed.to_string()),
        ("dt_s", num(cfg.dt)),
        ("laps", cfg.laps.to_string()),
        ("steps", s.steps.to_string()),
        ("sim_time_s", num(s.sim_time)),
        ("laps_completed", s.laps_completed.to_string()),
        ("ekf_position_rmse_m", num(s.ekf_position_rmse)),
        ("ekf_heading_rmse_rad", num(s.ekf_heading_rmse)),
        ("ekf_max_position_error_m", num(s.ekf_max_position_error)),
        ("odometry_position_rmse_m", num(s.odometry_position_rmse)),
        ("odometry_heading_rmse_rad", num(s.odometry_heading_rmse)),
        (
            "odometry_max_position_error_m",
            num(s.odometry_max_position_error),
        ),
        ("mean_nees", num(s.mean_nees)),
        ("nees_in_95_interval_share", num(s.nees_in_interval)),
        ("ir_readings", s.readings.to_string()),
        ("associated", s.associated.to_string()),
        ("corrections", s.corrections.to_string()),
        ("acceptance_share", num(s.acceptance)),
        ("wall_clock_s", num(s.wall_clock)),
        ("real_time_factor", num(s.real_time_factor)),
    ];
    let body: Vec<String> = fields
        .iter()
        .map(|(k, v)| format!("  \"{k}\": {v}"))
        .collect();
    format!("{{\n{}\n}}\n", body.join(",\n"))
}

/// Mean, sample standard deviation (n - 1; 0 for one value), min and max.
#[allow(clippy::cast_precision_loss)]
fn stats(values: &[f64]) -> [f64; 4] {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = if values.len() > 1 {
        values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1.0)
    } else {
        0.0
    };
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    [mean, var.sqrt(), min, max]
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
        label: "mean NEES (3 dof, ideal 3) [-]",
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
fn monte_carlo(args: &RunArgs, cfg: &SquareConfig, out: &Path) -> Result<()> {
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
    let results: Vec<(u64, Result<Summary, locus_sim::closed_loop::Error>)> = (args.seed..end)
        .into_par_iter()
        .map(|seed| {
            let r = run_square(cfg, seed, &mut |_: &StepRecord| {});
            bar.inc(1);
            (seed, r)
        })
        .collect();
    bar.finish_and_clear();
    let wall_clock = started.elapsed().as_secs_f64();
    let mut runs = Vec::with_capacity(results.len());
    for (seed, r) in results {
        runs.push((seed, r.with_context(|| format!("square run, seed {seed}"))?));
    }

    let runs_path = out.join("runs.csv");
    fs::write(&runs_path, runs_csv(&runs))
        .with_context(|| format!("writing {}", runs_path.display()))?;
    let metrics_path = out.join("metrics.json");
    fs::write(
        &metrics_path,
        monte_carlo_json(&args.scenario, args.seed, cfg, &runs),
    )
    .with_context(|| format!("writing {}", metrics_path.display()))?;

    println!(
        "locus run {}: paper 001 closed loop, Monte Carlo over {} runs (seeds {}..={}), {} laps each, {:.1} s wall clock",
        args.scenario,
        runs.len(),
        args.seed,
        end - 1,
        cfg.laps,
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
    for m in &METRICS {
        let values: Vec<f64> = runs.iter().map(|(_, s)| m.scale * (m.get)(s)).collect();
        let mut row = vec![m.label.to_string()];
        row.extend(stats(&values).iter().map(|v| format!("{v:.2}")));
        table.add_row(row);
    }
    println!("{table}");
    println!("no step logs with --runs > 1");
    println!("runs: {}", runs_path.display());
    println!("metrics: {}", metrics_path.display());
    Ok(())
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
            format!("{:.9}", s.odometry_position_rmse),
            format!("{:.9}", s.odometry_heading_rmse),
            format!("{:.9}", s.odometry_max_position_error),
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

/// Aggregate `metrics.json` of a Monte Carlo: settings, then
/// `{mean, std, min, max}` over runs of each metric (SI; std is n - 1).
fn monte_carlo_json(
    scenario: &str,
    first_seed: u64,
    cfg: &SquareConfig,
    runs: &[(u64, Summary)],
) -> String {
    let mut fields: Vec<(&str, String)> = vec![
        ("scenario", format!("\"{scenario}\"")),
        ("first_seed", first_seed.to_string()),
        ("runs", runs.len().to_string()),
        ("dt_s", num(cfg.dt)),
        ("laps", cfg.laps.to_string()),
    ];
    let extra: [(&str, Getter); 2] = [
        ("ekf_max_position_error_m", |s| s.ekf_max_position_error),
        ("nees_in_95_interval_share", |s| s.nees_in_interval),
    ];
    let all = METRICS
        .iter()
        .map(|m| (m.key, m.get))
        .chain(extra.iter().copied());
    for (key, get) in all {
        let values: Vec<f64> = runs.iter().map(|(_, s)| get(s)).collect();
        let [mean, std, min, max] = stats(&values);
        fields.push((
            key,
            format!(
                "{{ \"mean\": {}, \"std\": {}, \"min\": {}, \"max\": {} }}",
                num(mean),
                num(std),
                num(min),
                num(max)
            ),
        ));
    }
    let body: Vec<String> = fields
        .iter()
        .map(|(k, v)| format!("  \"{k}\": {v}"))
        .collect();
    format!("{{\n{}\n}}\n", body.join(",\n"))
}
