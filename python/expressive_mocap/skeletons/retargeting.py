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

from .. import ops, quat
from ..errors import MocapError
from ..features import percentiles_by_clip
from ..motion import Motion, Skeleton
from .conventions import AXES, Conventions, read_conventions
from .jointmap import JointMap, find_joint_map

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
    roles = [role for role in source.jmap.joints if role in target.jmap.joints]
    out = {}
    for role in ("hips", "chest"):
        frame_s = _orthonormal(*_frame_vectors(rest_s, source.jmap, role, target.jmap))
        frame_t = _orthonormal(*_frame_vectors(rest_t, target.jmap, role, source.jmap))
        out[role] = quat.from_matrix(frame_s @ frame_t.T)
    bones = [r for r in roles if r not in out]
    ends = [_bone(source.jmap, role, target.jmap)[:2] for role in bones]
    lines_t = np.array([rest_t[target.jmap[e]] - rest_t[target.jmap[s]] for s, e in ends]).reshape(-1, 3)
    lines_s = np.array([rest_s[source.jmap[e]] - rest_s[source.jmap[s]] for s, e in ends]).reshape(-1, 3)
    out.update(zip(bones, quat.between(lines_t, lines_s)))  # one call for every bone
    return {role: out[role] for role in roles}


def retarget(
    motion: Motion,
    target: Motion | Skeleton,
    *,
    source_map: dict | None = None,
    target_map: dict | None = None,
    plant_feet: bool = True,
    source_conventions: Conventions | None = None,
    target_conventions: Conventions | None = None,
    fps: float | None = None,
) -> Motion:
    """``motion`` moved onto ``target``'s skeleton (a :class:`Motion`, whose frames are used only
    to read its conventions and floor, or a bare :class:`Skeleton`, taken as Y up with its floor
    at 0), in the target's own axes and unit, at the source's frame rate (see the module's notes).

    ``source_map``/``target_map``: role -> joint name for roles the names and topology do not
    find (:func:`~expressive_mocap.skeletons.read_joint_map`). ``plant_feet``: hold the feet still
    through the source's contacts. ``fps``: resample the result to this frame rate (the
    target file's own, say) instead of keeping the source's.
    """
    if isinstance(target, Skeleton):
        target = rest_motion(target)
    source = Rig.of(motion, source_map, source_conventions)
    goal = Rig.of(target, target_map, target_conventions)
    out = retarget_rigs(motion, source, goal, plant_feet=plant_feet)
    return out if fps is None else out.resample(fps=fps)


def retarget_rigs(motion: Motion, source: Rig, goal: Rig, *, plant_feet: bool = True) -> Motion:
    """:func:`retarget` with both rigs known (``source`` must be ``motion``'s skeleton's)."""
    return _retarget_frames(motion, [0, motion.n_frames], source, goal, np.array([source.floor]), plant_feet)


def retarget_clips(
    motions: list[Motion], goal: Rig, *, plant_feet: bool = True, user_map: dict | None = None
) -> list[tuple[Motion, JointMap]]:
    """Many clips retargeted onto ``goal`` at once, each with the joint map it was read with:
    clips of one skeleton (same joints and offsets) are done together, their frames end to end
    in runs of about ``CHUNK_FRAMES``, each with its own floor and contacts; the conventions are
    read from the first clip of each skeleton. What :func:`retarget_rigs` gives clip by clip, in
    a fraction of the time for short clips (``preprocess --canonical``)."""
    groups: dict[tuple, list[int]] = {}
    for k, motion in enumerate(motions):
        skeleton = motion.skeleton
        key = (skeleton.names, skeleton.parents.tobytes(), skeleton.offsets.tobytes(), skeleton.channels)
        groups.setdefault(key, []).append(k)
    out: list = [None] * len(motions)
    for members in groups.values():
        source = Rig.of(motions[members[0]], user_map)
        for run in _runs(members, motions):
            _retarget_run(run, motions, source, goal, plant_feet, out)
    return out


# Frames retargeted together: enough that NumPy's work per call outweighs its overhead, few
# enough that the intermediate arrays stay in the allocator's reused memory and the caches
# (a whole batch at once spent a quarter of its time in fresh pages).
CHUNK_FRAMES = 4096


def _runs(members: list[int], motions: list[Motion]) -> list[list[int]]:
    """``members`` cut into runs of whole clips of about :data:`CHUNK_FRAMES` frames."""
    runs: list[list[int]] = [[]]
    frames = 0
    for k in members:
        if frames >= CHUNK_FRAMES:
            runs.append([])
            frames = 0
        runs[-1].append(k)
        frames += motions[k].n_frames
    return runs


