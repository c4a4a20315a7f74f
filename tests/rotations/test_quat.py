"""The quaternion helpers (rotations.quat): mean_rotation and resample (the package's one time
resampler), and matrices, rotations between vectors and rotation vectors against SciPy."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from expressive_mocap.rotations import quat


def random_rotations(rng, shape):
    return quat.normalize(rng.normal(size=shape + (4,)))


def test_resample_hits_the_frames_and_interpolates_between():
    rng = np.random.default_rng(0)
    q = random_rotations(rng, (6, 3))
    same = quat.resample(q, np.arange(6.0))
    np.testing.assert_allclose(np.abs(np.sum(same * q, axis=-1)), 1.0, atol=1e-12)
    half = quat.resample(q, [2.5])[0]
    np.testing.assert_allclose(half, quat.slerp(q[2], q[3], np.full(3, 0.5)), atol=1e-15)
    values = rng.normal(size=(6, 3, 2))
    np.testing.assert_allclose(
        quat.resample(values, [0.0, 2.25, 5.0], rotations=False),
        [values[0], 0.75 * values[2] + 0.25 * values[3], values[5]],
        atol=1e-15,
    )


def test_spanning_positions_stretch_first_to_first_and_last_to_last():
    positions = quat.spanning_positions(11, 21)
    assert positions[0] == 0.0 and positions[-1] == 10.0 and np.allclose(np.diff(positions), 0.5)
    values = np.arange(11.0)[:, None]
    np.testing.assert_allclose(quat.resample(values, positions, rotations=False)[:, 0], positions)


def test_mean_rotation_ignores_the_sign_of_each_quaternion():
    rng = np.random.default_rng(1)
    base = quat.about("Y", 30.0)
    q = quat.mul(base[None], quat.exp(rng.normal(scale=0.05, size=(200, 3))))
    signs = np.where(rng.random((200, 1)) < 0.5, -1.0, 1.0)
    mean = quat.mean_rotation(q * signs)
    assert np.degrees(quat.angle(quat.mul(quat.conjugate(base), mean))) < 1.0
    per_joint = quat.mean_rotation(np.stack([q, q], axis=1))
    assert per_joint.shape == (2, 4)


def test_mean_rotations_of_runs_laid_end_to_end_are_each_runs_own_mean():
    # Each run on its own first quaternion's hemisphere, never mixing frames of its neighbours,
    # whatever the signs; a run of none is the identity.
    rng = np.random.default_rng(2)
    runs = []
    for k, frames in enumerate((7, 0, 1, 90)):
        turned = quat.mul(quat.about("X", 20.0 * k)[None, None], quat.exp(rng.normal(scale=0.1, size=(frames, 2, 3))))
        runs.append(turned * np.where(rng.random((frames, 1, 1)) < 0.5, -1.0, 1.0))
    means = quat.mean_rotations(np.concatenate(runs), [len(r) for r in runs])
    assert means.shape == (4, 2, 4)
    np.testing.assert_array_equal(means[1], [[0.0, 0.0, 0.0, 1.0]] * 2)
    for run, mean in zip(runs, means):
        if len(run):
            np.testing.assert_allclose(mean, quat.mean_rotation(run), atol=1e-14)


def test_rotation_helpers_agree_with_scipy():
    rng = np.random.default_rng(3)
    rotations = Rotation.random(200, random_state=4)
    q = quat.from_matrix(rotations.as_matrix())
    np.testing.assert_allclose(np.abs(np.sum(q * rotations.as_quat(), axis=-1)), 1.0, atol=1e-12)
    u, v = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    turned = quat.rotate(quat.between(u, v), u)
    np.testing.assert_allclose(
        turned / np.linalg.norm(turned, axis=1)[:, None], v / np.linalg.norm(v, axis=1)[:, None], atol=1e-12
    )
    half = quat.between(np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0]))
    assert quat.angle(half) == pytest.approx(np.pi)


def test_rotation_vectors_agree_with_scipy_and_round_trip():
    from expressive_mocap.rotations import quat

    q = Rotation.random(500, random_state=11).as_quat()
    q[:5] = [0.0, 0.0, 0.0, 1.0]  # identity: the small-angle branch
    q[5:10] *= -1.0  # the other hemisphere: the same rotations
    v = quat.log(q)
    np.testing.assert_allclose(v, Rotation.from_quat(q).as_rotvec(), atol=1e-12)
    assert np.all(np.linalg.norm(v, axis=-1) <= np.pi + 1e-12)
    back = quat.exp(v)
    np.testing.assert_allclose(np.abs(np.sum(back * q, axis=-1)), 1.0, atol=1e-12)
    rotvecs = Rotation.from_quat(q).as_rotvec()
    np.testing.assert_allclose(quat.exp(rotvecs), Rotation.from_rotvec(rotvecs).as_quat(), atol=1e-12)


def test_smooth_keeps_a_steady_turn_ignores_signs_and_removes_a_pop():
    # A turn about Z at 2 degrees a frame with every other quaternion's sign flipped: smoothing
    # reads the rotations, not the signs, so the turn comes back (away from the held ends).
    degrees = 2.0 * np.arange(40)
    turn = Rotation.from_euler("z", degrees[:, None], degrees=True).as_quat()
    flipped = turn * np.where(np.arange(40) % 2, -1.0, 1.0)[:, None]
    smoothed = quat.smooth(flipped, 2.0)
    off = np.degrees(quat.angle(quat.mul(smoothed, quat.conjugate(turn))))[8:-8]
    assert off.max() < 1e-6, off.max()
    # A 20-degree pop on one frame of a held pose shrinks to a fifth of it or less.
    held = np.tile(Rotation.from_euler("x", 30, degrees=True).as_quat(), (21, 1))
    held[10] = Rotation.from_euler("x", 50, degrees=True).as_quat()
    pop = np.degrees(quat.angle(quat.mul(quat.smooth(held, 2.0), quat.conjugate(held[:1])))).max()
    assert pop < 4.0, pop
    np.testing.assert_array_equal(quat.smooth(held, 0.0), held)
