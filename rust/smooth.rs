//! Gaussian smoothing along frames, zero phase with the ends held: SciPy's `gaussian_filter1d`
//! (`mode="nearest"`, `truncate=4`), which the NumPy twins call.

use rayon::prelude::*;

/// The normalised weights of a Gaussian of `sigma` frames over `-r..=r`, `r = floor(4 sigma + 0.5)`.
#[must_use]
pub fn gaussian_weights(sigma: f64) -> Vec<f64> {
    // Truncation to an integer radius, as SciPy does.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let radius = (4.0 * sigma + 0.5) as usize;
    #[allow(clippy::cast_precision_loss)]
    let mut weights: Vec<f64> = (0..=2 * radius)
        .map(|i| {
            let x = i as f64 - radius as f64;
            (-0.5 * (x / sigma) * (x / sigma)).exp()
        })
        .collect();
    let total: f64 = weights.iter().sum();
    for w in &mut weights {
        *w /= total;
    }
    weights
}

/// `series` (frame after frame, `width` values each) smoothed along the frames with `weights`
/// (of odd length, centred), frames before the first and after the last read as those.
#[must_use]
pub fn smooth_frames(series: &[f64], width: usize, weights: &[f64]) -> Vec<f64> {
    let frames = series.len() / width;
    let radius = weights.len() / 2;
    let mut out = vec![0.0; series.len()];
    if frames == 0 {
        return out;
    }
    out.par_chunks_mut(width)
        .enumerate()
        .with_min_len(64)
        .for_each(|(frame, row)| {
            for (k, w) in weights.iter().enumerate() {
                let source = (frame + k).saturating_sub(radius).min(frames - 1);
                let values = &series[source * width..(source + 1) * width];
                row.iter_mut().zip(values).for_each(|(r, v)| *r += w * v);
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_hold_a_constant_and_a_line() {
        let w = gaussian_weights(1.5);
        assert_eq!(w.len(), 13);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        let line: Vec<f64> = (0..40).map(f64::from).collect();
        let smoothed = smooth_frames(&line, 1, &w);
        for f in 6..34 {
            assert!((smoothed[f] - line[f]).abs() < 1e-12, "{f}");
        }
        assert!(smoothed[0] > line[0]); // the first frame held: the line bends up at its start
    }
}
