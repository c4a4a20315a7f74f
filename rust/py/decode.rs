//! Bindings of `crate::decode`: channel values to local rotations, and MOTION blocks read whole.

use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use super::{contiguous, motion_arrays, orders_from, owned_indices};
use crate::decode::ChannelLayout;
use crate::error::KernelError;
use crate::rotations::Order;

/// A channel layout, read by attribute name (`expressive_mocap.ops.ChannelLayout`):
/// `rotation_columns` [J, 3] (column of each angle in the joint's order, -1 = none), `orders`
/// [J, 3], `position_columns` [J, 3] (x, y, z; -1 keeps the offset), `offsets` [J, 3].
#[derive(FromPyObject)]
pub(super) struct LayoutArgs<'py> {
    channels: usize,
    rotation_columns: PyReadonlyArray2<'py, i64>,
    orders: PyReadonlyArray2<'py, u8>,
    position_columns: PyReadonlyArray2<'py, i64>,
    offsets: PyReadonlyArray2<'py, f64>,
}

/// A MOTION block to read (`expressive_mocap.ops.MotionBlock`): `data[start:]` holds `frames` lines.
#[derive(FromPyObject)]
struct BlockArgs<'py> {
    data: Bound<'py, PyBytes>,
    start: usize,
    frames: usize,
    layout: LayoutArgs<'py>,
}

/// A layout's arrays, copied under the GIL (see `owned_indices`).
pub(super) struct OwnedLayout {
    channels: usize,
    rotation_columns: Vec<i64>,
    orders: Vec<Order>,
    position_columns: Vec<i64>,
    offsets: Vec<f64>,
}

impl OwnedLayout {
    pub(super) fn new(layout: &LayoutArgs<'_>) -> PyResult<Self> {
        Ok(Self {
            channels: layout.channels,
            rotation_columns: owned_indices("rotation_columns", &layout.rotation_columns)?,
            orders: orders_from(&layout.orders)?,
            position_columns: owned_indices("position_columns", &layout.position_columns)?,
            offsets: contiguous("offsets", &layout.offsets)?.to_vec(),
        })
    }

    pub(super) fn joints(&self) -> usize {
        self.orders.len()
    }

    pub(super) fn view(&self) -> ChannelLayout<'_> {
        ChannelLayout {
            channels: self.channels,
            rotation_columns: &self.rotation_columns,
            orders: &self.orders,
            position_columns: &self.position_columns,
            offsets: &self.offsets,
        }
    }
}

/// Channel values [F, C] to local rotations [F, J, 4] and translations [F, J, 3], with the
/// layout's arrays as for `LayoutArgs`.
#[pyfunction]
fn decode_channels<'py>(
    py: Python<'py>,
    values: PyReadonlyArray2<'py, f64>,
    rotation_columns: PyReadonlyArray2<'py, i64>,
    orders: PyReadonlyArray2<'py, u8>,
    position_columns: PyReadonlyArray2<'py, i64>,
    offsets: PyReadonlyArray2<'py, f64>,
) -> PyResult<Py<PyAny>> {
    let (frames, channels) = (values.shape()[0], values.shape()[1]);
    let layout = OwnedLayout::new(&LayoutArgs {
        channels,
        rotation_columns,
        orders,
        position_columns,
        offsets,
    })?;
    let slice = contiguous("values", &values)?;
    let decoded = py.detach(|| crate::decode::decode_channels(slice, frames, &layout.view()))?;
    motion_arrays(py, frames, layout.joints(), decoded)
}

/// Local rotations and translations of one block.
type Decoded = (Vec<f64>, Vec<f64>);

/// Parse and decode many MOTION blocks (`BlockArgs`), in parallel across blocks; returns per
/// block a (rotations, translations) pair or a `ParseError` instance.
#[pyfunction]
fn read_motion_blocks<'py>(
    py: Python<'py>,
    blocks: Vec<BlockArgs<'py>>,
) -> PyResult<Vec<Py<PyAny>>> {
    use rayon::prelude::*;
    let mut jobs = Vec::with_capacity(blocks.len());
    for block in &blocks {
        jobs.push((
            block.data.as_bytes(),
            block.start,
            block.frames,
            OwnedLayout::new(&block.layout)?,
        ));
    }
    let results: Vec<crate::error::Result<Decoded>> = py.detach(|| {
        jobs.par_iter()
            .map(|(bytes, start, frames, layout)| {
                let block = bytes
                    .get(*start..)
                    .ok_or_else(|| KernelError::argument("start", "past the end of `data`"))?;
                crate::decode::read_motion_block(block, *frames, &layout.view())
            })
            .collect()
    });
    results
        .into_iter()
        .zip(&jobs)
        .map(|(result, (_, _, frames, layout))| match result {
            Ok(decoded) => motion_arrays(py, *frames, layout.joints(), decoded),
            // A malformed block is that block's result; a bad argument is the caller's error.
            Err(error @ KernelError::Parse { .. }) => {
                Ok(PyErr::from(error).into_value(py).into_any())
            }
            Err(error) => Err(error.into()),
        })
        .collect()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(decode_channels, m)?)?;
    m.add_function(wrap_pyfunction!(read_motion_blocks, m)?)
}
