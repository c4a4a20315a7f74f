//! Binding of the whole per-clip work (`crate::clip`): many clips in one call, in parallel.

use std::path::PathBuf;

use numpy::ndarray::{Array, Dimension, Ix2, Ix3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList};

use super::features::{array2, gait_joints, thigh_reference_values};
use super::{owned_indices, to_py, OwnedLayout};
use crate::clip::{clip_outputs, read_input, ClipInput, ClipOutputs, ClipRequest, ReadError};
use crate::error::KernelError;
use crate::features::N_FEATURES;
use crate::gait::{BodyScale, FeatureRequest, GaitParams};

/// Where a clip's text is: in memory, or in a file this call reads (inside the parallel work,
/// so an archive's files are read on every core without the GIL).
#[derive(FromPyObject)]
enum Source<'py> {
    Bytes(Bound<'py, PyBytes>),
    Path(PathBuf),
}

enum Text<'a> {
    Bytes(&'a [u8]),
    Path(PathBuf),
}

enum Failure {
    Kernel(KernelError),
    Read(ReadError),
}

/// A float array in the precision asked for, converted inside the parallel work.
enum Floats {
    F64(Vec<f64>),
    F32(Vec<f32>),
}

impl Floats {
    fn new(values: Vec<f64>, float32: bool) -> Self {
        if float32 {
            Self::F32(values.iter().map(|&v| v as f32).collect())
        } else {
            Self::F64(values)
        }
    }

    fn into_py<D: Dimension>(self, py: Python<'_>, shape: D) -> PyResult<Py<PyAny>> {
        let error = |e: numpy::ndarray::ShapeError| PyValueError::new_err(e.to_string());
        Ok(match self {
            Self::F64(v) => Array::from_shape_vec(shape, v)
                .map_err(error)?
                .into_pyarray(py)
                .into_any()
                .unbind(),
            Self::F32(v) => Array::from_shape_vec(shape, v)
                .map_err(error)?
                .into_pyarray(py)
                .into_any()
                .unbind(),
        })
    }
}

struct Converted {
    positions: Option<Floats>,
    rotations: Option<Floats>,
    features: Vec<Floats>,
    contacts: Option<Vec<bool>>,
}

type ClipArgs<'py> = (
    Source<'py>,
    usize,
    usize,
    usize,
    PyReadonlyArray2<'py, i64>,
    PyReadonlyArray2<'py, u8>,
    PyReadonlyArray2<'py, i64>,
    PyReadonlyArray2<'py, f64>,
    f64,
    f64,
    f64,
);

