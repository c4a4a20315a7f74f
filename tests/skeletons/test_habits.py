"""A rig's habits (:mod:`expressive_mocap.skeletons.habits`), on the procedural walk and synthetic
rigs (no data needed): limbs twisted about their bones by fixed angles, as a rig with other elbow
and knee axes holds them, lend those twists to the untwisted walk; hips turned keep the upper
body; stance feet pitched keep their ankles."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from expressive_mocap.procedural import walk_and_wave
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons.habits import (
    habits,
    hips_habit,
    stance_pitch,
    with_habits,
    with_hips_habit,
    with_stance_pitch,
)
from expressive_mocap.skeletons.retargeting import rigs_for
from expressive_mocap.skeletons.synthetic import synthetic_walk

TWISTS = {"left_upper_arm": 30.0, "left_forearm": 30.0, "right_upper_arm": -25.0, "right_lower_leg": 12.0}


def twisted(motion, rig, degrees: dict[str, float]):
    """``motion`` with each role's joint turned about its bone by fixed ``degrees``, its child's
    world rotation kept (what :func:`with_habits` does, written here independently: by world
    rotations of the whole skeleton)."""
    world, positions = motion.fk()
    parents = motion.skeleton.parents
    for role, angle in degrees.items():
        j = rig.jmap[role]
        child = int(np.flatnonzero(parents == j)[0])
        bone = positions[:, child] - positions[:, j]
        bone /= np.linalg.norm(bone, axis=-1, keepdims=True)
        half = np.radians(angle) / 2
        about = np.concatenate([bone * np.sin(half), np.full((len(bone), 1), np.cos(half))], axis=-1)
        world[:, j] = quat.mul(about, world[:, j])
    local = world.copy()
    local[:, 1:] = quat.mul(quat.conjugate(world[:, parents[1:]]), world[:, 1:])
    return type(motion)(motion.skeleton, quat.normalize(local), motion.translations, motion.frame_time)


@pytest.fixture(scope="module")
def walk_and_rig():
    walk, _ = walk_and_wave()
    _, rig = rigs_for(walk, walk)
    return walk, rig


def test_habits_are_read_and_given(walk_and_rig):
    walk, rig = walk_and_rig
    own = habits(walk, rig)
    other = twisted(walk, rig, TWISTS)
    theirs = habits(other, rig)
    for role, angle in TWISTS.items():
        j = rig.jmap[role]
        # the twisted rig's second axes sit ``angle`` further round: the facing that far back
        assert np.degrees(own[j] - theirs[j]) == pytest.approx(angle, abs=0.5), role
    given = with_habits(walk, rig, theirs)
    assert np.allclose(given.positions(), walk.positions(), atol=1e-9)  # nothing moves
    turned = np.degrees(quat.angle(quat.mul(quat.conjugate(given.fk()[0]), other.fk()[0])))
    assert turned.max() < 0.5  # every joint's world rotation as the twisted walk's


def test_no_habits_change_nothing(walk_and_rig):
    walk, rig = walk_and_rig
    assert with_habits(walk, rig, {}) is walk
    same = with_habits(walk, rig, habits(walk, rig))
    assert np.allclose(np.abs(np.sum(same.rotations * walk.rotations, -1)), 1.0, atol=1e-9)  # q or -q


@pytest.mark.parametrize("rig_name", ["procedural", "smpl", "game"])  # Y up; Z up; Z up, facing -Y
def test_hips_turned_about_the_spine_keep_the_upper_body(walk_and_rig, rig_name):
    """The hips given a habit 15 degrees off their own: the hips joint turns by it (on the right,
    in its own axes), everything from the spine up keeps its place and rotation, the legs their
    rotations (they move with the pelvis)."""
    if rig_name == "procedural":
        walk, rig = walk_and_rig
    else:
        walk = synthetic_walk(rig_name).motion
        _, rig = rigs_for(walk, walk)
    jmap, parents = rig.jmap, walk.skeleton.parents
    axis = np.array([0.3, 0.5, 0.8]) / np.linalg.norm([0.3, 0.5, 0.8])  # none of the joint's own axes
    turn = Rotation.from_rotvec(np.radians(15.0) * axis).as_quat()  # x, y, z, w: as the package's
    wanted = quat.mul(hips_habit(walk, rig), turn)
    given = with_hips_habit(walk, rig, wanted)
    (w0, p0), (w1, p1) = walk.fk(), given.fk()
    hips = jmap["hips"]
    canonical = rig.conventions.rotation()  # the habit's axes: the turn, seen in the file's
    native = quat.mul(quat.mul(quat.conjugate(canonical), turn), canonical)
    assert np.allclose(np.abs(np.sum(w1[:, hips] * quat.mul(w0[:, hips], native), -1)), 1.0, atol=1e-9)
    upper = _upper_body(parents, hips, jmap["chest"])
    assert np.allclose(p1[:, upper], p0[:, upper], atol=1e-9)
    legs = [jmap[f"{s}_{p}"] for s in ("left", "right") for p in ("upper_leg", "lower_leg", "foot")]
    assert np.allclose(np.abs(np.sum(w1[:, legs] * w0[:, legs], -1)), 1.0, atol=1e-9)
    moved = np.linalg.norm(p1[:, legs] - p0[:, legs], axis=-1)
    assert moved.min() > 1e-3  # the legs did go with the pelvis
    assert with_hips_habit(walk, rig, hips_habit(walk, rig)) is walk  # a habit already held: nothing


def _upper_body(parents: np.ndarray, hips: int, chest: int) -> list[int]:
    """The joints from the hips' spine child up to the chest, and all that hang from the chest."""

    def chain(j: int) -> list[int]:
        return [j] + chain(int(parents[j])) if j >= 0 else []

    spine = chain(chest)[: chain(chest).index(hips)]
    return [j for j in range(len(parents)) if j in spine or chest in chain(j)]


def test_stance_feet_are_pitched_as_the_rig_stands_them(walk_and_rig):
    """The walk's feet given a stance pitch 6 degrees steeper than their own: their stance pitch
    becomes it, the ankles stay, the toes move."""
    walk, rig = walk_and_rig
    own = stance_pitch(walk, rig)
    wanted = {side: pitch - np.radians(6.0) for side, pitch in own.items()}
    given = with_stance_pitch(walk, rig, wanted)
    for side, pitch in stance_pitch(given, rig).items():
        assert np.degrees(pitch - wanted[side]) == pytest.approx(0.0, abs=0.3), side
    before, after = walk.positions(), given.positions()
    ankles = [rig.jmap[f"{s}_foot"] for s in ("left", "right")]
    toes = [rig.jmap[f"{s}_toes"] for s in ("left", "right")]
    assert np.allclose(after[:, ankles], before[:, ankles], atol=1e-9)
    assert np.linalg.norm(after[:, toes] - before[:, toes], axis=-1).min() > 0.5  # cm: the toes went down
    assert with_stance_pitch(walk, rig, own) is walk
