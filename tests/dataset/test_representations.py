"""Rotation representations for learning: every kind round-trips and agrees with SciPy."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from expressive_mocap.dataset import representations as rep
from expressive_mocap.errors import ArgumentError
from expressive_mocap.rotations import quat


@pytest.fixture(scope="module")
def rotations() -> Rotation:
    """Random rotations, with the hard ones: the identity, half turns, tiny angles."""
    rng = np.random.default_rng(7)
    random = Rotation.random(500, random_state=rng).as_quat()
    axes = rng.normal(size=(20, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    special = np.concatenate(
        [
            [[0.0, 0.0, 0.0, 1.0]],
            np.concatenate([axes, np.zeros((20, 1))], axis=1),  # half turns
            Rotation.from_rotvec(axes * 1e-9).as_quat(),
            Rotation.from_rotvec(axes * (np.pi - 1e-7)).as_quat(),
        ]
    )
    return Rotation.from_quat(np.concatenate([random, special]))


def same_rotation(a: np.ndarray, b: np.ndarray) -> float:
    """Largest angle (radians) between the rotations of two quaternion arrays (by the angle of
    ``a^-1 b``: the arc cosine of their dot product loses precision near 1)."""
    return float(quat.angle(quat.mul(quat.conjugate(a), b)).max())


@pytest.mark.parametrize("kind", list(rep.KINDS))
def test_every_kind_round_trips(kind, rotations, backend):
    q = rotations.as_quat().reshape(-1, 11, 4)  # any leading shape
    values = rep.encode(q, kind)
    assert values.shape == q.shape[:-1] + (rep.KINDS[kind],)
    back = rep.decode(values, kind)
    assert back.shape == q.shape and (back[..., 3] >= 0).all()
    np.testing.assert_allclose(np.linalg.norm(back, axis=-1), 1.0, atol=1e-12)
    # Euler angles lose the third angle's precision near gimbal lock (the middle at +-90 degrees).
    assert same_rotation(back, q) < (1e-6 if kind == "euler" else 1e-9), kind


def test_the_kinds_agree_with_scipy(rotations, backend):
    q = rotations.as_quat()
    matrix = rotations.as_matrix()
    np.testing.assert_allclose(rep.encode(q, "matrix"), matrix.reshape(-1, 9), atol=1e-12)
    np.testing.assert_allclose(rep.encode(q, "6d"), np.concatenate([matrix[:, :, 0], matrix[:, :, 1]], 1), atol=1e-12)
    ours = rep.encode(q, "axis-angle")
    theirs = rotations.as_rotvec()
    half_turn = np.isclose(np.linalg.norm(theirs, axis=1), np.pi)  # +-axis are the same rotation there
    np.testing.assert_allclose(ours[~half_turn], theirs[~half_turn], atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(ours, axis=1), np.linalg.norm(theirs, axis=1), atol=1e-9)
    for order in ("ZXY", "XYZ", "ZYX"):
        euler = rotations.as_euler(order, degrees=True)
        easy = np.abs(euler[:, 1]) < 80  # away from gimbal lock, where the angles are unique
        np.testing.assert_allclose(rep.encode(q, "euler", order)[easy], euler[easy], atol=1e-9)


def test_a_6d_output_off_the_manifold_decodes_to_the_nearest_frame(rotations):
    """A network's 6D output is not exact: Gram-Schmidt keeps the first column's direction and
    the plane of the two."""
    q = rotations.as_quat()[:100]
    noisy = rep.encode(q, "6d") * 1.7 + np.random.default_rng(1).normal(scale=0.05, size=(100, 6))
    back = Rotation.from_quat(rep.decode(noisy, "6d")).as_matrix()
    first = noisy[:, :3] / np.linalg.norm(noisy[:, :3], axis=1, keepdims=True)
    np.testing.assert_allclose(back[:, :, 0], first, atol=1e-12)
    assert np.abs(np.einsum("ij,ij->i", back[:, :, 2], noisy[:, 3:])).max() < 1e-12  # second in the plane


def test_bad_kinds_and_shapes_are_named():
    with pytest.raises(ArgumentError, match="argument `kind`: expected one of quaternion, 6d"):
        rep.encode(np.array([0.0, 0.0, 0.0, 1.0]), "so3")
    with pytest.raises(ArgumentError, match="a 6d is 6 values"):
        rep.decode(np.zeros((2, 5)), "6d")
    with pytest.raises(ArgumentError, match=r"expected shape \[..., 4\]"):
        rep.encode(np.zeros((2, 3)), "matrix")


@pytest.mark.parametrize("kind", list(rep.KINDS))
def test_interpolation_follows_slerp_between_neighbouring_frames(kind):
    """Rotations 3 degrees apart (a fast joint between two frames at 30 fps), mixed at random t."""
    rng = np.random.default_rng(5)
    a = Rotation.random(500, random_state=5)
    axes = rng.normal(size=(500, 3))
    b = Rotation.from_rotvec(axes / np.linalg.norm(axes, axis=1, keepdims=True) * np.radians(3.0)) * a
    t = rng.uniform(size=500)
    slerped = Rotation.from_quat(
        [Slerp([0, 1], Rotation.concatenate([a[i], b[i]]))(t[i]).as_quat() for i in range(500)]
    )
    va, vb = (rep.encode(r.as_quat(), kind).astype(np.float32) for r in (a, b))
    mixed = rep.interpolate(va, vb, t[:, None], kind)
    assert mixed.dtype == np.float32 and mixed.shape == va.shape
    off = np.degrees((Rotation.from_quat(rep.decode(mixed, kind)).inv() * slerped).magnitude())
    assert off.max() < (0.015 if kind in ("6d", "matrix") else 1e-3)
    for end, expected in ((0.0, a), (1.0, b)):  # the ends are the frames themselves
        at = rep.decode(rep.interpolate(va, vb, np.full((500, 1), end), kind), kind)
        assert np.degrees((Rotation.from_quat(at).inv() * expected).magnitude()).max() < 1e-3
