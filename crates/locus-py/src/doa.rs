//! Paper 002's domain of attraction (`locus_doa`), for `locus.doa`: one
//! cell, a deterministic shard of the grid (the unit a Dask worker
//! computes, `locus doa --shard I/N`'s), and the merge of shards into the
//! whole grid's CSV, byte for byte `locus doa`'s `doa.csv`.

use locus_doa::{DoaConfig, Shard, Study, merge_csv};
use pyo3::prelude::*;

use crate::error::{locus_error, value_error};
use crate::interrupt;

/// The study of the TOML `config` (named `name` in errors), or the
/// spec's defaults.
fn study(config: Option<&str>, name: &str) -> anyhow::Result<Study> {
    let config = match config {
        Some(text) => DoaConfig::from_toml_str(text, name)?,
        None => DoaConfig::default(),
    };
    Ok(Study::new(config)?)
}

/// The CSV of shard `index` of `count` (`count` 1: the whole grid) of the
/// study configured by the TOML text `config` (None: the spec's
/// defaults), computed on `threads` threads (None: all cores).
#[pyfunction]
#[pyo3(signature = (config=None, name="config".to_string(), index=0, count=1, threads=None))]
pub fn doa_shard(
    py: Python<'_>,
    config: Option<String>,
    name: String,
    index: usize,
    count: usize,
    threads: Option<usize>,
) -> PyResult<String> {
    let shard = Shard::parse(&format!("{index}/{count}"))
        .map_err(|e| value_error("index", format!("{e}")))?;
    interrupt::run(py, move |stop| {
        let study = study(config.as_deref(), &name)?;
        let mut pool = rayon::ThreadPoolBuilder::new();
        if let Some(t) = threads {
            pool = pool.num_threads(t);
        }
        let pool = pool.build()?;
        // The sweep has no stop: an interrupted one finishes here, dropped.
        let result = pool.install(|| study.sweep(shard, &|_| {}));
        if stop.asked() {
            anyhow::bail!("stopped");
        }
        Ok(result.to_csv())
    })?
    .map_err(|e| locus_error(&e))
}

/// The whole grid's CSV from the CSVs of all its shards (`locus doa
/// merge`), checked against the configuration when given.
#[pyfunction]
#[pyo3(signature = (shards, config=None, name="config".to_string()))]
pub fn doa_merge(shards: Vec<String>, config: Option<String>, name: String) -> PyResult<String> {
    let run = || -> anyhow::Result<String> {
        let config = config
            .as_deref()
            .map(|t| DoaConfig::from_toml_str(t, &name))
            .transpose()?;
        let names: Vec<String> = (0..shards.len()).map(|i| format!("shard {i}")).collect();
        let merged = merge_csv(
            names
                .iter()
                .map(String::as_str)
                .zip(shards.iter().map(String::as_str)),
            config.as_ref().map(|c| (c, name.as_str())),
        )?;
        Ok(merged.to_csv())
    };
    run().map_err(|e| locus_error(&e))
}

/// One cell of the grid, row `i_vg` and column `i_alpha`: `(v_g, alpha,
/// m_zeta, evaluations, settle_time_s)` (settling time None if some vertex
/// did not converge).
#[pyfunction]
#[pyo3(signature = (i_vg, i_alpha, config=None, name="config".to_string()))]
#[allow(clippy::type_complexity)]
pub fn doa_cell(
    py: Python<'_>,
    i_vg: usize,
    i_alpha: usize,
    config: Option<String>,
    name: String,
) -> PyResult<(f64, f64, f64, u32, Option<f64>)> {
    interrupt::run(py, move |_| {
        let study = study(config.as_deref(), &name)?;
        let cell = study
            .cells()
            .find(|c| c.i_vg == i_vg && c.i_alpha == i_alpha)
            .ok_or_else(|| anyhow::anyhow!("cell ({i_vg}, {i_alpha}) is outside the grid"))?;
        let r = study.solve(cell);
        Ok((cell.v_g, cell.alpha, r.m_zeta, r.evaluations, r.settle))
    })?
    .map_err(|e| locus_error(&e))
}
