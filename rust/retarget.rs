//! Retargeting's transfer of a pose, frame by frame: the target skeleton's local rotations from
//! the source's world rotations and positions, along a plan made once per pair of skeletons
//! (`expressive_mocap.skeletons.retargeting`: which joints carry each role, the alignment of
//! each role's rest bone, the roles swung onto the source's bones, the spine joints sharing a
//! turn, the joints held at rest).

use glam::{DQuat, DVec3};
use rayon::prelude::*;

use crate::decouple::power;
use crate::error::{KernelError, Result};
use crate::fk::check_parents;
use crate::rotations::PARALLEL_MIN_ITEMS;

/// What is done in every frame. Indices are joints of the source (`source`, `starts`, `ends`)
/// or of the target (`target`, `shared`, `tops`, `bottoms`, `held`, `copied`), or roles
/// (`swung`: positions in `source`).
#[derive(Debug, Clone, Copy)]
pub struct TransferPlan<'a> {
    /// Per role: the source joint and the target joint that carry it.
    pub source: &'a [i64],
    pub target: &'a [i64],
    /// Per role `[R, 4]`: the rotation taking the target's rest bone onto the source's.
    pub aligns: &'a [f64],
    /// The roles swung so that their bone, from joint `starts` to joint `ends` of the source,
    /// lies where the source's positions put it; `rest_lines` `[S, 3]` the bone at rest.
    pub swung: &'a [i64],
    pub starts: &'a [i64],
    pub ends: &'a [i64],
    pub rest_lines: &'a [f64],
    /// Target joints that take the share `shares` of the turn from `tops` to `bottoms`.
    pub shared: &'a [i64],
    pub tops: &'a [i64],
    pub bottoms: &'a [i64],
    pub shares: &'a [f64],
    /// Target joints held as in the reference pose relative to `copied`, their nearest computed
    /// ancestor (-1: none).
    pub held: &'a [i64],
    pub copied: &'a [i64],
    /// `[Jt, 4]`: the target's world rotations in its reference pose (canonical axes; the rest
    /// pose: every one the identity). Shared and held joints turn as changes from it.
    pub reference: &'a [f64],
    /// The target skeleton's parents.
    pub parents: &'a [i64],
    /// The source's and the target's turn onto the canonical axes (x, y, z, w).
    pub turn_source: [f64; 4],
    pub turn_target: [f64; 4],
}

fn quat_at(values: &[f64], index: usize) -> DQuat {
    DQuat::from_xyzw(
        values[4 * index],
        values[4 * index + 1],
        values[4 * index + 2],
        values[4 * index + 3],
    )
}

fn vec_at(values: &[f64], index: usize) -> DVec3 {
    DVec3::new(
        values[3 * index],
        values[3 * index + 1],
        values[3 * index + 2],
    )
}

/// `v` rotated by the unit quaternion `q`, as `expressive_mocap.quat.rotate` computes it.
fn rotate(q: DQuat, v: DVec3) -> DVec3 {
    let u = q.xyz();
    let t = 2.0 * u.cross(v);
    v + q.w * t + u.cross(t)
}

/// The shortest-arc rotation taking direction `u` onto `v` (a half turn for opposite ones),
/// as `expressive_mocap.quat.between`.
fn between(u: DVec3, v: DVec3) -> DQuat {
    let u = u / u.length();
    let v = v / v.length();
    let w = 1.0 + u.dot(v);
    let q = if w < 1e-12 {
        let other = if u.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
        let flip = u.cross(other);
        DQuat::from_xyzw(flip.x, flip.y, flip.z, 0.0)
    } else {
        let axis = u.cross(v);
        DQuat::from_xyzw(axis.x, axis.y, axis.z, w)
    };
    q / q.length()
}

/// Whether a turn is the identity (the skeleton already has the canonical axes).
fn is_identity(turn: [f64; 4]) -> bool {
    turn[0].abs() <= 1e-15
        && turn[1].abs() <= 1e-15
        && turn[2].abs() <= 1e-15
        && (turn[3] - 1.0).abs() <= 1e-15
}

fn check_indices(name: &'static str, indices: &[i64], bound: usize, none: bool) -> Result<()> {
    for &index in indices {
        let fits = usize::try_from(index).is_ok_and(|i| i < bound) || (none && index == -1);
        if !fits {
            return Err(KernelError::argument(
                "plan",
                format!("{name} holds {index}, not a joint or role below {bound}"),
            ));
        }
    }
    Ok(())
}

