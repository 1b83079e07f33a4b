//! `locus replay mrclam DIR [--robot N]`, `locus replay csv FILE` and
//! `locus replay librsf FILE`: a recorded log replayed through the EKF by
//! `locus_replay`, which settles the noise ([`locus_replay::policy`]),
//! replays, writes the CSV files ([`locus_replay::csv_out`]) and judges
//! the start. This command parses the flags ([`crate::args::replay`]) and
//! prints: the summary tables (plus the replay's settings, calibration and
//! counts; for `locus replay carmen --relations`, the errors against the
//! relations, [`relations`]), `log.csv` (one row per event), `metrics.json`
//! (the results schema with the replay's section, [`locus_replay::results`],
//! and the `relations` section when judged against them) and the
//! pictures (map with the landmarks as crosses, true/estimated/odometry
//! paths and covariance ellipses; errors with +-3 sigma; variances; the NIS
//! with the consistency monitor's window mean and interval).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use comfy_table::Table;
use locus_eval::Sample;
use locus_eval::results::{Calibration, Results};
use locus_replay::policy::Settled;
use locus_replay::results::Section;
use locus_replay::{Log, Prepared, Report, csv_out::replay_to_csv, prepare};

use crate::args::replay::{Flags, Source};
use crate::metrics::{self, Metrics};
use crate::output::{print_out, progress_bar};
use crate::run::files_written;
use crate::table::{fig, with_header};

mod bag;
pub mod relations;

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
    if let Source::Bag {
        file, list: true, ..
    } = &args.source
    {
        print!("{}", bag::list(file)?);
        return Ok(());
    }
    let mut loaded = args.source.read()?;
    let options = loaded.flags.options();
    // The noise search replays the log hundreds of times: minutes on a
    // long log of scans.
    let searching = crate::output::spinner(
        "settling the noise and the odometry delay from the log, {elapsed} elapsed",
    )?;
    let prepared = prepare(&mut loaded.log, &options)
        .with_context(|| format!("settling the noise of {}", loaded.log.name));
    searching.finish_and_clear();
    let Prepared { settled, clock } = prepared?;
    let (log, flags) = (&loaded.log, loaded.flags);
    if let Some(path) = loaded.export {
        // The log as replayed: with the start given and the truth on the
        // sensors' clock.
        fs::write(path, locus_logs::locus_csv::write(&log.to_locus()))
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let slug: String = log
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    let out = flags
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/replay-{slug}")));
    execute(
        log,
        &settled,
        flags,
        &out,
        loaded.rail,
        loaded.relations.as_ref(),
        clock,
    )
}

/// The replay's sections of `metrics.json` and, when it was judged against
/// relations, their section after them.
#[derive(serde::Serialize)]
struct Sections<'a> {
    #[serde(flatten)]
    replay: &'a Section,
    #[serde(skip_serializing_if = "Option::is_none")]
    relations: Option<&'a locus_eval::results::Relations>,
}

