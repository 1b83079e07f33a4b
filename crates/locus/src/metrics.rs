//! `metrics.json`, written by `locus run` and `locus replay` through serde
//! (`serde_json`): the settings, then the figures in SI units under keys
//! that name the unit (`_m`, `_rad`, `_s`, `_share`). A figure that cannot
//! be computed (NaN, e.g. odometry in a scenario without it) is `null`,
//! never 0.
//!
//! Layout: one key per line; a nested object (the spread of a Monte Carlo
//! metric) on the line of its key.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use locus_eval::Summary;
use serde::Serialize;

use crate::run::Info;

/// The settings that open every `metrics.json`: the scenario, its seed (one
/// run) or first seed and number of runs (a Monte Carlo), the filter step
/// and the laps (scenarios that drive laps).
#[derive(Debug, Serialize)]
pub struct Settings<'a> {
    /// Scenario or log name.
    pub scenario: &'a str,
    /// Seed of a single run.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// First seed of a Monte Carlo.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_seed: Option<u64>,
    /// Runs of a Monte Carlo.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runs: Option<usize>,
    /// Filter step (s).
    pub dt_s: f64,
    /// Laps to drive.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub laps: Option<usize>,
}

impl<'a> Settings<'a> {
    /// The settings of the scenario `info`, without seeds.
    #[must_use]
    pub fn of(info: &'a Info) -> Self {
        Self {
            scenario: &info.name,
            seed: None,
            first_seed: None,
            runs: None,
            dt_s: info.dt,
            laps: info.laps,
        }
    }
}

/// A [`Summary`] under the keys of `metrics.json` (in this order).
#[derive(Serialize)]
#[serde(remote = "Summary")]
struct SummaryKeys {
    steps: usize,
    #[serde(rename = "sim_time_s")]
    sim_time: f64,
    laps_completed: usize,
    #[serde(rename = "ekf_position_rmse_m")]
    ekf_position_rmse: f64,
    #[serde(rename = "ekf_heading_rmse_rad")]
    ekf_heading_rmse: f64,
    #[serde(rename = "ekf_heading_offset_rad")]
    ekf_heading_offset: f64,
    #[serde(rename = "ekf_heading_rmse_about_offset_rad")]
    ekf_heading_rmse_about_offset: f64,
    #[serde(rename = "within_3_sigma_heading_about_offset_share")]
    within_3_sigma_heading_about_offset: f64,
    mean_nees_about_offset: f64,
    #[serde(rename = "ekf_max_position_error_m")]
    ekf_max_position_error: f64,
    #[serde(rename = "odometry_position_rmse_m")]
    odometry_position_rmse: f64,
    #[serde(rename = "odometry_heading_rmse_rad")]
    odometry_heading_rmse: f64,
    #[serde(rename = "odometry_max_position_error_m")]
    odometry_max_position_error: f64,
    mean_nees: f64,
    #[serde(rename = "nees_in_95_interval_share")]
    nees_in_interval: f64,
    /// Measurements of any kind (the key is named for the square's IR
    /// sensors).
    #[serde(rename = "ir_readings")]
    readings: usize,
    associated: usize,
    corrections: usize,
    #[serde(rename = "acceptance_share")]
    acceptance: f64,
    #[serde(rename = "wall_clock_s")]
    wall_clock: f64,
    nees_dof: u32,
    real_time_factor: f64,
}

/// `metrics.json` of one run or replay: the settings, the summary, then
/// the fields of `extra` (`()` for none).
#[derive(Serialize)]
pub struct RunMetrics<'a, E: Serialize> {
    /// Scenario and settings.
    #[serde(flatten)]
    pub settings: Settings<'a>,
    /// The run's summary.
    #[serde(flatten, with = "SummaryKeys")]
    pub summary: Summary,
    /// More fields, after the summary's.
    #[serde(flatten)]
    pub extra: E,
}

/// A JSON formatter: the outer object one key per line (indented by two
/// spaces), nested objects on one line (`{ "mean": 1.0, "std": 0.5 }`).
#[derive(Default)]
struct Formatter {
    depth: usize,
}

impl serde_json::ser::Formatter for Formatter {
    fn begin_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth += 1;
        w.write_all(b"{")
    }

    fn end_object<W: ?Sized + io::Write>(&mut self, w: &mut W) -> io::Result<()> {
        self.depth -= 1;
        w.write_all(if self.depth == 0 { b"\n}" } else { b" }" })
    }

    fn begin_object_key<W: ?Sized + io::Write>(
        &mut self,
        w: &mut W,
        first: bool,
    ) -> io::Result<()> {
        if !first {
            w.write_all(b",")?;
        }
        w.write_all(if self.depth == 1 { b"\n  " } else { b" " })
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

    fn summary() -> Summary {
        Summary {
            steps: 3,
            sim_time: 0.03,
            laps_completed: 0,
            ekf_position_rmse: 0.0117,
            ekf_heading_rmse: 0.02,
            ekf_heading_offset: 0.01,
            ekf_heading_rmse_about_offset: f64::NAN,
            within_3_sigma_heading_about_offset: f64::NAN,
            mean_nees_about_offset: f64::NAN,
            ekf_max_position_error: 0.05,
            odometry_position_rmse: f64::NAN,
            odometry_heading_rmse: f64::NAN,
            odometry_max_position_error: f64::INFINITY,
            mean_nees: 3.0,
            nees_dof: 3,
            nees_in_interval: 1.0,
            within_3_sigma: [1.0, 1.0, f64::NAN],
            readings: 2,
            associated: 2,
            corrections: 1,
            acceptance: 0.5,
            wall_clock: 0.001,
            real_time_factor: 30.0,
        }
    }

    #[test]
    fn a_missing_figure_is_null_and_the_keys_keep_their_order() {
        let settings = Settings {
            scenario: "a \"quoted\" name",
            seed: Some(7),
            first_seed: None,
            runs: None,
            dt_s: 0.01,
            laps: Some(2),
        };
        let text = to_json(&RunMetrics {
            settings,
            summary: summary(),
            extra: (),
        })
        .unwrap();
        assert!(text.starts_with(
            "{\n  \"scenario\": \"a \\\"quoted\\\" name\",\n  \"seed\": 7,\n  \"dt_s\": 0.01,\n  \"laps\": 2,\n  \"steps\": 3,\n"
        ), "{text}");
        assert!(
            text.contains("\n  \"odometry_position_rmse_m\": null,\n"),
            "{text}"
        );
        assert!(
            text.contains("\n  \"odometry_max_position_error_m\": null,\n"),
            "{text}"
        );
        assert!(
            text.ends_with("\n  \"real_time_factor\": 30.0\n}\n"),
            "{text}"
        );
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(value["ekf_position_rmse_m"], 0.0117);
        assert_eq!(value["ir_readings"], 2);
        assert!(value.get("first_seed").is_none());
    }

    #[test]
    fn nested_objects_stand_on_one_line() {
        #[derive(Serialize)]
        struct Spread {
            mean: f64,
            std: f64,
        }
        #[derive(Serialize)]
        struct Outer {
            runs: usize,
            x: Spread,
        }
        let text = to_json(&Outer {
            runs: 4,
            x: Spread {
                mean: 1.5,
                std: f64::NAN,
            },
        })
        .unwrap();
        assert_eq!(
            text,
            "{\n  \"runs\": 4,\n  \"x\": { \"mean\": 1.5, \"std\": null }\n}\n"
        );
    }
}
