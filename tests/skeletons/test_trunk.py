"""The trunk's lean survives a retarget: the line from the hips to the chest and from the chest to
the head, seen in each frame's heading frame (Y up, facing +Z, from the hips' line), is the
source's on the target, whatever joints the target's spine and neck hold between. Before, a walk
of another rig retargeted onto the Bandai-Namco body leaned 2-16 degrees (mean) off its own."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.conventions import read_conventions
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.motion import Motion
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.canonical import onto_canonical
from expressive_mocap.skeletons.retargeting import retarget


def trunk_lines(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """Unit hips-to-chest and chest-to-head lines ``[F, 3]`` in each frame's heading frame."""
    jmap = find_joint_map(motion.skeleton)
    points = quat.rotate(read_conventions(motion, jmap).rotation(), motion.positions())  # Y up, facing +Z
    left = points[:, jmap["left_upper_leg"]] - points[:, jmap["right_upper_leg"]]
    yaw = np.arctan2(-left[:, 2], left[:, 0])
    turn = quat.about("Y", -np.degrees(yaw))

    def seen(a: str, b: str) -> np.ndarray:
        line = quat.rotate(turn, points[:, jmap[b]] - points[:, jmap[a]])
        return line / np.linalg.norm(line, axis=-1, keepdims=True)

    return seen("hips", "chest"), seen("chest", "head")


def degrees_apart(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)))


def hunched(seconds: float = 2.0) -> Motion:
    """The demo's walk bent forward 25 degrees at the spine and 15 more at the neck."""
    walk = procedural_walk(seconds)  # Y up, walking along +Z: forward is a turn about +X
    names, parents = walk.skeleton.names, walk.skeleton.parents
    rotations = walk.rotations.copy()
    for joint, degrees in (("Spine", 25.0), ("Neck", 15.0)):
        j = names.index(joint)
        world = Motion(walk.skeleton, rotations, walk.translations, walk.frame_time).fk()[0]
        bent = quat.mul(quat.about("X", np.full(walk.n_frames, degrees)), world[:, j])
        rotations[:, j] = quat.mul(quat.conjugate(world[:, parents[j]]), bent)
    return Motion(walk.skeleton, rotations, walk.translations, walk.frame_time)


@pytest.mark.parametrize("rig", ["cmu", "mixamo", "smpl", "game"])
def test_a_hunched_walk_keeps_its_lean_on_every_rig(rig):
    source = hunched()
    target = synthetic_walk(rig, seconds=1.0).motion
    out = retarget(source, target, plant_feet=False)
    for mine, theirs in zip(trunk_lines(out), trunk_lines(source)):
        apart = degrees_apart(mine, theirs)
        assert apart.mean() < 2.0 and apart.max() < 5.0, (rig, apart.mean(), apart.max())
    # The lean is there to keep: the chest-to-head line leans forward by tens of degrees.
    lean = np.degrees(np.arctan2(trunk_lines(source)[1][:, 2], trunk_lines(source)[1][:, 1]))
    assert np.median(lean) > 20.0


def test_mapped_joints_keep_their_world_rotations():
    """Only the joints between the trunk's roles turn: every mapped role's world rotation is the
    transfer's (a round trip then gives back the source's)."""
    source = hunched()
    target = synthetic_walk("mixamo", seconds=1.0).motion
    out = retarget(source, target, plant_feet=False)
    back = retarget(out, source, plant_feet=False)
    jmap = find_joint_map(source.skeleton)
    mine, theirs = back.fk()[0], source.fk()[0]
    for role in ("hips", "chest", "head", "left_upper_arm", "right_forearm", "left_upper_leg"):
        apart = np.degrees(quat.angle(quat.mul(mine[:, jmap[role]], quat.conjugate(theirs[:, jmap[role]]))))
        assert apart.max() < 1.0, (role, apart.max())


@pytest.mark.real_data
def test_real_walks_of_other_rigs_keep_their_lean_on_the_canonical_body(other_dir):
    for path in sorted(other_dir.glob("*.bvh")):
        if path.stem == "dme_rest":
            continue
        source = em.read_bvh(path)
        out, _ = onto_canonical(source)
        for mine, theirs in zip(trunk_lines(out), trunk_lines(source)):
            assert degrees_apart(mine, theirs).mean() < 2.0, path.name
