//! Two-bone inverse kinematics (a leg: upper leg, lower leg, foot), frame by frame: the chain
//! bends in its own plane to the wanted reach, then turns about its root to aim at the target
//! (after D. Holden's two-joint IK; `expressive_mocap.ik`).

use glam::{DQuat, DVec3};
use rayon::prelude::*;

use crate::error::{KernelError, Result};
use crate::rotations::PARALLEL_MIN_ITEMS;

/// The solver stops short of a fully straight knee: this share of the chain's length at most.
pub const REACH: f64 = 0.9999;

/// Unit vector along `v`, or +X where `v` is (nearly) zero (its rotation angle is 0 then).
fn unit(v: DVec3) -> DVec3 {
    let norm = v.length();
    if norm > 1e-12 {
        v / norm
    } else {
        DVec3::X
    }
}

/// `v` held between `low` and `high` as NumPy's `clip` does it: NaN stays NaN, and `high` wins
/// when the bounds cross.
fn clip(v: f64, low: f64, high: f64) -> f64 {
    if v.is_nan() {
        v
    } else {
        v.max(low).min(high)
    }
}

fn angle_between(a: DVec3, b: DVec3) -> f64 {
    clip(unit(a).dot(unit(b)), -1.0, 1.0).acos()
}

/// The rotation by `radians` about the unit `axis`.
fn about(axis: DVec3, radians: f64) -> DQuat {
    let (sin, cos) = ((radians / 2.0).sin(), (radians / 2.0).cos());
    DQuat::from_xyzw(axis.x * sin, axis.y * sin, axis.z * sin, cos)
}

/// `v` rotated by the unit quaternion `q`, as `expressive_mocap.quat.rotate` computes it.
fn rotate(q: DQuat, v: DVec3) -> DVec3 {
    let u = q.xyz();
    let t = 2.0 * u.cross(v);
    v + q.w * t + u.cross(t)
}

/// One frame: the new world rotations of the first and second joint.
#[must_use]
pub fn two_bone_ik_one(
    root: DVec3,
    upper: DQuat,
    lower: DQuat,
    upper_bone: DVec3,
    lower_bone: DVec3,
    target: DVec3,
) -> (DQuat, DQuat) {
    let a = root;
    let b = a + rotate(upper, upper_bone);
    let c = b + rotate(lower, lower_bone);
    let (thigh, shin) = (upper_bone.length(), lower_bone.length());
    // Bounds relative to the chain's length: the same pose in centimetres or metres. Never
    // straighter than REACH, unless the chain already is: a target where its end is moves nothing.
    let longest = ((thigh + shin) * REACH).max((c - a).length());
    let reach = clip(
        (target - a).length(),
        (thigh - shin).abs() + 1e-5 * (thigh + shin),
        longest,
    );
    let (hip_now, knee_now) = (angle_between(c - a, b - a), angle_between(a - b, c - b));
    let hip_wanted = clip(
        (shin * shin - thigh * thigh - reach * reach) / (-2.0 * thigh * reach),
        -1.0,
        1.0,
    )
    .acos();
    let knee_wanted = clip(
        (reach * reach - thigh * thigh - shin * shin) / (-2.0 * thigh * shin),
        -1.0,
        1.0,
    )
    .acos();
    let bend_axis = unit((c - a).cross(b - a));
    let bend_hip = about(bend_axis, hip_wanted - hip_now);
    let bend_knee = about(bend_axis, knee_wanted - knee_now);
    let c_bent = a + rotate(bend_hip, b - a) + rotate(bend_knee * bend_hip, c - b);
    let aim = about(
        unit((c_bent - a).cross(target - a)),
        angle_between(c_bent - a, target - a),
    );
    (
        aim * (bend_hip * upper),
        aim * (bend_knee * (bend_hip * lower)),
    )
}

