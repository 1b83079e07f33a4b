//! `locus tune DIR` (an MRCLAM dataset): estimates the replay's noise (Q as the power
//! spectral densities `q_v`, `q_omega`; R as the range and bearing standard
//! deviations) and the odometry scale factors of `v` and `omega` by
//! minimising the innovations' negative log-likelihood
//! (`locus_replay::Report::innovation_nll`, summed over the tuning robots)
//! with argmin's Nelder-Mead, then reports every robot with the default
//! and the tuned values against ground truth. With `--objective truth` the
//! score is instead the summed position RMSE against the ground truth
//! (tuning *on* the truth, for comparison).

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
    /// `../shared/data/mrclam/MRCLAM_Dataset6`).
    dir: PathBuf,
    /// Robots whose logs the parameters are tuned on (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [1u32, 2, 3])]
    tune_on: Vec<u32>,
    /// Robots reported with the tuned values but not tuned on.
    #[arg(long, value_delimiter = ',', default_values_t = [4u32, 5])]
    held_out: Vec<u32>,
    /// What to minimise: `nll`, the innovations' negative log-likelihood
    /// (no ground truth needed), or `truth`, the summed position RMSE
    /// against the ground truth.
    #[arg(long, value_enum, default_value_t = Objective::Nll)]
    objective: Objective,
    /// Nelder-Mead iterations at most.
    #[arg(long, default_value_t = 150)]
    max_iters: u64,
}

/// The score `locus tune` minimises.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Objective {
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
                Objective::Nll => r.innovation_nll,
                Objective::Truth => r.summary.ekf_position_rmse,
            };
        }
        Ok(if sum.is_finite() { sum } else { f64::MAX })
    }
}

/// Runs `locus tune`.
///
/// # Errors
/// Unreadable logs, a failed replay or optimisation, standard output closed.
pub fn run(args: &Args) -> Result<()> {
    let dataset = Dataset::open(&args.dir)?;
    let read = |robots: &[u32]| -> Result<Vec<Log>> {
        robots
            .iter()
            .map(|&r| Log::mrclam(&dataset, r).with_context(|| format!("robot {r}")))
            .collect()
    };
    let tune_logs = read(&args.tune_on)?;
    let held_logs = read(&args.held_out)?;
    if tune_logs.is_empty() {
        return Err(anyhow!("no robot to tune on"));
    }
    let start = Config::default();
    let p0 = to_params(&start);
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
            logs: &tune_logs,
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

    let mut text = format!(
        "locus tune {}: objective {:?}, tuned on robots {:?} ({} Nelder-Mead iterations, {} evaluations), held out {:?}\n",
        dataset.dir().display(),
        args.objective,
        args.tune_on,
        state.get_iter(),
        bar.position(),
        args.held_out
    );
    let mut values = with_header(["parameter [unit]", "default", "tuned"]);
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
    ];
    for (k, a, b) in rows {
        values.add_row(vec![k.to_string(), format!("{a:.5}"), format!("{b:.5}")]);
    }
    text.push_str(&format!("{values}\n"));

    let mut table = with_header([
        "robot",
        "role",
        "EKF position RMSE default / tuned [m]",
        "EKF heading RMSE default / tuned [deg]",
        "odometry position RMSE default / tuned [m]",
        "gated default / tuned [%]",
        "innovation NLL default / tuned",
    ]);
    let all = args
        .tune_on
        .iter()
        .zip(&tune_logs)
        .map(|(r, l)| (*r, "tuned on", l))
        .chain(
            args.held_out
                .iter()
                .zip(&held_logs)
                .map(|(r, l)| (*r, "held out", l)),
        );
    for (robot, role, log) in all {
        let a: Report = replay(log, &start, |_| {})?;
        let b: Report = replay(log, &tuned, |_| {})?;
        let (sa, sb) = (&a.summary, &b.summary);
        table.add_row(vec![
            robot.to_string(),
            role.to_string(),
            format!("{:.3} / {:.3}", sa.ekf_position_rmse, sb.ekf_position_rmse),
            format!(
                "{:.2} / {:.2}",
                sa.ekf_heading_rmse.to_degrees(),
                sb.ekf_heading_rmse.to_degrees()
            ),
            format!(
                "{:.3} / {:.3}",
                sa.odometry_position_rmse, sb.odometry_position_rmse
            ),
            format!(
                "{:.2} / {:.2}",
                100.0 * a.gated_share(),
                100.0 * b.gated_share()
            ),
            format!("{:.0} / {:.0}", a.innovation_nll, b.innovation_nll),
        ]);
    }
    text.push_str(&format!("{table}\n"));
    print_out(&text)
}
