"""Joints without a role that source and target both have (a second neck joint, hip joints,
fingers and thumbs, the segments of spines of one length) turn as the source's do, instead of
being held at rest: a motion retargeted onto its own skeleton comes back joint for joint."""

from __future__ import annotations

import numpy as np
import pytest

from expressive_mocap import Motion, Skeleton
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import retarget, synthetic_walk
from expressive_mocap.skeletons.rig import Rig
from expressive_mocap.skeletons.transfer import matched_chains

# Wiggled below: not the hip joints, whose turn would move the line across the upper legs, by
# which the hips themselves are aligned (a real capture keeps them still: CMU's do).
FREE = ("Neck1", "LeftFingerBase", "LeftHandIndex1", "LThumb", "RightFingerBase", "LowerBack", "Spine")


def wiggled(motion: Motion) -> Motion:
    """The CMU-like walk with its role-less joints turning (each about its own axis and rate)."""
    rotations = motion.rotations.copy()
    t = np.arange(motion.n_frames) * motion.frame_time
    for k, name in enumerate(FREE):
        j = motion.skeleton.index(name)
        axis = np.roll([1.0, 0.3, 0.0], k) / np.linalg.norm([1.0, 0.3, 0.0])
        angle = np.radians(15.0 + 3 * k) * np.sin(2 * np.pi * (0.7 + 0.2 * k) * t)
        turn = np.concatenate([axis * np.sin(angle / 2)[:, None], np.cos(angle / 2)[:, None]], axis=1)
        rotations[:, j] = quat.mul(rotations[:, j], turn)
    return Motion(motion.skeleton, rotations, motion.translations, motion.frame_time)


def directions(motion: Motion) -> np.ndarray:
    """Unit bone directions ``[F, J, 3]`` (the root's: zero)."""
    _, positions = motion.fk()
    parents = motion.skeleton.parents
    out = np.zeros_like(positions)
    inner = parents >= 0
    bones = positions[:, inner] - positions[:, parents[inner]]
    length = np.linalg.norm(bones, axis=-1, keepdims=True)
    out[:, inner] = np.where(length > 1e-9, bones / np.maximum(length, 1e-12), 0.0)
    return out


def degrees_apart(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    both = (np.linalg.norm(a, axis=-1) > 0) & (np.linalg.norm(b, axis=-1) > 0)
    return np.where(both, np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1, 1))), 0.0)


@pytest.fixture(scope="module")
def walk() -> Motion:
    return wiggled(synthetic_walk("cmu", seconds=2.0).motion)


def test_the_chains_both_skeletons_have_are_matched(walk):
    rig = Rig.of(walk)
    names = walk.skeleton.names
    matched = {names[t]: names[s] for t, _, s, _ in matched_chains(rig, rig)}
    assert {n: n for n in FREE + ("LHipJoint", "RHipJoint")}.items() <= matched.items()
    bandai = synthetic_walk("bandai", seconds=1.0).motion
    assert matched_chains(rig, Rig.of(bandai)) == []  # no neck joint, fingers nor hip joints there


def test_a_motion_retargeted_onto_its_own_skeleton_comes_back_joint_for_joint(walk):
    back = retarget(walk, walk, plant_feet=False)
    apart = degrees_apart(directions(back), directions(walk))
    assert apart.max() < 1e-4, walk.skeleton.names[int(np.argmax(apart.max(axis=0)))]


def test_onto_other_proportions_the_chains_still_follow(walk):
    """Onto the same hierarchy with longer bones: the role-less joints still point as the
    source's (held at rest, the wiggle was lost: 10-20 degrees)."""
    s = walk.skeleton
    longer = Skeleton(
        s.names, s.parents, s.offsets * np.linspace(0.9, 1.2, s.n_joints)[:, None], s.channels, s.end_sites
    )
    target = Motion(longer, walk.rotations[:1], longer.offsets[None], walk.frame_time)
    out = retarget(walk, target, plant_feet=False)
    joints = [s.index(n) for n in FREE]
    apart = degrees_apart(directions(out), directions(walk))[:, joints]
    assert apart.mean() < 1.0 and apart.max() < 3.0


@pytest.mark.real_data
def test_a_real_cmu_walk_onto_its_own_skeleton(other_dir):
    from expressive_mocap import read_bvh

    walk = read_bvh(other_dir / "cmu_01_01.bvh")[:600]
    back = retarget(walk, walk, plant_feet=False)
    # Its fingers turned 27-37 degrees from where they were, its second neck joint 4.7, held at rest.
    assert degrees_apart(directions(back), directions(walk)).max() < 1e-4
