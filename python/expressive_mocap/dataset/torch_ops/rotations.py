"""Rotation conversions in PyTorch, in the package's conventions, batched over any leading axes and
differentiable.

- quaternions ``[..., 4]`` are x, y, z, w (the scalar last); the functions that return one give
  ``w >= 0``, as :func:`expressive_mocap.dataset.representations.decode` does;
- rotation matrices ``[..., 3, 3]`` act on column vectors (``v' = R v``), so a matrix's columns
  are the rotated x, y and z axes; the ``"matrix"`` form of a dataset is its 9 entries row after row;
- ``"6d"`` ``[..., 6]`` is the first two columns of the matrix, column after column
  (``R[:, 0]`` then ``R[:, 1]``), turned back into a rotation by Gram-Schmidt (the first column
  keeps its direction), as ``preprocess --rotations 6d`` stores it;
- axis-angle ``[..., 3]`` is the rotation vector: the unit axis times the angle in radians, the
  angle in [0, pi];
- Euler angles ``[..., 3]`` are degrees about the axes of an order (``"ZXY"``: Z, then X, then Y),
  intrinsic, the first axis outermost, as BVH channels are written (``R = R_Z R_X R_Y``); the
  middle angle comes back in [-90, 90]. A dataset's form is ``"euler:ORDER"``.

Every conversion goes through the matrix or the quaternion. Near the identity and near a half
turn the formulas switch to series or pick the well-conditioned branch, so values and gradients
stay finite there.
"""

from __future__ import annotations

import torch

from ...errors import ArgumentError

FORMS = {"quaternion": 4, "6d": 6, "matrix": 9, "axis-angle": 3}

# Below this squared sine of the half angle (or squared angle), the series replace the quotients.
_SMALL = 1e-12


def _shaped(name: str, x, tail: tuple[int, ...]) -> torch.Tensor:
    if not isinstance(x, torch.Tensor):
        raise ArgumentError(f"argument `{name}`: expected a torch.Tensor, got {type(x).__name__}")
    if tuple(x.shape[len(x.shape) - len(tail) :]) != tail or x.dim() < len(tail):
        shape = "[..., " + ", ".join(map(str, tail)) + "]"
        raise ArgumentError(f"argument `{name}`: expected shape {shape}, got {list(x.shape)}")
    if not x.is_floating_point():
        raise ArgumentError(f"argument `{name}`: expected a floating-point tensor, got {x.dtype}")
    return x


def form_size(form: str) -> int:
    """The values a rotation of ``form`` takes: :data:`FORMS`, or 3 for ``"euler:ORDER"``
    (``"euler"`` alone: ZXY). An :class:`~expressive_mocap.errors.ArgumentError` names a bad form."""
    if isinstance(form, str) and form.split(":")[0] == "euler":
        _euler_order(form)
        return 3
    if form not in FORMS:
        raise ArgumentError(f"argument `form`: expected one of {', '.join(FORMS)} or euler:ORDER, got {form!r}")
    return FORMS[form]


def _euler_order(form: str) -> str:
    order = form.partition(":")[2].upper() or "ZXY"
    if sorted(order) != ["X", "Y", "Z"]:
        raise ArgumentError(f"argument `form`: an Euler order is X, Y and Z once each (euler:ZXY), got {form!r}")
    return order


# --------------------------------------------------------------------------- quaternion algebra


def quat_mul(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """Hamilton product ``a * b`` (broadcasting): rotate by ``b``, then by ``a``."""
    _shaped("a", a, (4,))
    _shaped("b", b, (4,))
    ax, ay, az, aw = a.unbind(-1)
    bx, by, bz, bw = b.unbind(-1)
    return torch.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        dim=-1,
    )


def quat_conjugate(q: torch.Tensor) -> torch.Tensor:
    """The inverse of unit quaternions."""
    _shaped("q", q, (4,))
    return torch.cat([-q[..., :3], q[..., 3:]], dim=-1)


def quat_normalize(q: torch.Tensor) -> torch.Tensor:
    """Quaternions scaled to unit length."""
    _shaped("q", q, (4,))
    return q / torch.linalg.vector_norm(q, dim=-1, keepdim=True)


