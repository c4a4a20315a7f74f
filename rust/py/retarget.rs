//! Binding of `crate::retarget`.

use numpy::{
    IntoPyArray, PyArray3, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3,
    PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use super::{array, contiguous, owned_indices, shape_error};
use crate::retarget::{transfer, TransferPlan};

/// Joint-frames below which the transfer runs without releasing the GIL (as FK: a rest pose).
const SMALL_JOINT_FRAMES: usize = 4096;

/// A retargeting plan (`expressive_mocap.ops.TransferPlan`), read by attribute name.
#[derive(FromPyObject)]
struct PlanArgs<'py> {
    source: PyReadonlyArray1<'py, i64>,
    target: PyReadonlyArray1<'py, i64>,
    aligns: PyReadonlyArray2<'py, f64>,
    swung: PyReadonlyArray1<'py, i64>,
    starts: PyReadonlyArray1<'py, i64>,
    ends: PyReadonlyArray1<'py, i64>,
    rest_lines: PyReadonlyArray2<'py, f64>,
    shared: PyReadonlyArray1<'py, i64>,
    tops: PyReadonlyArray1<'py, i64>,
    bottoms: PyReadonlyArray1<'py, i64>,
    shares: PyReadonlyArray1<'py, f64>,
    held: PyReadonlyArray1<'py, i64>,
    copied: PyReadonlyArray1<'py, i64>,
    parents: PyReadonlyArray1<'py, i64>,
    reference: PyReadonlyArray2<'py, f64>,
    turn_source: [f64; 4],
    turn_target: [f64; 4],
}

/// The target skeleton's local rotations [F, Jt, 4] from the source's world rotations
/// `world` [F, Js, 4] and positions `positions` [F, Js, 3], along `plan`.
#[pyfunction]
fn retarget_transfer<'py>(
    py: Python<'py>,
    world: PyReadonlyArray3<'py, f64>,
    positions: PyReadonlyArray3<'py, f64>,
    plan: PlanArgs<'py>,
) -> PyResult<Bound<'py, PyArray3<f64>>> {
    let (ws, ps) = (world.shape().to_vec(), positions.shape().to_vec());
    if ws[2] != 4 {
        return Err(shape_error("world", "[F, J, 4]", &ws));
    }
    if ps != [ws[0], ws[1], 3] {
        return Err(shape_error(
            "positions",
            &format!("[{}, {}, 3]", ws[0], ws[1]),
            &ps,
        ));
    }
    // Index arrays copied under the GIL (see `owned_indices`); float ones read in place.
    let indices = [
        owned_indices("plan", &plan.source)?,
        owned_indices("plan", &plan.target)?,
        owned_indices("plan", &plan.swung)?,
        owned_indices("plan", &plan.starts)?,
        owned_indices("plan", &plan.ends)?,
        owned_indices("plan", &plan.shared)?,
        owned_indices("plan", &plan.tops)?,
        owned_indices("plan", &plan.bottoms)?,
        owned_indices("plan", &plan.held)?,
        owned_indices("plan", &plan.copied)?,
        owned_indices("plan", &plan.parents)?,
    ];
    let [source, target, swung, starts, ends, shared, tops, bottoms, held, copied, parents] =
        &indices;
    let request = TransferPlan {
        source,
        target,
        aligns: contiguous("plan", &plan.aligns)?,
        swung,
        starts,
        ends,
        rest_lines: contiguous("plan", &plan.rest_lines)?,
        shared,
        tops,
        bottoms,
        shares: contiguous("plan", &plan.shares)?,
        held,
        copied,
        parents,
        reference: contiguous("plan", &plan.reference)?,
        turn_source: plan.turn_source,
        turn_target: plan.turn_target,
    };
    let (w, p) = (
        contiguous("world", &world)?,
        contiguous("positions", &positions)?,
    );
    let joints = parents.len();
    let out = if ws[0] * joints <= SMALL_JOINT_FRAMES {
        transfer(w, p, ws[1], &request)
    } else {
        py.detach(|| transfer(w, p, ws[1], &request))
    }?;
    Ok(array(out, (ws[0], joints, 4))?.into_pyarray(py))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(retarget_transfer, m)?)
}