/// New world rotations `(upper, lower)`, each `[F, 4]`, of a two-bone chain whose end should
/// reach `target` `[F, 3]`: `root` `[F, 3]` the first joint's world position, `upper` and
/// `lower` `[F, 4]` the two joints' world rotations, `upper_bone` and `lower_bone` `[F, 3]` the
/// second joint's and the end's offsets (local translations). A target out of reach is
/// approached as closely as `REACH` x the chain's length allows.
///
/// # Errors
/// `KernelError::Argument` when the lengths do not agree.
pub fn two_bone_ik(
    root: &[f64],
    upper: &[f64],
    lower: &[f64],
    upper_bone: &[f64],
    lower_bone: &[f64],
    target: &[f64],
) -> Result<(Vec<f64>, Vec<f64>)> {
    let frames = root.len() / 3;
    for (name, values, width) in [
        ("root", root, 3),
        ("upper", upper, 4),
        ("lower", lower, 4),
        ("upper_bone", upper_bone, 3),
        ("lower_bone", lower_bone, 3),
        ("target", target, 3),
    ] {
        if values.len() != frames * width {
            return Err(KernelError::argument(
                name,
                format!("expected {frames} x {width} values, got {}", values.len()),
            ));
        }
    }
    let mut out_upper = crate::error::zeros("upper", frames * 4)?;
    let mut out_lower = crate::error::zeros("lower", frames * 4)?;
    let frame = |(f, (u, l)): (usize, (&mut [f64], &mut [f64]))| {
        let v3 = |values: &[f64]| DVec3::from_slice(&values[3 * f..3 * f + 3]);
        let q = |values: &[f64]| DQuat::from_slice(&values[4 * f..4 * f + 4]);
        let (new_upper, new_lower) = two_bone_ik_one(
            v3(root),
            q(upper),
            q(lower),
            v3(upper_bone),
            v3(lower_bone),
            v3(target),
        );
        u.copy_from_slice(&new_upper.to_array());
        l.copy_from_slice(&new_lower.to_array());
    };
    if frames * 8 >= PARALLEL_MIN_ITEMS {
        out_upper
            .par_chunks_mut(4)
            .zip(out_lower.par_chunks_mut(4))
            .enumerate()
            .with_min_len(256)
            .for_each(frame);
    } else {
        out_upper
            .chunks_mut(4)
            .zip(out_lower.chunks_mut(4))
            .enumerate()
            .for_each(frame);
    }
    Ok((out_upper, out_lower))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reachable_target_is_reached() {
        let (upper, lower) = two_bone_ik_one(
            DVec3::ZERO,
            DQuat::IDENTITY,
            DQuat::IDENTITY,
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.5, -1.5, 0.2),
        );
        let knee = rotate(upper, DVec3::new(0.0, -1.0, 0.0));
        let end = knee + rotate(lower, DVec3::new(0.0, -1.0, 0.0));
        assert!(
            (end - DVec3::new(0.5, -1.5, 0.2)).length() < 1e-9,
            "{end:?}"
        );
    }

    #[test]
    fn a_straight_leg_at_its_own_end_stays_straight() {
        // Straighter than REACH: bending it to REACH moved a stance knee by 0.56 cm.
        let bone = DVec3::new(0.0, -1.0, 0.0);
        let (upper, lower) = two_bone_ik_one(
            DVec3::ZERO,
            DQuat::IDENTITY,
            DQuat::IDENTITY,
            bone,
            bone,
            DVec3::new(0.0, -2.0, 0.0),
        );
        let knee = rotate(upper, bone);
        assert!((knee - bone).length() < 1e-6, "{knee}");
        assert!((knee + rotate(lower, bone) - DVec3::new(0.0, -2.0, 0.0)).length() < 1e-9);
    }

    #[test]
    fn refuses_lengths_that_disagree() {
        let q = [0.0, 0.0, 0.0, 1.0];
        assert!(two_bone_ik(&[0.0; 3], &q, &q, &[0.0; 3], &[0.0; 3], &[0.0; 6]).is_err());
    }
}