def _retarget_run(run: list[int], motions: list[Motion], source: Rig, goal: Rig, plant_feet: bool, out: list) -> None:
    """The clips ``run`` of ``motions`` (one skeleton, ``source``'s) retargeted together, into ``out``."""
    members = run
    if True:
        clips = [motions[k] for k in members]
        bounds = np.cumsum([0] + [c.n_frames for c in clips])
        together = Motion(
            clips[0].skeleton,
            np.concatenate([c.rotations for c in clips]),
            np.concatenate([c.translations for c in clips]),
            clips[0].frame_time,
        )
        moved = _retarget_frames(together, bounds, source, goal, None, plant_feet, clips)
        for k, a, b, clip in zip(members, bounds[:-1], bounds[1:], clips):
            out[k] = (
                Motion(goal.skeleton, moved.rotations[a:b], moved.translations[a:b], clip.frame_time),
                source.jmap,
            )


def _retarget_frames(
    motion: Motion,
    bounds,
    source: Rig,
    goal: Rig,
    floors: np.ndarray | None,
    plant_feet: bool,
    clips: list[Motion] | None = None,
) -> Motion:
    """The retarget of ``motion``, whose frames are clips end to end (clip ``i`` is frames
    ``bounds[i]`` to ``bounds[i + 1]``, its floor ``floors[i]``, None: read from each clip;
    ``clips`` the clips themselves)."""
    kinematics = motion.fk()
    if floors is None:
        floors = _floors_of(kinematics[1], bounds, source.jmap, source.conventions)
    floor = np.repeat(floors, np.diff(bounds))  # per frame
    out = _transfer(motion, source, goal, kinematics, floor)
    if plant_feet:
        from .planting import plant_feet as plant
        from .planting import source_contacts

        positions = kinematics[1]
        turn = source.conventions.rotation()
        upright = positions if np.array_equal(turn, [0.0, 0.0, 0.0, 1.0]) else quat.rotate(turn, positions)
        contacts = source_contacts(clips or [motion], source, upright, bounds)
        feet = [source.jmap[f"{side}_foot"] for side in ("left", "right")]
        out = plant(out, goal.jmap, contacts, carried(positions[:, feet], source, goal, floor), starts=bounds)
    return out


def rest_motion(skeleton: Skeleton) -> Motion:
    """One frame of ``skeleton``'s rest pose."""
    rotations = np.zeros((1, skeleton.n_joints, 4))
    rotations[..., 3] = 1.0
    return Motion(skeleton, rotations, skeleton.offsets[None], 1 / 30)


_PLANS: dict = {}
_PLANS_KEPT = 64


def _rig_key(rig: Rig) -> tuple:
    skeleton, jmap = rig.skeleton, rig.jmap
    turn = rig.conventions.rotation().tobytes()
    return (skeleton.names, skeleton.parents.tobytes(), skeleton.offsets.tobytes(), turn, tuple(jmap.joints.items()))


def _plan(source: Rig, target: Rig) -> ops.TransferPlan:
    """The plan of a pair, kept for the pairs met last: an archive's clips share a few skeletons."""
    key = (_rig_key(source), _rig_key(target))
    plan = _PLANS.get(key)
    if plan is None:
        if len(_PLANS) >= _PLANS_KEPT:
            _PLANS.pop(next(iter(_PLANS)))
        plan = _PLANS[key] = _new_plan(source, target)
    return plan


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
        np.tile(_IDENTITY, (len(parents), 1)),  # the reference pose: the rest, no joint turned
        parents,
        source.conventions.rotation(),
        target.conventions.rotation(),
    )


def _transfer(
    motion: Motion, source: Rig, target: Rig, kinematics: tuple[np.ndarray, np.ndarray], floor: np.ndarray
) -> Motion:
    """The target's motion (see the module's notes) from the source's world rotations and
    positions, ``kinematics``, and its floor in each frame."""
    world_s, positions_s = kinematics
    rotations = ops.retarget_transfer(world_s, positions_s, _plan(source, target))
    frames, skeleton = motion.n_frames, target.skeleton
    translations = np.broadcast_to(skeleton.offsets, (frames, skeleton.n_joints, 3)).copy()
    _place_hips(translations, positions_s, source, target, floor)
    return Motion(skeleton, rotations, translations, motion.frame_time)


def _shared_chains(jmap: JointMap, aligned: set[int]) -> dict[int, tuple[int, int, float]]:
    """Spine joints between the hips and the chest -> (hips, chest, share of the turn)."""
    out: dict[int, tuple[int, int, float]] = {}
    chain = list(jmap.spine)
    if jmap["hips"] in aligned and chain[-1] in aligned:
        for i, j in enumerate(chain[:-1]):
            if j not in aligned:
                out[j] = (jmap["hips"], chain[-1], (i + 1) / len(chain))
    return out


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


__all__ = ["Rig", "alignments", "carried", "rest_motion", "retarget", "retarget_clips", "retarget_rigs"]
