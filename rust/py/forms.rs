//! Bindings of `crate::forms`.

use numpy::{IntoPyArray, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::{array, contiguous, owned_indices, shape_error};

/// Unit quaternions [N, 4] to rotation matrices, f32: [N, 9] row after row (`columns` 3) or
/// [N, 6] their first two columns (`columns` 2).
#[pyfunction]
fn matrix_columns<'py>(
    py: Python<'py>,
    quats: PyReadonlyArray2<'py, f64>,
    columns: usize,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let shape = quats.shape().to_vec();
    if shape[1] != 4 {
        return Err(shape_error("quats", "[N, 4]", &shape));
    }
    let values = contiguous("quats", &quats)?;
    let out = py.detach(|| crate::forms::matrix_columns(values, columns))?;
    Ok(array(out, (shape[0], 3 * columns))?.into_pyarray(py))
}

/// Per-clip time derivative of rows `values` [N, C]; clips begin at `starts` [K], each row's
/// seconds per frame in `frame_time` [N].
#[pyfunction]
fn clip_gradient<'py>(
    py: Python<'py>,
    values: PyReadonlyArray2<'py, f64>,
    starts: PyReadonlyArray1<'py, i64>,
    frame_time: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let shape = values.shape().to_vec();
    let starts = owned_indices("starts", &starts)?;
    let (v, t) = (
        contiguous("values", &values)?,
        contiguous("frame_time", &frame_time)?,
    );
    let out = py.detach(|| crate::forms::clip_gradient(v, shape[1], &starts, t))?;
    Ok(array(out, (shape[0], shape[1]))?.into_pyarray(py))
}

type Totals<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>);

/// f64 sums of the rows of each of `arrays` (each [n_i, C], f32) and of their squares, each array
/// summed row after row: ([A, C], [A, C]).
#[pyfunction]
fn column_totals<'py>(
    py: Python<'py>,
    arrays: Vec<PyReadonlyArray2<'py, f32>>,
    width: usize,
) -> PyResult<Totals<'py>> {
    let slices = arrays
        .iter()
        .enumerate()
        .map(|(k, a)| {
            if a.shape()[1] != width {
                return Err(shape_error(
                    "arrays",
                    &format!("[n, {width}] (array {k})"),
                    a.shape(),
                ));
            }
            contiguous("arrays", a)
        })
        .collect::<PyResult<Vec<&[f32]>>>()?;
    let (sums, squares) = py.detach(|| crate::forms::column_totals(&slices, width))?;
    let shape = (slices.len(), width);
    Ok((
        array(sums, shape)?.into_pyarray(py),
        array(squares, shape)?.into_pyarray(py),
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(matrix_columns, m)?)?;
    m.add_function(wrap_pyfunction!(clip_gradient, m)?)?;
    m.add_function(wrap_pyfunction!(column_totals, m)?)
}
