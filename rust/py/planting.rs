//! Binding of `crate::planting`.

use numpy::{
    IntoPyArray, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use super::{array, contiguous, owned_flags, owned_indices, shape_error};

/// Joint-frames below which planting runs without releasing the GIL (as FK: a rest pose).
const SMALL_JOINT_FRAMES: usize = 4096;

/// The local rotations [F, J, 4] of a motion (`rotations` [F, J, 4], `translations` [F, J, 3],
/// `parents` [J]) with its feet planted: `legs` [2, 3] (hip, knee, foot; -1s: left as it is),
/// `contacts` bool [F, 2], `guide` [F, 2, 3], `starts` [C + 1], `blend` frames of easing.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn plant_feet<'py>(
    py: Python<'py>,
    rotations: PyReadonlyArray3<'py, f64>,
    translations: PyReadonlyArray3<'py, f64>,
    parents: PyReadonlyArray1<'py, i64>,
    legs: PyReadonlyArray2<'py, i64>,
    contacts: PyReadonlyArray2<'py, bool>,
    guide: PyReadonlyArray3<'py, f64>,
    starts: PyReadonlyArray1<'py, i64>,
    blend: usize,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let rs = rotations.shape().to_vec();
    let joints = parents.len();
    if rs[1] != joints || rs[2] != 4 {
        return Err(shape_error("rotations", &format!("[F, {joints}, 4]"), &rs));
    }
    let frames = rs[0];
    for (name, shape, expected) in [
        (
            "translations",
            translations.shape(),
            vec![frames, joints, 3],
        ),
        ("contacts", contacts.shape(), vec![frames, 2]),
        ("guide", guide.shape(), vec![frames, 2, 3]),
        ("legs", legs.shape(), vec![2, 3]),
    ] {
        if shape != expected.as_slice() {
            return Err(shape_error(name, &format!("{expected:?}"), shape));
        }
    }
    let leg_joints = owned_indices("legs", &legs)?;
    let legs = [
        [leg_joints[0], leg_joints[1], leg_joints[2]],
        [leg_joints[3], leg_joints[4], leg_joints[5]],
    ];
    let (p, s, c) = (
        owned_indices("parents", &parents)?,
        owned_indices("starts", &starts)?,
        owned_flags("contacts", &contacts)?,
    );
    let (r, t, g) = (
        contiguous("rotations", &rotations)?,
        contiguous("translations", &translations)?,
        contiguous("guide", &guide)?,
    );
    let plant = || crate::planting::plant_feet(r, t, &p, &legs, &c, g, &s, blend);
    let out = if frames * joints <= SMALL_JOINT_FRAMES {
        plant()
    } else {
        py.detach(plant)
    }?;
    Ok(array(out, (frames, joints, 4))?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(plant_feet, m)?)
}
