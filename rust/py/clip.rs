//! Binding of the whole per-clip work (`crate::clip`): many clips in one call, in parallel.

use std::path::PathBuf;

use numpy::ndarray::{Dimension, Ix2, Ix3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList};

use super::decode::{LayoutArgs, OwnedLayout};
use super::gait::{gait_joints, thigh_reference_values, GaitArgs};
use super::{array, owned_indices};
use crate::clip::{clip_outputs, read_input, ClipInput, ClipOutputs, ClipRequest, ReadError};
use crate::error::KernelError;
use crate::features::N_FEATURES;
use crate::gait::{BodyScale, FeatureRequest, GaitParams};
use crate::heads::Head;

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
        Ok(match self {
            Self::F64(v) => array(v, shape)?.into_pyarray(py).into_any().unbind(),
            Self::F32(v) => array(v, shape)?.into_pyarray(py).into_any().unbind(),
        })
    }
}

struct Converted {
    positions: Option<Floats>,
    rotations: Option<Floats>,
    features: Vec<Floats>,
    contacts: Option<Vec<bool>>,
    velocities: Option<Floats>,
}

/// One clip (`expressive_mocap.ops.ClipInput`), read by attribute name: `source` the file's
/// bytes or its path, `start` where its MOTION block begins, `frames`, its channel `layout`,
/// `frame_time` and body scale (`height`, `hips_rest_height`).
#[derive(FromPyObject)]
struct ClipArgs<'py> {
    source: Source<'py>,
    start: usize,
    frames: usize,
    layout: LayoutArgs<'py>,
    frame_time: f64,
    height: f64,
    hips_rest_height: f64,
}

/// One causal feature array to compute (`expressive_mocap.ops.FeatureRequest`).
#[derive(FromPyObject)]
struct FeatureArgs<'py> {
    floor: Option<f64>,
    thigh_reference: Option<PyReadonlyArray2<'py, f64>>,
}

/// What to keep of each clip (`expressive_mocap.ops.PipelineOutputs`).
#[derive(FromPyObject)]
#[allow(clippy::struct_excessive_bools)] // one flag per output, named
struct OutputArgs<'py> {
    positions: bool,
    rotations: bool,
    rotation_columns: usize,
    velocities: bool,
    features: Vec<FeatureArgs<'py>>,
    contacts: bool,
    float32: bool,
}

