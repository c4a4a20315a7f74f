"""A rig: a skeleton with what retargeting needs to know about it (joint map, conventions,
floor), the reference pose its bones' twists are measured from, and the frame each role is read
in (the hips and chest by the lines across them and up the spine; a limb segment by its bone and
the plane its elbow or knee bends in; a foot by its flat stance), from which the alignments
between two rigs follow."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..body.body import Body
from ..body.contacts import percentiles_by_clip
from ..body.conventions import AXES, Conventions, read_conventions
from ..body.jointmap import JointMap
from ..body.take import Take
from ..errors import MocapError
from ..motion import Motion, Skeleton
from ..rotations import quat
from . import twist
from .planting import source_contacts

_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


# The joint whose rest bone direction aligns each role (the next mapped joint out); leaf roles
# (hand, toes, head) use the bone into them.
_NEXT = {
    "upper_leg": "lower_leg",
    "lower_leg": "foot",
    "foot": "toes",
    "clavicle": "upper_arm",
    "upper_arm": "forearm",
    "forearm": "hand",
}
_BEFORE = {"hand": "forearm", "toes": "foot", "foot": "lower_leg"}
_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])
_UP = np.array([0.0, 1.0, 0.0])
_FORWARD = np.array([0.0, 0.0, 1.0])


class Rig(NamedTuple):
    """A skeleton with what retargeting needs to know about it: its joint map, conventions, floor
    height (along its up axis, file units) and the roles whose rotations its motion twists
    arbitrarily, to be read from the positions instead (:func:`~.transfer.untrusted_twists`; None until a
    motion of it is a source: :func:`~.transfer.with_twists`)."""

    skeleton: Skeleton
    jmap: JointMap
    conventions: Conventions
    floor: float
    untrusted: frozenset | None = frozenset()
    user_map: dict | None = None
    stance: float | None = None  # where its stance feet stand (:func:`stance_level`; None: the floor)

    @property
    def body(self) -> Body:
        """The :class:`~expressive_mocap.body.Body` of the skeleton, read with the rig's user map."""
        return Body.of(self.skeleton, self.user_map)

    @classmethod
    def of(cls, motion: Motion | Take, user_map: dict | None = None, conventions: Conventions | None = None) -> Rig:
        """The rig of ``motion``'s skeleton (read with ``user_map``), its conventions and floor
        read from its frames (a take's positions, where given); its untrusted twists are read
        when it is first a source (:func:`~.transfer.with_twists`)."""
        take = Take.of(motion)
        motion = take.motion
        jmap = Body.of(motion.skeleton, user_map).joint_map
        conventions = conventions or read_conventions(motion, jmap)
        floor = _floor_of(take.positions, jmap, conventions)
        return cls(motion.skeleton, jmap, conventions, floor, None, user_map)


def _floor(motion: Motion, jmap: JointMap, conventions: Conventions) -> float:
    """The floor along the up axis: the 5th percentile of the lowest foot or toe joint."""
    return _floor_of(motion.positions(), jmap, conventions)


def _floor_of(positions: np.ndarray, jmap: JointMap, conventions: Conventions) -> float:
    return float(_floors_of(positions, [0, len(positions)], jmap, conventions)[0])


def _floors_of(positions: np.ndarray, bounds, jmap: JointMap, conventions: Conventions) -> np.ndarray:
    """The floor of each clip laid end to end in ``positions`` (see ``bounds``, :func:`_floor`)."""
    up = np.array(_axis(conventions.up))
    joints = [jmap[r] for r in ("left_foot", "right_foot", "left_toes", "right_toes") if r in jmap]
    return percentiles_by_clip((positions[:, joints] @ up).min(axis=1), bounds, 5)


def _axis(name: str) -> tuple[int, int, int]:
    return AXES[name]


def _role_of(jmap: JointMap, role: str) -> str:
    return role.split("_", 1)[1] if role.startswith(("left_", "right_")) else role


def _bone(jmap: JointMap, role: str, other: JointMap) -> tuple[str, str, bool]:
    """The two roles whose rest line aligns ``role`` (see the module's notes), and whether it is
    the role's own bone (out of it; False: the bone into a hand, toe or head). The same rule for
    both maps, so it uses only roles both hold."""
    side = role.split("_", 1)[0] + "_" if role.startswith(("left_", "right_")) else ""
    part = role[len(side) :]
    both = lambda r: r in jmap and r in other  # noqa: E731
    nxt = _NEXT.get(part)
    if nxt and both(side + nxt):
        return role, side + nxt, True
    if part == "neck" and both("head"):
        return "neck", "head", True
    if part == "head":
        return ("neck" if both("neck") else "chest"), "head", False
    before = _BEFORE.get(part)
    if before and both(side + before):
        return side + before, role, False
    raise MocapError(f"no bone to align the {role.replace('_', ' ')} by")


