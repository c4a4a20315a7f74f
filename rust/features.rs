//! Per-frame dynamic features of a motion (the decoupling method of Boehs et al.): hips velocity and its 1/3 s
//! mean in the heading frame, foot contacts, air time, relative hips height, thigh rotations.
//!
//! Y is up. The heading frame of a frame turns the world about Y so that the character's
//! forward direction (`(left upper leg - right upper leg) x up`, flattened) becomes +Z and its
//! left +X. Every feature of frame t uses frames `<= t` only.

use glam::{DQuat, DVec3};

use crate::error::{positive, KernelError, Result};
use crate::footsteps::air_time;

/// Features per frame.
pub const N_FEATURES: usize = 19;

/// Scalars of [`dynamic_features`].
#[derive(Debug, Clone, Copy)]
pub struct FeatureParams {
    /// Seconds between frames.
    pub frame_time: f64,
    /// The actor's height: velocities are divided by it.
    pub height: f64,
    /// Height of the hips above the floor in the rest pose: hips heights are divided by it.
    pub hips_rest_height: f64,
    /// Height (Y) of the floor.
    pub floor: f64,
    /// Frames in the running mean of the velocity (`round(fps / 3)`).
    pub window: usize,
}

/// Yaw (radians about +Y, 0 = facing +Z) of the line between the upper legs, or `None` when
/// that line is vertical.
#[must_use]
pub fn heading_yaw(left: DVec3, right: DVec3) -> Option<f64> {
    let across = left - right;
    // forward = across x up, with up = +Y.
    let (fx, fz) = (-across.z, across.x);
    (fx.hypot(fz) > 1e-9 * across.length()).then(|| fx.atan2(fz))
}

