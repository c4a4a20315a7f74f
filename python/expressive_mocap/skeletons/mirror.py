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

from .. import quat
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
    rig = Rig.of(motion, user_map)
    skeleton, parents = motion.skeleton, motion.skeleton.parents
    turn = rig.conventions.rotation()
    world, positions = motion.fk()
    world = _turned(turn, world)
    positions = quat.rotate(turn, positions)
    reference = _turned(turn, reference_pose(skeleton))
    partner = partners(skeleton, rig.jmap)
    change = quat.mul(world, quat.conjugate(reference))  # from the reference pose, canonical axes
    new_world = quat.mul(_reflected(change[:, partner]), reference)
    new_positions = positions[:, partner] * np.array([-1.0, 1.0, 1.0])
    new_world = _turned(quat.conjugate(turn), new_world)
    new_positions = quat.rotate(quat.conjugate(turn), new_positions)
    rotations = new_world.copy()
    inner = parents >= 0
    rotations[:, inner] = quat.mul(quat.conjugate(new_world[:, parents[inner]]), new_world[:, inner])
    translations = motion.translations.copy()
    moving = np.ptp(motion.translations, axis=0).max(axis=-1) > 1e-9  # the joints that carry the path
    for j in np.flatnonzero(moving | ~inner):
        if parents[j] < 0:
            translations[:, j] = new_positions[:, j]
        else:
            offset = new_positions[:, j] - new_positions[:, parents[j]]
            translations[:, j] = quat.rotate(quat.conjugate(new_world[:, parents[j]]), offset)
    return Motion(skeleton, rotations, translations, motion.frame_time)


__all__ = ["mirror", "partners"]
