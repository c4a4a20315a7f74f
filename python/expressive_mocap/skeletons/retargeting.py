"""Retargeting: a motion moved onto another skeleton, bone by bone in world space.

Both skeletons are mapped (:mod:`.jointmap`) and brought to the canonical axes (:mod:`.conventions`).
Each has a reference pose in which its bones' twists are known (:func:`reference_pose`: the rest,
or Bandai-Namco's average walking pose). For every role both maps hold, an alignment ``A_r`` takes
the target's frame of the role in its reference pose onto the source's (the hips and chest by
the lines across them and up the spine; a limb segment by its bone and the plane its elbow or
knee bends in; other joints by their bone and the body's forward, or up for the feet). The
target joint's world rotation is then the source joint's times ``A_r``: each mapped bone points
where the source's does and faces the same way about itself, and A -> B -> A gives back A's
world rotations of every joint both maps hold.

Unmapped joints of the target keep their reference pose relative to their mapped ancestor
(zero-length hip joints, twist bones, fingers), except the extra segments of the spine and the
neck, which take equal shares of the turn between the mapped joints either end of their chain;
then the lines from the hips to the chest and from the chest to the head are set to the source's
(:mod:`.trunk`).
The hips' path is scaled by the ratio of the leg lengths (which also converts the unit), above
the source's floor and onto the target's, then raised or lowered clip by clip so that the stance
feet stand on the target's floor; feet are aligned by their flat stance (forward along the floor,
up), not by their bones. With ``plant_feet``, each foot is held still through
the source's contacts (the package's contact detector on the source) with two-bone leg IK, eased
in and out over 3 frames.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import ops, quat
from ..errors import MocapError
from ..features import percentiles_by_clip
from ..motion import Motion, Skeleton, spread_frames
from . import twist
from .conventions import AXES, Conventions, read_conventions
from .jointmap import JointMap, find_joint_map
from .trunk import keep_trunk

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
_TWIST_FRAMES = 60  # frames read to tell untrusted twists


class Rig(NamedTuple):
    """A skeleton with what retargeting needs to know about it: its joint map, conventions, floor
    height (along its up axis, file units) and the roles whose rotations its motion twists
    arbitrarily, to be read from the positions instead (:func:`untrusted_twists`; None until a
    motion of it is a source: :meth:`with_twists`)."""

    skeleton: Skeleton
    jmap: JointMap
    conventions: Conventions
    floor: float
    untrusted: frozenset | None = frozenset()

    @classmethod
    def of(
        cls, motion: Motion, user_map: dict | None = None, conventions: Conventions | None = None, kinematics=None
    ) -> Rig:
        """The rig of ``motion``'s skeleton, its conventions and floor read from its frames
        (``kinematics``: ``motion.fk()``, when already known); its untrusted twists are read
        when it is first a source (:meth:`with_twists`)."""
        jmap = find_joint_map(motion.skeleton, user_map)
        conventions = conventions or read_conventions(motion, jmap)
        positions = motion.positions() if kinematics is None else kinematics[1]
        return cls(motion.skeleton, jmap, conventions, _floor_of(positions, jmap, conventions), None)

    def with_twists(self, motion: Motion, kinematics=None) -> Rig:
        """This rig with its untrusted twists read from ``motion`` (a motion of it), unless known."""
        if self.untrusted is not None:
            return self
        return self._replace(untrusted=untrusted_twists(motion, self, kinematics))


def untrusted_twists(motion: Motion, rig: Rig, kinematics=None) -> frozenset:
    """The roles whose twist ``motion``'s rotations set far from what its positions show (a median
    over the frames beyond :func:`~.twist.trusted`, 45 degrees for the hips and chest), such as a
    network's output that turns a thigh 100 degrees about itself and the shin back, or hips and a
    chest whose children all sit at the joint, leaving their rotations free. Real captures stay
    under the bounds (measured: the CMU file and 3,073 of the 3,076 Bandai-Namco clips).
    ``kinematics``: ``motion.fk()``, when already known."""
    return untrusted_twists_many([motion], rig, None if kinematics is None else [kinematics])[0]


def untrusted_twists_many(motions: list[Motion], rig: Rig, kinematics: list | None = None) -> list[frozenset]:
    """:func:`untrusted_twists` of each of ``motions`` (all of ``rig``'s skeleton), each from its
    own frames alone, computed together: one forward kinematics call and one pass of the per-frame
    algebra over every clip's sampled frames, then each clip's medians (an archive's short clips
    took 11 ms each one by one)."""
    picked = [spread_frames(m.n_frames, _TWIST_FRAMES) for m in motions]
    # A median over evenly spread frames: a clip's is as good.
    if kinematics is None:
        world, positions = ops.forward_kinematics(
            np.concatenate([m.rotations[f] for m, f in zip(motions, picked)]),
            np.concatenate([m.translations[f] for m, f in zip(motions, picked)]),
            rig.skeleton.parents,
        )
    else:
        world = np.concatenate([k[0][f] for k, f in zip(kinematics, picked)])
        positions = np.concatenate([k[1][f] for k, f in zip(kinematics, picked)])
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
    from ..demo import bandai_like_skeleton, bandai_standing_pose

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


def _flat_frame(points: np.ndarray, jmap: JointMap, role: str, other: JointMap) -> np.ndarray:
    """:func:`_role_frame`, but for a foot or toes (where both maps hold the toes) the frame a
    foot standing flat has: forward along the floor, up. Each rig's reference pose stands on flat
    feet, however its ankle sits (a flat Bandai-Namco foot points 40 degrees down to the toe
    joint, a CMU one 10): carried bone by bone, a flat foot came out toes-up on another rig."""
    part = _role_of(jmap, role)
    side = role.split("_", 1)[0]
    if part in ("foot", "toes") and f"{side}_toes" in jmap and f"{side}_toes" in other:
        forward = points[jmap[f"{side}_toes"]] - points[jmap[f"{side}_foot"]]
        forward = forward - _UP * np.dot(forward, _UP)
        if np.linalg.norm(forward) > 1e-9:
            return _orthonormal(forward, _UP)
    return _role_frame(points, jmap, role, other)


def alignments(source: Rig, target: Rig) -> dict[str, np.ndarray]:
    """Role -> ``A_r`` (canonical axes), which turns the source joint's world rotation into the
    target's: ``W_t = W_s A_r``. In the two reference poses (:func:`reference_pose`) it takes the
    target's frame of the role onto the source's, so each bone keeps its direction and its twist
    (which way its hinge faces) whatever the two rests are."""
    world_s, points_s = _reference(source)
    world_t, points_t = _reference(target)
    out = {}
    for role in source.jmap.joints:
        if role not in target.jmap.joints:
            continue
        frame_s = _flat_frame(points_s, source.jmap, role, target.jmap)
        frame_t = _flat_frame(points_t, target.jmap, role, source.jmap)
        onto = quat.from_matrix(frame_s @ frame_t.T)
        js, jt = source.jmap[role], target.jmap[role]
        out[role] = quat.mul(quat.mul(quat.conjugate(world_s[js]), onto), world_t[jt])
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


def retarget_rigs(motion: Motion, source: Rig, goal: Rig, *, plant_feet: bool = True, kinematics=None) -> Motion:
    """:func:`retarget` with both rigs known (``source`` must be ``motion``'s skeleton's)."""
    bounds, floors = [0, motion.n_frames], np.array([source.floor])
    return _retarget_frames(motion, bounds, source, goal, floors, plant_feet, kinematics=kinematics)


def retarget_clips(
    motions: list[Motion], goal: Rig, *, plant_feet: bool = True, user_map: dict | None = None
) -> list[tuple[Motion, JointMap]]:
    """Many clips retargeted onto ``goal`` at once, each with the joint map it was read with:
    each clip is what :func:`retarget_rigs` gives for it alone (its own conventions, twists,
    floor and contacts, whatever other clips come with it), but clips that agree on all of them
    (one skeleton, same joints and offsets) are done together, their frames end to end in runs
    of about ``CHUNK_FRAMES``: a fraction of the time for short clips (``preprocess --canonical``)."""
    read: dict[tuple, tuple[Rig, list[int]]] = {}  # clips by skeleton and conventions
    for k, motion in enumerate(motions):
        source = _conventions_rig(motion, user_map)
        c = source.conventions  # all but how sure each guess is and the rate: those change nothing
        key = (_rig_key(source), c.unit, c.metres_per_unit, c.height, c.rest_pose, motion.frame_time)
        read.setdefault(key, (source, []))[1].append(k)
    groups: dict[tuple, tuple[Rig, list[int]]] = {}  # ... and by twists
    for key, (source, members) in read.items():
        for k, untrusted in zip(members, untrusted_twists_many([motions[k] for k in members], source)):
            groups.setdefault((key, untrusted), (source._replace(untrusted=untrusted), []))[1].append(k)
    out: list = [None] * len(motions)
    for source, members in groups.values():
        for run in _runs(members, motions):
            _retarget_run(run, motions, source, goal, plant_feet, out)
    return out


def _conventions_rig(motion: Motion, user_map: dict | None = None) -> Rig:
    """``motion``'s rig as :meth:`Rig.of` reads it from ``motion`` alone, but for its floor (each
    clip's retarget reads its own) and its untrusted twists (read for many clips at once)."""
    jmap = find_joint_map(motion.skeleton, user_map)
    return Rig(motion.skeleton, jmap, read_conventions(motion, jmap), 0.0, None)


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
    kinematics=None,
) -> Motion:
    """The retarget of ``motion``, whose frames are clips end to end (clip ``i`` is frames
    ``bounds[i]`` to ``bounds[i + 1]``, its floor ``floors[i]``, None: read from each clip;
    ``clips`` the clips themselves; ``kinematics``: ``motion.fk()`` when known)."""
    kinematics = motion.fk() if kinematics is None else kinematics
    if floors is None:
        floors = _floors_of(kinematics[1], bounds, source.jmap, source.conventions)
    floor = np.repeat(floors, np.diff(bounds))  # per frame
    world, positions = kinematics
    source = source.with_twists(motion, kinematics)
    out = _transfer(motion, source, goal, (_trusted(world, positions, source), positions), floor)
    into_goal = quat.mul(quat.conjugate(goal.conventions.rotation()), source.conventions.rotation())
    out = keep_trunk(out, positions, source.jmap, goal.jmap, into_goal)
    from .planting import plant_feet as plant
    from .planting import source_contacts

    turn = source.conventions.rotation()
    upright = positions if np.array_equal(turn, [0.0, 0.0, 0.0, 1.0]) else quat.rotate(turn, positions)
    contacts = source_contacts(clips or [motion], source, upright, bounds)
    out, lift = _stand_on_floor(out, contacts, goal, bounds)
    if plant_feet:
        feet = [source.jmap[f"{side}_foot"] for side in ("left", "right")]
        ankles = carried(positions[:, feet], source, goal, floor) + lift[:, None, :]
        out = plant(out, goal.jmap, contacts, ankles, starts=bounds)
    return out


