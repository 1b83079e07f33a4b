//! `locus tune LOGS...`: settings for a fleet. The replay estimates its
//! noise from each log by itself (`locus_replay::policy`); `locus tune`
//! estimates on some logs (robots), combines the estimates by their
//! median, and reports every log replayed with the built-in values
//! (`--delay-only`) and with the tuned ones against its ground truth, the
//! tuning logs beside the held-out ones. The logs are a UTIAS MRCLAM
//! dataset directory (robots chosen with `--tune-on` and `--held-out`) or
//! Locus CSV logs (every one given tuned on; `--held-out-log` adds logs
//! only reported).
//!
//! * `--objective estimate` (the default): what `locus replay` estimates
//!   from each log with no flags (noise, odometry delay), medians.
//! * `--objective drift`: the process noise from the drift of dead
//!   reckoning between pose fixes, and the odometry delay, medians.
//! * `--objective nll`: argmin's Nelder-Mead on the innovations' negative
//!   log-likelihood (`locus_replay::Report::innovation_nll`, summed over
//!   the tuning logs) over the noise and the initial scale factors.
//! * `--objective truth`: the same search on the summed position RMSE
//!   against the ground truth (tuning *on* the truth, for comparison).
//!
//! A tuning log whose estimate cannot be computed (fewer than two odometry
//! records, no landmark sightings, an estimate that fails or comes out
//! non-finite or not positive) is named with the cause in a warning and left out: one
//! such log would otherwise move every median to another log's value. The
//! run fails, naming each log and its cause, when no log is left. A figure
//! of the table that cannot be computed (no motion compared with the
//! truth, no sighting judged) reads "n/a".

use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use clap::Args as ClapArgs;
use indicatif::ProgressBar;
use locus_logs::mrclam::Dataset;
use locus_replay::{Config, Log, Report, replay};

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
    /// How to estimate: `estimate`, what `locus replay` estimates from
    /// each log alone with no flags (the noise and the odometry delay);
    /// `drift`, the process noise from how fast dead reckoning drifts
    /// between pose fixes of the sightings, and the odometry delay; `nll`,
    /// Nelder-Mead on the innovations' negative log-likelihood (no ground
    /// truth needed); `truth`, Nelder-Mead on the summed position RMSE
    /// against the ground truth (for comparison: it needs the truth). The
    /// first two take the median of each value over the tuning logs.
    #[arg(long, value_enum, default_value_t = Objective::Estimate)]
    objective: Objective,
    /// Nelder-Mead iterations at most.
    #[arg(long, default_value_t = 150)]
    max_iters: u64,
}

/// The score `locus tune` minimises.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Objective {
    /// `locus_replay::policy::settle` with the noise estimated on each
    /// log, medians combined.
    Estimate,
    /// `locus_replay::drift::process_noise` and the odometry delay on each
    /// log, medians combined.
    Drift,
    /// Innovations' negative log-likelihood.
    Nll,
    /// Position RMSE against the ground truth.
    Truth,
}

/// The parameters searched: `[ln q_v, ln q_omega, ln sigma_range,
/// ln sigma_bearing, v_scale, omega_scale]` (logs keep the noises positive).
fn to_params(c: &Config) -> Vec<f64> {
    vec![
        c.q_v.ln(),
        c.q_omega.ln(),
        c.sigma_range.ln(),
        c.sigma_bearing.ln(),
        c.calibration.initial[0],
        c.calibration.initial[1],
    ]
}

fn from_params(p: &[f64]) -> Config {
    let mut c = Config {
        q_v: p[0].exp(),
        q_omega: p[1].exp(),
        sigma_range: p[2].exp(),
        sigma_bearing: p[3].exp(),
        ..Config::default()
    };
    c.calibration.initial[0] = p[4];
    c.calibration.initial[1] = p[5];
    c
}

