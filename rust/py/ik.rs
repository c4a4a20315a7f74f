//! Binding of `crate::ik`.

use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use super::{array, contiguous, shape_error};

/// Frames below which the solver runs without releasing the GIL (microseconds of work).
const SMALL_FRAMES: usize = 512;

/// New world rotations `(upper, lower)` [F, 4] of two-bone chains: `root` [F, 3], `upper` and
/// `lower` [F, 4], `upper_bone`, `lower_bone` and `target` [F, 3].
#[pyfunction]
#[allow(clippy::type_complexity)]
fn two_bone_ik<'py>(
    py: Python<'py>,
    root: PyReadonlyArray2<'py, f64>,
    upper: PyReadonlyArray2<'py, f64>,
    lower: PyReadonlyArray2<'py, f64>,
    upper_bone: PyReadonlyArray2<'py, f64>,
    lower_bone: PyReadonlyArray2<'py, f64>,
    target: PyReadonlyArray2<'py, f64>,
) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>)> {
    let frames = root.shape()[0];
    for (name, values, width) in [
        ("root", &root, 3),
        ("upper", &upper, 4),
        ("lower", &lower, 4),
        ("upper_bone", &upper_bone, 3),
        ("lower_bone", &lower_bone, 3),
        ("target", &target, 3),
    ] {
        if values.shape() != [frames, width] {
            return Err(shape_error(
                name,
                &format!("[{frames}, {width}]"),
                values.shape(),
            ));
        }
    }
    let args = [
        contiguous("root", &root)?,
        contiguous("upper", &upper)?,
        contiguous("lower", &lower)?,
        contiguous("upper_bone", &upper_bone)?,
        contiguous("lower_bone", &lower_bone)?,
        contiguous("target", &target)?,
    ];
    let solve = || crate::ik::two_bone_ik(args[0], args[1], args[2], args[3], args[4], args[5]);
    let (new_upper, new_lower) = if frames <= SMALL_FRAMES {
        solve()
    } else {
        py.detach(solve)
    }?;
    Ok((
        array(new_upper, (frames, 4))?.into_pyarray(py),
        array(new_lower, (frames, 4))?.into_pyarray(py),
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(two_bone_ik, m)?)
}