def _stand_on_floor(out: Motion, contacts: np.ndarray, goal: Rig, bounds) -> tuple[Motion, np.ndarray]:
    """``out`` with its path raised or lowered, clip by clip, so that its stance feet (the lower
    of each foot's ankle and toe joints through the source's ``contacts``, median over the clip)
    stand on the target's floor, and that lift ``[F, 3]`` (target axes). The leg lengths' ratio
    places the hips, but rigs set their ankles at different heights above their soles: a walk of
    a rig with low-set ankles stood 4-5 cm above the Bandai-Namco floor, one with high-set ankles
    sank."""
    jmap, skeleton = goal.jmap, goal.skeleton
    up = np.array(_axis(goal.conventions.up), float)
    heights = out.positions() @ up  # [F, J]
    lowest = []
    for side in ("left", "right"):
        joints = [jmap[f"{side}_{part}"] for part in ("foot", "toes") if f"{side}_{part}" in jmap]
        lowest.append(heights[:, joints].min(axis=1))
    standing = np.where(contacts, np.stack(lowest, axis=1), np.inf).min(axis=1)  # [F]
    lift = np.zeros(out.n_frames)
    for a, b in zip(bounds[:-1], bounds[1:]):
        stance = standing[a:b][np.isfinite(standing[a:b])]
        if len(stance):
            lift[a:b] = goal.floor - np.median(stance)
    translations = out.translations.copy()
    translations[:, _path_joint(skeleton, jmap["hips"])] += lift[:, None] * up
    return Motion(skeleton, out.rotations, translations, out.frame_time), lift[:, None] * up


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
    return (skeleton.content_key, turn, tuple(jmap.joints.items()))


