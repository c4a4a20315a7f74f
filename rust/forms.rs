//! Model-ready forms of a batch of clips (`expressive_mocap.dataset.derive`): rotations as
//! matrix columns, time derivatives clip by clip, and the column sums behind normalisation
//! statistics. Each is one pass over a batch's rows, in parallel, so a whole archive's
//! derived arrays cost a fraction of reading it.

use rayon::prelude::*;

use crate::error::{zeros, KernelError, Result};
use crate::rotations::PARALLEL_MIN_ITEMS;

/// Rows handed to one rayon task: big enough that scheduling is noise, small enough that two
/// cores share a batch evenly.
const ROWS_PER_TASK: usize = 4096;

/// The rotation matrices of unit quaternions `quats` `[N, 4]` (x, y, z, w), computed in f64 and
/// rounded to f32: with `columns == 3` the whole matrix row after row (`[N, 9]`), with
/// `columns == 2` its first two columns one after the other (`[N, 6]`, the "6D" form).
///
/// # Errors
/// `KernelError::Argument` when `quats` is not a multiple of 4 long or `columns` is not 2 or 3.
pub fn matrix_columns(quats: &[f64], columns: usize) -> Result<Vec<f32>> {
    if quats.len() % 4 != 0 {
        return Err(KernelError::argument(
            "quats",
            format!("length {} is not N x 4", quats.len()),
        ));
    }
    if !(columns == 2 || columns == 3) {
        return Err(KernelError::argument(
            "columns",
            format!("expected 2 (6d) or 3 (the whole matrix), got {columns}"),
        ));
    }
    let width = 3 * columns;
    let mut out = zeros("quats", quats.len() / 4 * width)?;
    let one = |(q, dst): (&[f64], &mut [f32])| write_matrix(q, dst, |v| v as f32);
    if quats.len() >= 4 * PARALLEL_MIN_ITEMS {
        quats
            .par_chunks(4)
            .zip(out.par_chunks_mut(width))
            .with_min_len(ROWS_PER_TASK)
            .for_each(one);
    } else {
        quats.chunks(4).zip(out.chunks_mut(width)).for_each(one);
    }
    Ok(out)
}

/// The rotation matrix of one unit quaternion `q` (x, y, z, w) into `dst`: 9 values row after
/// row, or 6 (its first two columns, column after column), each through `cast`.
#[inline]
pub(crate) fn write_matrix<T>(q: &[f64], dst: &mut [T], cast: impl Fn(f64) -> T) {
    let m = matrix(q[0], q[1], q[2], q[3]);
    let whole = dst.len() == 9;
    for (k, value) in dst.iter_mut().enumerate() {
        *value = cast(if whole {
            m[k / 3][k % 3]
        } else {
            m[k % 3][k / 3]
        });
    }
}

/// The rotation matrix `m[row][col]` of the unit quaternion (x, y, z, w).
#[inline]
fn matrix(x: f64, y: f64, z: f64, w: f64) -> [[f64; 3]; 3] {
    let (xx, yy, zz) = (x * x, y * y, z * z);
    let (xy, xz, yz, wx, wy, wz) = (x * y, x * z, y * z, w * x, w * y, w * z);
    [
        [1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)],
        [2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx)],
        [2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy)],
    ]
}

