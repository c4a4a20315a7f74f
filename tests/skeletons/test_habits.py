"""A rig's habitual limb twists (:mod:`expressive_mocap.skeletons.habits`), on the procedural walk
(no data needed): a copy whose arms and legs are twisted about their bones by fixed angles, as a
rig with other elbow and knee axes would hold them, lends those habits to the untwisted walk."""

from __future__ import annotations

import numpy as np
import pytest

from expressive_mocap.procedural import walk_and_wave
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons.habits import habits, with_habits
from expressive_mocap.skeletons.retargeting import rigs_for

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
