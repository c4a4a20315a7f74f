"""Euler <-> quaternion kernels: agreement with SciPy for all six orders, round trips,
gimbal lock, Rust/NumPy parity and argument errors."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from expressive_mocap import reference
from expressive_mocap.rotations.orders import ORDERS

ATOL = 1e-12  # float64 arithmetic, a few dozen operations


def same_rotation(q1, q2):
    """|dot| = 1 for equal rotations, whatever the sign of the quaternions."""
    return np.abs(np.sum(q1 * q2, axis=-1))


@pytest.mark.parametrize("order", ORDERS)
def test_euler_to_quat_matches_scipy(backend, order):
    angles = np.random.default_rng(1).uniform(-180, 180, size=(50, 7, 3))
    ours = em.euler_to_quat(angles, order)
    scipy = Rotation.from_euler(order, angles.reshape(-1, 3), degrees=True).as_quat().reshape(50, 7, 4)
    np.testing.assert_allclose(same_rotation(ours, scipy), 1.0, atol=ATOL)
    np.testing.assert_allclose(np.linalg.norm(ours, axis=-1), 1.0, atol=ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_quat_to_euler_matches_scipy_and_round_trips(backend, order):
    quats = Rotation.random(400, random_state=2).as_quat().reshape(100, 4, 4)
    angles = em.quat_to_euler(quats, order)
    scipy = Rotation.from_quat(quats.reshape(-1, 4)).as_euler(order, degrees=True).reshape(100, 4, 3)
    # Away from gimbal lock the decomposition is unique with the middle angle in [-90, 90].
    np.testing.assert_allclose(angles, scipy, atol=1e-8)
    assert np.all(np.abs(angles[..., 1]) <= 90.0)
    np.testing.assert_allclose(same_rotation(em.euler_to_quat(angles, order), quats), 1.0, atol=ATOL)


@pytest.mark.parametrize("order", ORDERS)
def test_gimbal_lock_still_composes_back(backend, order):
    angles = np.array([[[30.0, 90.0, 40.0], [-70.0, -90.0, 15.0], [0.0, 90.0, 0.0]]])
    quats = em.euler_to_quat(angles, order)
    back = em.quat_to_euler(quats, order)
    np.testing.assert_allclose(back[..., 2], 0.0, atol=1e-9)
    np.testing.assert_allclose(same_rotation(em.euler_to_quat(back, order), quats), 1.0, atol=1e-9)


def test_per_joint_orders_and_batch_dims():
    angles = np.random.default_rng(3).uniform(-90, 90, size=(2, 5, 6, 3))
    quats = em.euler_to_quat(angles, list(ORDERS))
    assert quats.shape == (2, 5, 6, 4)
    for j, order in enumerate(ORDERS):
        expected = Rotation.from_euler(order, angles[:, :, j].reshape(-1, 3), degrees=True).as_quat()
        np.testing.assert_allclose(same_rotation(quats[:, :, j].reshape(-1, 4), expected), 1.0, atol=ATOL)


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
def test_rust_matches_numpy_twin():
    from expressive_mocap import _core

    rng = np.random.default_rng(4)
    orders = rng.permuted(np.tile([0, 1, 2], (9, 1)), axis=1).astype(np.uint8)
    angles = rng.uniform(-360, 360, size=(300, 9, 3))
    np.testing.assert_allclose(_core.euler_to_quat(angles, orders), reference.euler_to_quat(angles, orders), atol=1e-14)
    quats = Rotation.random(2700, random_state=5).as_quat().reshape(300, 9, 4)
    np.testing.assert_allclose(_core.quat_to_euler(quats, orders), reference.quat_to_euler(quats, orders), atol=1e-9)


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
@pytest.mark.parametrize("order", ORDERS)
def test_rust_euler_to_quat_matches_scipy_at_large_angles_and_multiples_of_90(order):
    # The Rust kernel takes sines and cosines of the half-angles in degrees (rust/trig.rs),
    # reduced exactly: large angles and multiples of 90 are where that could go wrong.
    from expressive_mocap import _core

    rng = np.random.default_rng(6)
    angles = np.concatenate(
        [
            rng.uniform(-1e4, 1e4, size=(400, 3)),
            rng.uniform(-180, 180, size=(400, 3)),
            90.0 * rng.integers(-120, 121, size=(400, 3)),
            np.where(
                rng.random((400, 3)) < 0.5,
                90.0 * rng.integers(-8, 9, size=(400, 3)),
                rng.uniform(-720, 720, size=(400, 3)),
            ),
        ]
    )
    orders = np.array([["XYZ".index(axis) for axis in order]], dtype=np.uint8)
    ours = _core.euler_to_quat(angles[:, None, :], orders)[:, 0]
    scipy = Rotation.from_euler(order, angles, degrees=True).as_quat()
    sign = np.where(np.sum(ours * scipy, axis=-1) < 0.0, -1.0, 1.0)[:, None]
    np.testing.assert_allclose(ours, sign * scipy, rtol=0.0, atol=1e-12)


def test_bad_arguments_name_the_argument(backend):
    with pytest.raises(em.errors.ArgumentError, match="angles"):
        em.euler_to_quat(np.zeros((3, 4)), "XYZ")
    with pytest.raises(em.MocapError, match="rotation order"):
        em.euler_to_quat(np.zeros((1, 1, 3)), "XXY")
    with pytest.raises(em.errors.ArgumentError, match="orders"):
        em.euler_to_quat(np.zeros((1, 2, 3)), ["XYZ"])
    with pytest.raises(em.errors.ArgumentError, match="quats"):
        em.quat_to_euler(np.zeros((1, 2, 3)), "XYZ")