/// Features `[F, 19]` per frame, each from frames `<= t` only.
///
/// `points` `[F, 3, 3]`: world positions of the hips, left and right upper leg; `thighs`
/// `[F, 2, 4]`: local rotations of the left and right upper leg (x, y, z, w); `contacts`
/// `[F, 2]`: left, right foot; `reference` `[2, 4]`: each thigh rotation is kept on this
/// quaternion's hemisphere. Columns: hips velocity in the heading frame / height (3; 0 at
/// frame 0), its mean over the last `window` frames (3), contacts (2), air time in seconds
/// (2), (hips height - floor) / hips rest height (1), thigh rotations (2 x 4). A frame whose
/// upper legs line up vertically keeps the previous frame's heading (facing +Z at frame 0).
///
/// # Errors
/// `KernelError::Argument` naming the argument whose length disagrees with `points` or whose
/// value is out of range.
pub fn dynamic_features(
    points: &[f64],
    thighs: &[f64],
    contacts: &[bool],
    reference: &[f64],
    params: &FeatureParams,
) -> Result<Vec<f64>> {
    if points.len() % 9 != 0 {
        return Err(KernelError::argument(
            "points",
            format!("length {} is not frames x 3 joints x 3", points.len()),
        ));
    }
    let frames = points.len() / 9;
    if thighs.len() != frames * 8 {
        return Err(KernelError::argument(
            "thighs",
            format!("expected {frames} x 2 x 4 values, got {}", thighs.len()),
        ));
    }
    if contacts.len() != frames * 2 {
        return Err(KernelError::argument(
            "contacts",
            format!("expected {frames} x 2 values, got {}", contacts.len()),
        ));
    }
    if reference.len() != 8 {
        return Err(KernelError::argument(
            "reference",
            format!("expected 2 x 4 values, got {}", reference.len()),
        ));
    }
    positive("frame_time", params.frame_time)?;
    positive("height", params.height)?;
    positive("hips_rest_height", params.hips_rest_height)?;
    if params.window == 0 {
        return Err(KernelError::argument("window", "must be at least 1"));
    }
    let air = air_time(contacts, 2, params.frame_time)?;
    let references = [
        DQuat::from_slice(&reference[..4]),
        DQuat::from_slice(&reference[4..]),
    ];
    let point = |t: usize, k: usize| DVec3::from_slice(&points[9 * t + 3 * k..][..3]);

    let mut out = vec![0.0; frames * N_FEATURES];
    let mut velocities = Vec::with_capacity(frames);
    let (mut yaw, mut sum) = (0.0, DVec3::ZERO);
    for (t, row) in out.chunks_mut(N_FEATURES).enumerate() {
        yaw = heading_yaw(point(t, 1), point(t, 2)).unwrap_or(yaw);
        let world = if t == 0 {
            DVec3::ZERO
        } else {
            (point(t, 0) - point(t - 1, 0)) / params.frame_time / params.height
        };
        let velocity = DQuat::from_rotation_y(-yaw) * world;
        // Running sum over the last `window` frames.
        velocities.push(velocity);
        sum += velocity;
        if t >= params.window {
            sum -= velocities[t - params.window];
        }
        let mean = sum / (t + 1).min(params.window) as f64;
        velocity.write_to_slice(&mut row[0..3]);
        mean.write_to_slice(&mut row[3..6]);
        for side in 0..2 {
            row[6 + side] = f64::from(u8::from(contacts[2 * t + side]));
            row[8 + side] = air[2 * t + side];
            let q = DQuat::from_slice(&thighs[8 * t + 4 * side..][..4]);
            let q = if q.dot(references[side]) < 0.0 { -q } else { q };
            q.write_to_slice(&mut row[11 + 4 * side..15 + 4 * side]);
        }
        row[10] = (point(t, 0).y - params.floor) / params.hips_rest_height;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const PARAMS: FeatureParams = FeatureParams {
        frame_time: 0.5,
        height: 2.0,
        hips_rest_height: 4.0,
        floor: 1.0,
        window: 2,
    };

    /// Hips moving along `step` each frame, upper legs facing along `facing`.
    fn walk(frames: usize, step: DVec3, left: DVec3) -> Vec<f64> {
        let mut points = Vec::new();
        for t in 0..frames {
            let hips = DVec3::new(0.0, 5.0, 0.0) + step * t as f64;
            for p in [hips, hips + left, hips - left] {
                points.extend(p.to_array());
            }
        }
        points
    }

    #[test]
    fn constant_velocity_in_the_heading_frame() {
        let identity = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let thighs: Vec<f64> = identity.repeat(4);
        // Facing +X (left is -Z), moving 1 unit a frame forward: +Z in the heading frame.
        let points = walk(4, DVec3::X, DVec3::NEG_Z);
        let out = dynamic_features(&points, &thighs, &[false; 8], &identity, &PARAMS).unwrap();
        let row = |t: usize| &out[t * N_FEATURES..(t + 1) * N_FEATURES];
        // 1 unit / 0.5 s / height 2 = 1 height a second.
        assert!(row(0)[..6].iter().all(|&v| v == 0.0));
        for (got, want) in row(3)[..6].iter().zip([0.0, 0.0, 1.0, 0.0, 0.0, 1.0]) {
            assert!((got - want).abs() < 1e-12, "{:?}", row(3));
        }
        assert!((row(1)[5] - 0.5).abs() < 1e-12, "mean of frames 0 and 1");
        assert!((row(2)[10] - 1.0).abs() < 1e-12, "(5 - 1) / 4");
        assert!(
            (row(3)[8] - 2.0).abs() < 1e-12,
            "air time of the 4th frame in flight"
        );
    }

    #[test]
    fn thighs_are_kept_on_the_reference_hemisphere() {
        let flipped = [0.0, 0.0, 0.0, -1.0, 0.0, 1.0, 0.0, 0.0];
        let reference = [0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0];
        let out = dynamic_features(
            &walk(1, DVec3::X, DVec3::X),
            &flipped,
            &[true; 2],
            &reference,
            &PARAMS,
        )
        .unwrap();
        assert_eq!(&out[11..19], &[0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0, 0.0]);
    }

    #[test]
    fn rejects_bad_arguments() {
        let ok = (
            walk(2, DVec3::X, DVec3::X),
            vec![0.0; 16],
            vec![false; 4],
            vec![0.0; 8],
        );
        assert!(dynamic_features(&ok.0[1..], &ok.1, &ok.2, &ok.3, &PARAMS).is_err());
        assert!(dynamic_features(&ok.0, &ok.1[1..], &ok.2, &ok.3, &PARAMS).is_err());
        assert!(dynamic_features(&ok.0, &ok.1, &ok.2[1..], &ok.3, &PARAMS).is_err());
        assert!(dynamic_features(&ok.0, &ok.1, &ok.2, &ok.3[1..], &PARAMS).is_err());
        assert!(dynamic_features(
            &ok.0,
            &ok.1,
            &ok.2,
            &ok.3,
            &FeatureParams {
                window: 0,
                ..PARAMS
            }
        )
        .is_err());
        assert!(dynamic_features(
            &ok.0,
            &ok.1,
            &ok.2,
            &ok.3,
            &FeatureParams {
                height: f64::NAN,
                ..PARAMS
            }
        )
        .is_err());
    }
}
