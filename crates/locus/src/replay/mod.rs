//! `locus replay mrclam DIR [--robot N]` and `locus replay csv FILE`: a
//! recorded log replayed through the EKF (`locus_replay`), with the same
//! outputs as `locus run`: the summary tables (plus the replay's own
//! counts), `log.csv` (one row per event), `metrics.json` and the pictures
//! (map with the landmarks as crosses, true/estimated/odometry paths and
//! covariance ellipses; errors with +-3 sigma; variances; the NIS with the
//! consistency monitor's window mean and interval).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args as ClapArgs, Subcommand};
use comfy_table::Table;
use locus_eval::Sample;
use locus_eval::results::Results;
use locus_logs::mrclam::Dataset;
use locus_models::plausible::Limits;
use locus_replay::{Config, Log, Refusals, Report, Start, StartedFrom, replay};

mod csv_writer;
mod json;

use crate::metrics::{self, Metrics};
use crate::output::{print_out, progress_bar};
use crate::plot::PictureArgs;
use crate::run::files_written;
use crate::table::with_header;
use csv_writer::CsvWriter;
use json::ReplaySection;

/// Arguments of `locus replay`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(subcommand)]
    source: Source,
}

#[derive(Subcommand, Debug)]
enum Source {
    /// A robot of a UTIAS MRCLAM dataset directory (e.g.
    /// `../shared/data/mrclam/MRCLAM_Dataset6`; files plain or `.xz`).
    /// Robot-to-robot sightings and unknown barcodes are counted and left
    /// out.
    Mrclam {
        /// The dataset directory.
        dir: PathBuf,
        /// The robot (1-5).
        #[arg(long, default_value_t = 1)]
        robot: u32,
        /// Also write the robot's log in Locus's CSV format to this file
        /// (docs/log-format.md).
        #[arg(long)]
        export: Option<PathBuf>,
        #[command(flatten)]
        common: Common,
    },
    /// A log in Locus's CSV format (docs/log-format.md; `.xz` read
    /// directly).
    Csv {
        /// The log file.
        file: PathBuf,
        #[command(flatten)]
        common: Common,
    },
    /// A log in libRSF's text format (e.g.
    /// `../shared/data/indoor_uwb/Indoor_UWB_Input.txt`): UWB ranges to
    /// beacons (range-only sightings), differential-drive odometry. The
    /// ranges' declared variance is not used as the noise.
    Librsf {
        /// The input file (`range2`, `odom2diff` lines).
        input: PathBuf,
        /// The ground truth (`point2` lines, positions only). Default: the
        /// input's name with `_Input` replaced by `_GT`, if that file exists.
        #[arg(long)]
        truth: Option<PathBuf>,
        /// Also write the log in Locus's CSV format to this file
        /// (docs/log-format.md).
        #[arg(long)]
        export: Option<PathBuf>,
        #[command(flatten)]
        common: Common,
    },
}

