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

from .. import ops
from ..errors import ArgumentError
from ..reference.forms import matrix_entries
from ..rotations import quat

KINDS = {"quaternion": 4, "6d": 6, "matrix": 9, "axis-angle": 3, "euler": 3}


def _kind(kind: str) -> int:
    if kind not in KINDS:
        raise ArgumentError(f"argument `kind`: expected one of {', '.join(KINDS)}, got {kind!r}")
    return KINDS[kind]


def _positive(q: np.ndarray) -> np.ndarray:
    return np.where(q[..., 3:] < 0, -q, q)


def encode(quats, kind: str, order: str = "ZXY", dtype=np.float64) -> np.ndarray:
    """Unit quaternions ``[..., 4]`` as ``kind`` ``[..., n]`` (see the module's notes), in
    ``dtype``: computed in float64 then rounded (``"6d"`` and ``"matrix"`` in float32 straight
    from the :func:`~expressive_mocap.ops.matrix_columns` kernel)."""
    _kind(kind)
    if kind in ("6d", "matrix") and np.dtype(dtype) == np.float32:
        return ops.matrix_columns(quats, 3 if kind == "matrix" else 2)
    return _encode(np.asarray(quats, dtype=np.float64), kind, order).astype(dtype, copy=False)


def _encode(q: np.ndarray, kind: str, order: str) -> np.ndarray:
    if q.shape[-1:] != (4,):
        raise ArgumentError(f"argument `quats`: expected shape [..., 4], got {list(q.shape)}")
    if kind == "quaternion":
        return q.copy()
    if kind == "axis-angle":
        return quat.log(q)
    if kind == "euler":
        flat = q.reshape(-1, 1, 4)
        return ops.quat_to_euler(flat, order).reshape(q.shape[:-1] + (3,))
    return matrix_entries(q, 3 if kind == "matrix" else 2)


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
    first, second = _gram_schmidt(v)
    matrix = np.stack([first, second, quat.cross(first, second)], axis=-1)  # columns
    return _positive(quat.from_matrix(matrix))


def _gram_schmidt(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The orthonormal columns ``[..., 3]`` nearest a 6D value's two (the first kept in direction)."""
    # einsum: NumPy's reductions over a last axis of 3 are several times slower.
    first = v[..., :3] / np.sqrt(np.einsum("...i,...i->...", v[..., :3], v[..., :3]))[..., None]
    second = v[..., 3:] - first * np.einsum("...i,...i->...", first, v[..., 3:])[..., None]
    return first, second / np.sqrt(np.einsum("...i,...i->...", second, second))[..., None]


def interpolate(a, b, t, kind: str, order: str = "ZXY") -> np.ndarray:
    """Rotations between ``a`` and ``b`` (``kind`` values ``[..., n]``) at ``t`` (broadcast to
    ``[..., 1]``), in ``kind`` and ``a``'s dtype: for ``"6d"`` and ``"matrix"`` the values mixed
    linearly then made a rotation again (Gram-Schmidt on the first two columns): within 0.012
    degrees of slerp for rotations 3 degrees apart (0.13 for 10; neighbouring frames of a motion),
    at a tenth of the cost of going through quaternions; other forms through quaternions (nlerp
    along the shorter arc, within 4e-5 degrees of slerp at 3; quaternions as they are)."""
    a, b = np.asarray(a), np.asarray(b)
    t = np.asarray(t, dtype=a.dtype)
    if kind == "quaternion":
        return nlerp(a, b, t)
    if kind in ("6d", "matrix"):
        mixed = a + (b - a) * t
        if kind == "matrix":
            columns = mixed.reshape(mixed.shape[:-1] + (3, 3)).swapaxes(-1, -2)[..., :2, :]  # rows of the transpose
            first, second = _gram_schmidt(columns.reshape(mixed.shape[:-1] + (6,)))
            return np.stack([first, second, np.cross(first, second)], axis=-1).reshape(mixed.shape).astype(a.dtype)
        return np.concatenate(_gram_schmidt(mixed), axis=-1).astype(a.dtype)
    return encode(nlerp(decode(a, kind, order), decode(b, kind, order), t), kind, order).astype(a.dtype)


def nlerp(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Quaternions ``[..., 4]`` between ``a`` and ``b`` (shortest arc) at ``t`` (broadcast to
    ``[..., 1]``), normalised. Between neighbouring frames (a few degrees apart) it differs from
    slerp by less than float32's precision in angle (the error grows as the angle cubed), at a
    fraction of slerp's cost."""
    sign = np.where(np.einsum("...i,...i->...", a, b) < 0, -1.0, 1.0).astype(a.dtype)
    mixed = b * sign[..., None]
    mixed -= a
    mixed *= t
    mixed += a
    norm = np.sqrt(np.einsum("...i,...i->...", mixed, mixed))
    mixed /= norm[..., None]
    return mixed


__all__ = ["KINDS", "decode", "encode", "interpolate", "nlerp"]
