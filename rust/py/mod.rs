//! PyO3 bindings: argument checks, GIL release, arrays in and out. No algorithm lives here.
//! One binding file per kernel file; `errors` is the one conversion of kernel errors.

use numpy::ndarray::Dimension;
use numpy::{Element, PyArrayMethods, PyReadonlyArray, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::rotations::Order;

mod clip;
mod decode;
mod decouple;
mod errors;
mod features;
mod fk;
mod footsteps;
mod format;
mod forms;
mod gait;
mod ik;
mod mlp;
mod parse;
mod planting;
mod retarget;
mod rotations;

use errors::{array, shape_error};

fn not_contiguous(name: &str) -> PyErr {
    errors::argument_type_error(format!(
        "argument `{name}`: expected a C-contiguous array (see numpy.ascontiguousarray)"
    ))
}

/// A copy of an index array (parents, columns...), taken while the GIL is held.
///
/// Kernels run without the GIL, so another Python thread may write to the caller's arrays
/// meanwhile. An index checked in the array and read again later could then be out of range
/// (a panic), and reading memory another thread writes is a data race in Rust's terms. Index
/// arrays are small: the kernels check and use this copy only, so no write can reach them.
/// Float arrays are read in place (copying them would cost as much as some kernels): a write
/// during a call only mixes old and new values into the results (see `ops.py`).
fn owned_indices<D: Dimension>(
    name: &str,
    array: &PyReadonlyArray<'_, i64, D>,
) -> PyResult<Vec<i64>> {
    Ok(contiguous(name, array)?.to_vec())
}

/// A copy of a bool array, read as bytes: NumPy lets a bool array hold any byte (e.g.
/// `np.frombuffer(b"\\x02", bool)`), which is undefined behaviour as a Rust `bool`; any non-zero
/// byte is true, as NumPy reads it. Copied under the GIL like `owned_indices`.
fn owned_flags<D: Dimension>(
    name: &str,
    array: &PyReadonlyArray<'_, bool, D>,
) -> PyResult<Vec<bool>> {
    if !array.is_c_contiguous() {
        return Err(not_contiguous(name));
    }
    let len = array.len();
    if len == 0 {
        return Ok(Vec::new());
    }
    // SAFETY: the array is C-contiguous (checked above) with `len` one-byte elements at its
    // non-null data pointer, alive while borrowed; read as u8, every byte is a valid value.
    let bytes = unsafe { std::slice::from_raw_parts(array.data().cast::<u8>().cast_const(), len) };
    Ok(bytes.iter().map(|&b| b != 0).collect())
}

/// The elements of a C-contiguous array, or a TypeError naming the argument (the numpy crate's
/// own error does not say which argument).
fn contiguous<'a, T: Element, D: Dimension>(
    name: &str,
    array: &'a PyReadonlyArray<'_, T, D>,
) -> PyResult<&'a [T]> {
    // as_slice alone also takes Fortran-ordered arrays, whose elements it would hand over transposed.
    if !array.is_c_contiguous() {
        return Err(not_contiguous(name));
    }
    array.as_slice().map_err(|_| not_contiguous(name))
}

fn orders_from(orders: &PyReadonlyArray2<'_, u8>) -> PyResult<Vec<Order>> {
    if orders.shape()[1] != 3 {
        return Err(shape_error("orders", "[J, 3]", orders.shape()));
    }
    Ok(contiguous("orders", orders)?
        .chunks(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect())
}

/// A (rotations [F, J, 4], translations [F, J, 3]) pair as a Python tuple.
fn motion_arrays(
    py: Python<'_>,
    frames: usize,
    joints: usize,
    (rot, trans): (Vec<f64>, Vec<f64>),
) -> PyResult<Py<PyAny>> {
    use numpy::IntoPyArray;
    let rot = array(rot, (frames, joints, 4))?.into_pyarray(py);
    let trans = array(trans, (frames, joints, 3))?.into_pyarray(py);
    Ok((rot, trans).into_pyobject(py)?.into_any().unbind())
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("num_threads", rayon::current_num_threads())?;
    parse::register(m)?;
    decode::register(m)?;
    format::register(m)?;
    forms::register(m)?;
    rotations::register(m)?;
    fk::register(m)?;
    footsteps::register(m)?;
    features::register(m)?;
    gait::register(m)?;
    clip::register(m)?;
    mlp::register(m)?;
    decouple::register(m)?;
    retarget::register(m)?;
    ik::register(m)?;
    planting::register(m)?;
    Ok(())
}