fn check_len(name: &'static str, values: usize, expected: usize) -> Result<()> {
    if values == expected {
        Ok(())
    } else {
        Err(KernelError::argument(
            "plan",
            format!("{name} has {values} values, expected {expected}"),
        ))
    }
}

fn check_plan(plan: &TransferPlan<'_>, source_joints: usize) -> Result<()> {
    let roles = plan.source.len();
    let target_joints = plan.parents.len();
    check_parents(plan.parents)?;
    check_len("target", plan.target.len(), roles)?;
    check_len("aligns", plan.aligns.len(), 4 * roles)?;
    check_len("starts", plan.starts.len(), plan.swung.len())?;
    check_len("ends", plan.ends.len(), plan.swung.len())?;
    check_len("rest_lines", plan.rest_lines.len(), 3 * plan.swung.len())?;
    check_len("tops", plan.tops.len(), plan.shared.len())?;
    check_len("bottoms", plan.bottoms.len(), plan.shared.len())?;
    check_len("shares", plan.shares.len(), plan.shared.len())?;
    check_len("copied", plan.copied.len(), plan.held.len())?;
    check_len("reference", plan.reference.len(), 4 * target_joints)?;
    check_indices("source", plan.source, source_joints, false)?;
    check_indices("starts", plan.starts, source_joints, false)?;
    check_indices("ends", plan.ends, source_joints, false)?;
    check_indices("swung", plan.swung, roles, false)?;
    for (name, indices) in [
        ("target", plan.target),
        ("shared", plan.shared),
        ("tops", plan.tops),
        ("bottoms", plan.bottoms),
        ("held", plan.held),
    ] {
        check_indices(name, indices, target_joints, false)?;
    }
    check_indices("copied", plan.copied, target_joints, true)
}

/// One frame: `world` and `positions` the source's (`[Js, 4]`, `[Js, 3]`), `roles` scratch for
/// the roles' rotations, `out` the target's local rotations `[Jt, 4]`, `scratch` its world ones.
fn transfer_frame(
    world: &[f64],
    positions: &[f64],
    plan: &TransferPlan<'_>,
    roles: &mut [DQuat],
    scratch: &mut [DQuat],
    out: &mut [f64],
) {
    let turn_s = DQuat::from_array(plan.turn_source);
    let turn_t = DQuat::from_array(plan.turn_target);
    let (turn_s_identity, turn_t_identity) =
        (is_identity(plan.turn_source), is_identity(plan.turn_target));
    for (role, &joint) in roles.iter_mut().zip(plan.source) {
        let q = quat_at(world, joint as usize);
        *role = if turn_s_identity {
            q
        } else {
            turn_s * q * turn_s.conjugate()
        };
    }
    for (s, &role) in plan.swung.iter().enumerate() {
        let (start, end) = (plan.starts[s] as usize, plan.ends[s] as usize);
        let line = rotate(turn_s, vec_at(positions, end) - vec_at(positions, start));
        let role = role as usize;
        let predicted = rotate(roles[role], vec_at(plan.rest_lines, s));
        roles[role] = between(predicted, line) * roles[role];
    }
    for (r, (&joint, role)) in plan.target.iter().zip(roles.iter()).enumerate() {
        scratch[joint as usize] = *role * quat_at(plan.aligns, r);
    }
    // Unmapped joints turn with the mapped ones, as changes from the target's reference pose.
    let reference = |joint: usize| quat_at(plan.reference, joint);
    for (h, &joint) in plan.shared.iter().enumerate() {
        let (top, bottom) = (plan.tops[h] as usize, plan.bottoms[h] as usize);
        let top = scratch[top] * reference(top).conjugate();
        let bottom = scratch[bottom] * reference(bottom).conjugate();
        let turn = power(top.conjugate() * bottom, plan.shares[h]);
        scratch[joint as usize] = top * turn * reference(joint as usize);
    }
    for (&joint, &copied) in plan.held.iter().zip(plan.copied) {
        let change = if copied >= 0 {
            scratch[copied as usize] * reference(copied as usize).conjugate()
        } else {
            DQuat::IDENTITY
        };
        scratch[joint as usize] = change * reference(joint as usize);
    }
    if !turn_t_identity {
        for q in scratch.iter_mut() {
            *q = turn_t.conjugate() * *q * turn_t;
        }
    }
    for (joint, (&parent, local)) in plan.parents.iter().zip(out.chunks_mut(4)).enumerate() {
        let q = if parent >= 0 {
            scratch[parent as usize].conjugate() * scratch[joint]
        } else {
            scratch[joint]
        };
        local.copy_from_slice(&q.to_array());
    }
}

