//! `metrics.json`, written by `locus run` (one run or a Monte Carlo) and
//! `locus replay` through serde (`serde_json`), in the one schema of
//! [`locus_eval::results`] (`docs/metrics.schema.json`, `docs/results.md`):
//! the [`SCHEMA`](locus_eval::results::SCHEMA) tag, the source and its name, the source-neutral
//! [`Results`](locus_eval::results::Results), then the section of the source (`simulation`,
//! `monte_carlo`, `replay`). Figures in SI units under keys that name the
//! unit; a figure that cannot be computed (NaN) is `null`, never 0.
//!
//! Layout: one key per line for the file and its sections; an object
//! inside a section (a calibration term, a Monte Carlo spread, the
//! replay's start) on the line of its key.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use crate::run::Info;

pub use locus_eval::results::{Metrics, Source};

/// The `simulation` section of a `metrics.json`: the scenario's settings
/// (and of one run, its seed and laps completed).
#[derive(Debug, Serialize)]
pub struct Simulation {
    /// Seed of a single run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Filter step, s.
    pub dt_s: f64,
    /// Laps to drive (scenarios that drive laps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub laps: Option<usize>,
    /// Laps completed (one run of a scenario that drives laps).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub laps_completed: Option<usize>,
}

impl Simulation {
    /// The settings of the scenario `info`, without a seed or laps
    /// completed.
    #[must_use]
    pub fn of(info: &Info) -> Self {
        Self {
            seed: None,
            dt_s: info.dt,
            laps: info.laps,
            laps_completed: None,
        }
    }
}

/// The section of one simulated run.
#[derive(Serialize)]
pub struct SimulationSection {
    /// The scenario's settings.
    pub simulation: Simulation,
}

/// A JSON formatter: the file and its sections one key per line (indented
/// by two spaces a level), objects deeper down on one line
/// (`{ "mean": 1.0, "std": 0.5 }`).
#[derive(Default)]
struct Formatter {
    depth: usize,
}

impl Formatter {
    /// The deepest level written one key per line: the file's keys and
    /// its sections'.
    const LINES: usize = 2;

    /// A line break and the indentation of `depth`.
    fn indent<W: ?Sized + io::Write>(w: &mut W, depth: usize) -> io::Result<()> {
        w.write_all(b"\n")?;
        w.write_all(&b"  ".repeat(depth))
    }
}

impl serde_json::ser::Formatter for Formatter {
    fn begin_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth += 1;
        w.write_all(b"{")
    }

    fn end_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth -= 1;
        if self.depth < Self::LINES {
            Self::indent(w, self.depth)?;
            w.write_all(b"}")
        } else {
            w.write_all(b" }")
        }
    }

    fn begin_object_key<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        if !first {
            w.write_all(b",")?;
        }
        if self.depth <= Self::LINES {
            Self::indent(w, self.depth)
        } else {
            w.write_all(b" ")
        }
    }

    fn begin_object_value<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        w.write_all(b": ")
    }
}

/// `metrics` as the text of a `metrics.json` (ending with a newline).
///
/// # Errors
/// A value serde cannot serialise (none of the metrics types).
pub fn to_json(metrics: &impl Serialize) -> Result<String> {
    let mut text = Vec::new();
    metrics
        .serialize(&mut serde_json::Serializer::with_formatter(
            &mut text,
            Formatter::default(),
        ))
        .context("serialising the metrics")?;
    text.push(b'\n');
    String::from_utf8(text).context("serialising the metrics")
}

/// Writes `metrics` to `metrics.json` in `dir`; returns its path.
///
/// # Errors
/// The file cannot be written.
pub fn write(dir: &Path, metrics: &impl Serialize) -> Result<PathBuf> {
    let path = dir.join("metrics.json");
    fs::write(&path, to_json(metrics)?).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use locus_eval::Summary;
    use locus_eval::results::Results;

    fn summary() -> Summary {
        Summary {
            steps: 3,
            compared: 3,
            duration: 0.03,
            laps_completed: 0,
            position_rmse: 0.0117,
            heading_rmse: 0.02,
            heading_offset: 0.01,
            heading_rmse_about_offset: f64::NAN,
            within_3_sigma_heading_about_offset: f64::NAN,
            mean_nees_about_offset: f64::NAN,
            max_position_error: 0.05,
            odometry_position_rmse: f64::NAN,
            odometry_heading_rmse: f64::NAN,
            odometry_max_position_error: f64::INFINITY,
            mean_nees: 3.0,
            nees_dof: 3,
            nees_in_interval: 1.0,
            within_3_sigma: [1.0, 1.0, f64::NAN],
            readings: 2,
            associated: 2,
            applied: 1,
            acceptance: 0.5,
            wall_clock: 0.001,
            real_time_factor: 30.0,
        }
    }

    #[test]
    fn a_missing_figure_is_null_and_the_keys_keep_their_order() {
        let section = SimulationSection {
            simulation: Simulation {
                seed: Some(7),
                dt_s: 0.01,
                laps: Some(2),
                laps_completed: Some(0),
            },
        };
        let text = to_json(&Metrics::new(
            Source::Simulation,
            "a \"quoted\" name",
            Results::of(&summary()),
            section,
        ))
        .unwrap();
        assert!(
            text.starts_with(
                "{\n  \"schema\": \"locus-metrics/2\",\n  \"source\": \"simulation\",\n  \
                 \"scenario\": \"a \\\"quoted\\\" name\",\n  \"steps\": 3,\n  \
                 \"duration_s\": 0.03,\n  \"filter\": {\n    \"compared\": 3,\n    \
                 \"position_rmse_m\": 0.0117,\n"
            ),
            "{text}"
        );
        assert!(
            text.contains("\n  \"odometry\": {\n    \"position_rmse_m\": null,\n"),
            "{text}"
        );
        assert!(
            text.contains("\n    \"max_position_error_m\": null\n  },\n"),
            "{text}"
        );
        assert!(
            text.ends_with(
                "\n  \"simulation\": {\n    \"seed\": 7,\n    \"dt_s\": 0.01,\n    \
                 \"laps\": 2,\n    \"laps_completed\": 0\n  }\n}\n"
            ),
            "{text}"
        );
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(value["filter"]["position_rmse_m"], 0.0117);
        assert_eq!(value["filter"]["within_3_sigma_heading_share"], Value::Null);
        assert_eq!(value["counts"]["readings"], 2);
        assert_eq!(value["counts"]["applied"], 1);
        assert!(value.get("smoother").is_none());
    }

    use serde_json::Value;

    #[test]
    fn objects_below_the_sections_stand_on_one_line() {
        #[derive(Serialize)]
        struct Spread {
            mean: f64,
            std: f64,
        }
        #[derive(Serialize)]
        struct Section {
            x: Spread,
        }
        #[derive(Serialize)]
        struct Outer {
            runs: usize,
            section: Section,
        }
        let text = to_json(&Outer {
            runs: 4,
            section: Section {
                x: Spread {
                    mean: 1.5,
                    std: f64::NAN,
                },
            },
        })
        .unwrap();
        assert_eq!(
            text,
            "{\n  \"runs\": 4,\n  \"section\": {\n    \"x\": { \"mean\": 1.5, \"std\": null }\n  }\n}\n"
        );
    }
}