/// The whole per-clip work of many clips of one skeleton: MOTION block, FK, features, contacts.
///
/// `clips`: per clip `(source, start, frames, channels, rotation_columns, orders,
/// position_columns, offsets, frame_time, height, hips_rest_height)`: `source` the file's bytes
/// or its path (read here: a regular file of at most `max_bytes`, by default
/// `expressive_mocap.files.MAX_INPUT_BYTES`), `start` where its MOTION block begins, the layout arrays as for
/// `read_motion_blocks`, the body scale as for `clip_gait_many`. `parents` [J]; `roles` the 7
/// gait joints. Kept per clip: world `positions` [F, J, 3], local `rotations` [F, J, 4], one
/// causal feature array [F, 19] per `features` request `(floor or None, thigh_reference [2, 4]
/// or None)`, offline `contacts` bool [F, 2]; float arrays in float32 when `float32`. Returns per
/// clip `(positions or None, rotations or None, [features...], contacts or None)`, or a
/// `ParseError` (malformed block) or `OSError` (unreadable or refused file) instance in its place.
#[pyfunction]
#[pyo3(signature = (clips, parents, roles, height_threshold, speed_threshold, min_duration, floor_percentile, positions, rotations, features, contacts, float32, max_bytes=None))]
#[allow(
    clippy::too_many_arguments,
    clippy::too_many_lines,
    clippy::fn_params_excessive_bools
)] // Python keywords
fn clip_pipeline_many<'py>(
    py: Python<'py>,
    clips: Vec<ClipArgs<'py>>,
    parents: PyReadonlyArray1<'py, i64>,
    roles: Vec<usize>,
    height_threshold: f64,
    speed_threshold: f64,
    min_duration: f64,
    floor_percentile: f64,
    positions: bool,
    rotations: bool,
    features: Vec<(Option<f64>, Option<PyReadonlyArray2<'py, f64>>)>,
    contacts: bool,
    float32: bool,
    max_bytes: Option<u64>,
) -> PyResult<Vec<Py<PyAny>>> {
    use rayon::prelude::*;
    // One bound for every reader of BVH text: the package's, unless the caller gives one.
    let max_bytes = match max_bytes {
        Some(bound) => bound,
        None => py
            .import("expressive_mocap.files")?
            .getattr("MAX_INPUT_BYTES")?
            .extract()?,
    };
    let mut requests = Vec::with_capacity(features.len());
    for (floor, reference) in &features {
        let thigh_reference =
            thigh_reference_values("features", "[2, 4] thigh reference", reference.as_ref())?;
        requests.push(FeatureRequest {
            floor: *floor,
            thigh_reference,
        });
    }
    let parents = owned_indices("parents", &parents)?;
    let request = ClipRequest {
        parents: &parents,
        roles: gait_joints(&roles)?,
        params: GaitParams {
            height_threshold,
            speed_threshold,
            min_duration,
            floor_percentile,
        },
        positions,
        rotations,
        features: &requests,
        contacts,
    };
    let mut jobs = Vec::with_capacity(clips.len());
    for (
        source,
        start,
        frames,
        channels,
        rotation_columns,
        orders,
        position_columns,
        offsets,
        frame_time,
        height,
        hips_rest_height,
    ) in &clips
    {
        let text = match source {
            Source::Bytes(bytes) => Text::Bytes(bytes.as_bytes()),
            Source::Path(path) => Text::Path(path.clone()),
        };
        let layout = OwnedLayout::new(
            *channels,
            &(
                rotation_columns.clone(),
                orders.clone(),
                position_columns.clone(),
                offsets.clone(),
            ),
        )?;
        jobs.push((
            text,
            *start,
            *frames,
            layout,
            *frame_time,
            BodyScale {
                height: *height,
                hips_rest_height: *hips_rest_height,
            },
        ));
    }
    let results: Vec<Result<Converted, Failure>> = py.detach(|| {
        jobs.par_iter()
            .map(|(text, start, frames, layout, frame_time, scale)| {
                let read;
                let data = match text {
                    Text::Bytes(bytes) => *bytes,
                    Text::Path(path) => {
                        read = read_input(path, max_bytes).map_err(Failure::Read)?;
                        &read[..]
                    }
                };
                let block = data.get(*start..).ok_or_else(|| {
                    Failure::Kernel(KernelError::argument(
                        "start",
                        "past the end of the clip's text",
                    ))
                })?;
                let clip = ClipInput {
                    block,
                    frames: *frames,
                    layout: layout.view(),
                    frame_time: *frame_time,
                    scale: *scale,
                };
                let ClipOutputs {
                    positions,
                    rotations,
                    features,
                    contacts,
                } = clip_outputs(&clip, &request).map_err(Failure::Kernel)?;
                Ok(Converted {
                    positions: positions.map(|v| Floats::new(v, float32)),
                    rotations: rotations.map(|v| Floats::new(v, float32)),
                    features: features
                        .into_iter()
                        .map(|v| Floats::new(v, float32))
                        .collect(),
                    contacts,
                })
            })
            .collect()
    });
    let joints = parents.len();
    results
        .into_iter()
        .zip(&jobs)
        .map(|(result, (_, _, frames, _, _, _))| match result {
            Ok(out) => {
                let frames = *frames;
                let positions = out
                    .positions
                    .map(|p| p.into_py(py, Ix3(frames, joints, 3)))
                    .transpose()?;
                let rotations = out
                    .rotations
                    .map(|r| r.into_py(py, Ix3(frames, joints, 4)))
                    .transpose()?;
                let features = out
                    .features
                    .into_iter()
                    .map(|f| f.into_py(py, Ix2(frames, N_FEATURES)))
                    .collect::<PyResult<Vec<_>>>()?;
                let contacts = out
                    .contacts
                    .map(|c| array2(c, (frames, 2)).map(|a| a.into_pyarray(py)))
                    .transpose()?;
                Ok((positions, rotations, PyList::new(py, features)?, contacts)
                    .into_pyobject(py)?
                    .into_any()
                    .unbind())
            }
            // A malformed block or an unreadable file is that clip's result; a bad argument is the caller's error.
            Err(Failure::Kernel(error @ KernelError::Parse { .. })) => {
                Ok(to_py(error).into_value(py).into_any())
            }
            Err(Failure::Kernel(error)) => Err(to_py(error)),
            Err(Failure::Read(error)) => Ok(os_error(&error).into_value(py).into_any()),
        })
        .collect()
}

/// An `OSError` with `errno` and `strerror` as Python's own `open` (Rust's message without its
/// " (os error N)" suffix) or `io.open_input` gives them, so both backends name a failed read
/// the same way.
fn os_error(error: &ReadError) -> PyErr {
    let error = match error {
        ReadError::Refused { errno, message } => {
            return PyOSError::new_err((*errno, message.clone()))
        }
        ReadError::Os(error) => error,
    };
    match error.raw_os_error() {
        Some(code) => {
            let text = error.to_string();
            let suffix = format!(" (os error {code})");
            PyOSError::new_err((
                code,
                text.strip_suffix(&suffix).unwrap_or(&text).to_string(),
            ))
        }
        None => PyOSError::new_err(error.to_string()),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(clip_pipeline_many, m)?)?;
    Ok(())
}
