"""The bone-by-bone transfer of retargeting: a plan per pair of rigs (index arrays, so a transfer
is one pass over the frames in the kernel), the twists read from positions where a rig's
rotations twist arbitrarily, the chains shared between two maps, and the hips placed so the
target stands on its own floor."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import ops
from .._utils.kept import Kept
from ..body.jointmap import JointMap
from ..body.take import Take
from ..motion import Motion, spread_frames
from ..rotations import quat
from . import twist
from .rig import (
    _IDENTITY,
    Rig,
    _axis,
    _bone,
    _frame_vectors,
    _leg,
    _orthonormal,
    _path_joint,
    _reference,
    _role_frame,
    alignments,
)

_TWIST_FRAMES = 60  # frames read to tell untrusted twists


def with_twists(rig: Rig, motion: Motion | Take) -> Rig:
    """``rig`` with its untrusted twists read from ``motion`` (a motion of it), unless known."""
    if rig.untrusted is not None:
        return rig
    return rig._replace(untrusted=untrusted_twists(motion, rig))


def untrusted_twists(motion: Motion | Take, rig: Rig) -> frozenset:
    """The roles whose twist ``motion``'s rotations set far from what its positions show (a median
    over the frames beyond :func:`~.twist.trusted`, 45 degrees for the hips and chest), such as a
    network's output that turns a thigh 100 degrees about itself and the shin back, or hips and a
    chest whose children all sit at the joint, leaving their rotations free. Real captures stay
    under the bounds (measured: the CMU file and 3,073 of the 3,076 Bandai-Namco clips)."""
    return untrusted_twists_many([motion], rig)[0]


def untrusted_twists_many(sources: list[Motion | Take], rig: Rig) -> list[frozenset]:
    """:func:`untrusted_twists` of each of ``motions`` (all of ``rig``'s skeleton), each from its
    own frames alone, computed together: one forward kinematics call and one pass of the per-frame
    algebra over every clip's sampled frames, then each clip's medians (an archive's short clips
    took 11 ms each one by one). A take whose forward kinematics is known lends its frames."""
    takes = [Take.of(m) for m in sources]
    motions = [t.motion for t in takes]
    picked = [spread_frames(m.n_frames, _TWIST_FRAMES) for m in motions]
    # A median over evenly spread frames: a clip's is as good.
    kinematics = [t.fk_if_computed for t in takes]
    if any(k is None for k in kinematics):
        world, positions = ops.forward_kinematics(
            np.concatenate([m.rotations[f] for m, f in zip(motions, picked)]),
            np.concatenate([m.translations[f] for m, f in zip(motions, picked)]),
            rig.skeleton.parents,
        )
    else:
        world = np.concatenate([k[0][f] for k, f in zip(kinematics, picked) if k is not None])
        positions = np.concatenate([k[1][f] for k, f in zip(kinematics, picked) if k is not None])
    # Each clip's frames as a row of a [clips, _TWIST_FRAMES] table, NaN past its own.
    frames_of = np.array([len(f) for f in picked])
    rows = np.repeat(np.arange(len(motions)), frames_of)
    columns = np.concatenate([np.arange(len(f)) for f in picked])

    def per_clip(values: np.ndarray) -> np.ndarray:
        table = np.full((len(motions), _TWIST_FRAMES), np.nan)
        table[rows, columns] = values
        return table

    def median(table: np.ndarray) -> np.ndarray:
        """Each row's median over its values (np.median's, bit for bit; NaN for a row of none:
        never far). Sorted, not np.nanmedian: that one is 20x slower on small tables."""
        counts = np.sum(~np.isnan(table), axis=1)
        ordered, row = np.sort(table, axis=1), np.arange(len(table))  # NaN sorts last
        return 0.5 * (ordered[row, np.maximum(counts - 1, 0) // 2] + ordered[row, counts // 2])

    turn = rig.conventions.rotation()
    world, points = _turned(turn, world), quat.rotate(turn, positions)
    plan = _own_frames(rig)
    jmap, out = rig.jmap, [set[str]() for _ in motions]
    for role, joint, from_frame in plan.framed:
        seen = quat.mul(quat.from_matrix(_orthonormal(*_frame_vectors(points, jmap, role, jmap))), from_frame)
        off = per_clip(quat.angle(quat.mul(seen, quat.conjugate(world[:, joint]))))
        for k in np.flatnonzero(median(off) > twist.TRUSTED_ELSE):
            out[k].add(role)
    forward = twist.chest_forward(points, jmap)
    for role, joint, bone_axis, second_axis in plan.readable:
        bone = quat.rotate(world[:, joint], bone_axis)
        second = quat.rotate(world[:, joint], second_axis)
        angles = np.abs(twist.twist_angles(bone, second, twist.facing(points, jmap, role, bone, forward)))
        telling = twist.telling(points, jmap, role)
        share = np.bincount(rows, weights=telling, minlength=len(motions)) / np.maximum(frames_of, 1)
        far = median(per_clip(np.where(telling, angles, np.nan))) > twist.trusted(role)
        for k in np.flatnonzero((share > 0.1) & far):
            out[k].add(role)
    # A limb twisted arbitrarily at one joint is twisted back at the next: read the whole limb.
    for found in out:
        for side in ("left", "right"):
            for limb in (("clavicle", "upper_arm", "forearm", "hand"), ("upper_leg", "lower_leg", "foot", "toes")):
                roles = [f"{side}_{part}" for part in limb]
                if found.intersection(roles):
                    found.update(r for r in roles if twist.readable(jmap, r, twist.READABLE))
    return [frozenset(found) for found in out]


_PLANS_KEPT = 64
_PLANS: Kept[ops.TransferPlan] = Kept(_PLANS_KEPT)


def _rig_key(rig: Rig) -> tuple:
    skeleton, jmap = rig.skeleton, rig.jmap
    turn = rig.conventions.rotation().tobytes()
    return (skeleton.content_key, turn, tuple(jmap.joints.items()))


def _plan(source: Rig, target: Rig) -> ops.TransferPlan:
    """The plan of a pair, kept for the pairs met last: an archive's clips share a few skeletons."""
    return _PLANS.get((_rig_key(source), _rig_key(target)), lambda: _new_plan(source, target))