/// The time derivative of rows `values` `[N, width]`, clip by clip, as `np.gradient`: central
/// differences inside a clip, one-sided at its first and last row, zero for a one-row clip; no
/// difference spans two clips. Clips begin at rows `starts` (rising, the first 0); each row's
/// clip's seconds per frame are `frame_time` `[N]`.
///
/// # Errors
/// `KernelError::Argument` naming `values`, `starts` or `frame_time` when their lengths or the
/// starts do not fit these shapes.
pub fn clip_gradient(
    values: &[f64],
    width: usize,
    starts: &[i64],
    frame_time: &[f64],
) -> Result<Vec<f64>> {
    if width == 0 || values.len() % width != 0 {
        return Err(KernelError::argument(
            "values",
            format!("length {} is not N x {width}", values.len()),
        ));
    }
    let rows = values.len() / width;
    if frame_time.len() != rows {
        return Err(KernelError::argument(
            "frame_time",
            format!(
                "expected one value a row ({rows}), got {}",
                frame_time.len()
            ),
        ));
    }
    let rising = starts.windows(2).all(|w| w[0] <= w[1]);
    let fits = starts.first() == Some(&0) && rising && starts.last() <= Some(&(rows as i64));
    let nothing = rows == 0 && starts.is_empty();
    if !(fits || nothing) {
        return Err(KernelError::argument(
            "starts",
            format!("expected rising row indices from 0 to at most {rows}"),
        ));
    }
    let mut out = zeros("values", values.len())?;
    // Each clip's rows of the output, split off in turn so the clips can be filled in parallel.
    let mut clips = Vec::with_capacity(starts.len());
    let mut rest = out.as_mut_slice();
    let starts: Vec<usize> = starts.iter().map(|&s| s as usize).collect(); // checked: 0 to rows
    for (k, &start) in starts.iter().enumerate() {
        let end = starts.get(k + 1).copied().unwrap_or(rows);
        let (clip, tail) = rest.split_at_mut((end - start) * width);
        clips.push((start, clip));
        rest = tail;
    }
    let one = |(start, clip): (usize, &mut [f64])| {
        let rows = start * width..start * width + clip.len();
        write_gradient(&values[rows], width, |i| frame_time[start + i], clip);
    };
    if values.len() >= PARALLEL_MIN_ITEMS {
        clips.into_par_iter().for_each(one);
    } else {
        clips.into_iter().for_each(one);
    }
    Ok(out)
}

/// The time derivative of one clip's rows `values` `[n, width]` into `out` (as [`clip_gradient`]),
/// row `i` a frame of `frame_time(i)` seconds.
pub(crate) fn write_gradient(
    values: &[f64],
    width: usize,
    frame_time: impl Fn(usize) -> f64,
    out: &mut [f64],
) {
    let n = values.len() / width;
    if n < 2 {
        return; // zero: a clip of one row does not move
    }
    let row = |i: usize| &values[i * width..(i + 1) * width];
    for (i, dst) in out.chunks_exact_mut(width).enumerate() {
        let (ahead, behind, scale) = match i {
            0 => (row(1), row(0), frame_time(0)),
            _ if i == n - 1 => (row(i), row(i - 1), frame_time(i)),
            _ => (row(i + 1), row(i - 1), 2.0 * frame_time(i)),
        };
        for ((d, a), b) in dst.iter_mut().zip(ahead).zip(behind) {
            *d = (a - b) / scale;
        }
    }
}

