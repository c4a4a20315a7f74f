//! The one conversion of kernel errors to Python exceptions: the classes of
//! `expressive_mocap.errors`, imported once (on first use) so both backends raise the same ones.

use numpy::ndarray::{Array, Dimension, StrideShape};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyType;

use crate::error::KernelError;

static ARGUMENT_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static ARGUMENT_TYPE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();
static PARSE_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// `expressive_mocap.errors.<name>`, imported the first time it is needed.
fn error_class<'py>(
    py: Python<'py>,
    cell: &'static PyOnceLock<Py<PyType>>,
    name: &str,
) -> PyResult<&'py Bound<'py, PyType>> {
    cell.import(py, "expressive_mocap.errors", name)
}

/// An `ArgumentError(message)`: a bad argument, `message` naming it.
pub(super) fn argument_error(message: String) -> PyErr {
    Python::attach(
        |py| match error_class(py, &ARGUMENT_ERROR, "ArgumentError") {
            Ok(class) => PyErr::from_type(class.clone(), message),
            Err(error) => error,
        },
    )
}

/// An `ArgumentTypeError(message)` (an `ArgumentError` and a `TypeError`): an argument of the
/// wrong dtype or memory order, `message` naming it.
pub(super) fn argument_type_error(message: String) -> PyErr {
    Python::attach(
        |py| match error_class(py, &ARGUMENT_TYPE_ERROR, "ArgumentTypeError") {
            Ok(class) => PyErr::from_type(class.clone(), message),
            Err(error) => error,
        },
    )
}

/// An `ArgumentError` for `name` whose shape is not `expected`.
pub(super) fn shape_error(name: &str, expected: &str, got: &[usize]) -> PyErr {
    argument_error(format!(
        "argument `{name}`: expected shape {expected}, got {got:?}"
    ))
}

impl From<KernelError> for PyErr {
    fn from(error: KernelError) -> Self {
        match error {
            KernelError::Parse { line, message } => {
                Python::attach(|py| match error_class(py, &PARSE_ERROR, "ParseError") {
                    Ok(class) => PyErr::from_type(class.clone(), (message, line)),
                    Err(error) => error,
                })
            }
            other @ KernelError::Argument { .. } => argument_error(other.to_string()),
        }
    }
}

/// An n-D array of `values` in `shape`: the one place kernel outputs become arrays. A
/// mismatch would be a kernel's bug, not the caller's: a RuntimeError, not a panic.
pub(super) fn array<T, D: Dimension>(
    values: Vec<T>,
    shape: impl Into<StrideShape<D>>,
) -> PyResult<Array<T, D>> {
    Array::from_shape_vec(shape, values)
        .map_err(|e| PyRuntimeError::new_err(format!("kernel output of the wrong size: {e}")))
}
