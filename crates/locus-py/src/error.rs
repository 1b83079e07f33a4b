//! Errors as Python exceptions: `locus.LocusError` (a log that cannot be
//! read or replayed, a study that fails), with the message the command line
//! gives (file, line and field named); `ValueError` for an argument out of
//! range or of the wrong shape, naming the argument; `KeyboardInterrupt`
//! for a call stopped by Ctrl-C.

use pyo3::exceptions::{PyException, PyValueError};
use pyo3::{PyErr, create_exception};

create_exception!(
    locus,
    LocusError,
    PyException,
    "A log that cannot be read or replayed, or a study that fails: the message names the file, line and field, as the command line does."
);

/// `e` with its causes, as the command line prints it (`anyhow`'s `{:#}`).
pub fn locus_error(e: &anyhow::Error) -> PyErr {
    LocusError::new_err(format!("{e:#}"))
}

/// A `ValueError` naming the argument `name`.
pub fn value_error(name: &str, why: impl core::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("{name}: {why}"))
}
