//! `locus.simulate`: a built-in scenario or a TOML scenario file run by
//! the simulator (`locus_sim`) as `locus run` runs it, its log's columns
//! returned as arrays and its summary as the results schema.

use std::path::PathBuf;

use locus_eval::Record;
use locus_eval::results::Results;
use locus_sim::scenario_file::{self, Scenario, ScenarioConfig};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays;
use crate::error::{locus_error, value_error};
use crate::interrupt::{self, Stop};

/// A run's log as columns (its CSV header's names; a field that is not a
/// number is NaN) and its summary.
struct Simulated {
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
    results: String,
}

/// Collects each record's CSV row into columns.
fn collect<R: Record>(
    stop: &Stop,
    run: impl FnOnce(&mut dyn FnMut(&R)) -> Result<locus_eval::Summary, locus_sim::Error>,
) -> anyhow::Result<Simulated> {
    let names: Vec<String> = R::csv_header().split(',').map(str::to_string).collect();
    let mut columns = vec![Vec::new(); names.len()];
    let mut stopped = false;
    let summary = run(&mut |r: &R| {
        if stopped || (columns[0].len() % 4096 == 0 && stop.asked()) {
            stopped = true;
            return;
        }
        for (col, field) in columns.iter_mut().zip(r.csv_row().split(',')) {
            col.push(field.parse().unwrap_or(f64::NAN));
        }
    })?;
    if stopped {
        anyhow::bail!("stopped");
    }
    Ok(Simulated {
        names,
        columns,
        results: serde_json::to_string(&Results::of(&summary))?,
    })
}

/// Runs `scenario` (a built-in name or a `.toml` scenario file) with
/// `seed`; `guide_step` ("a" to "f") runs paper 001's guided experiment's
/// step on the square.
#[pyfunction]
#[pyo3(signature = (scenario="square".to_string(), seed=1, guide_step=None))]
pub fn simulate<'py>(
    py: Python<'py>,
    scenario: String,
    seed: u64,
    guide_step: Option<char>,
) -> PyResult<Bound<'py, PyDict>> {
    let config = if scenario.ends_with(".toml") {
        scenario_file::load(&PathBuf::from(&scenario)).map_err(|e| locus_error(&e.into()))?
    } else {
        scenario
            .parse::<Scenario>()
            .map_err(|e| value_error("scenario", format!("{e} (built-in: {})", Scenario::names())))?
            .config()
    };
    let config = match (guide_step, config) {
        (None, c) => c,
        (Some(step), ScenarioConfig::Square(base)) => {
            ScenarioConfig::Square(locus_sim::guide::step_config(step, &base).ok_or_else(|| {
                value_error(
                    "guide_step",
                    format!("{step:?} is not a step of the guide, a to f"),
                )
            })?)
        }
        (Some(_), _) => {
            return Err(value_error(
                "guide_step",
                "the guide's steps run on the square scenario",
            ));
        }
    };
    let out = interrupt::run(py, move |stop| match config {
        ScenarioConfig::Square(c) => collect(stop, |sink| {
            locus_sim::closed_loop::run_square(&c, seed, &mut |r| sink(r))
        }),
        ScenarioConfig::Wall45(c) => collect(stop, |sink| {
            locus_sim::wall45::run_wall45(&c, seed, &mut |r| sink(r))
        }),
        ScenarioConfig::TricycleSlip(c) => collect(stop, |sink| {
            locus_sim::tricycle_slip::run_tricycle_slip(&c, seed, &mut |r| sink(r))
        }),
        ScenarioConfig::Hover(c) => collect(stop, |sink| {
            locus_sim::hover::run_hover(&c, seed, &mut |r| sink(r))
        }),
    })?
    .map_err(|e| locus_error(&e))?;
    let d = PyDict::new(py);
    let columns = PyDict::new(py);
    for (name, col) in out.names.into_iter().zip(out.columns) {
        columns.set_item(name, arrays::vector(py, col))?;
    }
    d.set_item("columns", columns)?;
    d.set_item("results", out.results)?;
    Ok(d)
}
