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

import numpy as np

from ..body.body import Body
from ..body.conventions import Conventions, read_conventions
from ..body.jointmap import JointMap
from ..body.take import Take
from ..motion import Motion, Skeleton
from ..rotations import quat
from .rig import Rig, _axis, _floors_of, _path_joint, rest_motion, stance_level
from .transfer import _rig_key, _transfer, _trusted, carried, untrusted_twists_many, with_twists
from .trunk import keep_trunk


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
    find (:func:`~expressive_mocap.body.read_joint_map`). ``plant_feet``: hold the feet still
    through the source's contacts. ``fps``: resample the result to this frame rate (the
    target file's own, say) instead of keeping the source's.
    """
    take = Take.of(motion)
    source, goal = rigs_for(take, target, source_map, target_map, source_conventions, target_conventions)
    out = retarget_rigs(take, source, goal, plant_feet=plant_feet)
    return out if fps is None else out.resample(fps=fps)


def rigs_for(
    motion: Motion | Take,
    target: Motion | Take | Skeleton,
    source_map: dict | None = None,
    target_map: dict | None = None,
    source_conventions: Conventions | None = None,
    target_conventions: Conventions | None = None,
) -> tuple[Rig, Rig]:
    """The source's and the target's :class:`Rig` that :func:`retarget` moves ``motion`` with
    (arguments as there): the target's stance level read from its own frames."""
    target_take = Take.of(rest_motion(target) if isinstance(target, Skeleton) else target)
    goal = Rig.of(target_take, target_map, target_conventions)
    return Rig.of(motion, source_map, source_conventions), goal._replace(stance=stance_level(goal, target_take))


def retarget_rigs(motion: Motion | Take, source: Rig, goal: Rig, *, plant_feet: bool = True) -> Motion:
    """:func:`retarget` with both rigs known (``source`` must be ``motion``'s skeleton's)."""
    take = Take.of(motion)
    bounds, floors = [0, take.motion.n_frames], np.array([source.floor])
    return _retarget_frames(take, bounds, source, goal, floors, plant_feet)


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
    jmap = Body.of(motion.skeleton, user_map).joint_map
    return Rig(motion.skeleton, jmap, read_conventions(motion, jmap), 0.0, None, user_map)


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
    clips = [motions[k] for k in run]
    bounds = np.cumsum([0] + [c.n_frames for c in clips])
    together = Motion(
        clips[0].skeleton,
        np.concatenate([c.rotations for c in clips]),
        np.concatenate([c.translations for c in clips]),
        clips[0].frame_time,
    )
    moved = _retarget_frames(Take(together), bounds, source, goal, None, plant_feet, clips)
    for k, a, b, clip in zip(run, bounds[:-1], bounds[1:], clips):
        out[k] = (
            Motion(goal.skeleton, moved.rotations[a:b], moved.translations[a:b], clip.frame_time),
            source.jmap,
        )


def _retarget_frames(
    take: Take,
    bounds,
    source: Rig,
    goal: Rig,
    floors: np.ndarray | None,
    plant_feet: bool,
    clips: list[Motion] | None = None,
) -> Motion:
    """The retarget of ``take``'s motion, whose frames are clips end to end (clip ``i`` is frames
    ``bounds[i]`` to ``bounds[i + 1]``, its floor ``floors[i]``, None: read from each clip;
    ``clips`` the clips themselves)."""
    motion = take.motion
    world, positions = take.fk
    if floors is None:
        floors = _floors_of(positions, bounds, source.jmap, source.conventions)
    floor = np.repeat(floors, np.diff(bounds))  # per frame
    source = with_twists(source, take)
    out = _transfer(motion, source, goal, (_trusted(world, positions, source), positions), floor)
    into_goal = quat.mul(quat.conjugate(goal.conventions.rotation()), source.conventions.rotation())
    out = keep_trunk(out, positions, source.jmap, goal.jmap, into_goal)
    from .planting import plant_feet as plant
    from .planting import source_contacts

    turn = source.conventions.rotation()
    upright = positions if np.array_equal(turn, [0.0, 0.0, 0.0, 1.0]) else quat.rotate(turn, positions)
    contacts = source_contacts(clips or [motion], source, upright, bounds)
    placed = out.positions()  # before the lift, which moves every joint alike
    out, lift = _stand_on_floor(out, placed, contacts, goal, bounds)
    if plant_feet:
        ankles = _ankle_guides(placed, out.frame_time, positions, source, goal, floor, bounds) + lift[:, None, :]
        out = plant(out, goal.jmap, contacts, ankles, starts=bounds)
    return out


