"""Foot locking: after an edit, each stance foot put back where the input has it during its
contacts, with two-bone leg IK, the hips lowered where a leg cannot reach."""

from __future__ import annotations

import numpy as np

from ..body.body import Body
from ..body.ik import REACH, two_bone_ik
from ..body.roles import JointRoles
from ..errors import ArgumentError
from ..motion import Motion
from ..ops import forward_kinematics
from ..rotations import quat

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def contact_weights(contacts: np.ndarray, frames: int) -> np.ndarray:
    """Locking weights ``[F, S]`` from ``contacts bool [F, S]``: 1 in contact, easing to 0 over
    ``frames`` frames before and after each contact (smoothstep of the distance in frames)."""
    F = len(contacts)
    linear = contacts.astype(np.float64)
    for i in range(1, frames + 1):
        ramp = 1.0 - i / (frames + 1)
        linear[i:] = np.maximum(linear[i:], ramp * contacts[:-i])
        linear[:-i] = np.maximum(linear[:-i], ramp * contacts[i:])
    return linear * linear * (3 - 2 * linear) if F else linear


def _check_legs(skeleton, roles: JointRoles) -> None:
    parents = skeleton.parents
    for s in (0, 1):
        hip, foot = roles.upper_legs[s], roles.feet[s]
        if parents[foot] < 0 or parents[parents[foot]] != hip:
            names = skeleton.names
            raise ArgumentError(
                f"foot locking needs a two-bone leg: {names[foot]} is not the grandchild of {names[hip]}; "
                "use lock_feet=False"
            )


def lock_stance_feet(
    original: Motion,
    edited: Motion,
    contacts: np.ndarray,
    roles: JointRoles,
    blend_frames: int = 3,
    ankles: np.ndarray | None = None,
) -> tuple[Motion, float, float, float]:
    """``edited`` with each foot put back where ``original`` has it while it touches the floor.

    For each side, in the frames where the foot's locking weight ``w`` (1 in the contacts
    ``[F, 2]``, eased to 0 over ``blend_frames`` frames either side) is above 0, the ankle's
    target is ``(1 - w) edited + w original`` (world positions) and the foot's world rotation the
    slerp between the two by ``w``; two-bone IK (:func:`~expressive_mocap.body.ik.two_bone_ik`) turns
    the upper and lower leg to reach the target, and the foot's local rotation is set to give the
    wanted world rotation. The toe, fixed to the foot, follows. Where a target is beyond the leg's
    reach (the edit raised the hips or spread the legs), the hips are first lowered just enough,
    eased in and out over ``blend_frames``: a stance foot is never lifted off the floor.
    ``ankles [F, 2, 3]`` (left, right), when given, are the ankle positions held instead of the
    original's (a retimed edit holds each foot still where the retimed input would slide).

    Returns the new motion, the largest distance an ankle was moved to its target, the largest
    distance left where the target was out of the leg's reach (file units; the hips could not
    help: the target is beyond the leg's length across the floor), and how far the hips were lowered.
    """
    parents = original.skeleton.parents
    _check_legs(original.skeleton, roles)
    world_in, pos_in = forward_kinematics(original.rotations, original.translations, parents)
    if ankles is not None:
        pos_in = pos_in.copy()
        pos_in[:, list(roles.feet)] = ankles
    weights = contact_weights(np.asarray(contacts, dtype=bool), blend_frames)
    edited, lowered = _lowered_to_reach(edited, pos_in, weights, roles, blend_frames)
    world_out, pos_out = forward_kinematics(edited.rotations, edited.translations, parents)
    height = Body.of(original.skeleton).actor_height  # tolerances in the motion's units
    rotations = edited.rotations.copy()
    correction = 0.0
    legs = []
    for s in (0, 1):
        foot = roles.feet[s]
        # Frames to lock: weighted, and where the edit moved or turned the foot at all (elsewhere
        # the IK would only add rounding).
        turned = quat.angle(quat.mul(quat.conjugate(world_in[:, foot]), world_out[:, foot])) > 1e-9
        moved = (np.linalg.norm(pos_out[:, foot] - pos_in[:, foot], axis=1) > 1e-11 * height) | turned
        frames = np.flatnonzero((weights[:, s] > 0) & moved)
        if not len(frames):
            continue
        w = weights[frames, s, None]
        target = (1 - w) * pos_out[frames, foot] + w * pos_in[frames, foot]
        correction = max(correction, float(np.linalg.norm(target - pos_out[frames, foot], axis=1).max()))
        _turn_leg(rotations, edited, (world_in, world_out, pos_out), roles, s, frames, w[:, 0], target)
        legs.append((frames, foot, target))
    out = Motion(edited.skeleton, rotations, edited.translations, edited.frame_time)
    positions = out.positions()
    residual = max(
        (float(np.linalg.norm(positions[f, foot] - target, axis=1).max()) for f, foot, target in legs), default=0.0
    )
    return out, correction, residual, lowered


