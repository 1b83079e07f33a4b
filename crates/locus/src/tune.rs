//! `locus tune LOGS...`: settings for a fleet of alike robots. The
//! estimation is `locus_replay::fleet`'s; this module parses the
//! arguments, reads the logs, shows the progress and prints the tables.
//!
//! The logs are a UTIAS MRCLAM dataset directory (robots chosen with
//! `--tune-on` and `--held-out`) or Locus CSV logs (every one given tuned
//! on; `--held-out-log` adds logs only reported). It prints the values
//! tuned (`q_v` in m^2/s, `q_omega` in rad^2/s, `sigma_range` in m,
//! `sigma_bearing` in rad, the initial scale factors without unit, the
//! odometry delay in s) beside the built-in ones, then every log replayed
//! with both against its ground truth: position RMSE (m), heading RMSE
//! (deg), dead reckoning's position RMSE (m), gated sightings (%), the
//! worst 3-sigma share of x, y and heading (%), the innovation NLL. A
//! figure that cannot be computed reads "n/a".
//!
//! `--objective` picks `locus_replay::fleet::Method`:
//!
//! * `estimate` (the default): what `locus replay` estimates from each log
//!   with no flags (the four noise levels and the odometry delay); the
//!   median of each value.
//! * `drift`: each log's odometry delay and its process noise from the
//!   drift of dead reckoning between pose fixes of the sightings; the
//!   median of each value (the measurement noise stays built in).
//! * `nll`: argmin's Nelder-Mead over the four noise levels and the
//!   initial scale factors on the innovations' negative log-likelihood
//!   summed over the tuning logs (at most `--max-iters` iterations).
//! * `truth`: the same search on the summed position RMSE against the
//!   ground truth (for comparison: it needs the truth).
//!
//! A tuning log with no estimate is named with its cause in a warning and
//! left out; the run fails when no log is left.

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use clap::Args as ClapArgs;
use clap::ValueEnum;
use locus_logs::mrclam::Dataset;
use locus_replay::fleet::{self, Comparison, Figures, Method, Options, Progress, Role};
use locus_replay::{Config, Log};

use crate::output::{print_out, progress_bar};
use crate::table::with_header;

/// Arguments of `locus tune`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// An MRCLAM dataset directory (e.g.
    /// `../shared/data/mrclam/MRCLAM_Dataset6`), or one or more logs in
    /// Locus's CSV format (docs/log-format.md), all tuned on.
    #[arg(required = true)]
    logs: Vec<PathBuf>,
    /// Locus CSV logs reported with the tuned values but not tuned on.
    #[arg(long)]
    held_out_log: Vec<PathBuf>,
    /// MRCLAM robots whose logs the settings are tuned on
    /// (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1u32, 2, 3])]
    tune_on: Vec<u32>,
    /// MRCLAM robots reported with the tuned values but not tuned on.
    #[arg(long, value_delimiter = ',', default_values_t = [4u32, 5])]
    held_out: Vec<u32>,
    /// How to tune: `estimate`, what `locus replay` estimates from each
    /// log alone with no flags (q_v in m^2/s, q_omega in rad^2/s,
    /// sigma_range in m, sigma_bearing in rad, the odometry delay in s);
    /// `drift`, the process noise from how fast dead reckoning drifts
    /// between pose fixes of the sightings, and the odometry delay (the
    /// measurement noise stays built in); `nll`,
    /// Nelder-Mead over the noise and the initial scale factors on the
    /// innovations' negative log-likelihood (no ground truth needed);
    /// `truth`, the same search on the summed position RMSE against the
    /// ground truth, m (for comparison: it needs the truth). The first two
    /// take the median of each value over the tuning logs.
    #[arg(long, value_enum, default_value_t = Objective::Estimate)]
    objective: Objective,
    /// Nelder-Mead iterations at most (`nll`, `truth`).
    #[arg(long, default_value_t = 150)]
    max_iters: u64,
}

/// How `locus tune` tunes: `locus_replay::fleet::Method` on the command
/// line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Objective {
    /// The medians of what `locus replay` estimates from each log.
    Estimate,
    /// The medians of each log's drift estimate of the process noise and
    /// its odometry delay.
    Drift,
    /// Nelder-Mead on the innovations' negative log-likelihood.
    Nll,
    /// Nelder-Mead on the position RMSE against the ground truth, m.
    Truth,
}