/// The whole per-clip work of many clips of one skeleton: MOTION block, FK, features, contacts.
///
/// `clips`: `ClipArgs`, whose file, when given by path, is read here (a regular file of at most
/// `max_bytes`, by default `expressive_mocap._utils.files.MAX_INPUT_BYTES`). `parents` [J]; `roles` the
/// 7 gait joints; `gait` the thresholds of contact detection. Kept per clip (`outputs`): world
/// `positions` [F, J, 3], local `rotations` [F, J, 4] (or, with `rotation_columns` 2 or 3, their
/// matrices' first columns [F, J, 6] or whole matrices [F, J, 9]), one causal feature array
/// [F, 19] per `features` request `(floor or None, thigh_reference [2, 4] or None)`, offline
/// `contacts` bool [F, 2], the positions' `velocities` [F, J, 3]; float arrays in float32 when
/// `float32`. Returns per clip `(positions or None, rotations or None, [features...], contacts or
/// None, velocities or None)`, or a `ParseError` (malformed block) or `OSError` (unreadable or
/// refused file) instance in its place.
#[pyfunction]
#[pyo3(signature = (clips, parents, roles, gait, outputs, max_bytes=None))]
#[allow(clippy::too_many_lines)] // one sequence: arguments, parallel work, results
fn clip_pipeline_many<'py>(
    py: Python<'py>,
    clips: Vec<ClipArgs<'py>>,
    parents: PyReadonlyArray1<'py, i64>,
    roles: Vec<usize>,
    gait: GaitArgs,
    outputs: OutputArgs<'py>,
    max_bytes: Option<u64>,
) -> PyResult<Vec<Py<PyAny>>> {
    use rayon::prelude::*;
    let max_bytes = input_bound(py, max_bytes)?;
    let float32 = outputs.float32;
    let mut requests = Vec::with_capacity(outputs.features.len());
    for feature in &outputs.features {
        let thigh_reference = thigh_reference_values(
            "features",
            "[2, 4] thigh reference",
            feature.thigh_reference.as_ref(),
        )?;
        requests.push(FeatureRequest {
            floor: feature.floor,
            thigh_reference,
        });
    }
    let parents = owned_indices("parents", &parents)?;
    let request = ClipRequest {
        parents: &parents,
        roles: gait_joints(&roles)?,
        params: GaitParams::from(&gait),
        positions: outputs.positions,
        rotations: outputs.rotations,
        rotation_columns: outputs.rotation_columns,
        velocities: outputs.velocities,
        features: &requests,
        contacts: outputs.contacts,
    };
    let mut jobs = Vec::with_capacity(clips.len());
    for clip in &clips {
        let text = match &clip.source {
            Source::Bytes(bytes) => Text::Bytes(bytes.as_bytes()),
            Source::Path(path) => Text::Path(path.clone()),
        };
        let scale = BodyScale {
            height: clip.height,
            hips_rest_height: clip.hips_rest_height,
        };
        jobs.push((
            text,
            clip.start,
            clip.frames,
            OwnedLayout::new(&clip.layout)?,
            clip.frame_time,
            scale,
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
                    velocities,
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
                    velocities: velocities.map(|v| Floats::new(v, float32)),
                })
            })
            .collect()
    });
    let joints = parents.len();
    let rotation_width = match outputs.rotation_columns {
        0 => 4,
        columns => 3 * columns,
    };
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
                    .map(|r| r.into_py(py, Ix3(frames, joints, rotation_width)))
                    .transpose()?;
                let features = out
                    .features
                    .into_iter()
                    .map(|f| f.into_py(py, Ix2(frames, N_FEATURES)))
                    .collect::<PyResult<Vec<_>>>()?;
                let contacts = out
                    .contacts
                    .map(|c| array(c, (frames, 2)).map(|a| a.into_pyarray(py)))
                    .transpose()?;
                let velocities = out
                    .velocities
                    .map(|v| v.into_py(py, Ix3(frames, joints, 3)))
                    .transpose()?;
                let features = PyList::new(py, features)?;
                Ok((positions, rotations, features, contacts, velocities)
                    .into_pyobject(py)?
                    .into_any()
                    .unbind())
            }
            // A malformed block or an unreadable file is that clip's result; a bad argument is the caller's error.
            Err(Failure::Kernel(error @ KernelError::Parse { .. })) => {
                Ok(PyErr::from(error).into_value(py).into_any())
            }
            Err(Failure::Kernel(error)) => Err(error.into()),
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

/// The headers of files that repeat the header `template` (a header's bytes through its MOTION
/// line, of `joints` joints; `crate::heads`), read in parallel without the GIL from each file's
/// first `count` bytes (regular files of at most `max_bytes`, by default
/// `expressive_mocap._utils.files.MAX_INPUT_BYTES`). Per path `(frames, frame_time, block_start)`, or
/// `(first bytes, size)` of a file to read in full, or an `OSError` instance.
#[pyfunction]
#[pyo3(signature = (paths, template, joints, count, max_bytes=None))]
fn repeated_headers(
    py: Python<'_>,
    paths: Vec<PathBuf>,
    template: &[u8],
    joints: usize,
    count: usize,
    max_bytes: Option<u64>,
) -> PyResult<Vec<Py<PyAny>>> {
    let max_bytes = input_bound(py, max_bytes)?;
    let heads =
        py.detach(|| crate::heads::repeated_headers(&paths, count, max_bytes, template, joints));
    heads
        .into_iter()
        .map(|head| {
            Ok(match head {
                Head::Repeated(t) => (t.frames, t.frame_time, t.block_start)
                    .into_pyobject(py)?
                    .into_any()
                    .unbind(),
                Head::Other(data, size) => (PyBytes::new(py, &data), size)
                    .into_pyobject(py)?
                    .into_any()
                    .unbind(),
                Head::Failed(error) => os_error(&error).into_value(py).into_any(),
            })
        })
        .collect()
}

/// The bound on a file's bytes: the caller's, else the package's (one bound for every reader of
/// BVH text, `expressive_mocap._utils.files.MAX_INPUT_BYTES`).
fn input_bound(py: Python<'_>, given: Option<u64>) -> PyResult<u64> {
    match given {
        Some(bound) => Ok(bound),
        None => py
            .import("expressive_mocap._utils.files")?
            .getattr("MAX_INPUT_BYTES")?
            .extract(),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(clip_pipeline_many, m)?)?;
    m.add_function(wrap_pyfunction!(repeated_headers, m)?)?;
    Ok(())
}
