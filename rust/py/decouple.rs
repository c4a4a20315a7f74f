//! Bindings of `crate::decouple`.

use glam::DVec3;
use numpy::{
    IntoPyArray, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray3, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use rayon::prelude::*;

use super::{array, contiguous, shape_error};

/// A split's outputs: E* and B' [F, J, 4], the activity [F, J].
type Split<'py> = (
    Bound<'py, PyArray3<f64>>,
    Bound<'py, PyArray3<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// The shape [F, J, 4] two arrays of rotations share (each given with its argument's name), or
/// an error naming the second.
fn same_quaternions(
    (first_name, first): (&str, &PyReadonlyArray3<'_, f64>),
    (second_name, second): (&str, &PyReadonlyArray3<'_, f64>),
) -> PyResult<Vec<usize>> {
    let shape = first.shape().to_vec();
    if shape[2] != 4 || second.shape() != shape.as_slice() {
        return Err(shape_error(
            second_name,
            &format!("{shape:?} like `{first_name}` (quaternions [F, J, 4])"),
            second.shape(),
        ));
    }
    Ok(shape)
}

/// A kernel's `(E*, B', A)` as arrays of a clip of `shape` [F, J, 4].
fn split_arrays<'py>(
    py: Python<'py>,
    expressive: Vec<f64>,
    recovered: Vec<f64>,
    activity: Vec<f64>,
    shape: &[usize],
) -> PyResult<Split<'py>> {
    let dims = (shape[0], shape[1], 4);
    Ok((
        array(expressive, dims)?.into_pyarray(py),
        array(recovered, dims)?.into_pyarray(py),
        array(activity, (shape[0], shape[1]))?.into_pyarray(py),
    ))
}

/// Decouple `original` from `body` rotations (both [F, J, 4], x y z w): returns the filtered
/// expressive rotations E* [F, J, 4], the recovered body mechanics B' [F, J, 4] and the
/// activity index [F, J]. `gain` and `exponent` have no default here: the package's are
/// `expressive_mocap.decouple.GAIN` and `EXPONENT`, passed by `expressive_mocap.ops`.
#[pyfunction]
fn decouple_rotations<'py>(
    py: Python<'py>,
    original: PyReadonlyArray3<'py, f64>,
    body: PyReadonlyArray3<'py, f64>,
    gain: f64,
    exponent: f64,
) -> PyResult<Split<'py>> {
    let shape = same_quaternions(("original", &original), ("body", &body))?;
    let (o, b) = (
        contiguous("original", &original)?,
        contiguous("body", &body)?,
    );
    let (e, recovered, a) = py.detach(|| crate::decouple::decouple(o, b, gain, exponent))?;
    split_arrays(py, e, recovered, a, &shape)
}

/// One clip's split with the body mechanics and the activity smoothed in time: `original` and
/// `body` [F, J, 4], `scale` [J] (the angle's divisor per joint), the Gaussians' widths in frames
/// (0: none), and the trunk chain read as one (`trunk_joints` from the hips up, empty: none;
/// `trunk_bones` [n, 3] the bone each carries, the last one's to the neck; `trunk_scale` its
/// lean's divisor), and the limbs filtered in world axes (`arm_joints`, empty: none, with the
/// skeleton's `arm_parents`).
/// Returns E* [F, J, 4], B' [F, J, 4] and the activity [F, J].
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (original, body, gain, exponent, scale, body_sigma, activity_sigma, trunk_joints=vec![], trunk_bones=vec![], trunk_scale=1.0, arm_parents=vec![], arm_joints=vec![]))]
fn split_rotations<'py>(
    py: Python<'py>,
    original: PyReadonlyArray3<'py, f64>,
    body: PyReadonlyArray3<'py, f64>,
    gain: f64,
    exponent: f64,
    scale: PyReadonlyArray1<'py, f64>,
    body_sigma: f64,
    activity_sigma: f64,
    trunk_joints: Vec<usize>,
    trunk_bones: Vec<[f64; 3]>,
    trunk_scale: f64,
    arm_parents: Vec<i64>,
    arm_joints: Vec<usize>,
) -> PyResult<Split<'py>> {
    let shape = same_quaternions(("original", &original), ("body", &body))?;
    if scale.shape() != [shape[1]] {
        return Err(shape_error(
            "scale",
            &format!("[{}] (one value per joint of `original`)", shape[1]),
            scale.shape(),
        ));
    }
    let (o, b, s) = (
        contiguous("original", &original)?,
        contiguous("body", &body)?,
        contiguous("scale", &scale)?,
    );
    let bones: Vec<DVec3> = trunk_bones.into_iter().map(DVec3::from_array).collect();
    let chains = Chains {
        trunk: (&trunk_joints[..], &bones[..], trunk_scale),
        arms: (&arm_parents[..], &arm_joints[..]),
    };
    let (e, recovered, a) = py.detach(|| {
        smoothed_split(
            o,
            b,
            gain,
            exponent,
            s,
            (body_sigma, activity_sigma),
            &chains,
        )
    })?;
    split_arrays(py, e, recovered, a, &shape)
}

