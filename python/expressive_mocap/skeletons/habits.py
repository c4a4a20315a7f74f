"""How a rig habitually holds its limbs, hips and stance feet, read from its own motion, and a
motion given those habits (:func:`~.fit.fit_positions` gives them to positions fitted onto a rig).

Joint positions show where a limb bends (:func:`~.twist.facing`), not how a rig's rotations twist
its bones about that: every rig sets its own elbow and knee axes. The CMU skeletons' elbows bend
about an axis 28-32 degrees off the T-pose's, so their upper arms and forearms sit twisted that far
from the plane the elbow bends in, clip after clip (within 0.4-2.2 degrees over the frames).
A motion fitted to positions faces that plane exactly; given the target rig's own motion, its
limbs are turned about themselves by the difference, so it twists them as its own captures do.
Each turned joint's children keep their world rotations: no position moves.

Likewise the hips (:func:`hips_habit`): a CMU skeleton's pelvis sits 16 degrees from the frame of
its hip joints and the line up its spine, as its lower back bends; a T-pose rest does not show it.
And the feet (:func:`stance_pitch`): a CMU foot stands with its ankle-to-toe line 15.6 degrees
down, its rest's 10.5 (:func:`standing_as` gives both, and stands the body on its feet again).
"""

from __future__ import annotations

import numpy as np

from .. import ops
from ..body.take import Take
from ..motion import Motion, spread_frames
from ..rotations import quat
from . import twist
from .rig import Rig, _axis

HABITUAL = ("upper_arm", "forearm", "upper_leg", "lower_leg")  # the limb segments turned
_SAMPLED = 128  # frames a habit is read from, spread over the clip (256 read the same within 0.3 degrees)
_TELLING = 0.1  # the least share of frames that tell a limb's plane for its habit to be read
# The least turn of the hips worth giving: the fit's line up the spine sits 0.5-2.5 degrees from
# the capture's own where the fit already matched it (the Bandai-Namco, m21 and CMU 131 clips),
# and turning by that much moved their joints 0.1-0.2 cm further off; a CMU 01_01 fit needs 16.
HIPS_TURN_LEAST = np.radians(5.0)


def habits(motion: Motion | Take, rig: Rig) -> dict[int, float]:
    """Per joint of the :data:`HABITUAL` parts with one child, the median angle (radians, about
    its bone) from where ``motion``'s rotations put its second axis to where its positions say
    it faces, over the frames that tell (:func:`~.twist.telling`); none where too few tell."""
    return _habits(*_sampled_fk(motion, rig), rig)


def _sampled_fk(motion: Motion | Take, rig: Rig) -> tuple[np.ndarray, np.ndarray]:
    """World rotations and positions of ``motion``'s frames spread over the clip (a habit's median
    over evenly spread frames is as good as over all), from its take's when already computed."""
    take = Take.of(motion)
    picked = spread_frames(take.motion.n_frames, _SAMPLED)
    known = take.fk_if_computed
    if known is not None:
        return known[0][picked], known[1][picked]
    return ops.forward_kinematics(take.motion.rotations[picked], take.motion.translations[picked], rig.skeleton.parents)


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
    take = Take.of(motion)
    world, positions = take.fk
    have = habits(take, rig)  # from the frames just computed
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
        world[:, joint] = quat.mul(quat.exp(bone * angle), world[:, joint])
        touched.update((joint, child))
    local = motion.rotations.copy()
    for j in sorted(touched):  # a turned joint and its child: their rotations under their parents'
        local[:, j] = quat.normalize(quat.mul(quat.conjugate(world[:, parents[j]]), world[:, j]))
    return Motion(motion.skeleton, local, motion.translations, motion.frame_time)


def hips_habit(motion: Motion | Take, rig: Rig) -> np.ndarray:
    """How the hips joint of ``rig`` sits against the frame its positions show (the line across
    the hip joints, the line up the spine to the chest): the mean rotation ``[4]`` (canonical
    axes) from that frame, as the rig's reference pose relates them, to the joint's rotation, over
    ``motion``'s frames. A CMU skeleton's sits 16 degrees from it: its lower back bends that much."""
    return _hips_habit(*_sampled_fk(motion, rig), rig)


def _hips_habit(world: np.ndarray, positions: np.ndarray, rig: Rig) -> np.ndarray:
    from .rig import _frame_vectors, _orthonormal
    from .transfer import _own_frames, _turned

    turn = rig.conventions.rotation()
    world, points = _turned(turn, world), quat.rotate(turn, positions)
    joint, from_frame = next((j, f) for role, j, f in _own_frames(rig).framed if role == "hips")
    seen = quat.mul(quat.from_matrix(_orthonormal(*_frame_vectors(points, rig.jmap, "hips", rig.jmap))), from_frame)
    return quat.mean_rotation(quat.mul(quat.conjugate(seen), world[:, joint]))