class _OwnFrames(NamedTuple):
    """A rig's role frames in its reference pose, in its joints' rest terms: per role whose twist
    positions can tell, (role, joint, the bone and the second axis of its frame); per hips and
    chest, (role, joint, the rotation taking the role's frame onto the joint's world rotation)."""

    readable: list[tuple[str, int, np.ndarray, np.ndarray]]
    framed: list[tuple[str, int, np.ndarray]]


_FRAMES: Kept[_OwnFrames] = Kept(_PLANS_KEPT)


def _own_frames(rig: Rig) -> _OwnFrames:
    """The rig's :class:`_OwnFrames`, kept for the rigs met last."""
    return _FRAMES.get(_rig_key(rig), lambda: _new_own_frames(rig))


def _new_own_frames(rig: Rig) -> _OwnFrames:
    reference, points = _reference(rig)
    jmap, readable, framed = rig.jmap, [], []
    for role in jmap.joints:
        if twist.readable(jmap, role, twist.READABLE):
            frame = _role_frame(points, jmap, role, jmap)
            local = quat.conjugate(reference[jmap[role]])
            readable.append((role, jmap[role], quat.rotate(local, frame[:, 0]), quat.rotate(local, frame[:, 1])))
    for role in ("hips", "chest"):
        frame = _role_frame(points, jmap, role, jmap)
        framed.append((role, jmap[role], quat.mul(quat.conjugate(quat.from_matrix(frame)), reference[jmap[role]])))
    return _OwnFrames(readable, framed)


