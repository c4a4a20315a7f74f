//! Forward kinematics: local joint rotations and translations to world rotations and positions.

use glam::{DQuat, DVec3};
use rayon::prelude::*;

use crate::error::{KernelError, Result};
use crate::rotations::PARALLEL_MIN_ITEMS;

/// One frame's local rotations and translations, and its world rotations and positions.
type FrameSlices<'a> = (((&'a [f64], &'a [f64]), &'a mut [f64]), &'a mut [f64]);

/// Check that `parents` lists every joint after its parent (roots are -1).
///
/// # Errors
/// `KernelError::Argument` naming `parents` otherwise.
pub fn check_parents(parents: &[i64]) -> Result<()> {
    for (joint, &parent) in parents.iter().enumerate() {
        if parent < -1 || parent >= joint as i64 {
            return Err(KernelError::argument(
                "parents",
                format!("joint {joint} has parent {parent}: parents must be -1 (root) or an earlier joint"),
            ));
        }
    }
    Ok(())
}

/// World rotations `[F, J, 4]` and positions `[F, J, 3]` of every joint in every frame.
///
/// `rotations` is `[F, J, 4]` (x, y, z, w) and `translations` `[F, J, 3]`, both local to the
/// parent; a joint's world position is its parent's plus the parent's world rotation applied
/// to its translation. Roots take their translation and rotation as they are.
///
/// # Errors
/// `KernelError::Argument` when the lengths do not match `parents` or `parents` is not ordered.
pub fn forward_kinematics(
    rotations: &[f64],
    translations: &[f64],
    parents: &[i64],
) -> Result<(Vec<f64>, Vec<f64>)> {
    check_parents(parents)?;
    let joints = parents.len();
    if joints == 0 || rotations.len() % (4 * joints) != 0 {
        return Err(KernelError::argument(
            "rotations",
            format!(
                "length {} is not frames x {joints} joints x 4",
                rotations.len()
            ),
        ));
    }
    let frames = rotations.len() / (4 * joints);
    if translations.len() != frames * joints * 3 {
        return Err(KernelError::argument(
            "translations",
            format!(
                "expected {frames} x {joints} x 3 values, got {}",
                translations.len()
            ),
        ));
    }
    let mut world_rotations = vec![0.0; rotations.len()];
    let mut world_positions = vec![0.0; translations.len()];
    let frame = |(((rot, trans), out_rot), out_pos): FrameSlices| {
        fk_frame(rot, trans, parents, out_rot, out_pos);
    };
    let inputs = rotations
        .chunks(4 * joints)
        .zip(translations.chunks(3 * joints));
    if frames * joints >= PARALLEL_MIN_ITEMS {
        rotations
            .par_chunks(4 * joints)
            .zip(translations.par_chunks(3 * joints))
            .zip(world_rotations.par_chunks_mut(4 * joints))
            .zip(world_positions.par_chunks_mut(3 * joints))
            .with_min_len(32)
            .for_each(frame);
    } else {
        inputs
            .zip(world_rotations.chunks_mut(4 * joints))
            .zip(world_positions.chunks_mut(3 * joints))
            .for_each(frame);
    }
    Ok((world_rotations, world_positions))
}

fn fk_frame(rot: &[f64], trans: &[f64], parents: &[i64], out_rot: &mut [f64], out_pos: &mut [f64]) {
    for (j, &parent) in parents.iter().enumerate() {
        let local_rot = DQuat::from_slice(&rot[4 * j..4 * j + 4]);
        let local_pos = DVec3::from_slice(&trans[3 * j..3 * j + 3]);
        let (world_rot, world_pos) = if parent < 0 {
            (local_rot, local_pos)
        } else {
            let p = parent as usize;
            let parent_rot = DQuat::from_slice(&out_rot[4 * p..4 * p + 4]);
            let parent_pos = DVec3::from_slice(&out_pos[3 * p..3 * p + 3]);
            (parent_rot * local_rot, parent_pos + parent_rot * local_pos)
        };
        world_rot.write_to_slice(&mut out_rot[4 * j..4 * j + 4]);
        world_pos.write_to_slice(&mut out_pos[3 * j..3 * j + 3]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_joint_chain_by_hand() {
        // Root at (1, 0, 0) turned 90 degrees about Z; child 2 units along the root's x axis.
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let rot = [0.0, 0.0, s, s, 0.0, 0.0, 0.0, 1.0];
        let trans = [1.0, 0.0, 0.0, 2.0, 0.0, 0.0];
        let (wr, wp) = forward_kinematics(&rot, &trans, &[-1, 0]).unwrap();
        let child = DVec3::from_slice(&wp[3..6]);
        assert!(
            (child - DVec3::new(1.0, 2.0, 0.0)).length() < 1e-12,
            "{child}"
        );
        assert!((wr[6] - s).abs() < 1e-12);
    }

    #[test]
    fn rejects_unordered_parents_and_bad_lengths() {
        assert!(forward_kinematics(&[0.0; 8], &[0.0; 6], &[1, -1]).is_err());
        assert!(forward_kinematics(&[0.0; 8], &[0.0; 5], &[-1, 0]).is_err());
        assert!(forward_kinematics(&[0.0; 7], &[0.0; 6], &[-1, 0]).is_err());
    }
}
