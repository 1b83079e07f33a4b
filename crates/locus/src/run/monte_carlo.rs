//! `locus run --runs N > 1`: the scenario over `N` seeds in parallel
//! (`rayon`), without step logs; the spread of its metrics over the runs
//! ([`Spread`]) as a table and in `metrics.json` (every figure of a run's
//! [`Results`] replaced by its spread), every run's metrics in `runs.csv`.

use core::ops::Range;
use std::fs;
use std::path::Path;

use anyhow::{Context, Result};
use locus_eval::results::Results;
use locus_eval::{Record, Summary};
use rayon::prelude::*;
use serde::Serialize;

use super::{Info, RunArgs};
use crate::metrics::{self, Metrics, Simulation, Source};
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

/// One row of the Monte Carlo table: label (`{dof}` stands for the
/// NEES's degrees of freedom), display scale and how to read the metric
/// from a summary.
struct Metric {
    label: &'static str,
    scale: f64,
    get: Getter,
}

impl Metric {
    const fn new(label: &'static str, scale: f64, get: Getter) -> Self {
        Self { label, scale, get }
    }
}

/// Centimetres per metre.
const CM: f64 = 100.0;

/// Degrees per radian.
const DEG: f64 = 180.0 / core::f64::consts::PI;

/// The rows of the Monte Carlo table, in order.
const METRICS: [Metric; 6] = [
    Metric::new("EKF position RMSE [cm]", CM, |s| s.position_rmse),
    Metric::new("EKF heading RMSE [deg]", DEG, |s| s.heading_rmse),
    Metric::new("odometry position RMSE [cm]", CM, |s| {
        s.odometry_position_rmse
    }),
    Metric::new("odometry heading RMSE [deg]", DEG, |s| {
        s.odometry_heading_rmse
    }),
    Metric::new("mean NEES ({dof} dof, ideal {dof}) [-]", 1.0, |s| {
        s.mean_nees
    }),
    Metric::new("updates accepted by the gate [%]", 100.0, |s| s.acceptance),
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
    let summaries: Vec<Summary> = runs.iter().map(|(_, s)| *s).collect();
    let section = MonteCarloSection {
        simulation: Simulation::of(info),
        monte_carlo: MonteCarlo {
            first_seed: args.seed,
            runs: runs.len(),
        },
    };
    let metrics_path = metrics::write(
        out,
        &Metrics::new(
            Source::MonteCarlo,
            &info.name,
            spreads(&summaries)?,
            section,
        ),
    )?;

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
        let values: Vec<f64> = runs.iter().map(|(_, s)| (m.get)(s)).collect();
        let mut row = vec![m.label.replace("{dof}", &dof.to_string())];
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
        "seed,steps,duration_s,laps_completed,filter_position_rmse_m,filter_heading_rmse_rad,\
         filter_max_position_error_m,odometry_position_rmse_m,odometry_heading_rmse_rad,\
         odometry_max_position_error_m,mean_nees,nees_in_95_interval_share,readings,\
         associated,applied,acceptance_share,wall_clock_s\n",
    );
    for (seed, s) in runs {
        let fields = [
            seed.to_string(),
            s.steps.to_string(),
            format!("{:.2}", s.duration),
            s.laps_completed.to_string(),
            format!("{:.9}", s.position_rmse),
            format!("{:.9}", s.heading_rmse),
            format!("{:.9}", s.max_position_error),
            csv_num(s.odometry_position_rmse),
            csv_num(s.odometry_heading_rmse),
            csv_num(s.odometry_max_position_error),
            format!("{:.6}", s.mean_nees),
            format!("{:.6}", s.nees_in_interval),
            s.readings.to_string(),
            s.associated.to_string(),
            s.applied.to_string(),
            format!("{:.6}", s.acceptance),
            format!("{:.3}", s.wall_clock),
        ];
        csv.push_str(&fields.join(","));
        csv.push('\n');
    }
    csv
}

/// The Monte Carlo's sections of `metrics.json`: the scenario's settings
/// and the seeds.
#[derive(Serialize)]
struct MonteCarloSection {
    simulation: Simulation,
    monte_carlo: MonteCarlo,
}

/// `metrics.json`'s `monte_carlo`: the seeds `first_seed..first_seed +
/// runs`.
#[derive(Serialize)]
struct MonteCarlo {
    first_seed: u64,
    runs: usize,
}

