//! Binding of `crate::format`.

use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use super::contiguous;

/// Text of the MOTION number block for `values` [F, C]; `decimals` None = shortest exact.
#[pyfunction]
#[pyo3(signature = (values, decimals=None))]
fn format_motion_block<'py>(
    py: Python<'py>,
    values: PyReadonlyArray2<'py, f64>,
    decimals: Option<usize>,
) -> PyResult<Bound<'py, PyBytes>> {
    let channels = values.shape()[1];
    let slice = contiguous("values", &values)?;
    let text = py.detach(|| crate::format::format_motion_block(slice, channels, decimals))?;
    Ok(PyBytes::new(py, text.as_bytes()))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(format_motion_block, m)?)
}