/// The target's local rotations `[F, Jt, 4]` (x, y, z, w) from the source's world rotations
/// `world` `[F, Js, 4]` and positions `positions` `[F, Js, 3]`, along `plan`:
/// each role's source rotation turned to the canonical axes, swung onto the source's bone where
/// the plan says, times its alignment; the shared spine joints by a power of the turn between
/// their chain's ends and the held joints with their nearest computed ancestor, both as changes
/// from the target's reference pose; then turned to the
/// target's axes and made local to each parent.
///
/// # Errors
/// `KernelError::Argument` when the lengths or the plan's indices do not fit together.
pub fn transfer(
    world: &[f64],
    positions: &[f64],
    source_joints: usize,
    plan: &TransferPlan<'_>,
) -> Result<Vec<f64>> {
    check_plan(plan, source_joints)?;
    if source_joints == 0 || world.len() % (4 * source_joints) != 0 {
        return Err(KernelError::argument(
            "world",
            format!(
                "length {} is not frames x {source_joints} joints x 4",
                world.len()
            ),
        ));
    }
    let frames = world.len() / (4 * source_joints);
    if positions.len() != 3 * frames * source_joints {
        return Err(KernelError::argument(
            "positions",
            format!(
                "expected {frames} x {source_joints} x 3 values, got {}",
                positions.len()
            ),
        ));
    }
    let joints = plan.parents.len();
    let mut out = crate::error::zeros("world", frames * joints * 4)?;
    if joints == 0 {
        return Ok(out);
    }
    let scratch = || {
        (
            vec![DQuat::IDENTITY; plan.source.len()],
            vec![DQuat::IDENTITY; joints],
        )
    };
    let frame = |(roles, world_t): &mut (Vec<DQuat>, Vec<DQuat>),
                 ((w, p), o): ((&[f64], &[f64]), &mut [f64])| {
        world_t.fill(DQuat::IDENTITY); // a joint the plan leaves out is the identity in every frame
        transfer_frame(w, p, plan, roles, world_t, o);
    };
    if frames * joints >= PARALLEL_MIN_ITEMS {
        world
            .par_chunks(4 * source_joints)
            .zip(positions.par_chunks(3 * source_joints))
            .zip(out.par_chunks_mut(4 * joints))
            .with_min_len(64)
            .for_each_init(scratch, frame);
    } else {
        let mut buffers = scratch();
        world
            .chunks(4 * source_joints)
            .zip(positions.chunks(3 * source_joints))
            .zip(out.chunks_mut(4 * joints))
            .for_each(|item| frame(&mut buffers, item));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTITIES: [f64; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];

    fn plan<'a>(parents: &'a [i64]) -> TransferPlan<'a> {
        TransferPlan {
            source: &[0, 1],
            target: &[0, 1],
            aligns: &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            swung: &[],
            starts: &[],
            ends: &[],
            rest_lines: &[],
            shared: &[],
            tops: &[],
            bottoms: &[],
            shares: &[],
            held: &[2],
            copied: &[1],
            reference: &IDENTITIES,
            parents,
            turn_source: [0.0, 0.0, 0.0, 1.0],
            turn_target: [0.0, 0.0, 0.0, 1.0],
        }
    }

    #[test]
    fn identity_alignments_copy_world_rotations_made_local() {
        let half = std::f64::consts::FRAC_1_SQRT_2;
        let world = [0.0, 0.0, 0.0, 1.0, 0.0, half, 0.0, half];
        let positions = [0.0; 6];
        let out = transfer(&world, &positions, 2, &plan(&[-1, 0, 1])).unwrap();
        let expected = [0.0, 0.0, 0.0, 1.0, 0.0, half, 0.0, half, 0.0, 0.0, 0.0, 1.0];
        for (a, b) in out.iter().zip(expected) {
            assert!((a - b).abs() < 1e-15, "{out:?}");
        }
    }

    #[test]
    fn refuses_indices_out_of_range_and_bad_lengths() {
        let mut bad = plan(&[-1, 0, 1]);
        bad.source = &[0, 5];
        assert!(transfer(&[0.0; 8], &[0.0; 6], 2, &bad).is_err());
        assert!(transfer(&[0.0; 7], &[0.0; 6], 2, &plan(&[-1, 0, 1])).is_err());
        assert!(transfer(&[0.0; 8], &[0.0; 5], 2, &plan(&[-1, 0, 1])).is_err());
    }

    #[test]
    fn opposite_directions_give_a_half_turn() {
        let q = between(DVec3::X, -DVec3::X);
        assert!((rotate(q, DVec3::X) + DVec3::X).length() < 1e-12);
    }
}