/// Options shared by both sources.
#[derive(ClapArgs, Debug)]
struct Common {
    /// Output directory (created if missing). Default:
    /// `out/replay-<log name>`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Chi-square gate confidence in (0, 1).
    #[arg(long, default_value_t = Config::default().gate.unwrap_or(0.99), value_parser = crate::args::positive_f64)]
    gate: f64,
    /// No gate: apply every sighting.
    #[arg(long)]
    no_gate: bool,
    /// Power spectral density of the forward-speed noise, m^2/s.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = crate::args::positive_f64)]
    q_v: Option<f64>,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = crate::args::positive_f64)]
    q_omega: Option<f64>,
    /// Range noise standard deviation, m.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = crate::args::positive_f64)]
    sigma_range: Option<f64>,
    /// Bearing noise standard deviation, rad.
    /// Default: the log's `noise` record, else estimated from the log.
    #[arg(long, value_parser = crate::args::positive_f64)]
    sigma_bearing: Option<f64>,
    /// Initial value of the forward-speed scale factor (a state the filter
    /// estimates: the logged speed times it is the robot's).
    #[arg(long, default_value_t = 1.0, value_parser = crate::args::positive_f64)]
    v_scale: f64,
    /// Initial value of the turn-rate scale factor (estimated, as
    /// `--v-scale`).
    #[arg(long, default_value_t = 1.0, value_parser = crate::args::positive_f64)]
    omega_scale: f64,
    /// Student-t degrees of freedom of the sightings' noise: sightings far
    /// from the prediction are down-weighted rather than only gated.
    #[arg(long, default_value_t = 4.0, value_parser = crate::args::positive_f64)]
    robust_dof: f64,
    /// Gaussian sightings: no Student-t weighting (the gate alone).
    #[arg(long)]
    no_robust: bool,
    /// How long after an odometry record the robot moves as it says, s.
    /// Default: estimated from the log (the delay of smallest innovation likelihood
    /// on a grid from 0 to 0.4 s).
    #[arg(long, value_parser = crate::args::finite_f64)]
    odometry_delay: Option<f64>,
    /// Estimate only the odometry delay from the log: the noise from the
    /// flags, the log's noise records and the built-in values (MRCLAM's:
    /// q_v 0.002 m^2/s, q_omega 0.002 rad^2/s, range 1 m, bearing
    /// 0.01 rad), the biases held at 0. By default every noise level the
    /// flags and the log's records leave open is estimated from the log
    /// itself (no ground truth), and the turn-rate and bearing biases are
    /// estimated where the whole log tells them, else held at 0 and
    /// reported as held (docs/replay.md).
    #[arg(long)]
    delay_only: bool,
    /// Estimate nothing: the flags, the log's noise records and the
    /// built-in values as they are (odometry delay 0 unless given, biases
    /// held at 0).
    #[arg(long, conflicts_with = "delay_only")]
    no_estimate: bool,
    /// Also run the Rauch-Tung-Striebel smoother over the whole log: its
    /// accuracy, 3-sigma shares and NEES beside the filter's (table and
    /// metrics.json), and the smoothed trajectory in smoothed.csv.
    #[arg(long)]
    smooth: bool,
    /// Find the initial pose from the first sightings (the landmarks seen
    /// in the first seconds, carried back by dead reckoning and fitted to
    /// the map; later windows if those fix none), even when the log has a
    /// start pose or ground truth. A log with neither always starts this
    /// way. A pose that fewer than half of a window's sightings support,
    /// or whose landmarks fix no heading, is refused.
    #[arg(long)]
    start_from_sightings: bool,
    /// Top speed of the robot, m/s: an odometry record whose speed is
    /// above it is refused as implausible (counted, listed with its line;
    /// the velocities before it held). The same rule as the robot link's
    /// (docs/log-format.md, "Plausibility").
    #[arg(long, default_value_t = Limits::GENERIC.max_speed, value_parser = crate::args::positive_f64)]
    max_speed: f64,
    /// Top turn rate of the robot, rad/s (as --max-speed).
    #[arg(long, default_value_t = Limits::GENERIC.max_turn_rate, value_parser = crate::args::positive_f64)]
    max_turn_rate: f64,
    /// Longest time between two odometry records, s: a record later than
    /// this after the one before it is refused (as --max-speed).
    #[arg(long, default_value_t = Limits::GENERIC.max_odometry_gap, value_parser = crate::args::positive_f64)]
    max_odometry_gap: f64,
    /// Pictures.
    #[command(flatten)]
    pictures: PictureArgs,
}

impl Common {
    /// The replay's settings other than the noise and the odometry delay
    /// (settled by `locus_replay::policy`).
    fn config(&self) -> Config {
        Config {
            gate: (!self.no_gate).then_some(self.gate),
            robust_dof: (!self.no_robust).then_some(self.robust_dof),
            smooth: self.smooth,
            start: if self.start_from_sightings {
                Start::Sightings
            } else {
                Start::Log
            },
            calibration: locus_replay::Calibration {
                initial: [self.v_scale, self.omega_scale, 0.0, 0.0],
                ..locus_replay::Calibration::default()
            },
            limits: Limits {
                max_speed: self.max_speed,
                max_turn_rate: self.max_turn_rate,
                max_odometry_gap: self.max_odometry_gap,
                ..Limits::GENERIC
            },
            ..Config::default()
        }
    }
}

/// The replay's settings other than the noise and the odometry delay for
/// `locus replay csv FILE` with no flags (the flags' defaults, parsed as
/// the command parses them), for benchmarks that must replay as the
/// command does (`locus family`).
pub(crate) fn default_config() -> Config {
    #[derive(clap::Parser)]
    struct NoFlags {
        #[command(flatten)]
        common: Common,
    }
    <NoFlags as clap::Parser>::parse_from(["replay"])
        .common
        .config()
}