/// The f64 sums of the rows of each of `arrays` (each `[n_i, width]` f32) and of their squares,
/// column by column: `arrays.len()` rows of `width` each, the increments of running normalisation
/// statistics. Each array is summed row after row in its order (arrays in parallel), so an array's
/// sums are the same whatever arrays come with it: a dataset's statistics, added clip by clip in
/// the dataset's order, do not depend on how its clips were batched.
///
/// # Errors
/// `KernelError::Argument` naming `arrays` when one is not a multiple of `width` long.
pub fn column_totals(arrays: &[&[f32]], width: usize) -> Result<(Vec<f64>, Vec<f64>)> {
    if let Some(k) = arrays
        .iter()
        .position(|a| width == 0 || a.len() % width != 0)
    {
        return Err(KernelError::argument(
            "arrays",
            format!(
                "array {k} of {} values is not rows of {width}",
                arrays[k].len()
            ),
        ));
    }
    let (mut sums, mut squares) = (
        vec![0.0; arrays.len() * width],
        vec![0.0; arrays.len() * width],
    );
    sums.par_chunks_mut(width)
        .zip(squares.par_chunks_mut(width))
        .zip(arrays.par_iter())
        .for_each(|((sums, squares), array)| {
            for row in array.chunks_exact(width) {
                for ((s, q), &v) in sums.iter_mut().zip(squares.iter_mut()).zip(row) {
                    let v = f64::from(v);
                    *s += v;
                    *q += v * v;
                }
            }
        });
    Ok((sums, squares))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DQuat};

    #[test]
    fn matrix_columns_are_glams_matrix() {
        let q = DQuat::from_euler(glam::EulerRot::ZXY, 0.3, -1.1, 2.5);
        let m = DMat3::from_quat(q);
        let flat = [q.x, q.y, q.z, q.w];
        let whole = matrix_columns(&flat, 3).unwrap();
        let six = matrix_columns(&flat, 2).unwrap();
        for row in 0..3 {
            for col in 0..3 {
                let want = m.col(col)[row];
                assert!((f64::from(whole[3 * row + col]) - want).abs() < 1e-7);
                if col < 2 {
                    assert!((f64::from(six[3 * col + row]) - want).abs() < 1e-7);
                }
            }
        }
        assert!(matrix_columns(&flat[..3], 2).is_err());
        assert!(matrix_columns(&flat, 1).is_err());
    }

    #[test]
    fn gradient_is_per_clip_and_one_sided_at_the_ends() {
        // Two clips of one column: x = t^2 (rows 0-3) then a one-row clip, then x = 3t (rows 5-6).
        let values = [0.0, 1.0, 4.0, 9.0, 7.0, 0.0, 3.0];
        let out = clip_gradient(&values, 1, &[0, 4, 5], &[1.0; 7]).unwrap();
        assert_eq!(out, vec![1.0, 2.0, 4.0, 5.0, 0.0, 3.0, 3.0]);
        let halved = clip_gradient(&values, 1, &[0, 4, 5], &[0.5; 7]).unwrap();
        assert_eq!(halved[..2], [2.0, 4.0]);
        assert!(clip_gradient(&values, 1, &[1, 4], &[1.0; 7]).is_err());
        assert!(clip_gradient(&values, 1, &[0, 5, 4], &[1.0; 7]).is_err());
        assert!(clip_gradient(&values, 1, &[0, 8], &[1.0; 7]).is_err());
        assert!(clip_gradient(&values, 1, &[0], &[1.0; 6]).is_err());
        assert!(clip_gradient(&values, 2, &[0], &[1.0; 3]).is_err());
        assert!(clip_gradient(&[], 1, &[5], &[]).is_err());
        assert_eq!(clip_gradient(&[], 1, &[], &[]).unwrap(), Vec::<f64>::new());
    }

    #[test]
    fn totals_sum_each_array_row_after_row() {
        let long: Vec<f32> = (0..2 * (ROWS_PER_TASK + 3))
            .map(|i| (i % 7) as f32 * 0.1)
            .collect();
        let short = [1.0f32, -2.0];
        let (sums, squares) = column_totals(&[&long, &short], 2).unwrap();
        let mut want = (vec![0.0f64; 4], vec![0.0f64; 4]);
        for (k, array) in [&long[..], &short[..]].iter().enumerate() {
            for row in array.chunks(2) {
                for c in 0..2 {
                    want.0[2 * k + c] += f64::from(row[c]);
                    want.1[2 * k + c] += f64::from(row[c]).powi(2);
                }
            }
        }
        assert_eq!((sums, squares), want); // bit for bit: each array in its own order
        let (alone, _) = column_totals(&[&short], 2).unwrap();
        assert_eq!(alone, want.0[2..].to_vec()); // whatever arrays come with it
        assert!(column_totals(&[&short[..1]], 2).is_err());
        assert_eq!(column_totals(&[], 3).unwrap(), (vec![], vec![]));
    }
}