/// The chains a split reads as wholes: the trunk (joints, bones, scale; no joints: none) and the
/// arms (the skeleton's parents, the limbs filtered in world axes; no limbs: none).
struct Chains<'a> {
    trunk: (&'a [usize], &'a [DVec3], f64),
    arms: (&'a [i64], &'a [usize]),
}

/// One clip's [`crate::decouple::split`] with its smoothing widths `(body, activity)`, the
/// per-joint `scale` and its `chains`.
fn smoothed_split(
    original: &[f64],
    body: &[f64],
    gain: f64,
    exponent: f64,
    scale: &[f64],
    (body_sigma, activity_sigma): (f64, f64),
    chains: &Chains,
) -> crate::error::Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
    let (joints, bones, trunk_scale) = chains.trunk;
    let trunk = (!joints.is_empty()).then_some(crate::decouple::Trunk {
        joints,
        bones,
        scale: trunk_scale,
    });
    let (parents, limbs) = chains.arms;
    let arms = (!limbs.is_empty()).then_some(crate::decouple::Arms { parents, limbs });
    let smoothing = crate::decouple::Smoothing {
        body_sigma,
        activity_sigma,
        scale,
        trunk,
        arms,
    };
    crate::decouple::split(original, body, gain, exponent, &smoothing)
}

/// [`split_rotations`] of many clips in one call, clips in parallel: `originals` and `bodies`
/// (one [F, J, 4] array per clip, the same J for all), `body_sigmas` and `activity_sigmas` (one
/// width per clip: each clip smoothed in its own time), the other arguments shared. Returns each
/// clip's E*, B' and activity, in order, exactly as [`split_rotations`] gives them clip by clip.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
#[pyo3(signature = (originals, bodies, gain, exponent, scale, body_sigmas, activity_sigmas, trunk_joints=vec![], trunk_bones=vec![], trunk_scale=1.0, arm_parents=vec![], arm_joints=vec![]))]
fn split_rotations_many<'py>(
    py: Python<'py>,
    originals: Vec<PyReadonlyArray3<'py, f64>>,
    bodies: Vec<PyReadonlyArray3<'py, f64>>,
    gain: f64,
    exponent: f64,
    scale: PyReadonlyArray1<'py, f64>,
    body_sigmas: Vec<f64>,
    activity_sigmas: Vec<f64>,
    trunk_joints: Vec<usize>,
    trunk_bones: Vec<[f64; 3]>,
    trunk_scale: f64,
    arm_parents: Vec<i64>,
    arm_joints: Vec<usize>,
) -> PyResult<Vec<Split<'py>>> {
    let clips = originals.len();
    for (name, count) in [
        ("bodies", bodies.len()),
        ("body_sigmas", body_sigmas.len()),
        ("activity_sigmas", activity_sigmas.len()),
    ] {
        if count != clips {
            return Err(shape_error(
                name,
                &format!("{clips} entries (one per clip of `originals`)"),
                &[count],
            ));
        }
    }
    let s = contiguous("scale", &scale)?;
    let mut jobs = Vec::with_capacity(clips);
    for (original, body) in originals.iter().zip(&bodies) {
        let shape = same_quaternions(("originals", original), ("bodies", body))?;
        if shape[1] != s.len() {
            return Err(shape_error(
                "scale",
                &format!("[{}] (one value per joint of each clip)", shape[1]),
                scale.shape(),
            ));
        }
        jobs.push((
            contiguous("originals", original)?,
            contiguous("bodies", body)?,
            shape,
        ));
    }
    let bones: Vec<DVec3> = trunk_bones.into_iter().map(DVec3::from_array).collect();
    let chains = Chains {
        trunk: (&trunk_joints[..], &bones[..], trunk_scale),
        arms: (&arm_parents[..], &arm_joints[..]),
    };
    let results = py.detach(|| {
        jobs.par_iter()
            .zip(body_sigmas.par_iter().zip(&activity_sigmas))
            .map(|((o, b, _), (&body_sigma, &activity_sigma))| {
                smoothed_split(
                    o,
                    b,
                    gain,
                    exponent,
                    s,
                    (body_sigma, activity_sigma),
                    &chains,
                )
            })
            .collect::<Result<Vec<_>, _>>()
    })?;
    results
        .into_iter()
        .zip(&jobs)
        .map(|((e, recovered, a), (_, _, shape))| split_arrays(py, e, recovered, a, shape))
        .collect()
}

/// Recompose `expressive^scale * body` for rotations [F, J, 4].
#[pyfunction]
#[pyo3(signature = (expressive, body, scale=1.0))]
fn compose_rotations<'py>(
    py: Python<'py>,
    expressive: PyReadonlyArray3<'py, f64>,
    body: PyReadonlyArray3<'py, f64>,
    scale: f64,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let shape = same_quaternions(("body", &body), ("expressive", &expressive))?;
    let (e, b) = (
        contiguous("expressive", &expressive)?,
        contiguous("body", &body)?,
    );
    let out = py.detach(|| crate::decouple::compose(e, b, scale))?;
    Ok(array(out, (shape[0], shape[1], 4))?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(decouple_rotations, m)?)?;
    m.add_function(wrap_pyfunction!(split_rotations, m)?)?;
    m.add_function(wrap_pyfunction!(split_rotations_many, m)?)?;
    m.add_function(wrap_pyfunction!(compose_rotations, m)?)?;
    Ok(())
}