/// The [`Results`] of every run in `summaries`, each figure replaced by
/// its [`Spread`] over the runs (`null` ones read as NaN): the shape of a
/// single run's results, in its key order, with a spread wherever it has a
/// number.
///
/// # Errors
/// None in practice (the results serialise to JSON objects).
fn spreads(summaries: &[Summary]) -> Result<Tree> {
    let runs = summaries
        .iter()
        .map(|s| {
            let text = serde_json::to_string(&Results::of(s))?;
            serde_json::from_str::<Tree>(&text)
        })
        .collect::<Result<Vec<Tree>, _>>()
        .context("serialising the results")?;
    Ok(spread_of(&runs))
}

/// A run's results as JSON read back in their key order: objects and
/// numbers (`null` as NaN); in a Monte Carlo's `metrics.json`, a
/// [`Spread`] where a run has a number.
#[derive(Debug, Clone, PartialEq)]
enum Tree {
    Object(Vec<(String, Tree)>),
    Number(f64),
    Spread(Spread),
}

impl Serialize for Tree {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Tree::Object(members) => serializer.collect_map(members.iter().map(|(k, v)| (k, v))),
            Tree::Number(v) => serializer.serialize_f64(*v),
            Tree::Spread(s) => s.serialize(serializer),
        }
    }
}

impl<'de> serde::Deserialize<'de> for Tree {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Tree;

            fn expecting(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str("an object, a number or null")
            }

            fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Tree, A::Error> {
                let mut members = Vec::new();
                while let Some(member) = map.next_entry::<String, Tree>()? {
                    members.push(member);
                }
                Ok(Tree::Object(members))
            }

            fn visit_f64<E>(self, v: f64) -> Result<Tree, E> {
                Ok(Tree::Number(v))
            }

            #[allow(clippy::cast_precision_loss)]
            fn visit_u64<E>(self, v: u64) -> Result<Tree, E> {
                Ok(Tree::Number(v as f64))
            }

            #[allow(clippy::cast_precision_loss)]
            fn visit_i64<E>(self, v: i64) -> Result<Tree, E> {
                Ok(Tree::Number(v as f64))
            }

            fn visit_unit<E>(self) -> Result<Tree, E> {
                Ok(Tree::Number(f64::NAN))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

/// [`spreads`] of the trees `runs` (all of the first's shape): an object
/// of the spreads of its members, or the spread of numbers.
fn spread_of(runs: &[Tree]) -> Tree {
    match runs.first() {
        Some(Tree::Object(first)) => Tree::Object(
            first
                .iter()
                .enumerate()
                .map(|(i, (key, _))| {
                    let members: Vec<Tree> = runs
                        .iter()
                        .map(|r| match r {
                            Tree::Object(m) => {
                                m.get(i).map_or(Tree::Number(f64::NAN), |(_, v)| v.clone())
                            }
                            _ => Tree::Number(f64::NAN),
                        })
                        .collect();
                    (key.clone(), spread_of(&members))
                })
                .collect(),
        ),
        _ => {
            let values: Vec<f64> = runs
                .iter()
                .map(|v| match v {
                    Tree::Number(v) => *v,
                    _ => f64::NAN,
                })
                .collect();
            Tree::Spread(Spread::of(&values))
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

    /// A Monte Carlo's results have a run's shape and key order, with a
    /// spread for each number.
    #[test]
    fn the_spreads_keep_the_shape_and_order_of_a_run() {
        let mut tally = locus_eval::Tally::new(3).unwrap();
        tally.count(1.0, true, Some(true));
        let runs = [tally.summary(0), tally.summary(0)];
        let text = crate::metrics::to_json(&spreads(&runs).unwrap()).unwrap();
        let single = crate::metrics::to_json(&Results::of(&runs[0])).unwrap();
        let keys = |t: &str| -> Vec<String> {
            t.lines()
                .filter_map(|l| l.trim().split('"').nth(1).map(str::to_string))
                .filter(|k| !["mean", "std", "min", "max"].contains(&k.as_str()))
                .collect()
        };
        assert_eq!(keys(&text), keys(&single), "{text}");
        assert!(
            text.contains(
                "\"readings\": { \"mean\": 1.0, \"std\": 0.0, \"min\": 1.0, \"max\": 1.0 }"
            ),
            "{text}"
        );
        assert!(
            text.contains("\"position_rmse_m\": { \"mean\": null, \"std\": null, \"min\": null, \"max\": null }"),
            "{text}"
        );
    }

    #[test]
    fn seeds_that_overflow_are_an_error() {
        assert_eq!(seeds(3, 2).unwrap(), 3..5);
        assert!(seeds(u64::MAX, 1).is_err());
    }
}
