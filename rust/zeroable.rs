//! Element types `crate::error::zeros` may allocate zeroed. Sealed: only this crate can add a
//! type, since `zeros` relies on the promise for the soundness of `alloc_zeroed`.

mod sealed {
    pub trait Sealed {}
    impl Sealed for f64 {}
    impl Sealed for f32 {}
    impl Sealed for bool {}
}

/// Element types whose all-zero bit pattern is a valid value (zero, or `false`).
///
/// # Safety
/// An implementor's all-zero bit pattern must be a valid value of the type: `zeros` hands out
/// memory from `alloc_zeroed` as values of it. Sealed, so no other crate can implement it.
pub unsafe trait Zeroable: Copy + sealed::Sealed {}

// SAFETY: all-zero bits are 0.0 (f64, f32) and `false` (bool).
unsafe impl Zeroable for f64 {}
// SAFETY: as above.
unsafe impl Zeroable for f32 {}
// SAFETY: as above.
unsafe impl Zeroable for bool {}
