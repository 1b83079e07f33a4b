//! `locus run [SCENARIO]`: a closed-loop scenario of the simulator, its
//! summary table, a per-step CSV log written as the run goes, and
//! `metrics.json`.
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

/// The scenarios `locus run` knows.
pub const SCENARIOS: [&str; 1] = ["square"];

/// The CSV writer is flushed every this many steps (and at the end), so a
/// killed run leaves a readable prefix.
const FLUSH_EVERY: usize = 100;

/// Arguments of `locus run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Scenario to run (supported: square).
    #[arg(default_value = "square")]
    scenario: String,
    /// Seed of the random numbers (a run is reproducible from its seed).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output directory for `log.csv` and `metrics.json` (created if
    /// missing). Default: `out/run-<SCENARIO>`.
    #[arg(long)]
    out: Option<PathBuf>,
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
    let csv_path = out.join("log.csv");
    let file =
        File::create(&csv_path).with_context(|| format!("creating {}", csv_path.display()))?;
    let mut csv = BufWriter::new(file);
    writeln!(csv, "{}", StepRecord::csv_header())
        .and_then(|()| csv.flush())
        .with_context(|| format!("writing {}", csv_path.display()))?;

    let cfg = SquareConfig::default();
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
