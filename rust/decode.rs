//! From a frame's BVH channel values to local joint rotations and translations.

use glam::DQuat;

use crate::error::{product, zeros, KernelError, Result};
use crate::parse::{parse_frames, FrameSink};
use rayon::prelude::*;

use crate::rotations::{check_orders, euler_to_quat_one, Order, PARALLEL_MIN_ITEMS};

/// Where each joint's numbers sit in a frame of channel values.
#[derive(Debug, Clone, Copy)]
pub struct ChannelLayout<'a> {
    /// Values per frame.
    pub channels: usize,
    /// `[J, 3]`: column of each rotation angle, in the joint's order; -1 where the joint has no
    /// such channel (the angle is then 0).
    pub rotation_columns: &'a [i64],
    /// One Euler order per joint.
    pub orders: &'a [Order],
    /// `[J, 3]`: column of the x, y, z position channel; -1 keeps the rest offset.
    pub position_columns: &'a [i64],
    /// `[J, 3]`: rest offsets.
    pub offsets: &'a [f64],
}

impl ChannelLayout<'_> {
    /// # Errors
    /// `KernelError::Argument` naming the inconsistent part.
    pub fn check(&self) -> Result<()> {
        let joints = self.orders.len();
        if joints == 0 {
            return Err(KernelError::argument(
                "orders",
                "a skeleton needs at least one joint",
            ));
        }
        check_orders(self.orders)?;
        for (name, part) in [
            ("rotation_columns", self.rotation_columns),
            ("position_columns", self.position_columns),
        ] {
            if part.len() != 3 * joints {
                return Err(KernelError::argument(
                    name,
                    format!("expected {joints} x 3 values, got {}", part.len()),
                ));
            }
            if let Some(bad) = part.iter().find(|&&c| c < -1 || c >= self.channels as i64) {
                return Err(KernelError::argument(
                    name,
                    format!("column {bad} is outside 0..{} (or -1)", self.channels),
                ));
            }
        }
        if self.offsets.len() != 3 * joints {
            return Err(KernelError::argument(
                "offsets",
                format!("expected {joints} x 3 values, got {}", self.offsets.len()),
            ));
        }
        Ok(())
    }

    #[must_use]
    pub fn joints(&self) -> usize {
        self.orders.len()
    }
}

impl FrameSink for ChannelLayout<'_> {
    fn widths(&self) -> (usize, usize) {
        (4 * self.joints(), 3 * self.joints())
    }

    /// Decode one frame of channel values into its rotations and translations.
    fn emit(&self, frame: &[f64], rotations: &mut [f64], translations: &mut [f64]) {
        let value = |column: i64| {
            if column < 0 {
                0.0
            } else {
                frame[column as usize]
            }
        };
        for (j, order) in self.orders.iter().enumerate() {
            let c = &self.rotation_columns[3 * j..3 * j + 3];
            let q: DQuat = euler_to_quat_one([value(c[0]), value(c[1]), value(c[2])], *order);
            q.write_to_slice(&mut rotations[4 * j..4 * j + 4]);
        }
        for (i, (&column, &offset)) in self.position_columns.iter().zip(self.offsets).enumerate() {
            translations[i] = if column < 0 {
                offset
            } else {
                frame[column as usize]
            };
        }
    }
}

/// Decode `values` (`frames x channels`) into rotations `[F, J, 4]` and translations `[F, J, 3]`.
///
/// # Errors
/// `KernelError::Argument` when the layout is inconsistent or `values` does not hold
/// `frames x channels` numbers.
pub fn decode_channels(
    values: &[f64],
    frames: usize,
    layout: &ChannelLayout,
) -> Result<(Vec<f64>, Vec<f64>)> {
    layout.check()?;
    if values.len() != product("values", frames, layout.channels)? {
        return Err(KernelError::argument(
            "values",
            format!(
                "expected {frames} x {} values, got {}",
                layout.channels,
                values.len()
            ),
        ));
    }
    let (w0, w1) = layout.widths();
    let mut rotations = zeros("values", product("values", frames, w0)?)?;
    let mut translations = zeros("values", product("values", frames, w1)?)?;
    let decode_frame = |(f, (rot, trans)): (usize, (&mut [f64], &mut [f64]))| {
        layout.emit(
            &values[f * layout.channels..(f + 1) * layout.channels],
            rot,
            trans,
        );
    };
    if frames * layout.joints() >= PARALLEL_MIN_ITEMS {
        rotations
            .par_chunks_mut(w0)
            .zip(translations.par_chunks_mut(w1))
            .enumerate()
            .with_min_len(32)
            .for_each(decode_frame);
    } else {
        rotations
            .chunks_mut(w0)
            .zip(translations.chunks_mut(w1))
            .enumerate()
            .for_each(decode_frame);
    }
    Ok((rotations, translations))
}

/// Parse a MOTION number block and decode it in one pass: rotations `[F, J, 4]` and
/// translations `[F, J, 3]`, with no array of raw channel values in between.
///
/// # Errors
/// `KernelError::Argument` for an inconsistent layout; `KernelError::Parse` as
/// [`crate::parse::parse_frames`].
pub fn read_motion_block(
    block: &[u8],
    frames: usize,
    layout: &ChannelLayout,
) -> Result<(Vec<f64>, Vec<f64>)> {
    layout.check()?;
    parse_frames(block, frames, layout.channels, layout)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positions_replace_offsets_and_missing_angles_are_zero() {
        // One joint: channels "Yposition Zrotation"; order ZXY.
        let layout = ChannelLayout {
            channels: 2,
            rotation_columns: &[1, -1, -1],
            orders: &[[2, 0, 1]],
            position_columns: &[-1, 0, -1],
            offsets: &[1.0, 2.0, 3.0],
        };
        let (rot, trans) = decode_channels(&[5.0, 90.0], 1, &layout).unwrap();
        assert_eq!(trans, vec![1.0, 5.0, 3.0]);
        let s = std::f64::consts::FRAC_1_SQRT_2;
        assert!((rot[2] - s).abs() < 1e-12 && (rot[3] - s).abs() < 1e-12);
    }

    #[test]
    fn rejects_columns_outside_the_frame() {
        let layout = ChannelLayout {
            channels: 2,
            rotation_columns: &[2, -1, -1],
            orders: &[[0, 1, 2]],
            position_columns: &[-1; 3],
            offsets: &[0.0; 3],
        };
        assert!(decode_channels(&[0.0, 0.0], 1, &layout).is_err());
        let no_channels = ChannelLayout {
            channels: 0,
            rotation_columns: &[-1; 3],
            orders: &[[0, 1, 2]],
            position_columns: &[-1; 3],
            offsets: &[1.0; 3],
        };
        assert_eq!(
            decode_channels(&[], 2, &no_channels).unwrap().1,
            vec![1.0; 6]
        );
    }

    #[test]
    fn a_huge_frame_count_without_channels_is_an_error_not_an_abort() {
        let layout = ChannelLayout {
            channels: 0,
            rotation_columns: &[-1; 3],
            orders: &[[0, 1, 2]],
            position_columns: &[-1; 3],
            offsets: &[1.0; 3],
        };
        for frames in [usize::MAX, 1 << 61] {
            let e = decode_channels(&[], frames, &layout).unwrap_err();
            assert!(
                e.to_string().contains("does not fit") || e.to_string().contains("overflow"),
                "{e}"
            );
        }
        let e = read_motion_block(b"\n", usize::MAX, &layout).unwrap_err();
        assert!(matches!(e, KernelError::Parse { .. }), "{e:?}");
    }
}
