//! Binding of `crate::features`.

use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::{array, contiguous, owned_flags, shape_error};
use crate::features::{FeatureParams, N_FEATURES};

/// The 19 dynamic features [F, 19]: `points` [F, 3, 3] (hips, left and right upper leg, world),
/// `thighs` [F, 2, 4] (local, x y z w), `contacts` bool [F, 2], `reference` [2, 4].
#[pyfunction]
#[allow(clippy::too_many_arguments)] // Python keywords
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
        return Err(shape_error(
            "points",
            "[F, 3, 3] (hips, left and right upper leg)",
            points.shape(),
        ));
    }
    if thighs.shape() != [frames, 2, 4] {
        return Err(shape_error(
            "thighs",
            &format!("[{frames}, 2, 4]"),
            thighs.shape(),
        ));
    }
    if contacts.shape() != [frames, 2] {
        return Err(shape_error(
            "contacts",
            &format!("[{frames}, 2]"),
            contacts.shape(),
        ));
    }
    if reference.shape() != [2, 4] {
        return Err(shape_error("reference", "[2, 4]", reference.shape()));
    }
    let params = FeatureParams {
        frame_time,
        height,
        hips_rest_height,
        floor,
        window,
    };
    let (p, t, c, r) = (
        contiguous("points", &points)?,
        contiguous("thighs", &thighs)?,
        owned_flags("contacts", &contacts)?,
        contiguous("reference", &reference)?,
    );
    let features = py.detach(|| crate::features::dynamic_features(p, t, &c, r, &params))?;
    Ok(array(features, (frames, N_FEATURES))?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(dynamic_features, m)?)
}