def with_hips_habit(motion: Motion, rig: Rig, wanted: np.ndarray) -> Motion:
    """``motion`` (of ``rig``) with its hips joint turned so that it sits against the frame of
    its positions as ``wanted`` (:func:`hips_habit` of the rig's own motion) says, about the
    joint the spine leaves it from: the spine and all above it keep their places and rotations,
    the legs (their joints' world rotations kept) move with the pelvis."""
    parents, hips = rig.skeleton.parents, rig.jmap["hips"]
    take = Take.of(motion)
    world, positions = take.fk
    turn = rig.conventions.rotation()
    have = hips_habit(take, rig)  # from the frames just computed
    # The turn on the right of the joint's rotation, from canonical axes to the file's.
    correction = quat.mul(quat.mul(quat.conjugate(turn), quat.mul(quat.conjugate(have), wanted)), turn)
    if quat.angle(correction) < HIPS_TURN_LEAST:
        return motion
    spine_child = _child_towards(parents, hips, rig.jmap["chest"])
    pivot = positions[:, spine_child] if spine_child >= 0 else positions[:, hips]
    new = quat.mul(world[:, hips], correction)
    turned = quat.mul(new, quat.conjugate(world[:, hips]))  # the same turn, in world axes
    place = pivot + quat.rotate(turned, positions[:, hips] - pivot)
    local, translations = motion.rotations.copy(), motion.translations.copy()
    above = world[:, parents[hips]] if hips else np.broadcast_to(np.array([0.0, 0.0, 0.0, 1.0]), new.shape)
    local[:, hips] = quat.normalize(quat.mul(quat.conjugate(above), new))
    translations[:, hips] += quat.rotate(quat.conjugate(above), place - positions[:, hips])
    mapped = set(rig.jmap.joints.values()) | set(rig.jmap.spine)
    for child in np.flatnonzero(parents == hips):
        if child == spine_child or child in mapped:  # keeps its world rotation
            local[:, child] = quat.normalize(quat.mul(quat.conjugate(new), world[:, child]))
        else:  # a joint of the pelvis (CMU's hip joints' parents): turns with it, its children not
            moved = quat.mul(new, motion.rotations[:, child])
            for grandchild in np.flatnonzero(parents == child):
                local[:, grandchild] = quat.normalize(quat.mul(quat.conjugate(moved), world[:, grandchild]))
    return Motion(motion.skeleton, local, translations, motion.frame_time)


def _child_towards(parents: np.ndarray, joint: int, descendant: int) -> int:
    """The child of ``joint`` on the path down to ``descendant`` (-1: not below it)."""
    j = descendant
    while j >= 0 and parents[j] != joint:
        j = int(parents[j])
    return j


def stance_pitch(motion: Motion | Take, rig: Rig) -> dict[str, float]:
    """Per side with toes, the median pitch (radians, up positive) of the line from the ankle to
    the toe joint over the frames ``motion``'s foot stands (its contacts): how the rig's foot bone
    sits on the floor. A CMU skeleton's stands at -15.6 degrees, its rest's at -10.5: retargeting
    stands a foot as its rest does, so a fit onto it lifted the toes 5 degrees."""
    from ..body.contacts import foot_contacts

    take = Take.of(motion)  # its forward kinematics and contacts kept for the next reader
    contacts = foot_contacts(take)
    out = {}
    for s, side in enumerate(("left", "right")):
        if f"{side}_toes" not in rig.jmap or contacts[:, s].sum() < 3:
            continue
        standing = take.positions[contacts[:, s]]
        line = quat.rotate(
            rig.conventions.rotation(), standing[:, rig.jmap[f"{side}_toes"]] - standing[:, rig.jmap[f"{side}_foot"]]
        )
        out[side] = float(np.median(np.arctan2(line[:, 1], np.hypot(line[:, 0], line[:, 2]))))
    return out


def with_stance_pitch(motion: Motion, rig: Rig, wanted: dict[str, float]) -> Motion:
    """``motion`` (of ``rig``) with each foot of ``wanted`` (:func:`stance_pitch` of the rig's own
    motion) pitched about its ankle, in every frame, by what makes its stance pitch the wanted
    one; the toes turn with it, the ankles stay."""
    take = Take.of(motion)
    have = stance_pitch(take, rig)
    turns = {side: wanted[side] - have[side] for side in wanted if side in have}
    turns = {side: angle for side, angle in turns.items() if abs(angle) > np.radians(0.5)}
    if not turns:
        return motion
    parents = rig.skeleton.parents
    world, positions = take.fk
    up = np.array(_axis(rig.conventions.up), float)
    local = motion.rotations.copy()
    for side, angle in turns.items():
        foot, toes = rig.jmap[f"{side}_foot"], rig.jmap[f"{side}_toes"]
        line = positions[:, toes] - positions[:, foot]
        across = np.cross(line, up)  # pitching up is a turn about it
        across /= np.maximum(np.linalg.norm(across, axis=-1, keepdims=True), 1e-12)
        turned = quat.mul(quat.exp(across * angle), world[:, foot])
        local[:, foot] = quat.normalize(quat.mul(quat.conjugate(world[:, parents[foot]]), turned))
    return Motion(motion.skeleton, local, motion.translations, motion.frame_time)


def standing_as(motion: Motion, rig: Rig, own: Motion | Take, plant: bool = True) -> Motion:
    """``motion`` (of ``rig``, retargeted there, its feet planted if ``plant``) with the hips and
    stance feet the rig's ``own`` motion shows (:func:`hips_habit`, :func:`stance_pitch`), stood
    where the rig's stance feet stand (as retargeting stands them), and its stance ankles planted
    again: the legs moved with the pelvis, and should stay as steady as they were planted."""
    from ..body.contacts import foot_contacts
    from .planting import plant_feet
    from .retargeting import _stand_on_floor

    held = with_stance_pitch(with_hips_habit(motion, rig, hips_habit(own, rig)), rig, stance_pitch(own, rig))
    if held is motion:  # the rig's hips and feet sit so already: nothing to stand or plant again
        return motion
    pitched = Take.of(held)
    contacts = foot_contacts(pitched)
    out = _stand_on_floor(held, pitched.positions, contacts, rig, [0, motion.n_frames])[0]
    if not plant:
        return out
    planted = Take.of(motion).positions[:, [rig.jmap["left_foot"], rig.jmap["right_foot"]]]
    return plant_feet(out, rig.jmap, contacts, planted)


__all__ = [
    "HABITUAL",
    "habits",
    "hips_habit",
    "stance_pitch",
    "standing_as",
    "with_habits",
    "with_hips_habit",
    "with_stance_pitch",
]
