//! Shapes and values for the fuzz targets: mostly small counts (so the kernels run), sometimes
//! counts whose products overflow (which must be refused before anything is allocated).

use arbitrary::{Result, Unstructured};

/// Counts whose product with anything above 1 (or whose size in bytes) overflows.
const HUGE: [usize; 4] = [usize::MAX, usize::MAX / 2 + 1, usize::MAX / 3 + 1, 1 << 61];

/// A count: 0..=24 most of the time, sometimes one of [`HUGE`].
pub fn count(u: &mut Unstructured) -> Result<usize> {
    let pick = u.int_in_range(0..=27_usize)?;
    Ok(if pick > 24 { HUGE[pick - 24] } else { pick })
}

/// `wanted` floats (any bits: NaN, infinities, subnormals) or, one time in eight, a
/// length of the input's choosing, so mismatched lengths are tried too.
pub fn floats(u: &mut Unstructured, wanted: usize) -> Result<Vec<f64>> {
    let len = if u.ratio(1, 8)? || wanted > 4096 { u.int_in_range(0..=64)? } else { wanted };
    (0..len).map(|_| u.arbitrary::<f64>()).collect()
}

/// `wanted` values of any `Arbitrary` type, with the same length policy as [`floats`].
pub fn values<'a, T: arbitrary::Arbitrary<'a>>(u: &mut Unstructured<'a>, wanted: usize) -> Result<Vec<T>> {
    let len = if u.ratio(1, 8)? || wanted > 4096 { u.int_in_range(0..=64)? } else { wanted };
    (0..len).map(|_| u.arbitrary::<T>()).collect()
}