def _turn_leg(
    rotations: np.ndarray,
    edited: Motion,
    kinematics: tuple[np.ndarray, np.ndarray, np.ndarray],
    roles: JointRoles,
    side: int,
    frames: np.ndarray,
    w: np.ndarray,
    target: np.ndarray,
) -> None:
    """Set (in ``rotations``) the upper leg, knee and foot of ``side`` in ``frames`` so the ankle
    reaches ``target`` and the foot's world rotation is the slerp by ``w`` from the edited one
    to the input's; ``kinematics``: the input's world rotations, the edited world rotations and
    positions."""
    world_in, world_out, pos_out = kinematics
    parents = edited.skeleton.parents
    hip, foot = roles.upper_legs[side], roles.feet[side]
    knee = parents[foot]
    t = edited.translations[frames]
    upper, lower = two_bone_ik(
        pos_out[frames, hip], world_out[frames, hip], world_out[frames, knee], t[:, knee], t[:, foot], target
    )
    foot_world = quat.slerp(world_out[frames, foot], world_in[frames, foot], w)
    parent = parents[hip]
    parent_world = world_out[frames, parent] if parent >= 0 else np.broadcast_to(IDENTITY, (len(frames), 4))
    rotations[frames, hip] = quat.mul(quat.conjugate(parent_world), upper)
    rotations[frames, knee] = quat.mul(quat.conjugate(upper), lower)
    rotations[frames, foot] = quat.mul(quat.conjugate(lower), foot_world)


def _eased(drop: np.ndarray, blend_frames: int) -> np.ndarray:
    """A soft dilation of ``drop [F]`` over ``blend_frames`` frames either side (smoothstep)."""
    eased = drop.copy()
    for i in range(1, blend_frames + 1):
        x = 1.0 - i / (blend_frames + 1)
        ramp = x * x * (3 - 2 * x)
        eased[i:] = np.maximum(eased[i:], ramp * drop[:-i])
        eased[:-i] = np.maximum(eased[:-i], ramp * drop[i:])
    return eased


def _lowered_to_reach(
    edited: Motion, pos_in: np.ndarray, weights: np.ndarray, roles: JointRoles, blend_frames: int
) -> tuple[Motion, float]:
    """``edited`` with its hips lowered (along the vertical, in file units) in the frames where a
    locked foot's target, the input's ankle, is beyond its leg's reach from where the edit put
    the hip: just enough for the leg to reach it, eased over ``blend_frames`` frames either side
    (a soft dilation of the drop, so the hips never jump). Returns it and the largest drop."""
    parents = edited.skeleton.parents
    world, pos = forward_kinematics(edited.rotations, edited.translations, parents)
    drop = np.zeros(edited.n_frames)
    for s in (0, 1):
        hip, foot = roles.upper_legs[s], roles.feet[s]
        knee = parents[foot]
        frames = np.flatnonzero(weights[:, s] > 0)
        bones = np.linalg.norm(edited.translations[frames, knee], axis=1) + np.linalg.norm(
            edited.translations[frames, foot], axis=1
        )
        length = REACH * bones
        target = (1 - weights[frames, s, None]) * pos[frames, foot] + weights[frames, s, None] * pos_in[frames, foot]
        above = pos[frames, hip] - target
        across = np.hypot(above[:, 0], above[:, 2])
        # The hip must come within reach, |above - d up| = length; lowering the hips by `drop` lowers
        # the edited foot too, so the target (a blend of it and the input's ankle) by (1 - w) drop:
        # d = w drop.
        needed = above[:, 1] - np.sqrt(np.clip(length**2 - across**2, 0.0, None))
        drop[frames] = np.maximum(drop[frames], np.clip(needed, 0.0, None) / weights[frames, s])
    if not drop.any():
        return edited, 0.0
    eased = _eased(drop, blend_frames)
    hips, parent = roles.hips, parents[roles.hips]
    parent_rot = world[:, parent] if parent >= 0 else np.broadcast_to(IDENTITY, (edited.n_frames, 4))
    down = np.zeros((edited.n_frames, 3))
    down[:, 1] = -eased
    translations = edited.translations.copy()
    translations[:, hips] += quat.rotate(quat.conjugate(parent_rot), down)
    return Motion(edited.skeleton, edited.rotations, translations, edited.frame_time), float(eased.max())


__all__ = ["REACH", "contact_weights", "lock_stance_feet"]
