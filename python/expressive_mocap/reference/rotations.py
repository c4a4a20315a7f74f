"""Twin of ``rust/rotations.rs``: Euler angles (degrees, intrinsic) <-> quaternions (x, y, z, w)."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat


def _check(values: np.ndarray, orders: np.ndarray, name: str, width: int) -> np.ndarray:
    orders = np.asarray(orders)
    if orders.ndim != 2 or orders.shape[1] != 3:
        raise ArgumentError(f"argument `orders`: expected shape [J, 3], got {list(orders.shape)}")
    if not all(sorted(o) == [0, 1, 2] for o in orders.tolist()):
        raise ArgumentError("argument `orders`: every order must be a permutation of the axes 0, 1, 2")
    if values.ndim != 3 or values.shape[1:] != (len(orders), width):
        raise ArgumentError(f"argument `{name}`: expected shape [F, {len(orders)}, {width}], got {list(values.shape)}")
    return orders.astype(np.intp)


def euler_to_quat(angles: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """``angles [F, J, 3]`` degrees, ``orders [J, 3]`` axis indices -> quaternions ``[F, J, 4]``."""
    orders = _check(angles, orders, "angles", 3)
    half = np.radians(angles) * 0.5
    result = np.zeros(angles.shape[:2] + (4,))
    result[..., 3] = 1.0
    for k in range(3):  # the intrinsic rotations one after the other, first axis first
        q = np.zeros(angles.shape[:2] + (4,))
        axis_onehot = np.eye(3)[orders[:, k]]  # [J, 3]
        q[..., :3] = axis_onehot * np.sin(half[..., k : k + 1])
        q[..., 3] = np.cos(half[..., k])
        result = quat.mul(result, q)
    return result


def quat_to_euler(quats: np.ndarray, orders: np.ndarray) -> np.ndarray:
    """``quats [F, J, 4]`` -> angles ``[F, J, 3]`` degrees; middle angle in [-90, 90].

    At gimbal lock the third angle is 0 and the first carries the rest (as the Rust kernel).
    """
    orders = _check(quats, orders, "quats", 4)
    m = quat.to_matrix(quat.normalize(quats))  # [F, J, 3, 3]
    i, j, k = orders[:, 0], orders[:, 1], orders[:, 2]
    joints = np.arange(len(orders))

    def r(row, col):
        return m[:, joints, row, col]

    sign = np.where((j + 3 - i) % 3 == 1, 1.0, -1.0)
    sin_b = np.clip(sign * r(i, k), -1.0, 1.0)
    cos_b = np.hypot(r(i, i), r(i, j))
    locked = cos_b <= 1e-9
    a = np.where(locked, np.arctan2(sign * r(k, j), r(j, j)), np.arctan2(-sign * r(j, k), r(k, k)))
    b = np.where(locked, np.sign(sin_b) * np.pi / 2, np.arctan2(sin_b, cos_b))
    c = np.where(locked, 0.0, np.arctan2(-sign * r(i, j), r(i, i)))
    return np.degrees(np.stack([a, b, c], axis=-1))


__all__ = [
    "euler_to_quat",
    "quat_to_euler",
]
