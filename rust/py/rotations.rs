//! Bindings of `crate::rotations`.

use numpy::{IntoPyArray, PyArray3, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::{array, contiguous, orders_from, shape_error};

/// Euler angles [F, J, 3] in degrees to quaternions [F, J, 4] (x, y, z, w); `orders` [J, 3].
#[pyfunction]
fn euler_to_quat<'py>(
    py: Python<'py>,
    angles: PyReadonlyArray3<'py, f64>,
    orders: PyReadonlyArray2<'py, u8>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let shape = angles.shape().to_vec();
    let order_list = orders_from(&orders)?;
    if shape[1] != order_list.len() || shape[2] != 3 {
        return Err(shape_error(
            "angles",
            &format!("[F, {}, 3]", order_list.len()),
            &shape,
        ));
    }
    let values = contiguous("angles", &angles)?;
    let out = py.detach(|| crate::rotations::euler_to_quat(values, &order_list))?;
    Ok(array(out, (shape[0], shape[1], 4))?.into_pyarray(py))
}

/// Quaternions [F, J, 4] (x, y, z, w) to Euler angles [F, J, 3] in degrees; `orders` [J, 3].
#[pyfunction]
fn quat_to_euler<'py>(
    py: Python<'py>,
    quats: PyReadonlyArray3<'py, f64>,
    orders: PyReadonlyArray2<'py, u8>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let shape = quats.shape().to_vec();
    let order_list = orders_from(&orders)?;
    if shape[1] != order_list.len() || shape[2] != 4 {
        return Err(shape_error(
            "quats",
            &format!("[F, {}, 4]", order_list.len()),
            &shape,
        ));
    }
    let values = contiguous("quats", &quats)?;
    let out = py.detach(|| crate::rotations::quat_to_euler(values, &order_list))?;
    Ok(array(out, (shape[0], shape[1], 3))?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(euler_to_quat, m)?)?;
    m.add_function(wrap_pyfunction!(quat_to_euler, m)?)
}
