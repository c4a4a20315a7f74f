//! The arms filtered in world axes by the decoupling split ([`crate::decouple::split`]).

use glam::DQuat;

use crate::decouple::{angle, power};
use crate::error::{KernelError, Result};

/// World changes up to this angle (radians) are filtered in world axes, from the next on less and
/// less, and beyond [`WORLD_NONE`] joint by joint: a raised arm is a half turn from the network's
/// hanging one, where a part of that turn flips its way round as the angle crosses 180 degrees
/// (a hand jumped 38 cm in a frame). Filtered joint by joint there, as before, it does not.
pub const WORLD_FULL: f64 = std::f64::consts::FRAC_PI_3;
/// See [`WORLD_FULL`].
pub const WORLD_NONE: f64 = 2.0 * std::f64::consts::FRAC_PI_3;

/// The share of a limb's world filter for a world change of `angle`: 1 up to [`WORLD_FULL`], 0
/// from [`WORLD_NONE`], a smoothstep between.
#[must_use]
pub fn world_trust(angle: f64) -> f64 {
    let x = ((WORLD_NONE - angle) / (WORLD_NONE - WORLD_FULL)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Limbs whose filter is read in world axes. A relaxed arm hangs in the world: the actor's
/// shoulders sway and the arm below them counter-turns to hang as before. Filtered joint by
/// joint, the arm kept the actor's local rotation (its activity is low) on the trunk the body
/// mechanics gave it, so it swung with every difference between the two trunks: in a quarter of
/// dataset-2's held-out one-hand gestures the body mechanics' idle hand moved about its shoulder
/// more than the actor's own + 0.5 cm. For each of `limbs` (parents
/// before children) the filter blends world rotations instead: `E_w = W_O W_B^-1` (the limb's
/// world rotation in the original and in the body mechanics predicted), `E*_w = E_w^A` with the
/// limb's activity, and the limb's `B'` is made local again below the `B'` above it, so that
/// `B'`'s limb points where `E*_w^-1 W_O` does (for world changes up to [`WORLD_FULL`]; beyond,
/// less and less, see [`world_trust`]); its `E* = O B'^-1` (so `E* B' = O` still).
/// `parents`: the skeleton's (-1: the root; parents before children).
pub struct Arms<'a> {
    pub parents: &'a [i64],
    pub limbs: &'a [usize],
}

impl Arms<'_> {
    pub(crate) fn check(&self, joints: usize) -> Result<()> {
        let ordered = self.parents.len() == joints
            && self.parents.first() == Some(&-1)
            && self
                .parents
                .iter()
                .enumerate()
                .skip(1)
                .all(|(j, &p)| p >= 0 && (p as usize) < j);
        if !ordered {
            return Err(KernelError::argument(
                "arm_parents",
                format!("expected the {joints} joints' parents, the root's -1 first, each before its child"),
            ));
        }
        if let Some(&j) = self.limbs.iter().find(|&&j| j == 0 || j >= joints) {
            return Err(KernelError::argument(
                "arm_joints",
                format!("joint {j} is not one of the {joints} joints below the root"),
            ));
        }
        Ok(())
    }

    /// The world rotation of `joint` in one frame's local rotations `[J, 4]`.
    fn world(&self, rotations: &[f64], joint: usize) -> DQuat {
        let mut turn = DQuat::from_slice(&rotations[4 * joint..4 * joint + 4]);
        let mut j = self.parents[joint];
        while j >= 0 {
            let p = j as usize;
            turn = DQuat::from_slice(&rotations[4 * p..4 * p + 4]) * turn;
            j = self.parents[p];
        }
        turn
    }

    /// Refilter the limbs of one frame (`[J, 4]` each; `activity` `[J]`) in world axes.
    pub(crate) fn hang(
        &self,
        original: &[f64],
        body: &[f64],
        activity: &[f64],
        expressive: &mut [f64],
        recovered: &mut [f64],
    ) {
        for &limb in self.limbs {
            let seen = self.world(original, limb);
            let change = seen * self.world(body, limb).conjugate();
            let above = self.world(recovered, self.parents[limb] as usize);
            let hung = above.conjugate() * power(change, activity[limb]).conjugate() * seen;
            let own = DQuat::from_slice(&recovered[4 * limb..4 * limb + 4]);
            let local =
                (own * power(own.conjugate() * hung, world_trust(angle(change)))).normalize();
            let o = DQuat::from_slice(&original[4 * limb..4 * limb + 4]);
            local.write_to_slice(&mut recovered[4 * limb..4 * limb + 4]);
            (o * local.conjugate()).write_to_slice(&mut expressive[4 * limb..4 * limb + 4]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn trust_is_whole_then_fades_then_none() {
        assert!(
            (world_trust(0.0) - 1.0).abs() < 1e-15 && (world_trust(WORLD_FULL) - 1.0).abs() < 1e-15
        );
        assert!((world_trust(0.5 * (WORLD_FULL + WORLD_NONE)) - 0.5).abs() < 1e-12);
        assert!(world_trust(WORLD_NONE).abs() < 1e-15 && world_trust(3.0).abs() < 1e-15);
    }

    #[test]
    fn an_inactive_limb_keeps_its_world_rotation_under_another_trunk() {
        // root -> spine -> upper arm; the body mechanics turn the spine 30 degrees more.
        let parents = [-1, 0, 1];
        let arms = Arms {
            parents: &parents,
            limbs: &[2],
        };
        arms.check(3).unwrap();
        let quats = [
            DQuat::from_axis_angle(DVec3::Y, 0.3),
            DQuat::from_axis_angle(DVec3::X, 0.2),
            DQuat::from_axis_angle(DVec3::Z, 1.0),
        ];
        let flat = |qs: &[DQuat]| qs.iter().flat_map(|q| q.to_array()).collect::<Vec<f64>>();
        let original = flat(&quats);
        let mut turned = quats;
        turned[1] *= DQuat::from_axis_angle(DVec3::Z, 0.5);
        let (mut expressive, mut recovered) = (flat(&[DQuat::IDENTITY; 3]), flat(&turned));
        arms.hang(
            &original,
            &recovered.clone(),
            &[0.0; 3],
            &mut expressive,
            &mut recovered,
        );
        let apart = arms.world(&recovered, 2) * arms.world(&original, 2).conjugate();
        assert!(angle(apart) < 1e-12, "{apart:?}");
        let limb = DQuat::from_slice(&expressive[8..12]) * DQuat::from_slice(&recovered[8..12]);
        assert!(angle(limb * quats[2].conjugate()) < 1e-12);
        assert!(Arms {
            parents: &[0, 0, 1],
            limbs: &[2]
        }
        .check(3)
        .is_err());
        assert!(Arms {
            parents: &parents,
            limbs: &[3]
        }
        .check(3)
        .is_err());
    }
}