/// The objective: summed innovation NLL over the tuning logs.
struct Problem<'a> {
    logs: &'a [Log],
    bar: &'a ProgressBar,
    objective: Objective,
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        self.bar.inc(1);
        let cfg = from_params(p);
        if cfg.validate().is_err() {
            // Outside the valid domain (a scale <= 0, an overflow): worse
            // than any valid point.
            return Ok(f64::MAX);
        }
        let mut sum = 0.0;
        for log in self.logs {
            let r = replay(log, &cfg, |_| {})?;
            sum += match self.objective {
                Objective::Nll | Objective::Estimate | Objective::Drift => r.innovation_nll,
                Objective::Truth => r.summary.ekf_position_rmse,
            };
        }
        Ok(if sum.is_finite() { sum } else { f64::MAX })
    }
}

/// Runs `locus tune`.
///
/// # Errors
/// Unreadable logs, no tuning log with an estimate, a failed replay or
/// optimisation, standard output closed.
pub fn run(args: &Args) -> Result<()> {
    let (source, tuned_on, held_out) = read_logs(args)?;
    let start = Config::default();
    // Logs with nothing to estimate from are left out before any work.
    let mut left_out: Vec<LeftOut> = Vec::new();
    let usable: Named = tuned_on
        .iter()
        .filter(|(name, log)| match no_basis(log) {
            Some(cause) => {
                left_out.push(LeftOut {
                    name: name.clone(),
                    cause,
                });
                false
            }
            None => true,
        })
        .cloned()
        .collect();
    let (tuned, how) = match args.objective {
        Objective::Drift => drift_on(&usable, &start, &mut left_out)?,
        Objective::Estimate => estimate_on(&usable, &start, &mut left_out)?,
        Objective::Nll | Objective::Truth => {
            let logs: Vec<Log> = usable.iter().map(|(_, l)| l.clone()).collect();
            if logs.is_empty() {
                return Err(none_left(&left_out));
            }
            nelder_mead(args, &logs, &start)?
        }
    };
    for l in &left_out {
        eprintln!(
            "locus tune: warning: {} left out of the tuning: its estimate cannot be computed: {}",
            l.name, l.cause
        );
    }
    let names = |logs: &[(String, Log)]| {
        logs.iter()
            .map(|(n, _)| n.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let tuned_names: Named = tuned_on
        .iter()
        .filter(|(n, _)| !left_out.iter().any(|l| &l.name == n))
        .cloned()
        .collect();
    let mut text = format!(
        "locus tune {source}: objective {:?}, tuned on {} ({how}){}, held out {}\n",
        args.objective,
        names(&tuned_names),
        if left_out.is_empty() {
            String::new()
        } else {
            let each: Vec<&str> = left_out.iter().map(|l| l.name.as_str()).collect();
            format!(", left out {} (no estimate)", each.join(", "))
        },
        if held_out.is_empty() {
            "none".to_string()
        } else {
            names(&held_out)
        }
    );
    let mut values = with_header(["parameter [unit]", "built-in (--delay-only)", "tuned"]);
    let rows = [
        ("q_v, forward-speed noise PSD [m^2/s]", start.q_v, tuned.q_v),
        (
            "q_omega, turn-rate noise PSD [rad^2/s]",
            start.q_omega,
            tuned.q_omega,
        ),
        ("sigma_range [m]", start.sigma_range, tuned.sigma_range),
        (
            "sigma_bearing [rad]",
            start.sigma_bearing,
            tuned.sigma_bearing,
        ),
        (
            "initial v scale [-]",
            start.calibration.initial[0],
            tuned.calibration.initial[0],
        ),
        (
            "initial omega scale [-]",
            start.calibration.initial[1],
            tuned.calibration.initial[1],
        ),
        (
            "odometry delay [s]",
            start.odometry_delay,
            tuned.odometry_delay,
        ),
    ];
    for (k, a, b) in rows {
        values.add_row(vec![k.to_string(), format!("{a:.5}"), format!("{b:.5}")]);
    }
    text.push_str(&format!("{values}\n"));

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
    let role = |n: &String| {
        if left_out.iter().any(|l| &l.name == n) {
            "left out (no estimate)"
        } else {
            "tuned on"
        }
    };
    let all = tuned_on
        .iter()
        .map(|(n, l)| (n, role(n), l))
        .chain(held_out.iter().map(|(n, l)| (n, "held out", l)));
    for (robot, role, log) in all {
        let a: Report = replay(log, &start, |_| {})?;
        let b: Report = replay(log, &tuned, |_| {})?;
        // Against the truth: only over a run that moved and was compared.
        let moved = |r: &Report| r.odometry >= 2 && r.compared >= 2;
        let judged = |r: &Report| r.applied + r.gated > 0;
        let pair = |f: &dyn Fn(&Report) -> Option<f64>, decimals: usize| {
            let one = |r: &Report| {
                f(r).filter(|v| v.is_finite())
                    .map_or_else(|| "n/a".to_string(), |v| format!("{v:.decimals$}"))
            };
            format!("{} / {}", one(&a), one(&b))
        };
        table.add_row(vec![
            robot.to_string(),
            role.to_string(),
            pair(&|r| moved(r).then_some(r.summary.ekf_position_rmse), 3),
            pair(
                &|r| moved(r).then_some(r.summary.ekf_heading_rmse.to_degrees()),
                2,
            ),
            pair(&|r| moved(r).then_some(r.summary.odometry_position_rmse), 3),
            pair(&|r| judged(r).then(|| 100.0 * r.gated_share()), 2),
            pair(
                &|r| moved(r).then(|| 100.0 * worst(&r.summary.within_3_sigma)),
                1,
            ),
            pair(&|r| judged(r).then_some(r.innovation_nll), 0),
        ]);
    }
    text.push_str(&format!("{table}\n"));
    print_out(&text)
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

fn worst(shares: &[f64; 3]) -> f64 {
    shares.iter().copied().fold(f64::INFINITY, f64::min)
}

/// The median of `values` (the upper one of an even count).
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

/// A tuning log left out of the tuning, and why.
struct LeftOut {
    name: String,
    cause: String,
}

/// Why `log` has nothing to estimate from, if so: fewer than two odometry
/// records (no motion) or no landmark sightings (no innovation).
fn no_basis(log: &Log) -> Option<String> {
    let n = log.odometry.len();
    if n < 2 {
        Some(format!(
            "{n} odometry record{}: no motion to estimate from (at least 2 needed)",
            if n == 1 { "" } else { "s" }
        ))
    } else if log.sightings.is_empty() {
        Some("no landmark sightings: no innovation to estimate from".to_string())
    } else {
        None
    }
}

/// The error of a run whose every tuning log was left out.
fn none_left(left_out: &[LeftOut]) -> anyhow::Error {
    let each: Vec<String> = left_out
        .iter()
        .map(|l| format!("{}: {}", l.name, l.cause))
        .collect();
    anyhow!(
        "no tuning log has an estimate, nothing to tune on: {}",
        each.join("; ")
    )
}

/// `estimate` on each of `logs`, in order, with a progress bar; the
/// estimates of the logs where it succeeds and every named value (`values`)
/// is finite and `> 0` (`>= 0` for a delay), the others added to
/// `left_out` with the cause. Fails when no log is left.
fn each_log<T>(
    logs: &[(String, Log)],
    estimate: impl Fn(&Log) -> Result<T>,
    values: impl Fn(&T) -> Vec<(&'static str, f64)>,
    left_out: &mut Vec<LeftOut>,
) -> Result<Vec<T>> {
    let bar = progress_bar(
        logs.len() as u64,
        "{pos}/{len} logs estimated, {elapsed} elapsed",
    )?;
    let mut each = Vec::with_capacity(logs.len());
    for (name, log) in logs {
        let cause = match estimate(log) {
            Ok(e) => {
                let bad = values(&e).into_iter().find(|&(k, v)| {
                    !v.is_finite() || v < 0.0 || (v == 0.0 && k != "odometry delay")
                });
                match bad {
                    None => {
                        each.push(e);
                        None
                    }
                    Some((k, v)) => {
                        Some(format!("its {k} came out {v} (the log does not tell it)"))
                    }
                }
            }
            Err(e) => Some(format!("{e:#}")),
        };
        if let Some(cause) = cause {
            left_out.push(LeftOut {
                name: name.clone(),
                cause,
            });
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    if each.is_empty() {
        return Err(none_left(left_out));
    }
    Ok(each)
}

/// The odometry delay and then `locus_replay::drift::process_noise` on
/// each log from `start`, combined by the median of each; and how it was
/// reached.
fn drift_on(
    logs: &[(String, Log)],
    start: &Config,
    left_out: &mut Vec<LeftOut>,
) -> Result<(Config, String)> {
    let each = each_log(
        logs,
        |log| {
            let (delay, _) = locus_replay::noise::estimate_delay(log, start)
                .with_context(|| format!("estimating the odometry delay of {}", log.name))?;
            let cfg = Config {
                odometry_delay: delay,
                ..*start
            };
            let d = locus_replay::drift::process_noise(log, &cfg)
                .with_context(|| format!("estimating the process noise of {}", log.name))?;
            Ok((d.q_v, d.q_omega, delay))
        },
        |e| vec![("q_v", e.0), ("q_omega", e.1), ("odometry delay", e.2)],
        left_out,
    )?;
    let tuned = Config {
        q_v: median(each.iter().map(|e| e.0).collect()),
        q_omega: median(each.iter().map(|e| e.1).collect()),
        odometry_delay: median(each.iter().map(|e| e.2).collect()),
        ..*start
    };
    Ok((
        tuned,
        "process noise from the drift between pose fixes of the sightings, and the odometry \
         delay, each robot; medians"
            .to_string(),
    ))
}

/// What `locus replay` estimates from each log with no flags
/// (`locus_replay::policy::settle`, `Estimation::Noise`), combined by the
/// median of each value; and how it was reached.
fn estimate_on(
    logs: &[(String, Log)],
    start: &Config,
    left_out: &mut Vec<LeftOut>,
) -> Result<(Config, String)> {
    use locus_replay::policy::{Estimation, Overrides, settle};
    let overrides = Overrides {
        estimation: Estimation::Noise,
        ..Overrides::default()
    };
    let base = crate::replay::default_config();
    let each = each_log(
        logs,
        |log| {
            Ok(settle(log, &base, &overrides)
                .with_context(|| format!("estimating the noise of {}", log.name))?
                .config)
        },
        |c| {
            vec![
                ("q_v", c.q_v),
                ("q_omega", c.q_omega),
                ("sigma_range", c.sigma_range),
                ("sigma_bearing", c.sigma_bearing),
                ("odometry delay", c.odometry_delay),
            ]
        },
        left_out,
    )?;
    let pick = |f: fn(&Config) -> f64| median(each.iter().map(f).collect());
    let tuned = Config {
        q_v: pick(|c| c.q_v),
        q_omega: pick(|c| c.q_omega),
        sigma_range: pick(|c| c.sigma_range),
        sigma_bearing: pick(|c| c.sigma_bearing),
        odometry_delay: pick(|c| c.odometry_delay),
        ..*start
    };
    Ok((
        tuned,
        "the noise and the odometry delay `locus replay` estimates from each log; medians"
            .to_string(),
    ))
}

/// Nelder-Mead on `args.objective` over the noise and the initial scale
/// factors, from `start`; and how it was reached.
fn nelder_mead(args: &Args, tune_logs: &[Log], start: &Config) -> Result<(Config, String)> {
    let p0 = to_params(start);
    // Initial simplex: the default and one vertex per parameter, each
    // moved by a factor e^0.5 (noises) or by 5 % (scales).
    let mut simplex = vec![p0.clone()];
    for i in 0..p0.len() {
        let mut v = p0.clone();
        v[i] += if i < 4 { 0.5 } else { 0.05 };
        simplex.push(v);
    }
    let bar = progress_bar(
        args.max_iters * 2 + 7,
        "{pos} evaluations, {elapsed} elapsed",
    )?;
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(1e-3)
        .map_err(|e| anyhow!("Nelder-Mead: {e}"))?;
    let result = Executor::new(
        Problem {
            logs: tune_logs,
            bar: &bar,
            objective: args.objective,
        },
        solver,
    )
    .configure(|s| s.max_iters(args.max_iters))
    .run()
    .map_err(|e| anyhow!("Nelder-Mead: {e}"))?;
    bar.finish_and_clear();
    let state = result.state();
    let best = state
        .get_best_param()
        .ok_or_else(|| anyhow!("Nelder-Mead returned no parameters"))?;
    let tuned = from_params(best);

    Ok((
        tuned,
        format!(
            "{} Nelder-Mead iterations, {} evaluations",
            state.get_iter(),
            bar.position()
        ),
    ))
}
