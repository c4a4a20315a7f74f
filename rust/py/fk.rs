//! Bindings of `crate::fk`.

use numpy::{IntoPyArray, PyArray3, PyReadonlyArray1, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::errors::argument_error;
use super::{array, contiguous, motion_arrays, owned_indices, shape_error};
use crate::error::KernelError;

/// Joint-frames below which FK runs without releasing the GIL (microseconds of work).
const SMALL_JOINT_FRAMES: usize = 4096;

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
        return Err(shape_error(
            "translations",
            &format!("[{}, {joints}, 3]", rs[0]),
            &ts,
        ));
    }
    let (r, t, p) = (
        contiguous("rotations", &rotations)?,
        contiguous("translations", &translations)?,
        owned_indices("parents", &parents)?,
    );
    // Small work (a rest pose: one frame) keeps the GIL: releasing it costs more than the work,
    // and a daemon thread that must take it back while the interpreter exits (preprocessing's
    // header threads compute rest poses) aborts the process from inside Rust.
    let (world_rot, world_pos) = if rs[0] * joints <= SMALL_JOINT_FRAMES {
        crate::fk::forward_kinematics(r, t, &p)
    } else {
        py.detach(|| crate::fk::forward_kinematics(r, t, &p))
    }?;
    Ok((
        array(world_rot, (rs[0], joints, 4))?.into_pyarray(py),
        array(world_pos, (rs[0], joints, 3))?.into_pyarray(py),
    ))
}

/// Forward kinematics of many clips, in parallel across clips: `clips` holds
/// (rotations [F, J, 4], translations [F, J, 3], parents [J]) triples; returns a
/// (world rotations, world positions) pair per clip.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn forward_kinematics_many<'py>(
    py: Python<'py>,
    clips: Vec<(
        PyReadonlyArray3<'py, f64>,
        PyReadonlyArray3<'py, f64>,
        PyReadonlyArray1<'py, i64>,
    )>,
) -> PyResult<Vec<Py<PyAny>>> {
    use rayon::prelude::*;
    let mut jobs = Vec::with_capacity(clips.len());
    for (index, (rotations, translations, parents)) in clips.iter().enumerate() {
        let (rs, ts) = (rotations.shape(), translations.shape());
        let joints = parents.len();
        if rs[1..] != [joints, 4] || ts != [rs[0], joints, 3] {
            return Err(argument_error(format!(
                "argument `clips`: clip {index} has rotations {rs:?} and translations {ts:?} for {joints} parents, expected [F, {joints}, 4] and [F, {joints}, 3]"
            )));
        }
        jobs.push((
            contiguous("clips", rotations)?,
            contiguous("clips", translations)?,
            owned_indices("clips", parents)?,
            rs[0],
        ));
    }
    let results: Vec<Result<(Vec<f64>, Vec<f64>), KernelError>> = py.detach(|| {
        jobs.par_iter()
            .map(|(r, t, p, _)| crate::fk::forward_kinematics(r, t, p))
            .collect()
    });
    results
        .into_iter()
        .zip(&jobs)
        .map(|(result, (_, _, parents, frames))| motion_arrays(py, *frames, parents.len(), result?))
        .collect()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(forward_kinematics, m)?)?;
    m.add_function(wrap_pyfunction!(forward_kinematics_many, m)?)
}
