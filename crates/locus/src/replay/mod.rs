//! `locus replay mrclam DIR [--robot N]`, `locus replay csv FILE` and
//! `locus replay librsf FILE`: a recorded log replayed through the EKF by
//! `locus_replay`, which settles the noise ([`locus_replay::policy`]),
//! replays, writes the CSV files ([`locus_replay::csv_out`]) and judges
//! the start. This command parses the flags ([`crate::args::replay`]) and
//! prints: the summary tables (plus the replay's settings, calibration and
//! counts), `log.csv` (one row per event), `metrics.json` (the results
//! schema with the replay's section, [`locus_replay::results`]) and the
//! pictures (map with the landmarks as crosses, true/estimated/odometry
//! paths and covariance ellipses; errors with +-3 sigma; variances; the NIS
//! with the consistency monitor's window mean and interval).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use comfy_table::Table;
use locus_eval::Sample;
use locus_eval::results::{Calibration, Results};
use locus_replay::policy::{Settled, Source as From, settle};
use locus_replay::results::Section;
use locus_replay::{Log, Report, csv_out::replay_to_csv};

use crate::args::replay::{Flags, Source};
use crate::metrics::{self, Metrics};
use crate::output::{print_out, progress_bar};
use crate::run::files_written;
use crate::table::{fig, with_header};

/// Arguments of `locus replay`.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    source: Source,
}