STILL = 0.05  # actor heights a second: slower, a joint is standing still


def _ankle_guides(
    placed: np.ndarray, frame_time: float, positions: np.ndarray, source: Rig, goal: Rig, floor: np.ndarray, bounds
) -> np.ndarray:
    """Where each of the target's ankles ``[F, 2, 3]`` should move during a contact (target
    world, before the lift; ``placed``: the retarget's joint positions, ``positions``: the
    source's): the source's ankle carried over, or, as the foot rolls onto its toe,
    the ankle that puts the target's toe where the source's toe is carried (the target's foot
    keeps its own orientation), weighted per frame by how much faster the source's ankle moves
    than its toe (the toe is then the foot's pivot; a joint under STILL stands). A rig whose
    foot points steeper or flatter than the source's otherwise slid its toe when a raised heel
    turned the foot about the toe (a walk on the balls of the feet: toes at 1.3x the source's
    speed). Clip by clip (``bounds``)."""
    feet = [source.jmap[f"{side}_foot"] for side in ("left", "right")]
    ankles = carried(positions[:, feet], source, goal, floor)
    sides = ("left_toes", "right_toes")
    if not all(r in source.jmap and r in goal.jmap for r in sides) or len(positions) < 2:
        return ankles
    toes, goal_toes = [source.jmap[r] for r in sides], [goal.jmap[r] for r in sides]
    source_toes = carried(positions[:, toes], source, goal, floor)
    goal_feet = [goal.jmap[f"{side}_foot"] for side in ("left", "right")]
    reach = placed[:, goal_toes] - placed[:, goal_feet]  # [F, 2, 3]: the target's foot, ankle to toe
    by_toe = source_toes - reach
    # Blend the two paths' steps, not the paths: they stand apart by the rigs' different feet.
    heel_step, toe_step = np.diff(ankles, axis=0), np.diff(by_toe, axis=0)
    heel = np.linalg.norm(heel_step, axis=-1)
    toe = np.linalg.norm(np.diff(source_toes, axis=0), axis=-1)
    still = STILL * goal.body.actor_height * frame_time  # a step this short is standing
    toe_pivot = np.clip((heel - toe) / (heel + toe + still), 0.0, 1.0)[..., None]
    steps = (1.0 - toe_pivot) * heel_step + toe_pivot * toe_step
    guides = ankles.copy()
    for a, b in zip(bounds[:-1], bounds[1:]):
        guides[a + 1 : b] = ankles[a] + np.cumsum(steps[a : b - 1], axis=0)
    return guides


def _stand_on_floor(
    out: Motion, placed: np.ndarray, contacts: np.ndarray, goal: Rig, bounds
) -> tuple[Motion, np.ndarray]:
    """``out`` (its joint positions ``placed``) with its path raised or lowered, clip by clip, so
    that its stance feet (the lower of each foot's ankle and toe joints through the source's
    ``contacts``, median over the clip) stand where the target's own do
    (:func:`~.rig.stance_level`; else on its floor), and that lift ``[F, 3]`` (target axes). The
    leg lengths' ratio places the hips, but rigs set their ankles at different heights above
    their soles: a walk of a rig with low-set ankles stood 4-5 cm above the Bandai-Namco floor,
    one with high-set ankles sank."""
    jmap, skeleton = goal.jmap, goal.skeleton
    up = np.array(_axis(goal.conventions.up), float)
    heights = placed @ up  # [F, J]
    lowest = []
    for side in ("left", "right"):
        joints = [jmap[f"{side}_{part}"] for part in ("foot", "toes") if f"{side}_{part}" in jmap]
        lowest.append(heights[:, joints].min(axis=1))
    standing = np.where(contacts, np.stack(lowest, axis=1), np.inf).min(axis=1)  # [F]
    lift = np.zeros(out.n_frames)
    for a, b in zip(bounds[:-1], bounds[1:]):
        stance = standing[a:b][np.isfinite(standing[a:b])]
        if len(stance):
            lift[a:b] = (goal.floor if goal.stance is None else goal.stance) - np.median(stance)
    translations = out.translations.copy()
    translations[:, _path_joint(skeleton, jmap["hips"])] += lift[:, None] * up
    return Motion(skeleton, out.rotations, translations, out.frame_time), lift[:, None] * up


__all__ = ["CHUNK_FRAMES", "retarget", "retarget_clips", "retarget_rigs", "rigs_for"]