/// Runs `locus replay`.
///
/// # Errors
/// A log that cannot be read (file and line named), an invalid setting, a
/// file that cannot be written.
pub fn run(args: &Args) -> Result<()> {
    let (log, common) = match &args.source {
        Source::Mrclam {
            dir,
            robot,
            export,
            common,
        } => {
            let dataset = Dataset::open(dir)?;
            let log = Log::mrclam(&dataset, *robot)?;
            if let Some(path) = export {
                fs::write(path, locus_logs::locus_csv::write(&log.to_locus()))
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            (log, common)
        }
        Source::Csv { file, common } => (Log::locus_csv(file)?, common),
        Source::Librsf {
            input,
            truth,
            export,
            common,
        } => {
            let truth = truth
                .clone()
                .or_else(|| locus_logs::librsf::sibling_truth(input));
            let read = locus_logs::librsf::read(input, truth.as_deref())?;
            let name = input
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            let log = Log::from_locus_lines(&name, read.log, read.lines)?;
            if let Some(path) = export {
                fs::write(path, locus_logs::locus_csv::write(&log.to_locus()))
                    .with_context(|| format!("writing {}", path.display()))?;
            }
            (log, common)
        }
    };
    let (cfg, estimated) = calibrate(&log, common)?;
    let slug: String = log
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
        .collect();
    let out = common
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/replay-{slug}")));
    execute(&log, &cfg, common, &out, &estimated)
}

/// The replay's settings by `locus_replay::policy` (flags, then the log's
/// `noise` records, then the estimate, then the defaults), and a table of
/// what was estimated from the log (empty if nothing was).
fn calibrate(log: &Log, common: &Common) -> Result<(Config, String)> {
    use locus_replay::policy::{Estimation, Overrides, Source, settle};
    let overrides = Overrides {
        noise: locus_replay::log::NoiseRecords {
            q_v: common.q_v,
            q_omega: common.q_omega,
            sigma_range: common.sigma_range,
            sigma_bearing: common.sigma_bearing,
        },
        odometry_delay: common.odometry_delay,
        estimation: if common.no_estimate {
            Estimation::Nothing
        } else if common.delay_only {
            Estimation::Delay
        } else {
            Estimation::Noise
        },
    };
    let settled = settle(log, &common.config(), &overrides)
        .with_context(|| format!("settling the noise of {}", log.name))?;
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
            if s.source == Source::Estimated {
                figure(s.se, decimals)
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
        t.add_row(vec![
            format!("{} [{}]", b.name, b.unit),
            if b.held {
                "held at 0".to_string()
            } else {
                format!("estimated from 0 +- {}", b.prior_std)
            },
            "-".to_string(),
            "-".to_string(),
            if b.held {
                format!(
                    "the log cannot tell it: the whole log gives {m:.4} +- {sd:.4}, over {} of the prior's {}",
                    locus_replay::policy::HOLD_RATIO,
                    b.prior_std
                )
            } else {
                format!("the whole log tells it: {m:.4} +- {sd:.4}")
            },
        ]);
    }
    let text = format!("{t}\n");
    Ok((settled.config, text))
}

/// The log's landmarks, `[x, y]` (m), for the map.
fn landmarks(log: &Log) -> Vec<[f64; 2]> {
    log.landmarks.iter().map(|l| [l.x, l.y]).collect()
}

fn execute(log: &Log, cfg: &Config, common: &Common, out: &Path, estimated: &str) -> Result<()> {
    crate::output::prepare_run_dir(out)?;
    let csv_path = out.join("log.csv");
    // With --smooth, the smoothed trajectory goes to smoothed.csv
    // (prepare_run_dir removed an earlier run's).
    let smoothed_path = out.join("smoothed.csv");
    let total = (log.odometry.len() + log.sightings.len()) as u64;
    let bar = progress_bar(total, "{pos}/{len} events, {elapsed} elapsed")?;
    let mut samples: Vec<Sample> = Vec::new();
    let report = std::thread::scope(|scope| -> Result<Report> {
        let smoothed = cfg.smooth.then_some(smoothed_path.as_path());
        let mut writer = CsvWriter::start(scope, &csv_path, smoothed)?;
        let report = replay(log, cfg, |step| {
            if step.index % 4096 == 0 {
                bar.set_position(step.index as u64);
            }
            if !common.pictures.no_plots
                && let Some(s) = step.sample()
            {
                samples.push(s);
            }
            writer.push(step);
        });
        let written = writer.finish(report.is_ok());
        let report = report.with_context(|| format!("replaying {}", log.name))?;
        written?;
        Ok(report)
    })?;
    bar.finish_and_clear();

    let landmarks = landmarks(log);
    let results = Results::of(&report.summary).with_smoother(report.smoothed.as_ref());
    let metrics_path = metrics::write(
        out,
        &Metrics::new(
            metrics::Source::Replay,
            &log.name,
            results,
            ReplaySection::new(cfg, &report),
        ),
    )?;

    let pictures = if common.pictures.no_plots || samples.is_empty() {
        Vec::new()
    } else {
        let title = format!("locus replay {}", log.name);
        let mut written = crate::plot::write_all(
            out,
            &samples,
            crate::plot::Map::Landmarks(&landmarks),
            &title,
            common.pictures.ellipse_sigma,
        )?;
        if samples.iter().any(|s| s.correction.is_some()) {
            written.extend(crate::plot::write_nis(out, &samples, &title)?);
        }
        written
    };

    let mut text = format!(
        "locus replay {}: {} events over {:.1} s ({} compared with ground truth)\n",
        log.name,
        report.steps,
        log.duration(),
        report.compared
    );
    text.push_str(&started_from(&report.started_from));
    text.push_str(&start_check(&report));
    text.push_str(&crate::table::summary(
        ("EKF (odometry + landmarks)", "landmark"),
        &report.summary,
    ));
    text.push_str(&format!("{}\n", honesty_table(&report)));
    text.push_str(estimated);
    text.push_str(&format!("{}\n", calibration_table(&report)));
    text.push_str(&format!("{}\n", counts_table(cfg, &report)));
    text.push_str(&refused_list(&log.name, &report.refusals));
    text.push_str(&files_written(&csv_path, &metrics_path, &pictures, out));
    if cfg.smooth {
        text.push_str(&format!("smoothed: {}\n", smoothed_path.display()));
    }
    print_out(&text)
}

/// Where the initial pose came from, one line (with the fix's figures when
/// the sightings gave it).
fn started_from(from: &StartedFrom) -> String {
    match from {
        StartedFrom::Log => "initial pose: the log's start record\n".to_string(),
        StartedFrom::Truth => {
            "initial pose: the ground truth at the first odometry time\n".to_string()
        }
        StartedFrom::TruthPosition(h) => format!(
            "initial pose: the ground truth's position at the first odometry time (it has no \
             heading); heading {:.3} +- {:.3} rad (1 sigma, assumed) from its direction of motion \
             over its first {:.2} m ({:.1} s) against the odometry's\n",
            h.heading, h.std, h.travelled, h.span
        ),
        StartedFrom::Sightings(f) => {
            let sd = |k: usize| f.covariance[(k, k)].sqrt();
            let which = if f.later {
                format!(
                    "{} sightings of {:.1}-{:.1} s (the earlier ones fix none; carried back by \
                     dead reckoning, its drift added)",
                    f.sightings, f.from, f.span
                )
            } else {
                format!("the first {} sightings ({:.1} s)", f.sightings, f.span)
            };
            format!(
                "initial pose from {which}; {} of them agree ({:.0} %), on {} landmarks up to \
                 {:.2} m apart, rms {:.3} m: x {:.3} +- {:.3} m, y {:.3} +- {:.3} m, heading \
                 {:.3} +- {:.3} rad (1 sigma)\n",
                f.inliers,
                100.0 * f.share(),
                f.landmarks,
                f.baseline,
                f.rms,
                f.pose[0],
                sd(0),
                f.pose[1],
                sd(1),
                f.pose[2],
                sd(2)
            )
        }
    }
}

/// A warning when the log's start pose contradicts where its first
/// sightings put the robot ([`Report::start_disagreement`]), else nothing.
fn start_check(report: &Report) -> String {
    let Some(d) = report.start_disagreement else {
        return String::new();
    };
    format!(
        "warning: the log's start pose ({:.3} m, {:.3} m, {:.3} rad) is {:.1} sigma from where its first \
         sightings put the robot ({:.3} m, {:.3} m, {:.3} rad); if the start record is wrong, \
         replay with --start-from-sightings\n",
        d.log[0], d.log[1], d.log[2], d.sigma, d.sightings[0], d.sightings[1], d.sightings[2]
    )
}

/// Where a sighting is in its log: `name:line`, or `name` alone when the
/// line is not known (an MRCLAM log).
fn place(name: &str, line: Option<usize>) -> String {
    line.map_or_else(|| name.to_string(), |l| format!("{name}:{l}"))
}

/// The refused records, one line each (the first
/// [`KEPT`](locus_replay::refusals::KEPT)).
fn refused_list(name: &str, refusals: &Refusals) -> String {
    if refusals.total() == 0 {
        return String::new();
    }
    let mut text = format!("refused records ({}):\n", refusals.total());
    for r in refusals.first() {
        text.push_str(&format!("  {}: {r}\n", place(name, r.line())));
    }
    if refusals.total() > refusals.first().len() {
        text.push_str(&format!(
            "  ... and {} more\n",
            refusals.total() - refusals.first().len()
        ));
    }
    text
}

/// A share as a percentage, or "n/a" when it could not be computed.
fn percent(v: f64) -> String {
    if v.is_finite() {
        format!("{:.1}", 100.0 * v)
    } else {
        "n/a".to_string()
    }
}

fn figure(v: f64, decimals: usize) -> String {
    if v.is_finite() {
        format!("{v:.decimals$}")
    } else {
        "n/a".to_string()
    }
}

/// Accuracy and honesty of the filter (and the smoother): RMSE, and the
/// share of steps whose error lies inside the estimate's own 3 sigma.
fn honesty_table(r: &Report) -> Table {
    let mut t = with_header([
        "estimate",
        "position RMSE [m]",
        "heading RMSE [rad]",
        "heading RMSE about its offset [rad]",
        "heading offset [rad]",
        "inside 3 sigma x / y / theta [%] (theta about the offset)",
        "mean NEES [-] (its dof if honest; about the offset)",
    ]);
    let mut rows = vec![("filter", r.summary)];
    if let Some(s) = r.smoothed {
        rows.push(("smoother", s));
    }
    for (name, s) in rows {
        let shares = if s.compared == 0 {
            "n/a".to_string()
        } else {
            s.within_3_sigma
                .iter()
                .map(|v| percent(*v))
                .collect::<Vec<_>>()
                .join(" / ")
        };
        let (rmse, heading, nees) = if s.compared == 0 {
            (f64::NAN, f64::NAN, f64::NAN)
        } else {
            (s.ekf_position_rmse, s.ekf_heading_rmse, s.mean_nees)
        };
        t.add_row(vec![
            name.to_string(),
            figure(rmse, 3),
            figure(heading, 3),
            figure(s.ekf_heading_rmse_about_offset, 3),
            figure(s.ekf_heading_offset, 3),
            format!(
                "{shares} ({})",
                percent(s.within_3_sigma_heading_about_offset)
            ),
            format!(
                "{} ({} dof; {})",
                figure(nees, 2),
                s.nees_dof,
                figure(s.mean_nees_about_offset, 2)
            ),
        ]);
    }
    t
}

/// The calibration the filter estimated (and the smoother, from the whole
/// log).
fn calibration_table(r: &Report) -> Table {
    let mut t = with_header(["calibration [unit]", "filter (end)", "smoother (whole log)"]);
    let names = [
        "forward-speed scale [-]",
        "turn-rate scale [-]",
        "turn-rate bias [rad/s]",
        "bearing bias [rad]",
    ];
    for (i, name) in names.iter().enumerate() {
        let (m, s) = r.calibration[i];
        let smoothed = r.smoothed_calibration.map_or_else(
            || "-".to_string(),
            |c| format!("{:.4} +- {:.4}", c[i].0, c[i].1),
        );
        t.add_row(vec![
            (*name).to_string(),
            format!("{m:.4} +- {s:.4}"),
            smoothed,
        ]);
    }
    t
}

/// The replay's own counts: what happened to the sightings.
fn counts_table(cfg: &Config, r: &Report) -> Table {
    let mut t = with_header(["replay [unit]", "value"]);
    let gate = cfg
        .gate
        .map_or_else(|| "none".to_string(), |g| format!("{:.1} %", 100.0 * g));
    let rows = [
        ("gate confidence", gate),
        (
            "odometry records / landmark sightings [count]",
            format!("{} / {}", r.odometry, r.sightings),
        ),
        (
            "sightings applied / gated [count]",
            format!("{} / {}", r.applied, r.gated),
        ),
        (
            "applied with a Student-t weight below 1 [count]",
            format!("{}", r.down_weighted),
        ),
        (
            "share of sightings gated [%]",
            format!("{:.2}", 100.0 * r.gated_share()),
        ),
        (
            "covariance inflations / sightings applied after one [count]",
            format!("{} / {}", r.inflations, r.recovered),
        ),
        (
            "robot-to-robot / unknown / not in map [count, skipped]",
            format!(
                "{} / {} / {}",
                r.robot_sightings, r.unknown_sightings, r.not_in_map
            ),
        ),
        (
            "late sightings re-run / too late [count]",
            format!("{} / {}", r.late, r.too_late),
        ),
        (
            "sightings where the model predicts none [count, skipped]",
            format!("{}", r.no_measurement),
        ),
        (
            "refused: unusable / implausible time [count, listed below]",
            format!("{} / {}", r.unusable, r.implausible_time),
        ),
        (
            "odometry records refused as implausible [count, listed below]",
            format!("{}", r.implausible_odometry),
        ),
    ];
    for (k, v) in rows {
        t.add_row(vec![k.to_string(), v]);
    }
    t
}