def _plan(source: Rig, target: Rig) -> ops.TransferPlan:
    """The plan of a pair, kept for the pairs met last: an archive's clips share a few skeletons."""
    key = (_rig_key(source), _rig_key(target))
    plan = _PLANS.get(key)
    if plan is None:
        if len(_PLANS) >= _PLANS_KEPT:
            _PLANS.pop(next(iter(_PLANS)))
        plan = _PLANS[key] = _new_plan(source, target)
    return plan


class _OwnFrames(NamedTuple):
    """A rig's role frames in its reference pose, in its joints' rest terms: per role whose twist
    positions can tell, (role, joint, the bone and the second axis of its frame); per hips and
    chest, (role, joint, the rotation taking the role's frame onto the joint's world rotation)."""

    readable: list[tuple[str, int, np.ndarray, np.ndarray]]
    framed: list[tuple[str, int, np.ndarray]]


_FRAMES: dict = {}


def _own_frames(rig: Rig) -> _OwnFrames:
    """The rig's :class:`_OwnFrames`, kept for the rigs met last."""
    key = _rig_key(rig)
    if key not in _FRAMES:
        if len(_FRAMES) >= _PLANS_KEPT:
            _FRAMES.pop(next(iter(_FRAMES)))
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
        _FRAMES[key] = _OwnFrames(readable, framed)
    return _FRAMES[key]


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
    frames, skeleton = motion.n_frames, target.skeleton
    translations = np.broadcast_to(skeleton.offsets, (frames, skeleton.n_joints, 3)).copy()
    _place_hips(translations, positions_s, source, target, floor)
    return Motion(skeleton, rotations, translations, motion.frame_time)


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


__all__ = [
    "Rig",
    "alignments",
    "carried",
    "reference_pose",
    "rest_motion",
    "retarget",
    "untrusted_twists",
    "retarget_clips",
    "retarget_rigs",
]