def quat_rotate(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Vectors ``v [..., 3]`` rotated by unit quaternions ``q [..., 4]`` (broadcasting)."""
    _shaped("q", q, (4,))
    _shaped("v", v, (3,))
    u, w = q[..., :3], q[..., 3:]
    u, v = torch.broadcast_tensors(u, v)
    t = 2.0 * torch.linalg.cross(u, v)
    return v + w * t + torch.linalg.cross(u, t)


def _positive(q: torch.Tensor) -> torch.Tensor:
    """``q`` or ``-q``, whichever has ``w >= 0``."""
    return torch.where(q[..., 3:] < 0, -q, q)


# --------------------------------------------------------------------------- matrix <-> quaternion


def quat_to_matrix(q: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``[..., 3, 3]`` of quaternions ``[..., 4]``: for unit ones the package's
    formula; any other non-zero quaternion gives the rotation of its unit one (each product is
    divided by the squared norm), so a network's raw output needs no normalising first."""
    _shaped("q", q, (4,))
    x, y, z, w = q.unbind(-1)
    s = 2.0 / (x * x + y * y + z * z + w * w)
    xx, yy, zz = s * x * x, s * y * y, s * z * z
    xy, xz, yz, wx, wy, wz = s * x * y, s * x * z, s * y * z, s * w * x, s * w * y, s * w * z
    rows = [
        torch.stack([1 - (yy + zz), xy - wz, xz + wy], -1),
        torch.stack([xy + wz, 1 - (xx + zz), yz - wx], -1),
        torch.stack([xz - wy, yz + wx, 1 - (xx + yy)], -1),
    ]
    return torch.stack(rows, dim=-2)


def matrix_to_quat(m: torch.Tensor) -> torch.Tensor:
    """Unit quaternions ``[..., 4]`` (``w >= 0``) of rotation matrices ``[..., 3, 3]`` (Shepperd's
    method, as the package's: of the four candidate rows, each 4 x_k times the quaternion, the one
    of the largest x_k is normalised, so nothing divides by a small number). A matrix slightly off
    a rotation gives a nearby rotation's quaternion."""
    _shaped("m", m, (3, 3))
    m00, m01, m02 = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    m10, m11, m12 = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    m20, m21, m22 = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    trace = m00 + m11 + m22
    d0, d1, d2, d3 = 1 + 2 * m00 - trace, 1 + 2 * m11 - trace, 1 + 2 * m22 - trace, 1 + trace
    candidates = torch.stack(
        [
            torch.stack([d0, m01 + m10, m02 + m20, m21 - m12], -1),
            torch.stack([m01 + m10, d1, m12 + m21, m02 - m20], -1),
            torch.stack([m02 + m20, m12 + m21, d2, m10 - m01], -1),
            torch.stack([m21 - m12, m02 - m20, m10 - m01, d3], -1),
        ],
        dim=-2,
    )
    best = torch.stack([d0, d1, d2, d3], -1).argmax(-1)
    index = best[..., None, None].expand(*best.shape, 1, 4)
    q = torch.gather(candidates, -2, index).squeeze(-2)
    return _positive(q / torch.linalg.vector_norm(q, dim=-1, keepdim=True))


# --------------------------------------------------------------------------- 6D


def matrix_to_sixd(m: torch.Tensor) -> torch.Tensor:
    """The 6D form ``[..., 6]`` of rotation matrices: column 0, then column 1."""
    _shaped("m", m, (3, 3))
    return torch.cat([m[..., :, 0], m[..., :, 1]], dim=-1)


def sixd_to_matrix(d: torch.Tensor) -> torch.Tensor:
    """Rotation matrices ``[..., 3, 3]`` of 6D values (any two independent vectors): the first
    normalised is column 0, the second made orthogonal to it and normalised is column 1, their
    cross product column 2 (the package's Gram-Schmidt)."""
    _shaped("d", d, (6,))
    a, b = d[..., :3], d[..., 3:]
    first = a / torch.linalg.vector_norm(a, dim=-1, keepdim=True)
    second = b - first * (first * b).sum(-1, keepdim=True)
    second = second / torch.linalg.vector_norm(second, dim=-1, keepdim=True)
    third = torch.linalg.cross(first, second)
    return torch.stack([first, second, third], dim=-1)


def quat_to_sixd(q: torch.Tensor) -> torch.Tensor:
    """The 6D form ``[..., 6]`` of quaternions: the matrix's columns 0 and 1."""
    return matrix_to_sixd(quat_to_matrix(q))


def sixd_to_quat(d: torch.Tensor) -> torch.Tensor:
    """Unit quaternions (``w >= 0``) of 6D values, through :func:`sixd_to_matrix`."""
    return matrix_to_quat(sixd_to_matrix(d))


# --------------------------------------------------------------------------- axis-angle


def quat_to_axis_angle(q: torch.Tensor) -> torch.Tensor:
    """Rotation vectors ``[..., 3]`` (axis times angle, the angle in [0, pi]) of unit quaternions:
    ``q`` is first put on ``w >= 0``, then ``xyz * 2 atan2(|xyz|, w) / |xyz|``; near the identity
    the quotient is its series ``(2 / w) (1 - |xyz|^2 / (3 w^2))``."""
    _shaped("q", q, (4,))
    q = _positive(q)
    v, w = q[..., :3], q[..., 3:]
    s2 = (v * v).sum(-1, keepdim=True)
    small = s2 < _SMALL
    s = torch.sqrt(torch.where(small, torch.ones_like(s2), s2))
    exact = 2.0 * torch.atan2(s, w) / s
    w_safe = torch.where(small, w, torch.ones_like(w))  # w ~ 1 wherever the series is used
    series = (2.0 / w_safe) * (1.0 - s2 / (3.0 * w_safe * w_safe))
    return v * torch.where(small, series, exact)


def axis_angle_to_quat(v: torch.Tensor) -> torch.Tensor:
    """Unit quaternions ``[..., 4]`` of rotation vectors ``[..., 3]`` (any angle; ``w < 0``
    beyond a half turn, as the package's ``quat.exp``): ``[axis sin(a / 2), cos(a / 2)]``; near
    zero ``sin(a / 2) / a`` is its series ``1/2 - a^2 / 48``."""
    _shaped("v", v, (3,))
    a2 = (v * v).sum(-1, keepdim=True)
    small = a2 < _SMALL
    a = torch.sqrt(torch.where(small, torch.ones_like(a2), a2))
    scale = torch.where(small, 0.5 - a2 / 48.0, torch.sin(a / 2) / a)
    cos = torch.where(small, 1.0 - a2 / 8.0, torch.cos(a / 2))
    return torch.cat([v * scale, cos], dim=-1)


def axis_angle_to_matrix(v: torch.Tensor) -> torch.Tensor:
    """Rotation matrices of rotation vectors, through :func:`axis_angle_to_quat`."""
    return quat_to_matrix(axis_angle_to_quat(v))


def matrix_to_axis_angle(m: torch.Tensor) -> torch.Tensor:
    """Rotation vectors of rotation matrices, through :func:`matrix_to_quat`."""
    return quat_to_axis_angle(matrix_to_quat(m))


# --------------------------------------------------------------------------- Euler angles


def euler_to_quat(angles: torch.Tensor, order: str = "ZXY") -> torch.Tensor:
    """Unit quaternions ``[..., 4]`` (``w >= 0``) of Euler angles ``[..., 3]`` in degrees about
    the axes of ``order``, intrinsic (the first axis outermost): ``q = q_1 q_2 q_3``."""
    _shaped("angles", angles, (3,))
    order = _euler_order(f"euler:{order}")
    half = torch.deg2rad(angles) / 2
    zero = torch.zeros_like(half[..., 0])
    q = None
    for k, axis in enumerate(order):
        c, s = torch.cos(half[..., k]), torch.sin(half[..., k])
        parts = [s if "XYZ".index(axis) == i else zero for i in range(3)]
        turn = torch.stack([*parts, c], -1)
        q = turn if q is None else quat_mul(q, turn)
    assert q is not None  # three axes
    return _positive(q)


def matrix_to_euler(m: torch.Tensor, order: str = "ZXY") -> torch.Tensor:
    """Euler angles ``[..., 3]`` (degrees, ``order``, intrinsic) of rotation matrices: with the
    axes i, j, k of ``order``, ``R = R_i R_j R_k``, the middle angle ``asin(+-R[i, k])`` in
    [-90, 90] and the outer two by ``atan2`` (at 90 exactly, the gimbal lock, one of the two
    rotations that share an axis takes it all)."""
    _shaped("m", m, (3, 3))
    i, j, k = ("XYZ".index(a) for a in _euler_order(f"euler:{order}"))
    sign = 1.0 if (j - i) % 3 == 1 else -1.0  # a cyclic order (XYZ, YZX, ZXY) or not
    middle = torch.asin(torch.clamp(sign * m[..., i, k], -1.0, 1.0))
    first = torch.atan2(-sign * m[..., j, k], m[..., k, k])
    last = torch.atan2(-sign * m[..., i, j], m[..., i, i])
    return torch.rad2deg(torch.stack([first, middle, last], -1))


def quat_to_euler(q: torch.Tensor, order: str = "ZXY") -> torch.Tensor:
    """Euler angles ``[..., 3]`` (degrees, ``order``) of quaternions, through the matrix."""
    return matrix_to_euler(quat_to_matrix(q), order)


# --------------------------------------------------------------------------- a dataset's forms


def to_matrix(values: torch.Tensor, form: str) -> torch.Tensor:
    """Rotation matrices ``[..., 3, 3]`` of rotations stored in ``form`` (``"quaternion"``,
    ``"6d"``, ``"matrix"``: 9 entries row after row, ``"axis-angle"`` or ``"euler:ORDER"``;
    ``[..., n]``)."""
    n = form_size(form)
    _shaped("values", values, (n,))
    if form.startswith("euler"):
        return quat_to_matrix(euler_to_quat(values, _euler_order(form)))
    if form == "quaternion":
        return quat_to_matrix(values)
    if form == "6d":
        return sixd_to_matrix(values)
    if form == "axis-angle":
        return axis_angle_to_matrix(values)
    return values.reshape(*values.shape[:-1], 3, 3)


def to_quat(values: torch.Tensor, form: str) -> torch.Tensor:
    """Unit quaternions ``[..., 4]`` (``w >= 0``) of rotations in ``form`` ``[..., n]``: the torch
    twin of :func:`expressive_mocap.dataset.representations.decode` (a ``"matrix"`` slightly off a
    rotation still decodes)."""
    n = form_size(form)
    _shaped("values", values, (n,))
    if form == "quaternion":
        return _positive(values / torch.linalg.vector_norm(values, dim=-1, keepdim=True))
    if form == "axis-angle":
        return _positive(axis_angle_to_quat(values))
    if form.startswith("euler"):
        return euler_to_quat(values, _euler_order(form))
    return matrix_to_quat(to_matrix(values, form))


def from_quat(q: torch.Tensor, form: str) -> torch.Tensor:
    """Unit quaternions ``[..., 4]`` as ``form`` ``[..., n]``: the torch twin of
    :func:`expressive_mocap.dataset.representations.encode` (quaternions are returned as they are)."""
    form_size(form)
    _shaped("q", q, (4,))
    if form == "quaternion":
        return q
    if form == "axis-angle":
        return quat_to_axis_angle(q)
    if form.startswith("euler"):
        return quat_to_euler(q, _euler_order(form))
    if form == "6d":
        return quat_to_sixd(q)
    m = quat_to_matrix(q)
    return m.reshape(*m.shape[:-2], 9)


__all__ = [
    "FORMS",
    "axis_angle_to_matrix",
    "axis_angle_to_quat",
    "euler_to_quat",
    "form_size",
    "from_quat",
    "matrix_to_axis_angle",
    "matrix_to_euler",
    "matrix_to_quat",
    "matrix_to_sixd",
    "quat_conjugate",
    "quat_mul",
    "quat_normalize",
    "quat_rotate",
    "quat_to_axis_angle",
    "quat_to_euler",
    "quat_to_matrix",
    "quat_to_sixd",
    "sixd_to_matrix",
    "sixd_to_quat",
    "to_matrix",
    "to_quat",
]
