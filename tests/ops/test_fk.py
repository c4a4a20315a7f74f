"""Forward kinematics: a chain by hand, Rust/NumPy parity, and SciPy composition on real data."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from conftest import bvh_values, scipy_positions
from expressive_mocap import reference

RTOL = 1e-5  # the bar; measured agreement is ~1e-13 relative in float64


def test_two_joint_chain_by_hand(backend):
    # Root at (1, 0, 0) turned 90 degrees about Z; the child 2 units along the root's x axis.
    rotations = np.array([[Rotation.from_euler("z", 90, degrees=True).as_quat(), [0, 0, 0, 1]]])
    translations = np.array([[[1.0, 0, 0], [2.0, 0, 0]]])
    world_rot, world_pos = em.forward_kinematics(rotations, translations, [-1, 0])
    np.testing.assert_allclose(world_pos[0, 1], [1.0, 2.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(world_rot[0, 1], rotations[0, 0], atol=1e-12)


def random_tree(rng, joints):
    parents = np.array([-1] + [int(rng.integers(0, j)) for j in range(1, joints)])
    return parents


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
@pytest.mark.parametrize("frames", [1, 7, 5000])  # 5000 x 23 joints crosses the parallel threshold
def test_rust_matches_numpy_twin(frames):
    from expressive_mocap import _core

    rng = np.random.default_rng(frames)
    parents = random_tree(rng, 23)
    rotations = Rotation.random(frames * 23, random_state=frames).as_quat().reshape(frames, 23, 4)
    translations = rng.normal(scale=30.0, size=(frames, 23, 3))
    rust = _core.forward_kinematics(rotations, translations, parents)
    numpy = reference.forward_kinematics(rotations, translations, parents)
    for ours, twin in zip(rust, numpy):
        scale = np.abs(twin).max()
        np.testing.assert_allclose(ours, twin, rtol=0, atol=RTOL * scale)


def test_matches_scipy_composition_on_mixed_orders(backend, mixed_path):
    motion = em.read_bvh(mixed_path)
    expected = scipy_positions(motion.skeleton, bvh_values(mixed_path))
    np.testing.assert_allclose(motion.positions(), expected, atol=1e-9)


@pytest.mark.real_data
def test_matches_scipy_on_real_clips(backend, bandai2_dir, bandai1_dir):
    for path in [bandai2_dir / "dataset-2_walk_normal_001.bvh", bandai1_dir / "dataset-1_bow_angry_001.bvh"]:
        motion = em.read_bvh(path)
        expected = scipy_positions(motion.skeleton, bvh_values(path))
        scale = np.abs(expected).max()
        np.testing.assert_allclose(motion.positions(), expected, rtol=0, atol=RTOL * scale)


def test_parents_and_shapes_are_checked(backend):
    q = np.tile([0.0, 0, 0, 1], (1, 2, 1))
    t = np.zeros((1, 2, 3))
    with pytest.raises(em.errors.ArgumentError, match="parents"):
        em.forward_kinematics(q, t, [1, -1])
    with pytest.raises(em.errors.ArgumentError, match="translations"):
        em.forward_kinematics(q, np.zeros((2, 2, 3)), [-1, 0])
    with pytest.raises(em.errors.ArgumentError, match="rotations"):
        em.forward_kinematics(np.zeros((1, 2, 3)), t, [-1, 0])


def test_many_clips_at_once_match_one_by_one(backend, mixed_path):
    motion = em.read_bvh(mixed_path)
    clips = [motion, motion[1:3], motion.resample(n_frames=40)]
    for clip, (world_rot, world_pos) in zip(clips, em.forward_kinematics_many(clips)):
        expected_rot, expected_pos = clip.fk()
        np.testing.assert_array_equal(world_pos, expected_pos)
        np.testing.assert_array_equal(world_rot, expected_rot)
