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
from typing import NamedTuple

import numpy as np

from .. import ops
from ..body.body import Body
from ..body.conventions import SAMPLED_FRAMES, facing_of, frame_rotation, ups_of
from ..body.jointmap import JointMap
from ..body.names import label
from ..motion import Motion, Skeleton, spread_frames
from ..rotations import quat
from .rig import Rig, reference_pose
from .transfer import _turned

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


def mirror_many(motions: list[Motion], user_map: dict | None = None, rig: Rig | None = None) -> list[Motion]:
    """Each of ``motions`` mirrored as :func:`mirror` mirrors it alone (its own skeleton and
    conventions), the clips that share a rig all at once. What ``preprocess --mirror`` runs a
    batch's clips through. ``rig``: the rig of every clip, when known.

    When each joint's partner hangs from its parent's partner (a left-right symmetric hierarchy:
    every humanoid rig seen), the mirror image is linear in each joint's local values: a new local
    rotation is ``A q B`` of its partner's, ``A`` and ``B`` fixed per joint (from the reference pose
    and the axes), a 4 x 4 matrix applied to the quaternion; a moving joint's translation is a
    fixed 3 x 3 matrix times its partner's. No forward kinematics: a matrix product a joint over all
    the frames. Other hierarchies go through the world rotations and positions."""
    if rig is not None:
        return _mirror_together(motions, _Plane(rig.skeleton, rig.jmap, rig.conventions.rotation()))
    groups: dict[tuple, tuple[_Plane, list[int]]] = {}
    for k, own in enumerate(_planes_of(motions, user_map)):
        key = (own.skeleton.content_key, own.turn.tobytes(), tuple(own.jmap.joints.items()))
        groups.setdefault(key, (own, []))[1].append(k)
    out: list = [None] * len(motions)
    for own, members in groups.values():
        for k, image in zip(members, _mirror_together([motions[k] for k in members], own)):
            out[k] = image
    return out


class _Plane(NamedTuple):
    """What mirroring a motion needs of its rig: the skeleton, its joint map, and the turn to the
    canonical axes (Y up, facing +Z), across whose X the body is reflected."""

    skeleton: Skeleton
    jmap: JointMap
    turn: np.ndarray


def _planes_of(motions: list[Motion], user_map: dict | None = None) -> list[_Plane]:
    """The :class:`_Plane` of each motion, from that motion alone: its up axis from its frames
    (:func:`~.conventions.ups_of`), its facing from its skeleton (:func:`~.conventions.facing_of`);
    one forward kinematics call for the sampled frames of all the clips of one skeleton."""
    by_skeleton: dict[tuple, list[int]] = {}
    for k, motion in enumerate(motions):
        by_skeleton.setdefault(motion.skeleton.content_key, []).append(k)
    out: list = [None] * len(motions)
    for members in by_skeleton.values():
        skeleton = motions[members[0]].skeleton
        jmap = Body.of(skeleton, user_map).joint_map
        picked = [spread_frames(motions[k].n_frames, SAMPLED_FRAMES) for k in members]
        _, positions = ops.forward_kinematics(
            np.concatenate([m.rotations[f] for m, f in zip((motions[k] for k in members), picked)]),
            np.concatenate([m.translations[f] for m, f in zip((motions[k] for k in members), picked)]),
            skeleton.parents,
        )
        samples = np.split(positions, np.cumsum([len(f) for f in picked])[:-1])
        for k, up in zip(members, ups_of(jmap, samples)):
            facing, _ = facing_of(skeleton, jmap, up)
            out[k] = _Plane(motions[k].skeleton, jmap, frame_rotation(up, facing))
    return out


def _mirror_together(motions: list[Motion], rig: _Plane) -> list[Motion]:
    """:func:`mirror_many` of clips of one rig, ``rig``."""
    if not motions:
        return []
    skeleton, parents = motions[0].skeleton, motions[0].skeleton.parents
    frames = np.array([m.n_frames for m in motions])
    starts = np.concatenate([[0], np.cumsum(frames)[:-1]])
    rotations = np.concatenate([m.rotations for m in motions])
    translations = np.concatenate([m.translations for m in motions])
    partner = partners(skeleton, rig.jmap)
    # The joints that carry the path, clip by clip: any whose translation changes over the clip.
    spread = np.zeros((len(motions),) + translations.shape[1:])
    some = frames > 0  # reduceat would give a clip of no frames the next clip's first row
    if some.any():
        spread[some] = np.maximum.reduceat(translations, starts[some]) - np.minimum.reduceat(translations, starts[some])
    moving = np.repeat(spread.max(axis=-1) > 1e-9, frames, axis=0) | (parents < 0)  # [frames, J]
    inner = parents >= 0
    if np.all(partner[parents[inner]] == parents[partner[inner]]) and np.all(partner[~inner] == np.flatnonzero(~inner)):
        new_rotations, new_translations = _linear(rig, partner, rotations, translations, moving)
    else:
        new_rotations, new_translations = _through_positions(rig, partner, rotations, translations, moving)
    cuts = np.cumsum(frames)[:-1]
    return [
        Motion(skeleton, r, t, m.frame_time)
        for m, r, t in zip(motions, np.split(new_rotations, cuts), np.split(new_translations, cuts))
    ]


