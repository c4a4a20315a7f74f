"""Planted feet after retargeting: through each of the source's contacts, each ankle follows the
source's (carried onto the target: still where the source's is still), with two-bone leg IK
(the foot keeps its world rotation), eased in and out."""

from __future__ import annotations

import numpy as np

from .. import ops
from ..body.contacts import FLOOR_PERCENTILE, HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD
from ..body.jointmap import JointMap
from ..motion import Motion

BLEND_FRAMES = 3


def plant_feet(
    motion: Motion,
    jmap: JointMap,
    contacts: np.ndarray,
    guide: np.ndarray,
    blend_frames: int = BLEND_FRAMES,
    starts=None,
) -> Motion:
    """``motion`` with each ankle, through each contact run of ``contacts bool [F, 2]`` (left,
    right), moving as ``guide [F, 2, 3]`` (the source's ankles in this motion's world) does, from
    where this motion has it on average over the run. Legs whose knee is not the foot's parent
    and the upper leg's child (a twist bone in the chain) are left as they are. ``starts``: where
    clips laid end to end begin and the last one ends (runs and easing stop there). One kernel
    call (``plant_feet``: FK, weights, run means and leg IK of every frame)."""
    skeleton = motion.skeleton
    parents = skeleton.parents
    legs = []
    for side in ("left", "right"):
        hip, knee, foot = (jmap[f"{side}_{r}"] for r in ("upper_leg", "lower_leg", "foot"))
        legs.append([hip, knee, foot] if parents[foot] == knee and parents[knee] == hip else [-1, -1, -1])
    bounds = [0, motion.n_frames] if starts is None else [int(b) for b in starts]
    rotations = ops.plant_feet(
        motion.rotations, motion.translations, parents, legs, contacts, guide, bounds, blend_frames
    )
    return Motion(skeleton, rotations, motion.translations, motion.frame_time)


def source_contacts(clips: list[Motion], rig, upright_positions: np.ndarray, bounds=None) -> np.ndarray:
    """Contacts ``bool [F, 2]`` of ``clips`` (of the rig ``rig``, laid end to end as ``bounds``
    says; None: one clip) from their world positions turned to the canonical axes (Y up, file
    units), each clip on its own floor: :func:`~expressive_mocap.body.contacts.foot_contacts` with its
    defaults, all clips in one kernel call (``clip_gait_many``, clips in parallel)."""
    bounds = [0, len(upright_positions)] if bounds is None else bounds
    body = rig.body
    roles, height = body.roles, body.actor_height  # one skeleton: the same for every clip
    pieces = zip(clips, bounds[:-1], bounds[1:])
    # The hips' rest height is read by the features only: none are asked for.
    gait = [(upright_positions[a:b], c.rotations, c.frame_time, height, 1.0) for c, a, b in pieces]
    settings = ops.GaitSettings(HEIGHT_THRESHOLD, SPEED_THRESHOLD, MIN_DURATION, FLOOR_PERCENTILE)
    found = ops.clip_gait_many(gait, roles.gait_joints, settings, features=False, contacts=True)
    return np.concatenate([contacts for _, contacts in found] + [np.zeros((0, 2), bool)])


def toes_above(motion: Motion, jmap: JointMap, up: np.ndarray, level: float) -> Motion:
    """``motion`` with each foot whose toe joint would go below ``level`` (along the unit ``up``,
    file units) pitched up about its ankle just enough to stand the toe there, frame by frame;
    the ankles stay, and where the toe is above the level nothing turns (so nothing jumps where it
    touches it). For feet the positions did not orient (a layout without toes, Human3.6M's: the
    foot follows the shin, and at toe-off its toes went 4 cm into the floor)."""
    from ..rotations import quat

    world, positions = motion.fk()
    local = motion.rotations.copy()
    parents = motion.skeleton.parents
    for side in ("left", "right"):
        foot, toes = jmap.joints.get(f"{side}_foot", -1), jmap.joints.get(f"{side}_toes", -1)
        if foot < 0 or toes < 0 or parents[toes] != foot:
            continue
        bone = positions[:, toes] - positions[:, foot]
        length = np.maximum(np.linalg.norm(bone, axis=-1), 1e-12)
        height = bone @ up
        below = positions[:, toes] @ up < level
        if not below.any():
            continue
        wanted = np.clip((level - positions[:, foot] @ up) / length, -1.0, 1.0)
        angle = np.where(below, np.arcsin(wanted) - np.arcsin(np.clip(height / length, -1.0, 1.0)), 0.0)
        across = np.cross(bone, up)  # a turn about it takes the bone towards up
        across /= np.maximum(np.linalg.norm(across, axis=-1, keepdims=True), 1e-12)
        turned = quat.mul(quat.exp(across * angle[:, None]), world[:, foot])
        local[:, foot] = quat.normalize(quat.mul(quat.conjugate(world[:, parents[foot]]), turned))
    return Motion(motion.skeleton, local, motion.translations, motion.frame_time)


__all__ = ["BLEND_FRAMES", "plant_feet", "source_contacts", "toes_above"]
