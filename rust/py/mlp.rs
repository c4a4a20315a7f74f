//! Bindings of `crate::mlp`.

use numpy::{
    Element, IntoPyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

use super::errors::{argument_error, argument_type_error};
use super::{array, contiguous, shape_error};
use crate::mlp::{mlp_forward as forward, Activation, Layer, Scalar};

fn dtype_error(name: &str, layer: usize, array: &Bound<'_, PyAny>, dtype: &str) -> PyErr {
    let got = array.cast::<PyUntypedArray>().map_or_else(
        |_| array.get_type().to_string(),
        |a| format!("{} array of {} dimensions", a.dtype(), a.ndim()),
    );
    argument_type_error(format!(
        "argument `{name}`: layer {layer} must be a {dtype} array like `x`, got {got}"
    ))
}

fn forward_typed<'py, T: Scalar + Element>(
    py: Python<'py>,
    x: &PyReadonlyArray2<'py, T>,
    weights: &[Bound<'py, PyAny>],
    biases: &[Bound<'py, PyAny>],
    activations: &[String],
    dtype: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let n = weights.len();
    if biases.len() != n || activations.len() != n {
        return Err(argument_error(format!(
            "arguments `weights`, `biases`, `activations`: one of each a layer, got {n}, {} and {}",
            biases.len(),
            activations.len()
        )));
    }
    let mut ws = Vec::with_capacity(n);
    let mut bs = Vec::with_capacity(n);
    for (i, (w, b)) in weights.iter().zip(biases).enumerate() {
        ws.push(
            w.extract::<PyReadonlyArray2<'py, T>>()
                .map_err(|_| dtype_error("weights", i, w, &format!("2-D {dtype}")))?,
        );
        bs.push(
            b.extract::<PyReadonlyArray1<'py, T>>()
                .map_err(|_| dtype_error("biases", i, b, &format!("1-D {dtype}")))?,
        );
    }
    let acts = activations
        .iter()
        .enumerate()
        .map(|(i, a)| Activation::parse(a, i))
        .collect::<Result<Vec<_>, _>>()?;
    let (rows, columns) = (x.shape()[0], x.shape()[1]);
    if let Some(first) = ws.first() {
        if first.shape()[0] != columns {
            return Err(shape_error(
                "x",
                &format!("[N, {}] (the inputs of layer 0)", first.shape()[0]),
                x.shape(),
            ));
        }
    }
    let mut layers = Vec::with_capacity(n);
    for ((w, b), activation) in ws.iter().zip(&bs).zip(acts) {
        let (inputs, outputs) = (w.shape()[0], w.shape()[1]);
        layers.push(Layer {
            weights: contiguous("weights", w)?,
            bias: contiguous("biases", b)?,
            inputs,
            outputs,
            activation,
        });
    }
    let xs = contiguous("x", x)?;
    let out = py.detach(|| forward(xs, rows, &layers))?;
    let outputs = layers.last().map_or(0, |l| l.outputs);
    Ok(array(out, (rows, outputs))?.into_pyarray(py).into_any())
}

/// Batched forward pass of a dense network: `act_i(h_{i-1} @ weights[i] + biases[i])`.
///
/// Args:
///     x: float32 or float64 [N, in], C-contiguous.
///     weights: per layer [in_i, out_i], same dtype as `x`, C-contiguous.
///     biases: per layer [out_i], same dtype.
///     activations: per layer "tanh" or "linear".
///
/// Returns:
///     [N, out] in the dtype of `x`. The GIL is released: inputs written meanwhile give a mix of old and new values.
#[pyfunction]
fn mlp_forward<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    weights: Vec<Bound<'py, PyAny>>,
    biases: Vec<Bound<'py, PyAny>>,
    activations: Vec<String>,
) -> PyResult<Bound<'py, PyAny>> {
    if let Ok(x32) = x.extract::<PyReadonlyArray2<'py, f32>>() {
        return forward_typed(py, &x32, &weights, &biases, &activations, "float32");
    }
    let x64 = x.extract::<PyReadonlyArray2<'py, f64>>().map_err(|_| {
        let got = x.cast::<PyUntypedArray>().map_or_else(
            |_| x.get_type().to_string(),
            |a| format!("{} array of {} dimensions", a.dtype(), a.ndim()),
        );
        argument_type_error(format!(
            "argument `x`: expected a 2-D float32 or float64 array, got {got}"
        ))
    })?;
    forward_typed(py, &x64, &weights, &biases, &activations, "float64")
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mlp_forward, m)?)?;
    Ok(())
}
