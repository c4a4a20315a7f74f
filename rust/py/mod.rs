//! PyO3 bindings: argument checks, GIL release, arrays in and out. No algorithm lives here.

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::error::KernelError;
use crate::rotations::Order;

create_exception!(_core, ParseError, PyValueError, "A malformed MOTION block; args are (message, 0-based line within the block).");

fn to_py(error: KernelError) -> PyErr {
    match error {
        KernelError::Parse { line, message } => ParseError::new_err((message, line)),
        other @ KernelError::Argument { .. } => PyValueError::new_err(other.to_string()),
    }
}

fn shape_error(name: &str, expected: &str, got: &[usize]) -> PyErr {
    PyValueError::new_err(format!("argument `{name}`: expected shape {expected}, got {got:?}"))
}

fn orders_from(orders: &PyReadonlyArray2<'_, u8>) -> PyResult<Vec<Order>> {
    if orders.shape()[1] != 3 {
        return Err(shape_error("orders", "[J, 3]", orders.shape()));
    }
    Ok(orders.as_slice()?.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
}

fn array3(values: Vec<f64>, shape: (usize, usize, usize)) -> PyResult<Array3<f64>> {
    Array3::from_shape_vec(shape, values).map_err(|e| PyValueError::new_err(e.to_string()))
}

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
    let block = bytes.get(start..).ok_or_else(|| PyValueError::new_err("argument `start`: past the end of `data`"))?;
    let values = py.detach(|| crate::parse::parse_motion_block(block, frames, channels)).map_err(to_py)?;
    let array = Array2::from_shape_vec((frames, channels), values).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok(array.into_pyarray(py))
}

/// Parse many MOTION blocks at once, in parallel across blocks.
///
/// `blocks` is a list of (data, start, frames, channels); returns one array or one
/// `ParseError` instance per block, so one bad file does not hide the others.
#[pyfunction]
fn parse_motion_blocks<'py>(py: Python<'py>, blocks: Vec<(Bound<'py, PyBytes>, usize, usize, usize)>) -> PyResult<Vec<Py<PyAny>>> {
    use rayon::prelude::*;
    let views: Vec<(&[u8], usize, usize, usize)> = blocks.iter().map(|(d, s, f, c)| (d.as_bytes(), *s, *f, *c)).collect();
    let results: Vec<Result<Vec<f64>, KernelError>> = py.detach(|| {
        views
            .par_iter()
            .map(|&(bytes, start, frames, channels)| match bytes.get(start..) {
                Some(block) => crate::parse::parse_motion_block(block, frames, channels),
                None => Err(KernelError::argument("start", "past the end of `data`")),
            })
            .collect()
    });
    results
        .into_iter()
        .zip(views)
        .map(|(result, (_, _, frames, channels))| match result {
            Ok(values) => {
                let array = Array2::from_shape_vec((frames, channels), values).map_err(|e| PyValueError::new_err(e.to_string()))?;
                Ok(array.into_pyarray(py).into_any().unbind())
            }
            Err(error) => Ok(to_py(error).into_value(py).into_any()),
        })
        .collect()
}

/// Euler angles [F, J, 3] in degrees to quaternions [F, J, 4] (x, y, z, w); `orders` [J, 3].
#[pyfunction]
fn euler_to_quat<'py>(py: Python<'py>, angles: PyReadonlyArray3<'py, f64>, orders: PyReadonlyArray2<'py, u8>) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let shape = angles.shape().to_vec();
    let order_list = orders_from(&orders)?;
    if shape[1] != order_list.len() || shape[2] != 3 {
        return Err(shape_error("angles", &format!("[F, {}, 3]", order_list.len()), &shape));
    }
    let values = angles.as_slice()?;
    let out = py.detach(|| crate::rotations::euler_to_quat(values, &order_list)).map_err(to_py)?;
    Ok(array3(out, (shape[0], shape[1], 4))?.into_pyarray(py))
}

/// Quaternions [F, J, 4] (x, y, z, w) to Euler angles [F, J, 3] in degrees; `orders` [J, 3].
#[pyfunction]
fn quat_to_euler<'py>(py: Python<'py>, quats: PyReadonlyArray3<'py, f64>, orders: PyReadonlyArray2<'py, u8>) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let shape = quats.shape().to_vec();
    let order_list = orders_from(&orders)?;
    if shape[1] != order_list.len() || shape[2] != 4 {
        return Err(shape_error("quats", &format!("[F, {}, 4]", order_list.len()), &shape));
    }
    let values = quats.as_slice()?;
    let out = py.detach(|| crate::rotations::quat_to_euler(values, &order_list)).map_err(to_py)?;
    Ok(array3(out, (shape[0], shape[1], 3))?.into_pyarray(py))
}

/// World rotations [F, J, 4] and positions [F, J, 3] from local ones and `parents` [J].
#[pyfunction]
#[allow(clippy::type_complexity)]
fn forward_kinematics<'py>(
    py: Python<'py>,
    rotations: PyReadonlyArray3<'py, f64>,
    translations: PyReadonlyArray3<'py, f64>,
    parents: PyReadonlyArray1<'py, i64>,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray3<f64>>)> {
    let (rs, ts) = (rotations.shape().to_vec(), translations.shape().to_vec());
    let joints = parents.len();
    if rs[1] != joints || rs[2] != 4 {
        return Err(shape_error("rotations", &format!("[F, {joints}, 4]"), &rs));
    }
    if ts != [rs[0], joints, 3] {
        return Err(shape_error("translations", &format!("[{}, {joints}, 3]", rs[0]), &ts));
    }
    let (r, t, p) = (rotations.as_slice()?, translations.as_slice()?, parents.as_slice()?);
    let (world_rot, world_pos) = py.detach(|| crate::fk::forward_kinematics(r, t, p)).map_err(to_py)?;
    Ok((array3(world_rot, (rs[0], joints, 4))?.into_pyarray(py), array3(world_pos, (rs[0], joints, 3))?.into_pyarray(py)))
}

/// Text of the MOTION number block for `values` [F, C]; `decimals` None = shortest exact.
#[pyfunction]
#[pyo3(signature = (values, decimals=None))]
fn format_motion_block<'py>(py: Python<'py>, values: PyReadonlyArray2<'py, f64>, decimals: Option<usize>) -> PyResult<Bound<'py, PyBytes>> {
    let channels = values.shape()[1];
    let slice = values.as_slice()?;
    let text = py.detach(|| crate::format::format_motion_block(slice, channels, decimals)).map_err(to_py)?;
    Ok(PyBytes::new(py, text.as_bytes()))
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ParseError", m.py().get_type::<ParseError>())?;
    m.add_function(wrap_pyfunction!(parse_motion_block, m)?)?;
    m.add_function(wrap_pyfunction!(parse_motion_blocks, m)?)?;
    m.add_function(wrap_pyfunction!(euler_to_quat, m)?)?;
    m.add_function(wrap_pyfunction!(quat_to_euler, m)?)?;
    m.add_function(wrap_pyfunction!(forward_kinematics, m)?)?;
    m.add_function(wrap_pyfunction!(format_motion_block, m)?)?;
    m.add("num_threads", rayon::current_num_threads())?;
    Ok(())
}
