"""Rotations in the forms motion models are trained on, and back.

``encode(quats, kind)`` turns unit quaternions ``[..., 4]`` (x, y, z, w) into one of
:data:`KINDS`, ``decode(values, kind)`` back into unit quaternions with ``w >= 0``:

- ``"quaternion"`` (4 values): x, y, z, w as they are (``w >= 0`` after :func:`decode`);
- ``"6d"`` (6): the first two columns of the rotation matrix, column after column (Zhou et al.,
  "On the Continuity of Rotation Representations in Neural Networks", CVPR 2019): continuous,
  decoded by Gram-Schmidt, so a network's output need not be exact;
- ``"matrix"`` (9): the rotation matrix, row after row (decoded through its nearest rotation's
  quaternion, so a slightly off matrix still decodes);
- ``"axis-angle"`` (3): the rotation vector, axis times angle in radians, the angle in [0, pi];
- ``"euler"`` (3): angles in degrees in ``order`` (intrinsic, first axis outermost, as BVH
  channels and SciPy's upper-case orders), through the package's Euler kernel.
"""

from __future__ import annotations

import numpy as np

from . import ops, quat
from .errors import ArgumentError

KINDS = {"quaternion": 4, "6d": 6, "matrix": 9, "axis-angle": 3, "euler": 3}


def _kind(kind: str) -> int:
    if kind not in KINDS:
        raise ArgumentError(f"argument `kind`: expected one of {', '.join(KINDS)}, got {kind!r}")
    return KINDS[kind]


def _positive(q: np.ndarray) -> np.ndarray:
    return np.where(q[..., 3:] < 0, -q, q)


def encode(quats, kind: str, order: str = "ZXY") -> np.ndarray:
    """Unit quaternions ``[..., 4]`` as ``kind`` ``[..., n]`` (see the module's notes)."""
    _kind(kind)
    q = np.asarray(quats, dtype=np.float64)
    if q.shape[-1:] != (4,):
        raise ArgumentError(f"argument `quats`: expected shape [..., 4], got {list(q.shape)}")
    if kind == "quaternion":
        return q.copy()
    if kind == "axis-angle":
        return quat.log(q)
    if kind == "euler":
        flat = q.reshape(-1, 1, 4)
        return ops.quat_to_euler(flat, order).reshape(q.shape[:-1] + (3,))
    matrix = quat.to_matrix(q)
    if kind == "matrix":
        return matrix.reshape(q.shape[:-1] + (9,))
    return np.concatenate([matrix[..., :, 0], matrix[..., :, 1]], axis=-1)  # 6d


def decode(values, kind: str, order: str = "ZXY") -> np.ndarray:
    """``kind`` values ``[..., n]`` back as unit quaternions ``[..., 4]`` with ``w >= 0``."""
    n = _kind(kind)
    v = np.asarray(values, dtype=np.float64)
    if v.shape[-1:] != (n,):
        raise ArgumentError(f"argument `values`: a {kind} is {n} values, got shape {list(v.shape)}")
    if kind == "quaternion":
        return _positive(quat.normalize(v))
    if kind == "axis-angle":
        return _positive(quat.exp(v))
    if kind == "euler":
        flat = v.reshape(-1, 1, 3)
        return _positive(ops.euler_to_quat(flat, order).reshape(v.shape[:-1] + (4,)))
    if kind == "matrix":
        return _positive(quat.normalize(quat.from_matrix(v.reshape(v.shape[:-1] + (3, 3)))))
    first = v[..., :3] / np.linalg.norm(v[..., :3], axis=-1, keepdims=True)
    second = v[..., 3:] - first * np.sum(first * v[..., 3:], axis=-1, keepdims=True)
    second = second / np.linalg.norm(second, axis=-1, keepdims=True)
    matrix = np.stack([first, second, quat.cross(first, second)], axis=-1)  # columns
    return _positive(quat.from_matrix(matrix))


__all__ = ["KINDS", "decode", "encode"]