def _frame_vectors(points: np.ndarray, jmap: JointMap, role: str, other: JointMap) -> tuple[np.ndarray, np.ndarray]:
    """(across, along) ``[..., 3]`` of the hips or chest from joint positions ``[..., J, 3]``: the
    line across to the left, and up the spine."""

    def line(start: str, end: str) -> np.ndarray:
        return points[..., jmap[end], :] - points[..., jmap[start], :]

    if role == "hips":
        return line("right_upper_leg", "left_upper_leg"), line("hips", "chest")
    arm = next((p for p in ("upper_arm", "clavicle") if f"left_{p}" in jmap and f"left_{p}" in other), None)
    across = line("right_upper_leg", "left_upper_leg") if arm is None else line(f"right_{arm}", f"left_{arm}")
    return across, line("chest", "head")  # the neck may sit at the chest


def _orthonormal(across: np.ndarray, along: np.ndarray) -> np.ndarray:
    """The frame ``[..., 3, 3]`` (columns) of ``across`` and the part of ``along`` square to it."""
    x = across / np.linalg.norm(across, axis=-1, keepdims=True)
    y = along - x * np.sum(along * x, axis=-1, keepdims=True)
    y = y / np.linalg.norm(y, axis=-1, keepdims=True)
    return np.stack([x, y, np.cross(x, y)], axis=-1)  # columns


def reference_pose(skeleton: Skeleton) -> np.ndarray:
    """World rotations ``[J, 4]`` (the skeleton's own axes) of the pose its bones' twists are
    measured from: the rest pose (every rotation the identity) for T, A and most other rest poses,
    whose limbs hang or spread with their hinges crosswise; for the Bandai-Namco skeleton, whose
    rest lays every bone along its joint's X axis, a real neutral walk's average pose."""
    from ..body.canonical import bandai_like_skeleton, bandai_standing_pose

    bandai = bandai_like_skeleton()
    if skeleton.names == bandai.names and np.array_equal(skeleton.parents, bandai.parents):
        return bandai_standing_pose()
    return np.tile(_IDENTITY, (skeleton.n_joints, 1))


def _reference(rig: Rig) -> tuple[np.ndarray, np.ndarray]:
    """The rig's reference pose in canonical axes: world rotations ``[J, 4]`` and joint positions ``[J, 3]``."""
    skeleton = rig.skeleton
    world = reference_pose(skeleton)
    positions = np.zeros((skeleton.n_joints, 3))
    for j in range(1, skeleton.n_joints):  # parents come before their children
        parent = skeleton.parents[j]
        positions[j] = positions[parent] + quat.rotate(world[parent], skeleton.offsets[j])
    turn = rig.conventions.rotation()
    return quat.mul(quat.mul(turn, world), quat.conjugate(turn)), quat.rotate(turn, positions)


def _role_frame(points: np.ndarray, jmap: JointMap, role: str, other: JointMap) -> np.ndarray:
    """A role's frame (columns) in a reference pose: the hips and chest by their lines across and
    up the spine; a limb segment, clavicle or foot by its bone and the way the positions say it
    faces (:func:`~.twist.facing`: where its elbow or knee bends, its foot points); any other role
    by its bone and the body's forward (up for the toes, which point forward)."""
    if role in ("hips", "chest"):
        return _orthonormal(*_frame_vectors(points, jmap, role, other))
    start, end, _ = _bone(jmap, role, other)
    line = points[jmap[end]] - points[jmap[start]]
    if twist.readable(jmap, role) and twist.readable(other, role):
        return _orthonormal(line, twist.facing(points, jmap, role, line))
    return _orthonormal(line, _UP if _role_of(jmap, role) == "toes" else _FORWARD)


def _flat_frame(
    points: np.ndarray, jmap: JointMap, role: str, other: JointMap, tips: dict[str, np.ndarray], other_tips: dict
) -> np.ndarray:
    """:func:`_role_frame`, but for a foot or toes (where both rigs show where their toes are:
    :func:`_foot_tips`) the frame a foot standing flat has: forward along the floor, up. Each
    rig's reference pose stands on flat feet, however its ankle sits (a flat Bandai-Namco foot
    points 40 degrees down to the toe joint, a CMU one 10): carried bone by bone, a flat foot
    came out toes-up on another rig."""
    part = _role_of(jmap, role)
    side = role.split("_", 1)[0]
    if part in ("foot", "toes") and side in tips and side in other_tips:
        forward = tips[side] - points[jmap[f"{side}_foot"]]
        forward = forward - _UP * np.dot(forward, _UP)
        if np.linalg.norm(forward) > 1e-9:
            return _orthonormal(forward, _UP)
    return _role_frame(points, jmap, role, other)


