"""How a rig habitually twists its limbs, read from its own motion, and a motion given those habits.

Joint positions show where a limb bends (:func:`~.twist.facing`), not how a rig's rotations twist
its bones about that: every rig sets its own elbow and knee axes. The CMU skeletons' elbows bend
about an axis 28-32 degrees off the T-pose's, so their upper arms and forearms sit twisted that far
from the plane the elbow bends in, clip after clip (within 0.4-2.2 degrees over the frames).
A motion fitted to positions faces that plane exactly; given the target rig's own motion, its
limbs are turned about themselves by the difference, so it twists them as its own captures do.
Each turned joint's children keep their world rotations: no position moves.
"""

from __future__ import annotations

import numpy as np

from .. import ops
from ..motion import Motion, spread_frames
from ..rotations import quat
from . import twist
from .rig import Rig

HABITUAL = ("upper_arm", "forearm", "upper_leg", "lower_leg")  # the limb segments turned
_SAMPLED = 256  # frames a habit is read from, spread over the clip
_TELLING = 0.1  # the least share of frames that tell a limb's plane for its habit to be read


def habits(motion: Motion, rig: Rig) -> dict[int, float]:
    """Per joint of the :data:`HABITUAL` parts with one child, the median angle (radians, about
    its bone) from where ``motion``'s rotations put its second axis to where its positions say
    it faces, over the frames that tell (:func:`~.twist.telling`); none where too few tell."""
    picked = spread_frames(motion.n_frames, _SAMPLED)
    world, positions = ops.forward_kinematics(
        motion.rotations[picked], motion.translations[picked], rig.skeleton.parents
    )
    return _habits(world, positions, rig)


def _habits(world: np.ndarray, positions: np.ndarray, rig: Rig) -> dict[int, float]:
    """:func:`habits` of the frames of world rotations ``[F, J, 4]`` and positions ``[F, J, 3]``."""
    from .transfer import _own_frames, _turned

    turn = rig.conventions.rotation()
    world, points = _turned(turn, world), quat.rotate(turn, positions)
    forward = twist.chest_forward(points, rig.jmap)
    children = np.bincount(rig.skeleton.parents[1:], minlength=len(rig.skeleton.parents))
    out = {}
    for role, joint, bone_axis, second_axis in _own_frames(rig).readable:
        if role.split("_", 1)[-1] not in HABITUAL or children[joint] != 1:
            continue
        bone = quat.rotate(world[:, joint], bone_axis)
        second = quat.rotate(world[:, joint], second_axis)
        angles = twist.twist_angles(bone, second, twist.facing(points, rig.jmap, role, bone, forward))
        telling = twist.telling(points, rig.jmap, role)
        if telling.mean() >= _TELLING:
            out[joint] = _circular_median(angles[telling])
    return out


def _circular_median(angles: np.ndarray) -> float:
    """The median of ``angles`` (radians) about their circular mean: no wrap at +-pi."""
    centre = float(np.angle(np.mean(np.exp(1j * angles))))
    return centre + float(np.median((angles - centre + np.pi) % (2 * np.pi) - np.pi))


def with_habits(motion: Motion, rig: Rig, wanted: dict[int, float]) -> Motion:
    """``motion`` (of ``rig``) with each joint of ``wanted`` (:func:`habits` of the rig's own
    motion) turned about its bone so that its median twist from where it faces is the wanted
    one; its children keep their world rotations, so every position stays where it was."""
    world, positions = motion.fk()
    picked = spread_frames(motion.n_frames, _SAMPLED)
    have = _habits(world[picked], positions[picked], rig)
    turns = {j: have[j] - wanted[j] for j in wanted if j in have}
    if not turns:
        return motion
    parents = rig.skeleton.parents
    world = world.copy()
    touched: set[int] = set()
    for joint, angle in turns.items():
        child = int(np.flatnonzero(parents == joint)[0])
        bone = positions[:, child] - positions[:, joint]
        bone /= np.maximum(np.linalg.norm(bone, axis=-1, keepdims=True), 1e-12)
        about = np.concatenate([bone * np.sin(0.5 * angle), np.full((len(bone), 1), np.cos(0.5 * angle))], axis=-1)
        world[:, joint] = quat.mul(about, world[:, joint])
        touched.update((joint, child))
    local = motion.rotations.copy()
    for j in sorted(touched):  # a turned joint and its child: their rotations under their parents'
        local[:, j] = quat.normalize(quat.mul(quat.conjugate(world[:, parents[j]]), world[:, j]))
    return Motion(motion.skeleton, local, motion.translations, motion.frame_time)


__all__ = ["HABITUAL", "habits", "with_habits"]
