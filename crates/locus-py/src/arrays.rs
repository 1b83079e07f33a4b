//! numpy arrays in and out: shapes checked, naming the argument.

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::error::value_error;

/// `array` as rows of `cols` numbers (a float array of shape (N, cols)),
/// each number finite unless `nan_ok` says which columns may hold NaN.
pub fn rows(
    name: &str,
    array: &Bound<'_, PyAny>,
    cols: usize,
    nan_ok: &[usize],
) -> PyResult<Vec<Vec<f64>>> {
    let a: PyReadonlyArray2<'_, f64> = array.extract().map_err(|_| {
        value_error(
            name,
            format!("expected a 2-D array of floats of shape (N, {cols})"),
        )
    })?;
    let view = a.as_array();
    if view.ncols() != cols {
        return Err(value_error(
            name,
            format!(
                "expected shape (N, {cols}), got ({}, {})",
                view.nrows(),
                view.ncols()
            ),
        ));
    }
    let mut out = Vec::with_capacity(view.nrows());
    for (i, row) in view.rows().into_iter().enumerate() {
        for (j, v) in row.iter().enumerate() {
            if !(v.is_finite() || v.is_nan() && nan_ok.contains(&j)) {
                return Err(value_error(
                    name,
                    format!("row {i}, column {j}: {v} is not finite"),
                ));
            }
        }
        out.push(row.to_vec());
    }
    Ok(out)
}

/// `n` numbers, finite, from a sequence or array (a tuple of floats read
/// without building a list: the per-step calls of `locus.Filter`).
pub fn fixed<const N: usize>(name: &str, value: &Bound<'_, PyAny>) -> PyResult<[f64; N]> {
    if let Ok(t) = value.cast::<PyTuple>()
        && t.len() == N
    {
        let mut a = [0.0_f64; N];
        for (i, slot) in a.iter_mut().enumerate() {
            *slot = t
                .get_item(i)?
                .extract()
                .map_err(|_| value_error(name, format!("item {i} is not a number")))?;
        }
        if let Some(bad) = a.iter().find(|x| !x.is_finite()) {
            return Err(value_error(name, format!("{bad} is not finite")));
        }
        return Ok(a);
    }
    let v: Vec<f64> = value
        .extract()
        .map_err(|_| value_error(name, format!("expected {N} numbers")))?;
    let a: [f64; N] = v
        .as_slice()
        .try_into()
        .map_err(|_| value_error(name, format!("expected {N} numbers, got {}", v.len())))?;
    if let Some(bad) = a.iter().find(|x| !x.is_finite()) {
        return Err(value_error(name, format!("{bad} is not finite")));
    }
    Ok(a)
}

/// A square matrix of side `N`, finite, from a nested sequence or array.
pub fn square<const N: usize>(name: &str, value: &Bound<'_, PyAny>) -> PyResult<[[f64; N]; N]> {
    let a: PyReadonlyArray2<'_, f64> = value
        .extract()
        .map_err(|_| value_error(name, format!("expected a {N} x {N} array of floats")))?;
    let view = a.as_array();
    if view.dim() != (N, N) {
        let (r, c) = view.dim();
        return Err(value_error(
            name,
            format!("expected shape ({N}, {N}), got ({r}, {c})"),
        ));
    }
    let mut out = [[0.0; N]; N];
    for i in 0..N {
        for j in 0..N {
            let v = view[(i, j)];
            if !v.is_finite() {
                return Err(value_error(name, format!("[{i}, {j}]: {v} is not finite")));
            }
            out[i][j] = v;
        }
    }
    Ok(out)
}

/// A vector as a numpy array.
pub fn vector<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    Array1::from_vec(v).into_pyarray(py)
}

/// Rows of `cols` numbers stored flat as an (N, cols) numpy array.
pub fn matrix<'py>(py: Python<'py>, flat: Vec<f64>, cols: usize) -> Bound<'py, PyArray2<f64>> {
    let n = flat.len() / cols;
    Array2::from_shape_vec((n, cols), flat)
        .expect("a whole number of rows")
        .into_pyarray(py)
}

/// Square blocks of side `side` stored flat as an (N, side, side) array.
pub fn blocks<'py>(py: Python<'py>, flat: Vec<f64>, side: usize) -> Bound<'py, PyArray3<f64>> {
    let n = flat.len() / (side * side);
    Array3::from_shape_vec((n, side, side), flat)
        .expect("a whole number of blocks")
        .into_pyarray(py)
}

/// A 1-D array of integers.
pub fn integers<'py>(py: Python<'py>, v: Vec<i64>) -> Bound<'py, PyArray1<i64>> {
    Array1::from_vec(v).into_pyarray(py)
}

/// A pose or state vector as a numpy array.
pub fn column<'py, const N: usize>(
    py: Python<'py>,
    v: &nalgebra::SVector<f64, N>,
) -> Bound<'py, PyArray1<f64>> {
    vector(py, v.as_slice().to_vec())
}

/// A matrix as a numpy array (row-major).
pub fn dense<'py, const R: usize, const C: usize>(
    py: Python<'py>,
    m: &nalgebra::SMatrix<f64, R, C>,
) -> Bound<'py, PyArray2<f64>> {
    matrix(py, m.transpose().as_slice().to_vec(), C)
}
