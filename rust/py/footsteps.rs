//! Bindings of `crate::footsteps`.

use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyReadonlyArray4, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::{array, contiguous, owned_flags, shape_error};
use crate::footsteps::ContactParams;

/// Contact flags bool [F, S] from world positions `feet` [F, S, P, 3] of P points per foot.
/// Thresholds in the positions' units (per second for speed).
#[pyfunction]
#[allow(clippy::too_many_arguments)] // Python keywords
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
    let params = ContactParams {
        frame_time,
        floor,
        height_threshold,
        speed_threshold,
        min_frames,
        causal,
    };
    let positions = contiguous("feet", &feet)?;
    let contacts =
        py.detach(|| crate::footsteps::foot_contacts(positions, shape[1], shape[2], &params))?;
    Ok(array(contacts, (shape[0], shape[1]))?.into_pyarray(py))
}

/// Seconds since each foot last left contact [F, S] from `contacts` bool [F, S].
#[pyfunction]
fn air_time<'py>(
    py: Python<'py>,
    contacts: PyReadonlyArray2<'py, bool>,
    frame_time: f64,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let shape = contacts.shape().to_vec();
    if shape[1] == 0 {
        return Err(shape_error("contacts", "[F, S]", &shape));
    }
    let flags = owned_flags("contacts", &contacts)?;
    let times = py.detach(|| crate::footsteps::air_time(&flags, shape[1], frame_time))?;
    Ok(array(times, (shape[0], shape[1]))?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(foot_contacts, m)?)?;
    m.add_function(wrap_pyfunction!(air_time, m)?)
}