def _maps(rig: _Plane, partner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per joint, the 4 x 4 matrix taking its partner's local rotation to its mirrored one and
    the 3 x 3 matrix taking its partner's translation to its mirrored one ``([J, 4, 4], [J, 3, 3])``
    (see :func:`mirror_many`), each found by mapping the basis through :func:`mirror`'s formulas."""
    skeleton, parents = rig.skeleton, rig.skeleton.parents
    turn = rig.turn
    reference = reference_pose(skeleton)  # world rotations [J, 4], the file's axes
    flip = np.array([-1.0, 1.0, 1.0])

    def reflect(q: np.ndarray) -> np.ndarray:  # the reflection in the file's axes, on rotations
        return _turned(quat.conjugate(turn), _reflected(_turned(turn, q)))

    def reflect_vector(v: np.ndarray) -> np.ndarray:  # and on positions
        return quat.rotate(quat.conjugate(turn), quat.rotate(turn, v) * flip)

    identity = np.array([0.0, 0.0, 0.0, 1.0])
    parent_reference = np.where((parents >= 0)[:, None], reference[np.maximum(parents, 0)], identity)
    before = quat.mul(quat.conjugate(parent_reference), reflect(parent_reference[partner]))  # A [J, 4]
    after = quat.mul(quat.conjugate(reflect(reference[partner])), reference)  # B [J, 4]
    basis = np.eye(4)[:, None, :]  # [4, 1, 4]
    rotation_maps = quat.mul(quat.mul(before, reflect(basis)), after)  # [4 (basis), J, 4]
    vectors = np.eye(3)[:, None, :]
    moved = reflect_vector(quat.rotate(parent_reference[partner], vectors))  # [3, J, 3]
    translation_maps = quat.rotate(quat.conjugate(parent_reference), moved)
    return np.moveaxis(rotation_maps, 0, -1), np.moveaxis(translation_maps, 0, -1)


def _linear(rig: _Plane, partner: np.ndarray, rotations, translations, moving) -> tuple[np.ndarray, np.ndarray]:
    """:func:`mirror_many` on a left-right symmetric hierarchy: local values mapped joint by joint."""
    rotation_maps, translation_maps = _maps(rig, partner)
    new_rotations = (rotation_maps @ rotations[:, partner, :, None])[..., 0]  # 2x einsum's speed
    new_translations = translations.copy()
    for j in np.flatnonzero(moving.any(axis=0)):
        rows = slice(None) if moving[:, j].all() else moving[:, j]  # a slice: no copy of the rows picked
        new_translations[rows, j] = translations[rows, partner[j]] @ translation_maps[j].T
    return new_rotations, new_translations


def _through_positions(rig: _Plane, partner: np.ndarray, rotations, translations, moving) -> tuple:
    """:func:`mirror_many` on any hierarchy: world rotations and positions reflected, then local again."""
    skeleton, parents = rig.skeleton, rig.skeleton.parents
    turn = rig.turn
    world, positions = ops.forward_kinematics(rotations, translations, parents)
    world = _turned(turn, world)
    positions = quat.rotate(turn, positions)
    reference = _turned(turn, reference_pose(skeleton))
    change = quat.mul(world, quat.conjugate(reference))  # from the reference pose, canonical axes
    new_world = quat.mul(_reflected(change[:, partner]), reference)
    new_positions = positions[:, partner] * np.array([-1.0, 1.0, 1.0])
    new_world = _turned(quat.conjugate(turn), new_world)
    new_positions = quat.rotate(quat.conjugate(turn), new_positions)
    new_rotations = new_world.copy()
    inner = parents >= 0
    new_rotations[:, inner] = quat.mul(quat.conjugate(new_world[:, parents[inner]]), new_world[:, inner])
    new_translations = translations.copy()
    for j in np.flatnonzero(moving.any(axis=0)):
        rows = moving[:, j]
        if parents[j] < 0:
            new_translations[rows, j] = new_positions[rows, j]
        else:
            offset = new_positions[rows, j] - new_positions[rows, parents[j]]
            new_translations[rows, j] = quat.rotate(quat.conjugate(new_world[rows, parents[j]]), offset)
    return new_rotations, new_translations


__all__ = ["mirror", "mirror_many", "partners"]
