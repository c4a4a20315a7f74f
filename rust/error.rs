//! The one error type of the kernels. Pure Rust: `rust/py/` maps it to Python exceptions.

use std::fmt;

/// Everything a kernel can refuse. Kernels return these; they never panic on input.
#[derive(Debug, Clone, PartialEq)]
pub enum KernelError {
    /// The MOTION number block is malformed. `line` counts from 0 at the block's first line,
    /// so the caller (who knows where the block starts in the file) can name the file line.
    Parse { line: usize, message: String },
    /// An argument has the wrong shape or an invalid value.
    Argument { name: &'static str, message: String },
}

impl KernelError {
    pub(crate) fn argument(name: &'static str, message: impl Into<String>) -> Self {
        Self::Argument {
            name,
            message: message.into(),
        }
    }
}

impl fmt::Display for KernelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Parse { line, message } => {
                write!(f, "line {} of the MOTION block: {message}", line + 1)
            }
            Self::Argument { name, message } => write!(f, "argument `{name}`: {message}"),
        }
    }
}

impl std::error::Error for KernelError {}

pub type Result<T> = std::result::Result<T, KernelError>;

pub use crate::zeroable::Zeroable;

/// `len` zeros for an output array, or an error naming `name` when that many do not fit in
/// memory: a caller's shapes (e.g. a huge frame count with no channels, or a layer of a
/// million outputs) must give an error, not abort the process as `vec![0.0; len]` would.
/// Zeroed pages come from the allocator (`calloc`), as `vec!` does, so a large output is not
/// written twice.
///
/// # Errors
/// `KernelError::Argument` when `len` elements overflow or cannot be allocated.
#[allow(clippy::same_length_and_capacity)] // the allocation holds exactly `len` zeroed elements
pub fn zeros<T: Zeroable>(name: &'static str, len: usize) -> Result<Vec<T>> {
    let too_big = || {
        KernelError::argument(
            name,
            format!("the output of {len} values does not fit in memory"),
        )
    };
    if len == 0 || std::mem::size_of::<T>() == 0 {
        return Ok(Vec::new());
    }
    let layout = std::alloc::Layout::array::<T>(len).map_err(|_| too_big())?;
    // SAFETY: `layout` has a non-zero size (len > 0, T not zero-sized). A non-null pointer
    // from the global allocator with this layout holds `len` zeroed T, a valid value of every
    // `Zeroable` type; the Vec takes ownership with the same capacity and layout.
    unsafe {
        let pointer = std::alloc::alloc_zeroed(layout).cast::<T>();
        if pointer.is_null() {
            return Err(too_big());
        }
        Ok(Vec::from_raw_parts(pointer, len, len))
    }
}

/// `Ok` when `value` is finite and above 0, else an error naming `name`: the one check of
/// every positive parameter (frame times, body scale, decoupling gain and exponent).
///
/// # Errors
/// `KernelError::Argument` when `value` is NaN, infinite, zero or negative.
pub fn positive(name: &'static str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(KernelError::argument(
            name,
            format!("must be a positive number, got {value}"),
        ))
    }
}

/// `a * b`, or an error naming `name` when the product overflows.
///
/// # Errors
/// `KernelError::Argument` on overflow.
pub fn product(name: &'static str, a: usize, b: usize) -> Result<usize> {
    a.checked_mul(b)
        .ok_or_else(|| KernelError::argument(name, format!("{a} x {b} elements overflow")))
}
