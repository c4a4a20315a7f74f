"""Retargeting: a motion moved onto another skeleton, bone by bone in world space.

Both skeletons are mapped (:mod:`.jointmap`) and brought to the canonical axes (:mod:`.conventions`).
For every role both maps hold, an alignment ``A_r`` takes the target's rest bone onto the
source's rest bone (the hips and chest, which carry several bones, by a frame: the line across
the hip joints or the shoulders, and the spine; every other joint by the shortest arc from its
bone, the line to the next mapped joint, or for a hand, toe or head the bone into it). The
target joint's world rotation is then the source joint's times ``A_r``: each mapped bone points
where the source's does, so T, A, crouched and Bandai-Namco's rest poses map onto each other,
and A -> B -> A gives back A's world rotations of every joint both maps hold.

Unmapped joints of the target keep their rest rotation (zero-length hip joints, twist bones,
fingers), except the extra segments of the spine and the neck, which take equal shares of the
turn between the mapped joints either end of their chain. The hips' path is scaled by the
ratio of the leg lengths (which also converts the unit), above the source's floor and onto the
target's. With ``plant_feet``, each foot is held still through the source's contacts (the
package's contact detector on the source) with two-bone leg IK, eased in and out over 3 frames.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import quat
from ..errors import MocapError
from ..motion import Motion, Skeleton
from .conventions import AXES, Conventions, read_conventions, to_canonical
from .jointmap import JointMap, find_joint_map

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


class Rig(NamedTuple):
    """A skeleton with what retargeting needs to know about it: its joint map, conventions and
    floor height (along its up axis, file units)."""

    skeleton: Skeleton
    jmap: JointMap
    conventions: Conventions
    floor: float

    @classmethod
    def of(cls, motion: Motion, user_map: dict | None = None, conventions: Conventions | None = None) -> Rig:
        """The rig of ``motion``'s skeleton, its conventions and floor read from its frames."""
        jmap = find_joint_map(motion.skeleton, user_map)
        conventions = conventions or read_conventions(motion, jmap)
        return cls(motion.skeleton, jmap, conventions, _floor(motion, jmap, conventions))


def _floor(motion: Motion, jmap: JointMap, conventions: Conventions) -> float:
    """The floor along the up axis: the 5th percentile of the lowest foot or toe joint."""
    up = np.array(_axis(conventions.up))
    positions = motion.positions()
    joints = [jmap[r] for r in ("left_foot", "right_foot", "left_toes", "right_toes") if r in jmap]
    return float(np.percentile((positions[:, joints] @ up).min(axis=1), 5))


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


def _frame_vectors(rest: np.ndarray, jmap: JointMap, role: str, other: JointMap) -> tuple[np.ndarray, np.ndarray]:
    """(across, along) of the hips or chest: the line across to the left, and up the spine."""
    if role == "hips":
        across = rest[jmap["left_upper_leg"]] - rest[jmap["right_upper_leg"]]
        return across, rest[jmap["chest"]] - rest[jmap["hips"]]
    arm = next((p for p in ("upper_arm", "clavicle") if f"left_{p}" in jmap and f"left_{p}" in other), None)
    if arm is None:
        across = rest[jmap["left_upper_leg"]] - rest[jmap["right_upper_leg"]]
    else:
        across = rest[jmap[f"left_{arm}"]] - rest[jmap[f"right_{arm}"]]
    return across, rest[jmap["head"]] - rest[jmap["chest"]]  # the neck may sit at the chest


def _orthonormal(across: np.ndarray, along: np.ndarray) -> np.ndarray:
    x = across / np.linalg.norm(across)
    y = along - x * (along @ x)
    y = y / np.linalg.norm(y)
    return np.stack([x, y, np.cross(x, y)], axis=1)  # columns


def alignments(source: Rig, target: Rig) -> dict[str, np.ndarray]:
    """Role -> ``A_r``, the rotation (canonical axes) taking the target's rest bone onto the source's."""
    rest_s = quat.rotate(source.conventions.rotation(), source.skeleton.rest_positions()[0])
    rest_t = quat.rotate(target.conventions.rotation(), target.skeleton.rest_positions()[0])
    out = {}
    for role in source.jmap.joints:
        if role not in target.jmap.joints:
            continue
        if role in ("hips", "chest"):
            frame_s = _orthonormal(*_frame_vectors(rest_s, source.jmap, role, target.jmap))
            frame_t = _orthonormal(*_frame_vectors(rest_t, target.jmap, role, source.jmap))
            out[role] = quat.from_matrix(frame_s @ frame_t.T)
        else:
            start, end, _ = _bone(source.jmap, role, target.jmap)
            out[role] = quat.between(
                rest_t[target.jmap[end]] - rest_t[target.jmap[start]],
                rest_s[source.jmap[end]] - rest_s[source.jmap[start]],
            )
    return out


def retarget(
    motion: Motion,
    target: Motion | Skeleton,
    *,
    source_map: dict | None = None,
    target_map: dict | None = None,
    plant_feet: bool = True,
    source_conventions: Conventions | None = None,
    target_conventions: Conventions | None = None,
) -> Motion:
    """``motion`` moved onto ``target``'s skeleton (a :class:`Motion`, whose frames are used only
    to read its conventions and floor, or a bare :class:`Skeleton`, taken as Y up with its floor
    at 0), in the target's own axes and unit, at the source's frame rate (see the module's notes).

    ``source_map``/``target_map``: role -> joint name for roles the names and topology do not
    find (:func:`~expressive_mocap.skeletons.read_joint_map`). ``plant_feet``: hold the feet still
    through the source's contacts.
    """
    if isinstance(target, Skeleton):
        target = rest_motion(target)
    source = Rig.of(motion, source_map, source_conventions)
    goal = Rig.of(target, target_map, target_conventions)
    return retarget_rigs(motion, source, goal, plant_feet=plant_feet)