def _new_plan(source: Rig, target: Rig) -> ops.TransferPlan:
    """The transfer kernel's plan of a pair: index arrays, so a transfer is one pass over the frames."""
    aligns = alignments(source, target)
    roles = list(aligns)
    rest_s = quat.rotate(source.conventions.rotation(), source.skeleton.rest_positions()[0])
    swung, starts, ends = [], [], []
    for r, role in enumerate(roles):
        # The hips by the line across the hip joints, other roles by their own bone (not the
        # chest, whose bones are several, nor a hand, toe or head, aligned by the bone into them).
        if role == "hips":
            start, end = "right_upper_leg", "left_upper_leg"
        elif role == "chest":
            continue
        else:
            start, end, own = _bone(source.jmap, role, target.jmap)
            if not own:
                continue
        first, last = source.jmap[start], source.jmap[end]
        parents = source.skeleton.parents
        if (parents[last] == first) or (role == "hips" and parents[first] == parents[last] == source.jmap["hips"]):
            continue  # the bone hangs straight from the joint: it already lies where the rotation says
        swung.append(r)
        starts.append(first)
        ends.append(last)
    aligned = {target.jmap[r] for r in roles}
    shared = _shared_chains(target.jmap, aligned)
    parents = target.skeleton.parents
    held, copied = [], []
    computed = aligned | set(shared)
    for j in range(target.skeleton.n_joints):
        if j in computed:
            continue
        ancestor = int(parents[j])
        while ancestor >= 0 and ancestor not in computed:
            ancestor = int(parents[ancestor])
        held.append(j)
        copied.append(ancestor)
    return ops.TransferPlan.of(
        [source.jmap[r] for r in roles],
        [target.jmap[r] for r in roles],
        [aligns[r] for r in roles],
        swung,
        starts,
        ends,
        rest_s[ends] - rest_s[starts],
        list(shared),
        [t for t, _, _ in shared.values()],
        [b for _, b, _ in shared.values()],
        [x for _, _, x in shared.values()],
        held,
        copied,
        _reference(target)[0],  # unmapped joints turn as changes from the target's reference pose
        parents,
        source.conventions.rotation(),
        target.conventions.rotation(),
    )


def _mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Quaternion products ``a * b`` (broadcast) of frames of joints, by the composition kernel:
    seven times NumPy's on 30,000 frames of 31 joints (the same numbers)."""
    shape = np.broadcast_shapes(a.shape, b.shape)
    return ops.compose_rotations(np.broadcast_to(a, shape), np.broadcast_to(b, shape), 1.0)