impl Objective {
    /// The library's method.
    fn method(self) -> Method {
        match self {
            Objective::Estimate => Method::Estimate,
            Objective::Drift => Method::Drift,
            Objective::Nll => Method::Nll,
            Objective::Truth => Method::Truth,
        }
    }

    /// The name the user types (`--objective estimate`).
    fn name(self) -> String {
        self.to_possible_value()
            .map_or_else(String::new, |v| v.get_name().to_string())
    }
}

/// Runs `locus tune`.
///
/// # Errors
/// Unreadable logs, no tuning log with an estimate, a failed replay or
/// optimisation, standard output closed.
pub fn run(args: &Args) -> Result<()> {
    let (source, tuning, held_out) = read_logs(args)?;
    let options = Options {
        method: args.objective.method(),
        start: Config::default(),
        base: crate::args::replay::default_config(),
        max_iters: args.max_iters,
    };
    let bar = match args.objective {
        Objective::Estimate | Objective::Drift => {
            progress_bar(0, "{pos}/{len} logs estimated, {elapsed} elapsed")?
        }
        Objective::Nll | Objective::Truth => progress_bar(
            args.max_iters * 2 + 7,
            "{pos} evaluations, {elapsed} elapsed",
        )?,
    };
    let tuned = fleet::tune(&tuning, &options, |p| match p {
        Progress::Estimated { done, of } => {
            bar.set_length(of as u64);
            bar.set_position(done as u64);
        }
        Progress::Evaluated { count } => bar.set_position(count),
        _ => {}
    });
    bar.finish_and_clear();
    let tuned = tuned?;
    for l in &tuned.left_out {
        eprintln!(
            "locus tune: warning: {} left out of the tuning: its estimate cannot be computed: {}",
            l.name, l.cause
        );
    }
    let how = match (options.method, tuned.search) {
        (_, Some(s)) => format!(
            "{} Nelder-Mead iterations, {} evaluations",
            s.iterations, s.evaluations
        ),
        (Method::Drift, _) => "process noise from the drift between pose fixes of the \
                               sightings, and the odometry delay, each robot; medians"
            .to_string(),
        _ => "the noise and the odometry delay `locus replay` estimates from each log; medians"
            .to_string(),
    };
    let names = |names: &mut dyn Iterator<Item = &String>| {
        names.map(String::as_str).collect::<Vec<_>>().join(", ")
    };
    let mut text = format!(
        "locus tune {source}: objective {}, tuned on {} ({how}){}, held out {}\n",
        args.objective.name(),
        names(&mut tuned.tuned_on.iter()),
        if tuned.left_out.is_empty() {
            String::new()
        } else {
            format!(
                ", left out {} (no estimate)",
                names(&mut tuned.left_out.iter().map(|l| &l.name))
            )
        },
        if held_out.is_empty() {
            "none".to_string()
        } else {
            names(&mut held_out.iter().map(|(n, _)| n))
        }
    );
    let (start, tuned_cfg) = (&options.start, &tuned.config);
    let mut values = with_header(["parameter [unit]", "built-in (--delay-only)", "tuned"]);
    let rows = [
        (
            "q_v, forward-speed noise PSD [m^2/s]",
            start.q_v,
            tuned_cfg.q_v,
        ),
        (
            "q_omega, turn-rate noise PSD [rad^2/s]",
            start.q_omega,
            tuned_cfg.q_omega,
        ),
        ("sigma_range [m]", start.sigma_range, tuned_cfg.sigma_range),
        (
            "sigma_bearing [rad]",
            start.sigma_bearing,
            tuned_cfg.sigma_bearing,
        ),
        (
            "initial v scale [-]",
            start.calibration.initial[0],
            tuned_cfg.calibration.initial[0],
        ),
        (
            "initial omega scale [-]",
            start.calibration.initial[1],
            tuned_cfg.calibration.initial[1],
        ),
        (
            "odometry delay [s]",
            start.odometry_delay,
            tuned_cfg.odometry_delay,
        ),
    ];
    for (k, a, b) in rows {
        values.add_row(vec![k.to_string(), format!("{a:.5}"), format!("{b:.5}")]);
    }
    text.push_str(&format!("{values}\n"));
    let compared = fleet::compare(&tuning, &held_out, &tuned, start)?;
    text.push_str(&format!("{}\n", comparison_table(&compared)));
    print_out(&text)
}

