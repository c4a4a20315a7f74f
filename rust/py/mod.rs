//! PyO3 bindings: argument checks, GIL release, arrays in and out. No algorithm lives here.

use numpy::ndarray::{Array2, Array3, Dimension};
use numpy::{Element, IntoPyArray, PyArrayMethods, PyReadonlyArray, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use crate::error::KernelError;
mod clip;
mod decouple;
mod features;
mod mlp;

use crate::decode::ChannelLayout;
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

fn not_contiguous(name: &str) -> PyErr {
    PyTypeError::new_err(format!("argument `{name}`: expected a C-contiguous array (see numpy.ascontiguousarray)"))
}

/// A copy of an index array (parents, columns...), taken while the GIL is held.
///
/// Kernels run without the GIL, so another Python thread may write to the caller's arrays
/// meanwhile. An index checked in the array and read again later could then be out of range
/// (a panic), and reading memory another thread writes is a data race in Rust's terms. Index
/// arrays are small: the kernels check and use this copy only, so no write can reach them.
/// Float arrays are read in place (copying them would cost as much as some kernels): a write
/// during a call only mixes old and new values into the results (see `kernels.py`).
fn owned_indices<D: Dimension>(name: &str, array: &PyReadonlyArray<'_, i64, D>) -> PyResult<Vec<i64>> {
    Ok(contiguous(name, array)?.to_vec())
}

/// A copy of a bool array, read as bytes: NumPy lets a bool array hold any byte (e.g.
/// `np.frombuffer(b"\\x02", bool)`), which is undefined behaviour as a Rust `bool`; any non-zero
/// byte is true, as NumPy reads it. Copied under the GIL like `owned_indices`.
fn owned_flags<D: Dimension>(name: &str, array: &PyReadonlyArray<'_, bool, D>) -> PyResult<Vec<bool>> {
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
fn contiguous<'a, T: Element, D: Dimension>(name: &str, array: &'a PyReadonlyArray<'_, T, D>) -> PyResult<&'a [T]> {
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
    Ok(contiguous("orders", orders)?.chunks(3).map(|c| [c[0], c[1], c[2]]).collect())
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

/// The arrays of a channel layout, borrowed from NumPy.
type LayoutArrays<'py> = (PyReadonlyArray2<'py, i64>, PyReadonlyArray2<'py, u8>, PyReadonlyArray2<'py, i64>, PyReadonlyArray2<'py, f64>);

pub(super) struct OwnedLayout {
    channels: usize,
    rotation_columns: Vec<i64>,
    orders: Vec<Order>,
    position_columns: Vec<i64>,
    offsets: Vec<f64>,
}

impl OwnedLayout {
    pub(super) fn new(channels: usize, arrays: &LayoutArrays<'_>) -> PyResult<Self> {
        let (rotation_columns, orders, position_columns, offsets) = arrays;
        Ok(Self {
            channels,
            rotation_columns: owned_indices("rotation_columns", rotation_columns)?,
            orders: orders_from(orders)?,
            position_columns: owned_indices("position_columns", position_columns)?,
            offsets: contiguous("offsets", offsets)?.to_vec(),
        })
    }

    pub(super) fn view(&self) -> ChannelLayout<'_> {
        ChannelLayout {
            channels: self.channels,
            rotation_columns: &self.rotation_columns,
            orders: &self.orders,
            position_columns: &self.position_columns,
            offsets: &self.offsets,
        }
    }
}

fn motion_arrays(py: Python<'_>, frames: usize, joints: usize, (rot, trans): (Vec<f64>, Vec<f64>)) -> PyResult<Py<PyAny>> {
    let rot = array3(rot, (frames, joints, 4))?.into_pyarray(py);
    let trans = array3(trans, (frames, joints, 3))?.into_pyarray(py);
    Ok((rot, trans).into_pyobject(py)?.into_any().unbind())
}

/// Channel values [F, C] to local rotations [F, J, 4] and translations [F, J, 3].
///
/// `rotation_columns` [J, 3] (column of each angle in the joint's order, -1 = none),
/// `orders` [J, 3], `position_columns` [J, 3] (x, y, z; -1 keeps the offset), `offsets` [J, 3].
#[pyfunction]
fn decode_channels<'py>(
    py: Python<'py>,
    values: PyReadonlyArray2<'py, f64>,
    rotation_columns: PyReadonlyArray2<'py, i64>,
    orders: PyReadonlyArray2<'py, u8>,
    position_columns: PyReadonlyArray2<'py, i64>,
    offsets: PyReadonlyArray2<'py, f64>,
) -> PyResult<Py<PyAny>> {
    let (frames, channels) = (values.shape()[0], values.shape()[1]);
    let layout = OwnedLayout::new(channels, &(rotation_columns, orders, position_columns, offsets))?;
    let slice = contiguous("values", &values)?;
    let decoded = py.detach(|| crate::decode::decode_channels(slice, frames, &layout.view())).map_err(to_py)?;
    motion_arrays(py, frames, layout.orders.len(), decoded)
}

/// Parse and decode many MOTION blocks, in parallel across blocks.
///
/// `blocks` holds (data, start, frames, channels, rotation_columns, orders, position_columns,
/// offsets); returns per block a (rotations, translations) pair or a `ParseError` instance.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_motion_blocks<'py>(
    py: Python<'py>,
    blocks: Vec<(Bound<'py, PyBytes>, usize, usize, usize, PyReadonlyArray2<'py, i64>, PyReadonlyArray2<'py, u8>, PyReadonlyArray2<'py, i64>, PyReadonlyArray2<'py, f64>)>,
) -> PyResult<Vec<Py<PyAny>>> {
    use rayon::prelude::*;
    let mut jobs = Vec::with_capacity(blocks.len());
    for (data, start, frames, channels, rc, or, pc, off) in &blocks {
        jobs.push((data.as_bytes(), *start, *frames, OwnedLayout::new(*channels, &(rc.clone(), or.clone(), pc.clone(), off.clone()))?));
    }
    let results: Vec<Result<(Vec<f64>, Vec<f64>), KernelError>> = py.detach(|| {
        jobs.par_iter()
            .map(|(bytes, start, frames, layout)| {
                let block = bytes.get(*start..).ok_or_else(|| KernelError::argument("start", "past the end of `data`"))?;
                crate::decode::read_motion_block(block, *frames, &layout.view())
            })
            .collect()
    });
    results
        .into_iter()
        .zip(&jobs)
        .map(|(result, (_, _, frames, layout))| match result {
            Ok(decoded) => motion_arrays(py, *frames, layout.orders.len(), decoded),
            // A malformed block is that block's result; a bad argument is the caller's error.
            Err(error @ KernelError::Parse { .. }) => Ok(to_py(error).into_value(py).into_any()),
            Err(error) => Err(to_py(error)),
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
    let values = contiguous("angles", &angles)?;
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
    let values = contiguous("quats", &quats)?;
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
    let (r, t, p) = (contiguous("rotations", &rotations)?, contiguous("translations", &translations)?, owned_indices("parents", &parents)?);
    let (world_rot, world_pos) = py.detach(|| crate::fk::forward_kinematics(r, t, &p)).map_err(to_py)?;
    Ok((array3(world_rot, (rs[0], joints, 4))?.into_pyarray(py), array3(world_pos, (rs[0], joints, 3))?.into_pyarray(py)))
}

/// Forward kinematics of many clips, in parallel across clips: `clips` holds
/// (rotations [F, J, 4], translations [F, J, 3], parents [J]) triples; returns a
/// (world rotations, world positions) pair per clip.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn forward_kinematics_many<'py>(
    py: Python<'py>,
    clips: Vec<(PyReadonlyArray3<'py, f64>, PyReadonlyArray3<'py, f64>, PyReadonlyArray1<'py, i64>)>,
) -> PyResult<Vec<Py<PyAny>>> {
    use rayon::prelude::*;
    let mut jobs = Vec::with_capacity(clips.len());
    for (index, (rotations, translations, parents)) in clips.iter().enumerate() {
        let (rs, ts) = (rotations.shape(), translations.shape());
        let joints = parents.len();
        if rs[1..] != [joints, 4] || ts != [rs[0], joints, 3] {
            return Err(PyValueError::new_err(format!(
                "argument `clips`: clip {index} has rotations {rs:?} and translations {ts:?} for {joints} parents, expected [F, {joints}, 4] and [F, {joints}, 3]"
            )));
        }
        jobs.push((contiguous("clips", rotations)?, contiguous("clips", translations)?, owned_indices("clips", parents)?, rs[0]));
    }
    let results: Vec<Result<(Vec<f64>, Vec<f64>), KernelError>> =
        py.detach(|| jobs.par_iter().map(|(r, t, p, _)| crate::fk::forward_kinematics(r, t, p)).collect());
    results
        .into_iter()
        .zip(&jobs)
        .map(|(result, (_, _, parents, frames))| motion_arrays(py, *frames, parents.len(), result.map_err(to_py)?))
        .collect()
}

/// Text of the MOTION number block for `values` [F, C]; `decimals` None = shortest exact.
#[pyfunction]
#[pyo3(signature = (values, decimals=None))]
fn format_motion_block<'py>(py: Python<'py>, values: PyReadonlyArray2<'py, f64>, decimals: Option<usize>) -> PyResult<Bound<'py, PyBytes>> {
    let channels = values.shape()[1];
    let slice = contiguous("values", &values)?;
    let text = py.detach(|| crate::format::format_motion_block(slice, channels, decimals)).map_err(to_py)?;
    Ok(PyBytes::new(py, text.as_bytes()))
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("ParseError", m.py().get_type::<ParseError>())?;
    m.add_function(wrap_pyfunction!(parse_motion_block, m)?)?;
    m.add_function(wrap_pyfunction!(decode_channels, m)?)?;
    m.add_function(wrap_pyfunction!(read_motion_blocks, m)?)?;
    m.add_function(wrap_pyfunction!(euler_to_quat, m)?)?;
    m.add_function(wrap_pyfunction!(quat_to_euler, m)?)?;
    m.add_function(wrap_pyfunction!(forward_kinematics, m)?)?;
    m.add_function(wrap_pyfunction!(forward_kinematics_many, m)?)?;
    m.add_function(wrap_pyfunction!(format_motion_block, m)?)?;
    m.add("num_threads", rayon::current_num_threads())?;
    features::register(m)?;
    clip::register(m)?;
    mlp::register(m)?;
    decouple::register(m)?;
    Ok(())
}
