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
        Self::Argument { name, message: message.into() }
    }
}

impl fmt::Display for KernelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Parse { line, message } => write!(f, "line {} of the MOTION block: {message}", line + 1),
            Self::Argument { name, message } => write!(f, "argument `{name}`: {message}"),
        }
    }
}

impl std::error::Error for KernelError {}

pub type Result<T> = std::result::Result<T, KernelError>;