def _turned(turn: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """World ``rotations`` expressed in axes turned by ``turn``: ``turn * q * turn^-1``."""
    if np.allclose(turn, _IDENTITY, rtol=0, atol=1e-15):  # Y up, facing +Z: nothing to turn
        return rotations
    return _mul(_mul(turn, rotations), quat.conjugate(turn))


def _transfer(
    motion: Motion, source: Rig, target: Rig, kinematics: tuple[np.ndarray, np.ndarray], floor: np.ndarray
) -> Motion:
    """The target's motion (see the module's notes) from the source's world rotations and
    positions, ``kinematics``, and its floor in each frame."""
    world_s, positions_s = kinematics
    rotations = ops.retarget_transfer(world_s, positions_s, _plan(source, target))
    rotations = _chains_turned(rotations, world_s, source, target)
    frames, skeleton = motion.n_frames, target.skeleton
    translations = np.broadcast_to(skeleton.offsets, (frames, skeleton.n_joints, 3)).copy()
    _place_hips(translations, positions_s, source, target, floor)
    return Motion(skeleton, rotations, translations, motion.frame_time)


def matched_chains(source: Rig, target: Rig) -> list[tuple[int, int, int, int]]:
    """The joints without a role that both skeletons have in the same place, as ``(target joint,
    its nearest mapped ancestor, source joint, that role's source joint)``, parents first: below
    the same role, along the same branches (each step the same child, counted in order, of as
    many unmapped children on both sides): a second neck joint, a hip joint before the upper leg,
    fingers and thumbs; and the segments of spines of the same length. Each then turns as the
    source's does beyond that role (see :func:`_chains_turned`) instead of being held at rest or
    given an equal share of the spine's turn."""
    return _CHAINS.get((_rig_key(source), _rig_key(target)), lambda: _new_matched_chains(source, target))


def _new_matched_chains(source: Rig, target: Rig) -> list[tuple[int, int, int, int]]:
    def unmapped(rig: Rig) -> set[int]:
        named = set(rig.jmap.joints.values()) | set(rig.jmap.spine)
        return set(range(rig.skeleton.n_joints)) - named

    free_s, free_t = unmapped(source), unmapped(target)
    children_s = _free_children(source.skeleton.parents, free_s)
    children_t = _free_children(target.skeleton.parents, free_t)
    role_of_t = {j: role for role, j in target.jmap.joints.items()}
    # Spines of as many segments: each takes the source's own share of the turn, not an equal one.
    spine_s, spine_t = source.jmap.spine[:-1], target.jmap.spine[:-1]
    spine = dict(zip(spine_t, spine_s)) if len(spine_s) == len(spine_t) else {}
    out: list[tuple[int, int, int, int]] = []
    counterpart: dict[int, tuple[int, int, int]] = {}  # target joint -> (source joint, the two mapped ancestors)
    for j in range(target.skeleton.n_joints):  # parents first
        if j in spine:
            out.append((j, target.jmap["hips"], spine[j], source.jmap["hips"]))
            continue
        if j not in free_t:
            continue
        parent = int(target.skeleton.parents[j])
        if parent in counterpart:
            s_parent, anchor_t, anchor_s = counterpart[parent]
        elif parent in role_of_t and role_of_t[parent] in source.jmap.joints:
            s_parent, anchor_t, anchor_s = source.jmap[role_of_t[parent]], parent, source.jmap[role_of_t[parent]]
        else:
            continue
        siblings_t, siblings_s = children_t.get(parent, []), children_s.get(s_parent, [])
        if len(siblings_t) != len(siblings_s):
            continue
        joint_s = siblings_s[siblings_t.index(j)]
        counterpart[j] = (joint_s, anchor_t, anchor_s)
        out.append((j, anchor_t, joint_s, anchor_s))
    return out


def _free_children(parents: np.ndarray, free: set[int]) -> dict[int, list[int]]:
    out: dict[int, list[int]] = {}
    for j in sorted(free):
        if parents[j] >= 0:
            out.setdefault(int(parents[j]), []).append(j)
    return out


_CHAINS: Kept[list[tuple[int, int, int, int]]] = Kept(_PLANS_KEPT)


def _chains_turned(rotations: np.ndarray, world_s: np.ndarray, source: Rig, target: Rig) -> np.ndarray:
    """The target's local ``rotations`` with each joint of :func:`matched_chains` turned, beyond
    its mapped ancestor, as the source's counterpart turns beyond the same role (both as changes
    from their reference poses, in canonical axes); every other joint keeps its world rotation."""
    matches = matched_chains(source, target)
    if not matches:
        return rotations
    parents = target.skeleton.parents
    reference_s, _ = _reference(source)
    reference_t, _ = _reference(target)
    turn_s, turn_t = source.conventions.rotation(), target.conventions.rotation()
    world_t, _ = ops.forward_kinematics(rotations, np.zeros(rotations.shape[:-1] + (3,)), parents)
    canonical_s, canonical_t = _turned(turn_s, world_s), _turned(turn_t, world_t).copy()
    for j_t, anchor_t, j_s, anchor_s in matches:
        beyond = _mul(
            quat.conjugate(_mul(canonical_s[:, anchor_s], quat.conjugate(reference_s[anchor_s]))),
            _mul(canonical_s[:, j_s], quat.conjugate(reference_s[j_s])),
        )
        change = _mul(canonical_t[:, anchor_t], quat.conjugate(reference_t[anchor_t]))
        canonical_t[:, j_t] = _mul(_mul(change, beyond), reference_t[j_t])
    world = _turned(quat.conjugate(turn_t), canonical_t)
    local = world.copy()
    inner = parents >= 0
    local[:, inner] = _mul(quat.conjugate(world[:, parents[inner]]), world[:, inner])
    return local


def _trusted(world: np.ndarray, positions: np.ndarray, rig: Rig) -> np.ndarray:
    """The world rotations ``world`` of a motion of ``rig`` with the twists its rotations do not
    tell (``rig.untrusted``) read from its ``positions``: what the transfer then carries over."""
    if not rig.untrusted:
        return world
    plan = _own_frames(rig)
    turn = rig.conventions.rotation()
    canonical, points = _turned(turn, world).copy(), quat.rotate(turn, positions)
    _reframe(canonical, points, rig.jmap, rig.jmap, [f for f in plan.framed if f[0] in rig.untrusted])
    _retwist(canonical, points, rig.jmap, [r for r in plan.readable if r[0] in rig.untrusted])
    return _turned(quat.conjugate(turn), canonical)


def _reframe(world: np.ndarray, points: np.ndarray, jmap: JointMap, other: JointMap, framed: list) -> None:
    """The hips or chest of ``world`` (canonical axes) set from the frame the positions
    ``points`` show, for the roles ``framed`` (of a plan of the rig onto itself)."""
    for role, joint, from_frame in framed:
        frame = _orthonormal(*_frame_vectors(points, jmap, role, other))
        world[:, joint] = quat.mul(quat.from_matrix(frame), from_frame)


def _retwist(world: np.ndarray, points: np.ndarray, jmap: JointMap, readable: list) -> None:
    """The limb bones ``readable`` (of a plan of the rig onto itself) of ``world`` (canonical
    axes) turned about themselves to face the way the positions ``points`` say."""
    forward = twist.chest_forward(points, jmap)
    for role, joint, bone_axis, second_axis in readable:
        bone = quat.rotate(world[:, joint], bone_axis)
        second = quat.rotate(world[:, joint], second_axis)
        half = 0.5 * twist.twist_angles(bone, second, twist.facing(points, jmap, role, bone, forward))[:, None]
        about = np.concatenate([bone * np.sin(half), np.cos(half)], axis=-1)
        world[:, joint] = _mul(about, world[:, joint])


def _shared_chains(jmap: JointMap, aligned: set[int]) -> dict[int, tuple[int, int, float]]:
    """Spine joints between the hips and the chest -> (hips, chest, share of the turn)."""
    out: dict[int, tuple[int, int, float]] = {}
    chain = list(jmap.spine)
    if jmap["hips"] in aligned and chain[-1] in aligned:
        for i, j in enumerate(chain[:-1]):
            if j not in aligned:
                out[j] = (jmap["hips"], chain[-1], (i + 1) / len(chain))
    return out


def without_counterpart(source: Rig, target: Rig) -> tuple[list[str], list[str]]:
    """The target's joints that no joint of the source gives a rotation to, by name: those held at
    rest with their nearest carried ancestor (no role, or a role the source lacks, and no
    counterpart in :func:`matched_chains`), and the extra spine segments that take a share of
    the turn between the hips and the chest."""
    plan = _plan(source, target)
    names = target.skeleton.names
    matched = {j for j, _, _, _ in matched_chains(source, target)}
    return [names[j] for j in plan.held if j not in matched], [names[j] for j in plan.shared if j not in matched]


def carried(points: np.ndarray, source: Rig, target: Rig, floor=None) -> np.ndarray:
    """Source world points ``[F, ..., 3]`` carried into the target's world: turned to its axes,
    and scaled by the ratio of the leg lengths from the source's floor (``floor``: one per
    frame, default the rig's) onto the target's."""
    up_s = np.array(_axis(source.conventions.up), float)
    floor = np.asarray(source.floor if floor is None else floor, dtype=np.float64)
    if floor.ndim:
        floor = floor.reshape(floor.shape + (1,) * (points.ndim - 1))
    canonical = quat.rotate(source.conventions.rotation(), points - up_s * floor) * (_leg(target) / _leg(source))
    up_t = np.array(_axis(target.conventions.up), float)
    return quat.rotate(quat.conjugate(target.conventions.rotation()), canonical) + up_t * target.floor


def _place_hips(translations: np.ndarray, positions_s: np.ndarray, source: Rig, target: Rig, floor: np.ndarray) -> None:
    """Move the target's path joint so its hips follow the source's (:func:`carried`)."""
    skeleton = target.skeleton
    hips = target.jmap["hips"]
    mover = _path_joint(skeleton, hips)
    placed = carried(positions_s[:, source.jmap["hips"]], source, target, floor)
    translations[:, mover] = skeleton.offsets[mover] + (placed - skeleton.rest_positions()[0][hips])


__all__ = [
    "carried",
    "matched_chains",
    "untrusted_twists",
    "untrusted_twists_many",
    "with_twists",
    "without_counterpart",
]
