//! Bindings of `crate::features` and `crate::footsteps`.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyReadonlyArray4, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::{contiguous, shape_error, to_py};
use crate::features::{FeatureParams, N_FEATURES};
use crate::footsteps::ContactParams;

fn array2<T: numpy::Element>(values: Vec<T>, shape: (usize, usize)) -> PyResult<Array2<T>> {
    Array2::from_shape_vec(shape, values).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// Contact flags bool [F, S] from world positions `feet` [F, S, P, 3] of P points per foot.
/// Thresholds in the positions' units (per second for speed).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn foot_contacts<'py>(
    py: Python<'py>,
    feet: PyReadonlyArray4<'py, f64>,
    frame_time: f64,
    floor: f64,
    height_threshold: f64,
    speed_threshold: f64,
    min_frames: usize,
    causal: bool,
) -> PyResult<Bound<'py, PyArray2<bool>>> {
    let shape = feet.shape().to_vec();
    if shape[1] == 0 || shape[2] == 0 || shape[3] != 3 {
        return Err(shape_error("feet", "[F, S, P, 3]", &shape));
    }
    let params = ContactParams { frame_time, floor, height_threshold, speed_threshold, min_frames, causal };
    let positions = contiguous("feet", &feet)?;
    let contacts = py.detach(|| crate::footsteps::foot_contacts(positions, shape[1], shape[2], &params)).map_err(to_py)?;
    Ok(array2(contacts, (shape[0], shape[1]))?.into_pyarray(py))
}

/// Seconds since each foot last left contact [F, S] from `contacts` bool [F, S].
#[pyfunction]
fn air_time<'py>(py: Python<'py>, contacts: PyReadonlyArray2<'py, bool>, frame_time: f64) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let shape = contacts.shape().to_vec();
    if shape[1] == 0 {
        return Err(shape_error("contacts", "[F, S]", &shape));
    }
    let flags = contiguous("contacts", &contacts)?;
    let times = py.detach(|| crate::footsteps::air_time(flags, shape[1], frame_time)).map_err(to_py)?;
    Ok(array2(times, (shape[0], shape[1]))?.into_pyarray(py))
}

/// The 19 dynamic features [F, 19]: `points` [F, 3, 3] (hips, left and right upper leg, world),
/// `thighs` [F, 2, 4] (local, x y z w), `contacts` bool [F, 2], `reference` [2, 4].
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn dynamic_features<'py>(
    py: Python<'py>,
    points: PyReadonlyArray3<'py, f64>,
    thighs: PyReadonlyArray3<'py, f64>,
    contacts: PyReadonlyArray2<'py, bool>,
    reference: PyReadonlyArray2<'py, f64>,
    frame_time: f64,
    height: f64,
    hips_rest_height: f64,
    floor: f64,
    window: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let frames = points.shape()[0];
    if points.shape()[1..] != [3, 3] {
        return Err(shape_error("points", "[F, 3, 3] (hips, left and right upper leg)", points.shape()));
    }
    if thighs.shape() != [frames, 2, 4] {
        return Err(shape_error("thighs", &format!("[{frames}, 2, 4]"), thighs.shape()));
    }
    if contacts.shape() != [frames, 2] {
        return Err(shape_error("contacts", &format!("[{frames}, 2]"), contacts.shape()));
    }
    if reference.shape() != [2, 4] {
        return Err(shape_error("reference", "[2, 4]", reference.shape()));
    }
    let params = FeatureParams { frame_time, height, hips_rest_height, floor, window };
    let (p, t, c, r) = (contiguous("points", &points)?, contiguous("thighs", &thighs)?, contiguous("contacts", &contacts)?, contiguous("reference", &reference)?);
    let features = py.detach(|| crate::features::dynamic_features(p, t, c, r, &params)).map_err(to_py)?;
    Ok(array2(features, (frames, N_FEATURES))?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(foot_contacts, m)?)?;
    m.add_function(wrap_pyfunction!(air_time, m)?)?;
    m.add_function(wrap_pyfunction!(dynamic_features, m)?)?;
    Ok(())
}
