//! Writing the MOTION number block: the inverse of `parse`.

use std::fmt::Write;

use rayon::prelude::*;

use crate::error::{KernelError, Result};

/// Format `values` (`frames x channels`, frame-major) as text, one frame a line, separated by
/// single spaces. `decimals = None` writes the shortest text that reads back to the same
/// float64 (exact round trip); `Some(n)` writes `n` digits after the point.
///
/// # Errors
/// `KernelError::Argument` when `values` is not a multiple of `channels` long or holds a
/// non-finite number.
pub fn format_motion_block(
    values: &[f64],
    channels: usize,
    decimals: Option<usize>,
) -> Result<String> {
    if channels == 0 || values.len() % channels != 0 {
        return Err(KernelError::argument(
            "values",
            format!(
                "length {} is not a multiple of {channels} channels",
                values.len()
            ),
        ));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(KernelError::argument(
            "values",
            format!(
                "frame {}, channel {} is {}",
                i / channels,
                i % channels,
                values[i]
            ),
        ));
    }
    let lines: Vec<String> = values
        .par_chunks(channels)
        .with_min_len(256)
        .map(|frame| {
            let mut line = String::with_capacity(frame.len() * 12);
            for (c, &v) in frame.iter().enumerate() {
                if c > 0 {
                    line.push(' ');
                }
                // Writing into a String cannot fail.
                let _ = match decimals {
                    // Shortest round-trip representation; never an exponent.
                    None => write!(line, "{}", if v == 0.0 { 0.0 } else { v }),
                    Some(n) => write!(line, "{v:.n$}"),
                };
            }
            line.push('\n');
            line
        })
        .collect();
    Ok(lines.concat())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::parse_motion_block;

    #[test]
    fn shortest_format_round_trips_exactly() {
        let values = [0.1, -1.0 / 3.0, 1e-300, 123_456_789.123_456_78, 0.0, -0.0];
        let text = format_motion_block(&values, 3, None).unwrap();
        let back = parse_motion_block(text.as_bytes(), 2, 3).unwrap();
        assert_eq!(back, values);
    }

    #[test]
    fn fixed_decimals() {
        assert_eq!(
            format_motion_block(&[1.0, -0.25], 2, Some(3)).unwrap(),
            "1.000 -0.250\n"
        );
        assert!(format_motion_block(&[f64::NAN], 1, None).is_err());
    }
}