def retarget_rigs(motion: Motion, source: Rig, goal: Rig, *, plant_feet: bool = True) -> Motion:
    """:func:`retarget` with both rigs known (``source`` must be ``motion``'s skeleton's)."""
    out = _transfer(motion, source, goal)
    if plant_feet:
        from .planting import plant_feet as plant
        from .planting import source_contacts

        contacts = source_contacts(to_canonical(motion, source.conventions), source.jmap)
        positions = motion.positions()
        feet = [source.jmap[f"{side}_foot"] for side in ("left", "right")]
        out = plant(out, goal.jmap, contacts, carried(positions[:, feet], source, goal))
    return out


def rest_motion(skeleton: Skeleton) -> Motion:
    """One frame of ``skeleton``'s rest pose."""
    rotations = np.zeros((1, skeleton.n_joints, 4))
    rotations[..., 3] = 1.0
    return Motion(skeleton, rotations, skeleton.offsets[None], 1 / 30)


def _transfer(motion: Motion, source: Rig, target: Rig) -> Motion:
    turn_s, turn_t = source.conventions.rotation(), target.conventions.rotation()
    world_s, positions_s = motion.fk()
    world_s = quat.mul(quat.mul(turn_s, world_s), quat.conjugate(turn_s))  # canonical axes
    frames = motion.n_frames
    skeleton = target.skeleton
    parents = skeleton.parents
    world = np.empty((frames, skeleton.n_joints, 4))
    aligns = alignments(source, target)
    positions_c = quat.rotate(turn_s, positions_s)
    rest_s = quat.rotate(turn_s, source.skeleton.rest_positions()[0])
    for role, align in aligns.items():
        world[:, target.jmap[role]] = quat.mul(_swing(role, world_s, positions_c, rest_s, source, target), align)
    aligned = {target.jmap[r] for r in aligns}
    shared = _shared_chains(target.jmap, aligned)
    for j in range(skeleton.n_joints):
        if j in aligned:
            continue
        if j in shared:
            top, bottom, share = shared[j]
            turn = quat.mul(quat.conjugate(world[:, top]), world[:, bottom])
            world[:, j] = quat.mul(world[:, top], quat.power(turn, share))
        elif parents[j] < 0:
            world[:, j] = _IDENTITY
        else:
            world[:, j] = world[:, parents[j]]  # held at its rest rotation
    world = quat.mul(quat.mul(quat.conjugate(turn_t), world), turn_t)  # the target's axes
    rotations = world.copy()
    rotations[:, 1:] = quat.mul(quat.conjugate(world[:, parents[1:]]), world[:, 1:])
    translations = np.broadcast_to(skeleton.offsets, (frames, skeleton.n_joints, 3)).copy()
    _place_hips(translations, positions_s, source, target)
    return Motion(skeleton, rotations, translations, motion.frame_time)


def _swing(
    role: str, world_s: np.ndarray, positions_s: np.ndarray, rest_s: np.ndarray, source: Rig, target: Rig
) -> np.ndarray:
    """The source joint's world rotation ``[F, 4]`` for ``role``, swung so that its own bone (or
    for the hips, the line across the hip joints) lies where the source's positions put it: joints
    the map leaves out between two mapped ones (CMU's ``LHipJoint``, a ``Neck1``) may turn in the
    source, and the target holds them at rest."""
    world = world_s[:, source.jmap[role]]
    if role == "hips":
        start, end = "right_upper_leg", "left_upper_leg"
    elif role == "chest":
        return world
    else:
        start, end, own = _bone(source.jmap, role, target.jmap)
        if not own:
            return world
    jmap = source.jmap
    predicted = quat.rotate(world, rest_s[jmap[end]] - rest_s[jmap[start]])
    actual = positions_s[:, jmap[end]] - positions_s[:, jmap[start]]
    return quat.mul(quat.between(predicted, actual), world)


def _shared_chains(jmap: JointMap, aligned: set[int]) -> dict[int, tuple[int, int, float]]:
    """Spine joints between the hips and the chest -> (hips, chest, share of the turn)."""
    chains = [(jmap["hips"], list(jmap.spine))]
    out: dict[int, tuple[int, int, float]] = {}
    for top, chain in chains:
        if top in aligned and chain[-1] in aligned:
            for i, j in enumerate(chain[:-1]):
                if j not in aligned:
                    out[j] = (top, chain[-1], (i + 1) / len(chain))
    return out


def carried(points: np.ndarray, source: Rig, target: Rig) -> np.ndarray:
    """Source world points ``[..., 3]`` carried into the target's world: turned to its axes, and
    scaled by the ratio of the leg lengths from the source's floor onto the target's."""
    up_s = np.array(_axis(source.conventions.up), float)
    canonical = quat.rotate(source.conventions.rotation(), points - up_s * source.floor) * (_leg(target) / _leg(source))
    up_t = np.array(_axis(target.conventions.up), float)
    return quat.rotate(quat.conjugate(target.conventions.rotation()), canonical) + up_t * target.floor


def _place_hips(translations: np.ndarray, positions_s: np.ndarray, source: Rig, target: Rig) -> None:
    """Move the target's path joint so its hips follow the source's (:func:`carried`)."""
    skeleton = target.skeleton
    hips = target.jmap["hips"]
    mover = _path_joint(skeleton, hips)
    placed = carried(positions_s[:, source.jmap["hips"]], source, target)
    translations[:, mover] = skeleton.offsets[mover] + (placed - skeleton.rest_positions()[0][hips])


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


__all__ = ["Rig", "alignments", "carried", "rest_motion", "retarget", "retarget_rigs"]
