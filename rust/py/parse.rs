//! Binding of `crate::parse`.

use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use super::array;
use super::errors::argument_error;

/// Parse the MOTION number block `data[start:]` into a float64 array [frames, channels].
#[pyfunction]
fn parse_motion_block<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyBytes>,
    start: usize,
    frames: usize,
    channels: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let bytes = data.as_bytes();
    let block = bytes
        .get(start..)
        .ok_or_else(|| argument_error("argument `start`: past the end of `data`".into()))?;
    let values = py.detach(|| crate::parse::parse_motion_block(block, frames, channels))?;
    Ok(array(values, (frames, channels))?.into_pyarray(py))
}

/// Check the MOTION number block `data[start:]` as `parse_motion_block` reads it, keeping no
/// value: None, or the ParseError it would raise.
#[pyfunction]
fn check_motion_block(
    py: Python<'_>,
    data: &Bound<'_, PyBytes>,
    start: usize,
    frames: usize,
    channels: usize,
) -> PyResult<()> {
    let bytes = data.as_bytes();
    let block = bytes
        .get(start..)
        .ok_or_else(|| argument_error("argument `start`: past the end of `data`".into()))?;
    py.detach(|| crate::parse::check_motion_block(block, frames, channels))?;
    Ok(())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(parse_motion_block, m)?)?;
    m.add_function(wrap_pyfunction!(check_motion_block, m)?)
}
