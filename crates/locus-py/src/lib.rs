//! The `locus` Python package's native module, `locus._locus` (built by
//! maturin from `python/`; the package's Python side wraps it). numpy in
//! and out; errors become Python exceptions (`error.rs`); long calls
//! release the GIL and stop on Ctrl-C (`interrupt.rs`).

extern crate alloc;

mod arrays;
mod doa;
mod error;
mod filter;
mod interrupt;
mod models;
mod replay;
mod simulate;

use pyo3::prelude::*;

#[pymodule]
fn _locus(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("LocusError", m.py().get_type::<error::LocusError>())?;
    m.add_class::<filter::Filter>()?;
    m.add_class::<models::DiffDrive>()?;
    m.add_class::<models::Unicycle>()?;
    m.add_class::<models::SkidSteer>()?;
    m.add_class::<models::RangeBearing>()?;
    m.add_class::<models::IrPair>()?;
    m.add_class::<models::LaserRange>()?;
    m.add_function(wrap_pyfunction!(replay::replay_file, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(doa::doa_shard, m)?)?;
    m.add_function(wrap_pyfunction!(doa::doa_merge, m)?)?;
    m.add_function(wrap_pyfunction!(doa::doa_cell, m)?)?;
    m.add_function(wrap_pyfunction!(replay::replay_arrays, m)?)?;
    Ok(())
}
