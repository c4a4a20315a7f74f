"""Clavicles turned towards the shoulders positions give (skeletons.clavicles), on the synthetic
rigs (no data needed): a motion reaching for its own shoulders is itself; a shrug is followed with
the arm keeping its world orientation; a shoulder another body's proportions put far away turns
the clavicle no more than the bounds say."""

from __future__ import annotations

import numpy as np
import pytest

from expressive_mocap.body import Body
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.clavicles import MOST_MEAN, MOST_SWING, reach_shoulders


def _walk(rig: str):
    motion = synthetic_walk(rig, seconds=2.0).motion
    return motion, Body.of(motion.skeleton).joint_map


def _arms(motion, jmap) -> np.ndarray:
    return motion.positions()[:, [jmap["left_upper_arm"], jmap["right_upper_arm"]]]


@pytest.mark.parametrize("rig", ["cmu", "mixamo", "smpl"])
def test_a_motion_reaching_for_its_own_shoulders_is_itself(rig):
    motion, jmap = _walk(rig)
    out = reach_shoulders(motion, jmap, _arms(motion, jmap), motion.rotations)
    assert np.abs(out.positions() - motion.positions()).max() < 1e-9 * np.abs(motion.positions()).max()


def test_a_shrug_is_followed_and_the_arm_keeps_its_world_orientation():
    motion, jmap = _walk("cmu")
    left = jmap["left_clavicle"]
    positions = motion.positions()
    # Each frame, the left shoulder raised by a turn of the clavicle about the forward axis growing
    # to 15 degrees: a shrug.
    shrug = quat.about("Z", np.linspace(0.0, 15.0, motion.n_frames))
    wanted = _arms(motion, jmap)
    wanted[:, 0] = positions[:, left] + quat.rotate(shrug, wanted[:, 0] - positions[:, left])
    out = reach_shoulders(motion, jmap, wanted, None)
    arm = jmap["left_upper_arm"]
    reached = out.positions()[:, arm]
    bone = np.linalg.norm(positions[:, arm] - positions[:, left], axis=-1)
    # The mean swing (7.5 degrees) is within MOST_MEAN: the whole shrug is followed.
    assert np.linalg.norm(reached - wanted[:, 0], axis=-1).max() < 1e-9 * bone.max()
    world_in, _ = motion.fk()
    world_out, _ = out.fk()
    for joint in (arm, jmap["left_forearm"], jmap["left_hand"]):  # the arm turned as it was, in the world
        assert np.degrees(quat.angle(quat.mul(quat.conjugate(world_in[:, joint]), world_out[:, joint]))).max() < 1e-6
    right = jmap["right_upper_arm"]
    assert np.abs(out.positions()[:, right] - positions[:, right]).max() < 1e-9 * bone.max()  # its own place


def test_a_far_shoulder_turns_the_clavicle_no_more_than_the_bounds():
    motion, jmap = _walk("cmu")
    left = jmap["left_clavicle"]
    positions = motion.positions()
    wanted = _arms(motion, jmap)
    wanted[:, 0] += np.array([0.0, 0.5, 0.0]) * np.linalg.norm(wanted[0, 0] - positions[0, left])  # half a bone up
    out = reach_shoulders(motion, jmap, wanted, None)
    world_in, _ = motion.fk()
    world_out, _ = out.fk()
    turned = np.degrees(quat.angle(quat.mul(world_out[:, left], quat.conjugate(world_in[:, left]))))
    # About 27 degrees would reach it: the constant part, the two bodies' proportions, is cut to
    # MOST_MEAN; what is left is how the wanted place moves about its mean (0.03 degrees here).
    assert abs(np.median(turned) - MOST_MEAN) < 0.1 and turned.max() < MOST_MEAN + 0.1 < MOST_SWING, turned


def test_a_shoulder_at_the_clavicle_joint_leaves_it_unturned():
    motion, jmap = _walk("cmu")
    wanted = _arms(motion, jmap)
    wanted[::2, 0] = motion.positions()[::2, jmap["left_clavicle"]]  # every other frame: no direction
    out = reach_shoulders(motion, jmap, wanted, None)
    assert np.isfinite(out.rotations).all()