/// The table of every log replayed with the built-in and the tuned values.
fn comparison_table(compared: &[Comparison]) -> comfy_table::Table {
    let mut table = with_header([
        "log",
        "role",
        "EKF position RMSE built-in / tuned [m]",
        "EKF heading RMSE built-in / tuned [deg]",
        "odometry position RMSE built-in / tuned [m]",
        "gated built-in / tuned [%]",
        "worst inside 3 sigma, x/y/theta, built-in / tuned [%]",
        "innovation NLL built-in / tuned",
    ]);
    for c in compared {
        let pair = |f: &dyn Fn(&Figures) -> Option<f64>, decimals: usize| {
            let one =
                |r: &Figures| f(r).map_or_else(|| "n/a".to_string(), |v| format!("{v:.decimals$}"));
            format!("{} / {}", one(&c.built_in), one(&c.tuned))
        };
        let role = match c.role {
            Role::TunedOn => "tuned on",
            Role::LeftOut => "left out (no estimate)",
            _ => "held out",
        };
        table.add_row(vec![
            c.name.clone(),
            role.to_string(),
            pair(&|r| r.position_rmse_m, 3),
            pair(&|r| r.heading_rmse_rad.map(f64::to_degrees), 2),
            pair(&|r| r.odometry_position_rmse_m, 3),
            pair(&|r| r.gated_share.map(|s| 100.0 * s), 2),
            pair(&|r| r.worst_within_3_sigma.map(|s| 100.0 * s), 1),
            pair(&|r| r.innovation_nll, 0),
        ]);
    }
    table
}

/// The logs of `args`: a name for the output, the logs tuned on and the
/// logs held out (each with its name).
type Named = Vec<(String, Log)>;
fn read_logs(args: &Args) -> Result<(String, Named, Named)> {
    // The robot sets are checked before any log is read.
    check_robot_sets(&args.tune_on, &args.held_out)?;
    let first = &args.logs[0];
    if args.logs.len() == 1 && first.is_dir() {
        if !args.held_out_log.is_empty() {
            return Err(anyhow!(
                "--held-out-log is for Locus CSV logs; an MRCLAM dataset holds out robots \
                 (--held-out)"
            ));
        }
        let dataset = Dataset::open(first)?;
        let read = |robots: &[u32]| -> Result<Named> {
            robots
                .iter()
                .map(|&r| {
                    Ok((
                        format!("robot {r}"),
                        Log::mrclam(&dataset, r).with_context(|| format!("robot {r}"))?,
                    ))
                })
                .collect()
        };
        return Ok((
            dataset.dir().display().to_string(),
            read(&args.tune_on)?,
            read(&args.held_out)?,
        ));
    }
    let read = |paths: &[PathBuf]| -> Result<Named> {
        paths
            .iter()
            .map(|p| {
                if p.is_dir() {
                    return Err(anyhow!(
                        "{}: a directory among log files (an MRCLAM dataset is tuned on alone)",
                        p.display()
                    ));
                }
                Ok((p.display().to_string(), Log::locus_csv(p)?))
            })
            .collect()
    };
    let tuned = read(&args.logs)?;
    let held = read(&args.held_out_log)?;
    if let Some((n, _)) = held.iter().find(|(n, _)| tuned.iter().any(|(m, _)| m == n)) {
        return Err(anyhow!(
            "{n} is both tuned on and held out: a log tuned on cannot be held out"
        ));
    }
    Ok((
        format!("{} CSV logs", tuned.len() + held.len()),
        tuned,
        held,
    ))
}

/// The robot sets must be disjoint and without repeats: a held-out robot
/// that is also tuned on is not held out, and a robot listed twice would
/// count twice. Checked before any work.
fn check_robot_sets(tune_on: &[u32], held_out: &[u32]) -> Result<()> {
    if tune_on.is_empty() {
        return Err(anyhow!("no robot to tune on (--tune-on is empty)"));
    }
    for (flag, set) in [("--tune-on", tune_on), ("--held-out", held_out)] {
        let repeated = set
            .iter()
            .enumerate()
            .find_map(|(i, r)| set[..i].contains(r).then_some(r));
        if let Some(r) = repeated {
            return Err(anyhow!("robot {r} is listed twice in {flag}"));
        }
    }
    if let Some(r) = tune_on.iter().find(|r| held_out.contains(r)) {
        return Err(anyhow!(
            "robot {r} is in both --tune-on and --held-out: a robot tuned on \
             cannot be held out"
        ));
    }
    Ok(())
}
