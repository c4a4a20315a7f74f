"""A motion mirrored left for right: the augmentation motion datasets use most.

The body is reflected across its own sagittal plane, read from the data (the plane of the up axis
and the facing, :mod:`.conventions`), and each joint takes its partner's motion: a role's partner
is the same role on the other side (:mod:`.jointmap`), an unmapped joint's the joint whose name
says the same part on the other side (``LeftHandIndex1``, ``upperarm_twist_01_r``), any other
joint (the spine, the head) its own. Rotations are reflected as changes from the skeleton's
reference pose (:func:`~.retargeting.reference_pose`, upright and left-right symmetric), so a
skeleton whose rest lays bones along their joints' axes (Bandai-Namco's) mirrors as a T-posed one
does; joints that carry the path (the root, the hips where they have position channels) are
placed at their mirrored positions. Mirroring twice gives the motion back.
"""

from __future__ import annotations

import re

import numpy as np

from .. import ops, quat
from ..motion import Motion, Skeleton
from .jointmap import JointMap
from .names import label
from .retargeting import Rig, _turned, reference_pose

_SIDES = {"left": "right", "right": "left"}


def partners(skeleton: Skeleton, jmap: JointMap) -> np.ndarray:
    """Each joint's mirror partner ``[J]`` (itself where it has none)."""
    out = np.arange(skeleton.n_joints)
    for role, joint in jmap.joints.items():
        side = role.split("_", 1)[0]
        if side in _SIDES and _SIDES[side] + role[len(side) :] in jmap.joints:
            out[joint] = jmap.joints[_SIDES[side] + role[len(side) :]]
    mapped = set(jmap.joints.values())
    named: dict[tuple, int] = {}
    for j, name in enumerate(skeleton.names):
        if j not in mapped:
            said = label(name)
            named[(said.side, said.part, tuple(re.findall(r"\d+", name)))] = j
    for (side, part, digits), j in named.items():
        if side in _SIDES:
            out[j] = named.get((_SIDES[side], part, digits), j)
        elif part[:1] in ("l", "r"):  # "lhand" and "rhand": a side letter in one lower-case word
            other = named.get(("", {"l": "r", "r": "l"}[part[0]] + part[1:], digits))
            out[j] = j if other is None else other
    return out


def _reflected(q: np.ndarray) -> np.ndarray:
    """Rotations reflected across the plane square to +X (canonical axes: left is +X): the axis
    mirrored and the turn reversed, ``(x, -y, -z, w)``."""
    return q * np.array([1.0, -1.0, -1.0, 1.0])


def mirror(motion: Motion, user_map: dict | None = None) -> Motion:
    """``motion`` mirrored left for right (see the module's notes), on the same skeleton."""
    return mirror_many([motion], user_map)[0]


def mirror_many(motions: list[Motion], user_map: dict | None = None) -> list[Motion]:
    """Each of ``motions`` (all of one skeleton) mirrored as :func:`mirror` mirrors it, all at
    once: one forward kinematics and one pass of quaternion products over their frames together,
    the skeleton's conventions read from the first. What ``preprocess --mirror`` runs a batch through."""
    if not motions:
        return []
    rig = Rig.of(motions[0], user_map)
    skeleton, parents = motions[0].skeleton, motions[0].skeleton.parents
    frames = np.array([m.n_frames for m in motions])
    starts = np.concatenate([[0], np.cumsum(frames)[:-1]])
    rotations = np.concatenate([m.rotations for m in motions])
    translations = np.concatenate([m.translations for m in motions])
    turn = rig.conventions.rotation()
    world, positions = ops.forward_kinematics(rotations, translations, parents)
    world = _turned(turn, world)
    positions = quat.rotate(turn, positions)
    reference = _turned(turn, reference_pose(skeleton))
    partner = partners(skeleton, rig.jmap)
    change = quat.mul(world, quat.conjugate(reference))  # from the reference pose, canonical axes
    new_world = quat.mul(_reflected(change[:, partner]), reference)
    new_positions = positions[:, partner] * np.array([-1.0, 1.0, 1.0])
    new_world = _turned(quat.conjugate(turn), new_world)
    new_positions = quat.rotate(quat.conjugate(turn), new_positions)
    new_rotations = new_world.copy()
    inner = parents >= 0
    new_rotations[:, inner] = quat.mul(quat.conjugate(new_world[:, parents[inner]]), new_world[:, inner])
    new_translations = translations.copy()
    # The joints that carry the path, clip by clip: any whose translation changes over the clip.
    spread = np.maximum.reduceat(translations, starts) - np.minimum.reduceat(translations, starts)
    moving = np.repeat(spread.max(axis=-1) > 1e-9, frames, axis=0) | ~inner  # [frames, J]
    for j in np.flatnonzero(moving.any(axis=0)):
        rows = moving[:, j]
        if parents[j] < 0:
            new_translations[rows, j] = new_positions[rows, j]
        else:
            offset = new_positions[rows, j] - new_positions[rows, parents[j]]
            new_translations[rows, j] = quat.rotate(quat.conjugate(new_world[rows, parents[j]]), offset)
    cuts = np.cumsum(frames)[:-1]
    return [
        Motion(skeleton, r, t, m.frame_time)
        for m, r, t in zip(motions, np.split(new_rotations, cuts), np.split(new_translations, cuts))
    ]


__all__ = ["mirror", "mirror_many", "partners"]
