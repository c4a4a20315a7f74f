//! Binding of `crate::gait`: the gait arrays of many clips.

use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::errors::argument_error;
use super::{array, contiguous, shape_error};
use crate::features::N_FEATURES;
use crate::gait::{BodyScale, FeatureRequest, GaitParams};

/// Joint order of `roles`.
const GAIT_ROLES: &str =
    "[hips, left upper leg, right upper leg, left foot, right foot, left toe, right toe]";

/// The thresholds of contact detection (`expressive_mocap.ops.GaitSettings`), read by attribute name.
#[derive(FromPyObject)]
pub(super) struct GaitArgs {
    height_threshold: f64,
    speed_threshold: f64,
    min_duration: f64,
    floor_percentile: f64,
}

impl From<&GaitArgs> for GaitParams {
    fn from(args: &GaitArgs) -> Self {
        GaitParams {
            height_threshold: args.height_threshold,
            speed_threshold: args.speed_threshold,
            min_duration: args.min_duration,
            floor_percentile: args.floor_percentile,
        }
    }
}

/// The 7 gait joints `roles` in `GAIT_ROLES` order, or an ArgumentError naming the argument.
pub(super) fn gait_joints(roles: &[usize]) -> PyResult<crate::gait::GaitJoints> {
    let [hips, left_leg, right_leg, left_foot, right_foot, left_toe, right_toe] = roles[..] else {
        return Err(argument_error(format!(
            "argument `roles`: expected 7 joint indices {GAIT_ROLES}, got {}",
            roles.len()
        )));
    };
    Ok(crate::gait::GaitJoints {
        hips,
        upper_legs: [left_leg, right_leg],
        feet: [left_foot, right_foot],
        toes: [left_toe, right_toe],
    })
}

/// The 8 numbers of a thigh reference `[2, 4]` (None stays None), or an error naming the
/// argument `name` and the `expected` shape.
pub(super) fn thigh_reference_values(
    name: &str,
    expected: &str,
    array: Option<&PyReadonlyArray2<'_, f64>>,
) -> PyResult<Option<[f64; 8]>> {
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
#[allow(
    clippy::too_many_arguments,
    clippy::type_complexity,
    clippy::fn_params_excessive_bools
)] // Python keywords
fn clip_gait_many<'py>(
    py: Python<'py>,
    clips: Vec<(
        PyReadonlyArray3<'py, f64>,
        PyReadonlyArray3<'py, f64>,
        f64,
        f64,
        f64,
    )>,
    roles: Vec<usize>,
    height_threshold: f64,
    speed_threshold: f64,
    min_duration: f64,
    floor_percentile: f64,
    features: bool,
    contacts: bool,
    feature_floor: Option<f64>,
    thigh_reference: Option<PyReadonlyArray2<'py, f64>>,
) -> PyResult<
    Vec<(
        Option<Bound<'py, PyArray2<f64>>>,
        Option<Bound<'py, PyArray2<bool>>>,
    )>,
> {
    use crate::gait::clip_gait;
    use rayon::prelude::*;
    let joints = gait_joints(&roles)?;
    let reference = thigh_reference_values("thigh_reference", "[2, 4]", thigh_reference.as_ref())?;
    let request = features.then_some(FeatureRequest {
        floor: feature_floor,
        thigh_reference: reference,
    });
    let params = GaitParams {
        height_threshold,
        speed_threshold,
        min_duration,
        floor_percentile,
    };
    let mut jobs = Vec::with_capacity(clips.len());
    for (index, (positions, rotations, frame_time, height, hips_rest_height)) in
        clips.iter().enumerate()
    {
        let (ps, rs) = (positions.shape(), rotations.shape());
        if ps[2] != 3 || rs != [ps[0], ps[1], 4] {
            return Err(argument_error(format!(
                "argument `clips`: clip {index} has positions {ps:?} and rotations {rs:?}, expected [F, J, 3] and [F, J, 4]"
            )));
        }
        let scale = BodyScale {
            height: *height,
            hips_rest_height: *hips_rest_height,
        };
        jobs.push((
            contiguous("clips", positions)?,
            contiguous("clips", rotations)?,
            ps[1],
            *frame_time,
            scale,
        ));
    }
    let results: Vec<_> = py.detach(|| {
        jobs.par_iter()
            .map(|&(p, r, j, ft, scale)| {
                clip_gait(
                    p,
                    r,
                    j,
                    ft,
                    scale,
                    &joints,
                    &params,
                    request.as_ref(),
                    contacts,
                )
            })
            .collect()
    });
    results
        .into_iter()
        .enumerate()
        .map(|(index, result)| {
            let gait = result.map_err(|e| argument_error(format!("clip {index}: {e}")))?;
            let frames = jobs[index].0.len() / (jobs[index].2 * 3);
            let features = gait
                .features
                .map(|f| array(f, (frames, N_FEATURES)).map(|a| a.into_pyarray(py)))
                .transpose()?;
            let contacts = gait
                .contacts
                .map(|c| array(c, (frames, 2)).map(|a| a.into_pyarray(py)))
                .transpose()?;
            Ok((features, contacts))
        })
        .collect()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(clip_gait_many, m)?)
}