def _foot_tips(rig: Rig, world: np.ndarray, points: np.ndarray) -> dict[str, np.ndarray]:
    """Per side, where the toes are in the reference pose (``world``, ``points``: canonical axes):
    the toe joint, else the farthest End Site of a foot without one (a rig whose foot chain ends
    at the ankle); a side with neither is left out."""
    out = {}
    turn = rig.conventions.rotation()
    for side in ("left", "right"):
        if f"{side}_toes" in rig.jmap:
            out[side] = points[rig.jmap[f"{side}_toes"]]
            continue
        foot = rig.jmap[f"{side}_foot"]
        sites = [np.asarray(off, dtype=np.float64) for j, off in rig.skeleton.end_sites if j == foot]
        far = max(sites, key=np.linalg.norm, default=None)
        if far is not None and np.linalg.norm(far) > 0:
            out[side] = points[foot] + quat.rotate(world[foot], quat.rotate(turn, far))
    return out


def alignments(source: Rig, target: Rig) -> dict[str, np.ndarray]:
    """Role -> ``A_r`` (canonical axes), which turns the source joint's world rotation into the
    target's: ``W_t = W_s A_r``. In the two reference poses (:func:`reference_pose`) it takes the
    target's frame of the role onto the source's, so each bone keeps its direction and its twist
    (which way its hinge faces) whatever the two rests are."""
    world_s, points_s = _reference(source)
    world_t, points_t = _reference(target)
    tips_s, tips_t = _foot_tips(source, world_s, points_s), _foot_tips(target, world_t, points_t)
    out = {}
    for role in source.jmap.joints:
        if role not in target.jmap.joints:
            continue
        frame_s = _flat_frame(points_s, source.jmap, role, target.jmap, tips_s, tips_t)
        frame_t = _flat_frame(points_t, target.jmap, role, source.jmap, tips_t, tips_s)
        onto = quat.from_matrix(frame_s @ frame_t.T)
        js, jt = source.jmap[role], target.jmap[role]
        out[role] = quat.mul(quat.mul(quat.conjugate(world_s[js]), onto), world_t[jt])
    return out


def stance_level(rig: Rig, motion: Motion | Take) -> float:
    """Where ``rig``'s own feet stand in ``motion`` (a motion of it), along its up axis: the
    median over its stance frames (its own contacts) of the lower of the standing foot's ankle and
    toe joints; its floor where it never stands (a rest pose). A retarget puts the target's stance
    feet there: at the floor (a low percentile of every frame's lowest foot joint) they stood a
    little low, and a round trip came back lower than it went."""
    take = Take.of(motion)
    upright = quat.rotate(rig.conventions.rotation(), take.positions)
    contacts = source_contacts([take.motion], rig, upright)
    lowest = []
    for side in ("left", "right"):
        joints = [rig.jmap[f"{side}_{part}"] for part in ("foot", "toes") if f"{side}_{part}" in rig.jmap]
        lowest.append(upright[:, joints, 1].min(axis=1))
    standing = np.where(contacts, np.stack(lowest, axis=1), np.inf).min(axis=1)
    standing = standing[np.isfinite(standing)]
    return float(np.median(standing)) if len(standing) else rig.floor


def rest_motion(skeleton: Skeleton) -> Motion:
    """One frame of ``skeleton``'s rest pose."""
    rotations = np.zeros((1, skeleton.n_joints, 4))
    rotations[..., 3] = 1.0
    return Motion(skeleton, rotations, skeleton.offsets[None], 1 / 30)


def _leg(rig: Rig) -> float:
    rest = rig.skeleton.rest_positions()[0]
    total = 0.0
    for side in ("left", "right"):
        hip, knee, ankle = (rest[rig.jmap[f"{side}_{r}"]] for r in ("upper_leg", "lower_leg", "foot"))
        total += float(np.linalg.norm(knee - hip) + np.linalg.norm(ankle - knee))
    return total / 2


def _path_joint(skeleton: Skeleton, hips: int) -> int:
    """The joint that moves the hips: the hips if they have position channels, else the nearest
    joint above them that has."""
    j = hips
    while j >= 0:
        if any(c.endswith("position") for c in skeleton.channels[j]):
            return j
        j = int(skeleton.parents[j])
    raise MocapError(
        f"the target skeleton has no position channels on {skeleton.names[hips]!r} or above it: its hips cannot move"
    )


__all__ = ["Rig", "alignments", "reference_pose", "rest_motion", "stance_level"]
