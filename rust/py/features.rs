//! Bindings of `crate::features` and `crate::footsteps`.

use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyReadonlyArray4, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use super::{contiguous, owned_flags, shape_error, to_py};
use crate::features::{FeatureParams, N_FEATURES};
use crate::footsteps::ContactParams;

pub(super) fn array2<T: numpy::Element>(values: Vec<T>, shape: (usize, usize)) -> PyResult<Array2<T>> {
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
    let flags = owned_flags("contacts", &contacts)?;
    let times = py.detach(|| crate::footsteps::air_time(&flags, shape[1], frame_time)).map_err(to_py)?;
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
    let (p, t, c, r) = (contiguous("points", &points)?, contiguous("thighs", &thighs)?, owned_flags("contacts", &contacts)?, contiguous("reference", &reference)?);
    let features = py.detach(|| crate::features::dynamic_features(p, t, &c, r, &params)).map_err(to_py)?;
    Ok(array2(features, (frames, N_FEATURES))?.into_pyarray(py))
}

/// Joint order of `clip_gait_many`'s `roles`.
const GAIT_ROLES: &str = "[hips, left upper leg, right upper leg, left foot, right foot, left toe, right toe]";

/// The 7 gait joints `roles` in `GAIT_ROLES` order, or a ValueError naming the argument.
pub(super) fn gait_joints(roles: &[usize]) -> PyResult<crate::gait::GaitJoints> {
    let [hips, left_leg, right_leg, left_foot, right_foot, left_toe, right_toe] = roles[..] else {
        return Err(PyValueError::new_err(format!("argument `roles`: expected 7 joint indices {GAIT_ROLES}, got {}", roles.len())));
    };
    Ok(crate::gait::GaitJoints { hips, upper_legs: [left_leg, right_leg], feet: [left_foot, right_foot], toes: [left_toe, right_toe] })
}

/// The 8 numbers of a thigh reference `[2, 4]` (None stays None), or an error naming the
/// argument `name` and the `expected` shape.
pub(super) fn thigh_reference_values(name: &str, expected: &str, array: Option<&PyReadonlyArray2<'_, f64>>) -> PyResult<Option<[f64; 8]>> {
    match array {
        None => Ok(None),
        Some(array) if array.shape() == [2, 4] => {
            let mut values = [0.0; 8];
            values.copy_from_slice(contiguous(name, array)?);
            Ok(Some(values))
        }
        Some(array) => Err(shape_error(name, expected, array.shape())),
    }
}

/// Gait arrays of many clips, clips in parallel: each clip `(positions [F, J, 3] world,
/// rotations [F, J, 4] local, frame_time, height, hips_rest_height)`; `roles`: 7 joint indices (see `GAIT_ROLES`).
/// Returns per clip `(features [F, 19] or None, contacts bool [F, 2] or None)`: causal features
/// on `feature_floor` (None: the toe-height percentile) with `thigh_reference` [2, 4] (None: the
/// first frame), offline contacts on the toe-height percentile floor.
#[pyfunction]
#[pyo3(signature = (clips, roles, height_threshold, speed_threshold, min_duration, floor_percentile, features, contacts, feature_floor=None, thigh_reference=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn clip_gait_many<'py>(
    py: Python<'py>,
    clips: Vec<(PyReadonlyArray3<'py, f64>, PyReadonlyArray3<'py, f64>, f64, f64, f64)>,
    roles: Vec<usize>,
    height_threshold: f64,
    speed_threshold: f64,
    min_duration: f64,
    floor_percentile: f64,
    features: bool,
    contacts: bool,
    feature_floor: Option<f64>,
    thigh_reference: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<Vec<(Option<Bound<'py, PyArray2<f64>>>, Option<Bound<'py, PyArray2<bool>>>)>> {
    use crate::gait::{clip_gait, BodyScale, FeatureRequest, GaitParams};
    use rayon::prelude::*;
    let joints = gait_joints(&roles)?;
    let reference = thigh_reference_values("thigh_reference", "[2, 4]", thigh_reference.as_ref())?;
    let request = features.then_some(FeatureRequest { floor: feature_floor, thigh_reference: reference });
    let params = GaitParams { height_threshold, speed_threshold, min_duration, floor_percentile };
    let mut jobs = Vec::with_capacity(clips.len());
    for (index, (positions, rotations, frame_time, height, hips_rest_height)) in clips.iter().enumerate() {
        let (ps, rs) = (positions.shape(), rotations.shape());
        if ps[2] != 3 || rs != [ps[0], ps[1], 4] {
            return Err(PyValueError::new_err(format!(
                "argument `clips`: clip {index} has positions {ps:?} and rotations {rs:?}, expected [F, J, 3] and [F, J, 4]"
            )));
        }
        let scale = BodyScale { height: *height, hips_rest_height: *hips_rest_height };
        jobs.push((contiguous("clips", positions)?, contiguous("clips", rotations)?, ps[1], *frame_time, scale));
    }
    let results: Vec<_> = py.detach(|| {
        jobs.par_iter().map(|&(p, r, j, ft, scale)| clip_gait(p, r, j, ft, scale, &joints, &params, request.as_ref(), contacts)).collect()
    });
    results
        .into_iter()
        .enumerate()
        .map(|(index, result)| {
            let gait = result.map_err(|e| PyValueError::new_err(format!("clip {index}: {e}")))?;
            let frames = jobs[index].0.len() / (jobs[index].2 * 3);
            let features = gait.features.map(|f| array2(f, (frames, N_FEATURES)).map(|a| a.into_pyarray(py))).transpose()?;
            let contacts = gait.contacts.map(|c| array2(c, (frames, 2)).map(|a| a.into_pyarray(py))).transpose()?;
            Ok((features, contacts))
        })
        .collect()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(foot_contacts, m)?)?;
    m.add_function(wrap_pyfunction!(air_time, m)?)?;
    m.add_function(wrap_pyfunction!(dynamic_features, m)?)?;
    m.add_function(wrap_pyfunction!(clip_gait_many, m)?)?;
    Ok(())
}
