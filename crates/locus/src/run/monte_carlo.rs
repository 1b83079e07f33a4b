//! `locus run --runs N > 1`: the scenario over `N` seeds in parallel
//! (`rayon`), without step logs; the spread of its metrics over the runs
//! ([`Spread`]) as a table and in `metrics.json`, every run's metrics in
//! `runs.csv`.

use core::ops::Range;
use std::fs;
use std::path::Path;

use anyhow::{Context, Result};
use locus_eval::{Record, Summary};
use rayon::prelude::*;
use serde::Serialize;

use super::{Info, RunArgs};
use crate::metrics::{self, Settings};
use crate::output::{print_out, progress_bar};
use crate::table::{fig, with_header};

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

/// One Monte Carlo metric: JSON key (SI), table label (`None`: in
/// `metrics.json` only; `{dof}` stands for the NEES's degrees of freedom),
/// display scale and how to read it from a summary.
struct Metric {
    key: &'static str,
    label: Option<&'static str>,
    scale: f64,
    get: Getter,
}

impl Metric {
    const fn new(key: &'static str, label: Option<&'static str>, scale: f64, get: Getter) -> Self {
        Self {
            key,
            label,
            scale,
            get,
        }
    }
}

/// Centimetres per metre.
const CM: f64 = 100.0;

/// Degrees per radian.
const DEG: f64 = 180.0 / core::f64::consts::PI;

/// The metrics summarised over Monte Carlo runs, in the order of the table
/// and of `metrics.json`.
const METRICS: [Metric; 8] = [
    Metric::new(
        "ekf_position_rmse_m",
        Some("EKF position RMSE [cm]"),
        CM,
        |s| s.ekf_position_rmse,
    ),
    Metric::new(
        "ekf_heading_rmse_rad",
        Some("EKF heading RMSE [deg]"),
        DEG,
        |s| s.ekf_heading_rmse,
    ),
    Metric::new(
        "odometry_position_rmse_m",
        Some("odometry position RMSE [cm]"),
        CM,
        |s| s.odometry_position_rmse,
    ),
    Metric::new(
        "odometry_heading_rmse_rad",
        Some("odometry heading RMSE [deg]"),
        DEG,
        |s| s.odometry_heading_rmse,
    ),
    Metric::new(
        "mean_nees",
        Some("mean NEES ({dof} dof, ideal {dof}) [-]"),
        1.0,
        |s| s.mean_nees,
    ),
    Metric::new(
        "acceptance_share",
        Some("updates accepted by the gate [%]"),
        100.0,
        |s| s.acceptance,
    ),
    Metric::new("ekf_max_position_error_m", None, CM, |s| {
        s.ekf_max_position_error
    }),
    Metric::new("nees_in_95_interval_share", None, 100.0, |s| {
        s.nees_in_interval
    }),
];

/// The seeds `first..first + runs`.
///
/// # Errors
/// The range overflows `u64`.
pub(crate) fn seeds(first: u64, runs: u64) -> Result<Range<u64>> {
    let end = first
        .checked_add(runs)
        .context("--seed + --runs overflows u64")?;
    Ok(first..end)
}

/// Runs the scenario over the seeds `args.seed..args.seed + args.runs` in
/// parallel, without step logs; prints the Monte Carlo table, writes
/// `runs.csv` and `metrics.json`.
pub(super) fn monte_carlo<R, E, F>(args: &RunArgs, info: &Info, out: &Path, runner: F) -> Result<()>
where
    R: Record,
    E: core::error::Error + Send + Sync + 'static,
    F: Fn(u64, &mut dyn FnMut(&R)) -> Result<Summary, E> + Sync,
{
    let seeds = seeds(args.seed, args.runs)?;
    let bar = progress_bar(args.runs, "{pos}/{len} runs, {elapsed} elapsed, eta {eta}")?;
    let started = std::time::Instant::now();
    let results: Vec<(u64, Result<Summary, E>)> = seeds
        .clone()
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
    let metrics_path = metrics::write(out, &MonteCarloMetrics::new(info, args.seed, &runs))?;

    let laps = info
        .laps
        .map_or_else(String::new, |l| format!(", {l} laps each"));
    let mut text = format!(
        "locus run {}: {}, Monte Carlo over {} runs (seeds {}..={}){laps}, {:.1} s wall clock\n",
        info.name,
        info.title,
        runs.len(),
        seeds.start,
        seeds.end - 1,
        wall_clock
    );
    let mut table = with_header(["metric over runs [unit]", "mean", "std (n-1)", "min", "max"]);
    let dof = runs.first().map_or(0, |(_, s)| s.nees_dof);
    for m in &METRICS {
        let Some(label) = m.label else { continue };
        let values: Vec<f64> = runs.iter().map(|(_, s)| (m.get)(s)).collect();
        let mut row = vec![label.replace("{dof}", &dof.to_string())];
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
/// [`Spread`] over the runs of each of the [`METRICS`] (SI).
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

impl<'a> MonteCarloMetrics<'a> {
    /// The metrics of `runs` from `first_seed`.
    fn new(info: &'a Info, first_seed: u64, runs: &[(u64, Summary)]) -> Self {
        let spreads = METRICS
            .iter()
            .map(|m| {
                let values: Vec<f64> = runs.iter().map(|(_, s)| (m.get)(s)).collect();
                (m.key, Spread::of(&values))
            })
            .collect();
        Self {
            settings: Settings {
                first_seed: Some(first_seed),
                runs: Some(runs.len()),
                ..Settings::of(info)
            },
            spreads,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spread_uses_the_sample_deviation() {
        let s = Spread::of(&[1.0, 2.0, 3.0]);
        assert_eq!(s.figures(), [2.0, 1.0, 1.0, 3.0]);
        assert_eq!(Spread::of(&[5.0]).std, 0.0);
        assert!(Spread::of(&[f64::NAN, 1.0]).mean.is_nan());
    }

    #[test]
    fn a_missing_figure_leaves_its_csv_field_empty() {
        assert_eq!(csv_num(f64::NAN), "");
        assert_eq!(csv_num(0.5), "0.500000000");
    }

    #[test]
    fn seeds_that_overflow_are_an_error() {
        assert_eq!(seeds(3, 2).unwrap(), 3..5);
        assert!(seeds(u64::MAX, 1).is_err());
    }
}