fn execute(
    log: &Log,
    settled: &Settled,
    flags: &Flags,
    out: &Path,
    rail: Option<[f64; 3]>,
    reference: Option<&relations::Reference>,
    clock: Option<locus_replay::truth_clock::TruthClock>,
) -> Result<()> {
    let cfg = &settled.config;
    crate::output::prepare_run_dir(out)?;
    let csv_path = out.join("log.csv");
    // With --smooth, the smoothed trajectory goes to smoothed.csv
    // (prepare_run_dir removed an earlier run's).
    let smoothed_path = out.join("smoothed.csv");
    let total = (log.odometry.len() + log.sightings.len() + log.scans.len()) as u64;
    let bar = progress_bar(total, "{pos}/{len} events, {elapsed} elapsed")?;
    let mut samples: Vec<Sample> = Vec::new();
    let mut at_scans = reference.map(relations::Reference::gather);
    let smoothed = cfg.smooth.then_some(smoothed_path.as_path());
    let mut recorder = match &flags.foxglove.mcap {
        Some(path) => {
            let scene =
                crate::foxglove::scene(Vec::new(), &log.landmarks, log.map.as_ref().map(|m| &*m.0));
            Some(crate::foxglove::Recorder::create(
                path,
                scene,
                flags.pictures.ellipse_sigma,
            )?)
        }
        None => None,
    };
    let report = replay_to_csv(log, cfg, &csv_path, smoothed, |step| {
        if let Some(rec) = &mut recorder {
            rec.push(&crate::foxglove::frame_of_step(step));
        }
        if step.index % 4096 == 0 {
            bar.set_position(step.index as u64);
        }
        if let Some(at) = &mut at_scans {
            at.take(step);
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
    let section = Section::new(cfg, &report).with_truth_clock(clock.as_ref());
    let judged = reference
        .zip(at_scans.as_ref())
        .map(|(r, at)| r.judge(at, cfg.smooth));
    let sections = Sections {
        replay: &section,
        relations: judged.as_ref(),
    };
    let metrics_path = metrics::write(
        out,
        &Metrics::new(metrics::Source::Replay, &log.name, results, &sections),
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
    if let Some(c) = clock {
        text.push_str(&format!("{c}\n"));
    }
    let labels = match (log.sightings.is_empty(), log.scans.is_empty()) {
        (true, false) => ("EKF (odometry + beams)", "scan"),
        (false, false) => ("EKF (odometry + landmarks + beams)", "landmark or scan"),
        _ => ("EKF (odometry + landmarks)", "landmark"),
    };
    text.push_str(&crate::table::summary(labels, &report.summary));
    let smoother_calibration = report.smoothed_calibration.map(Calibration::from_pairs);
    let mut honesty = crate::table::honesty(&results);
    if let Some([wall, r_var, v_var]) = rail {
        // Beside them: what the rail's range alone and the linear Kalman
        // filter given the published noise reach (x only).
        let [range, kf] = locus_replay::rail::baselines(log, wall, r_var, v_var, cfg.truth_max_gap);
        for (name, b) in [("range alone", range), ("linear KF, published noise", kf)] {
            let share = format!("{} (x)", fig(b.within_3_sigma, 100.0, 1));
            honesty.add_row([name, &fig(b.rmse, 1.0, 4), "n/a", "n/a", "n/a", &share]);
        }
    }
    text.push_str(&format!("{honesty}\n"));
    if let Some((r, judged)) = reference.zip(judged.as_ref()) {
        text.push_str(&r.table(judged));
    }
    for table in [
        crate::table::settings(settled),
        crate::table::calibration(&section.calibration, smoother_calibration.as_ref()),
        counts(&report, &section),
    ] {
        text.push_str(&format!("{table}\n"));
    }
    text.push_str(&report.refusals.listing(&log.name));
    let mcap = recorder
        .map(|rec| rec.finish(&text, "locus replay"))
        .transpose()?;
    text.push_str(&files_written(&csv_path, &metrics_path, &pictures, out));
    if cfg.smooth {
        text.push_str(&format!("smoothed: {}\n", smoothed_path.display()));
    }
    if let Some(w) = &mcap {
        text.push_str(&crate::foxglove::written(w));
    }
    print_out(&text)
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
    let b = &r.beams;
    if r.scans > 0 {
        t.add_row(vec![
            "scans / beams in them / beams chosen [count]".to_string(),
            format!("{} / {} / {}", r.scans, b.beams, b.chosen),
        ]);
        t.add_row(vec![
            "beams applied / gated / down-weighted [count]".to_string(),
            format!("{} / {} / {}", b.applied, b.gated, b.down_weighted),
        ]);
        t.add_row(vec![
            "beams skipped: no return / no surface or grazing / short / unusable [count]"
                .to_string(),
            format!(
                "{} / {} / {} / {}",
                b.no_return, b.no_surface, b.short, b.unusable
            ),
        ]);
        t.add_row(vec![
            "scans aligned to the map and corrected there [count]".to_string(),
            b.aligned.to_string(),
        ]);
    }
    t
}