/// Runs `locus replay`.
///
/// # Errors
/// A log that cannot be read (file and line named), an invalid setting, a
/// file that cannot be written.
pub fn run(args: &Args) -> Result<()> {
    let (log, export, flags) = args.source.read()?;
    if let Some(path) = export {
        fs::write(path, locus_logs::locus_csv::write(&log.to_locus()))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let settled = settle(&log, &flags.config(), &flags.overrides())
        .with_context(|| format!("settling the noise of {}", log.name))?;
    let slug: String = log
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    let out = flags
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/replay-{slug}")));
    execute(&log, &settled, flags, &out)
}

fn execute(log: &Log, settled: &Settled, flags: &Flags, out: &Path) -> Result<()> {
    let cfg = &settled.config;
    crate::output::prepare_run_dir(out)?;
    let csv_path = out.join("log.csv");
    // With --smooth, the smoothed trajectory goes to smoothed.csv
    // (prepare_run_dir removed an earlier run's).
    let smoothed_path = out.join("smoothed.csv");
    let total = (log.odometry.len() + log.sightings.len() + log.scans.len()) as u64;
    let bar = progress_bar(total, "{pos}/{len} events, {elapsed} elapsed")?;
    let mut samples: Vec<Sample> = Vec::new();
    let smoothed = cfg.smooth.then_some(smoothed_path.as_path());
    let report = replay_to_csv(log, cfg, &csv_path, smoothed, |step| {
        if step.index % 4096 == 0 {
            bar.set_position(step.index as u64);
        }
        if !flags.pictures.no_plots
            && let Some(s) = step.sample()
        {
            samples.push(s);
        }
    })
    .with_context(|| format!("replaying {}", log.name))?;
    bar.finish_and_clear();

    let results = Results::of(&report.summary).with_smoother(report.smoothed.as_ref());
    let section = Section::new(cfg, &report);
    let metrics_path = metrics::write(
        out,
        &Metrics::new(metrics::Source::Replay, &log.name, results, &section),
    )?;

    let pictures = if flags.pictures.no_plots || samples.is_empty() {
        Vec::new()
    } else {
        let title = format!("locus replay {}", log.name);
        let landmarks: Vec<[f64; 2]> = log.landmarks.iter().map(|l| [l.x, l.y]).collect();
        let map = crate::plot::Map::Landmarks(&landmarks);
        let sigma = flags.pictures.ellipse_sigma;
        let mut written = crate::plot::write_all(out, &samples, map, &title, sigma)?;
        if samples.iter().any(|s| s.correction.is_some()) {
            written.extend(crate::plot::write_nis(out, &samples, &title)?);
        }
        written
    };

    let mut text = format!(
        "locus replay {}: {} events over {:.1} s ({} compared with ground truth)\n{}\n",
        log.name,
        report.steps,
        log.duration(),
        report.compared,
        report.started_from
    );
    if let Some(d) = &report.start_disagreement {
        text.push_str(&format!("{d}\n"));
    }
    text.push_str(&crate::table::summary(
        ("EKF (odometry + landmarks)", "landmark"),
        &report.summary,
    ));
    let smoother_calibration = report.smoothed_calibration.map(Calibration::from_pairs);
    for table in [
        crate::table::honesty(&results),
        settings(settled),
        crate::table::calibration(&section.calibration, smoother_calibration.as_ref()),
        counts(&report, &section),
    ] {
        text.push_str(&format!("{table}\n"));
    }
    text.push_str(&report.refusals.listing(&log.name));
    text.push_str(&files_written(&csv_path, &metrics_path, &pictures, out));
    if cfg.smooth {
        text.push_str(&format!("smoothed: {}\n", smoothed_path.display()));
    }
    print_out(&text)
}

/// The noise and odometry delay replayed with, where each came from (flag,
/// the log's record, the estimate, the default) and, for an estimate, its
/// standard error and the level the log itself shows; the biases held or
/// estimated.
fn settings(settled: &Settled) -> Table {
    let mut t = with_header([
        "setting [unit]",
        "value",
        "+- (1 sigma)",
        "level the log shows (x widening)",
        "from",
    ]);
    for s in &settled.settings {
        let decimals = if s.name == "odometry_delay" { 2 } else { 5 };
        t.add_row(vec![
            format!("{} [{}]", s.name, s.unit),
            format!("{:.decimals$}", s.value),
            if s.source == From::Estimated {
                fig(s.se, 1.0, decimals)
            } else {
                "-".to_string()
            },
            if s.level == s.value {
                "-".to_string()
            } else {
                format!("{:.decimals$} (x{:.2})", s.level, s.value / s.level)
            },
            s.source.to_string(),
        ]);
    }
    if let Some(e) = &settled.estimate {
        t.add_row(vec![
            "process noise raised after the gaps [x]".to_string(),
            format!("{}", e.gap_factor),
            "-".to_string(),
            "-".to_string(),
            format!(
                "the median NIS of the sightings after gaps of {} s or more against \
                 chi-square's (1: honest already, or fewer than {} such sightings)",
                locus_replay::noise::GAP,
                locus_replay::noise::MIN_POST_GAP
            ),
        ]);
    }
    for b in &settled.biases {
        let (m, sd) = b.smoothed;
        let (value, from) = if b.held {
            (
                "held at 0".to_string(),
                format!(
                    "the log cannot tell it: the whole log gives {m:.4} +- {sd:.4}, over {} of \
                     the prior's {}",
                    locus_replay::policy::HOLD_RATIO,
                    b.prior_std
                ),
            )
        } else {
            (
                format!("estimated from 0 +- {}", b.prior_std),
                format!("the whole log tells it: {m:.4} +- {sd:.4}"),
            )
        };
        let name = format!("{} [{}]", b.name, b.unit);
        t.add_row(vec![name, value, "-".to_string(), "-".to_string(), from]);
    }
    t
}

/// The replay's own counts: what happened to the log's records.
fn counts(r: &Report, section: &Section) -> Table {
    let s = &section.replay;
    let gate = s
        .gate_confidence
        .map_or_else(|| "none".to_string(), |g| format!("{:.1} %", 100.0 * g));
    let pair = |a: usize, b: usize| format!("{a} / {b}");
    let rows = [
        ("gate confidence", gate),
        (
            "odometry records / landmark sightings [count]",
            pair(s.odometry_records, r.sightings),
        ),
        (
            "sightings applied / gated [count]",
            pair(r.applied, s.gated),
        ),
        (
            "applied with a Student-t weight below 1 [count]",
            r.down_weighted.to_string(),
        ),
        (
            "share of sightings gated [%]",
            format!("{:.2}", 100.0 * s.gated_share),
        ),
        (
            "covariance inflations / sightings applied after one [count]",
            pair(s.inflations, s.recovered),
        ),
        (
            "robot-to-robot / unknown / not in map [count, skipped]",
            format!(
                "{} / {} / {}",
                s.robot_sightings, s.unknown_sightings, s.not_in_map
            ),
        ),
        (
            "late sightings re-run / too late [count]",
            pair(s.late, s.too_late),
        ),
        (
            "sightings where the model predicts none [count, skipped]",
            s.no_measurement.to_string(),
        ),
        (
            "refused: unusable / implausible time [count, listed below]",
            pair(s.unusable, s.implausible_time),
        ),
        (
            "odometry records refused as implausible [count, listed below]",
            s.implausible_odometry.to_string(),
        ),
    ];
    let mut t = with_header(["replay [unit]", "value"]);
    for (k, v) in rows {
        t.add_row(vec![k.to_string(), v]);
    }
    t
}
