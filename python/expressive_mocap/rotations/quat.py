"""Quaternion algebra on arrays ``[..., 4]`` (x, y, z, w), in NumPy.

Used by the reference kernels and by the package wherever a quaternion operation is not a
hot loop (resampling, editing). ``mul(a, b)`` is the Hamilton product: rotate by ``b``, then ``a``.
"""

from __future__ import annotations

import numpy as np


def mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b`` of quaternion arrays (broadcasting)."""
    ax, ay, az, aw = np.moveaxis(np.asarray(a, dtype=np.float64), -1, 0)
    bx, by, bz, bw = np.moveaxis(np.asarray(b, dtype=np.float64), -1, 0)
    return np.stack(
        [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ],
        axis=-1,
    )


def conjugate(q: np.ndarray) -> np.ndarray:
    """Inverse of unit quaternions."""
    return np.asarray(q, dtype=np.float64) * np.array([-1.0, -1.0, -1.0, 1.0])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of vectors ``[..., 3]`` (broadcast): ``np.cross``'s numbers, without its
    axis handling, which costs more than the products on small arrays."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    x = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    y = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    z = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return np.stack([x, y, z], axis=-1)


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v [..., 3]`` by unit quaternions ``q [..., 4]``."""
    u, w = q[..., :3], q[..., 3:]
    t = 2.0 * cross(u, v)
    return v + w * t + cross(u, t)


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices ``[..., 3, 3]`` of unit quaternions."""
    x, y, z, w = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def normalize(q: np.ndarray) -> np.ndarray:
    """Scale quaternions to unit length."""
    q = np.asarray(q)
    return q / np.sqrt(np.einsum("...i,...i->...", q, q))[..., None]  # half np.linalg.norm's time


def slerp(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical interpolation from ``a`` to ``b`` by ``t`` (broadcast to ``[..., 1]``), shortest arc."""
    t = np.asarray(t, dtype=np.float64)[..., None]
    dot = np.sum(a * b, axis=-1, keepdims=True)
    b = np.where(dot < 0, -b, b)
    dot = np.abs(dot)
    angle = np.arccos(np.clip(dot, -1.0, 1.0))
    sin = np.sin(angle)
    near = sin < 1e-9  # nearly the same rotation: linear interpolation is exact enough
    safe = np.where(near, 1.0, sin)
    wa = np.where(near, 1.0 - t, np.sin((1.0 - t) * angle) / safe)
    wb = np.where(near, t, np.sin(t * angle) / safe)
    return normalize(wa * a + wb * b)


def about(axis: str, degrees) -> np.ndarray:
    """Rotations ``[..., 4]`` by ``degrees`` about the ``axis`` "X", "Y" or "Z"."""
    half = np.radians(np.asarray(degrees, dtype=np.float64)) / 2
    q = np.zeros(half.shape + (4,))
    q[..., "XYZ".index(axis)] = np.sin(half)
    q[..., 3] = np.cos(half)
    return q


def angle(q: np.ndarray) -> np.ndarray:
    """Rotation angles ``[...]`` in ``[0, pi]`` of unit quaternions ``[..., 4]``."""
    return 2.0 * np.arctan2(np.linalg.norm(q[..., :3], axis=-1), np.abs(q[..., 3]))


def power(q: np.ndarray, s) -> np.ndarray:
    """``q^s``: the rotation about the same axis by ``s`` times the angle (``s`` broadcasts to ``[...]``)."""
    q = np.where(q[..., 3:] < 0, -q, q)  # w >= 0: angle in [0, pi], q^0 = identity
    sin_half = np.linalg.norm(q[..., :3], axis=-1, keepdims=True)
    half = np.arctan2(sin_half, q[..., 3:]) * np.asarray(s, dtype=np.float64)[..., None]
    axis = q[..., :3] / np.where(sin_half < 1e-15, 1.0, sin_half)
    out = np.concatenate([axis * np.sin(half), np.cos(half)], axis=-1)
    return np.where(sin_half < 1e-15, np.array([0.0, 0.0, 0.0, 1.0]), out)


def log(q: np.ndarray) -> np.ndarray:
    """Rotation vectors ``[..., 3]`` (axis times angle, radians) of unit quaternions (shortest arc: w >= 0)."""
    q = np.where(q[..., 3:] < 0, -q, q)
    sin_half = np.linalg.norm(q[..., :3], axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(sin_half, q[..., 3:])
    return q[..., :3] * np.where(sin_half < 1e-12, 2.0, angle / np.where(sin_half < 1e-12, 1.0, sin_half))


def exp(v: np.ndarray) -> np.ndarray:
    """Unit quaternions of rotation vectors ``[..., 3]``: the inverse of :func:`log`."""
    angle = np.linalg.norm(v, axis=-1, keepdims=True)
    scale = np.where(angle < 1e-12, 0.5, np.sin(angle / 2) / np.where(angle < 1e-12, 1.0, angle))
    return np.concatenate([v * scale, np.cos(angle / 2)], axis=-1)


def between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The shortest-arc rotations ``[..., 4]`` taking directions ``u`` to ``v`` (``[..., 3]``, any
    length); for opposite directions, a half turn about an axis perpendicular to ``u``."""
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    axis = np.cross(u, v)
    w = 1.0 + np.sum(u * v, axis=-1, keepdims=True)
    # Opposite: any axis perpendicular to u (x or y, whichever u is further from).
    other = np.where(np.abs(u[..., :1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    flip = np.cross(u, other)
    opposite = w < 1e-12
    q = np.where(opposite, np.concatenate([flip, np.zeros_like(w)], axis=-1), np.concatenate([axis, w], axis=-1))
    return normalize(q)


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Unit quaternions ``[..., 4]`` of rotation matrices ``[..., 3, 3]`` (Shepperd's method: the
    largest of w, x, y, z is found first, so no branch divides by a small number)."""
    m = np.asarray(m, dtype=np.float64)
    trace = m[..., 0, 0] + m[..., 1, 1] + m[..., 2, 2]
    candidates = np.stack(
        [
            np.stack(
                [
                    1 + 2 * m[..., 0, 0] - trace,
                    m[..., 0, 1] + m[..., 1, 0],
                    m[..., 0, 2] + m[..., 2, 0],
                    m[..., 2, 1] - m[..., 1, 2],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 0, 1] + m[..., 1, 0],
                    1 + 2 * m[..., 1, 1] - trace,
                    m[..., 1, 2] + m[..., 2, 1],
                    m[..., 0, 2] - m[..., 2, 0],
                ],
                -1,
            ),
            np.stack(
                [
                    m[..., 0, 2] + m[..., 2, 0],
                    m[..., 1, 2] + m[..., 2, 1],
                    1 + 2 * m[..., 2, 2] - trace,
                    m[..., 1, 0] - m[..., 0, 1],
                ],
                -1,
            ),
            np.stack(
                [m[..., 2, 1] - m[..., 1, 2], m[..., 0, 2] - m[..., 2, 0], m[..., 1, 0] - m[..., 0, 1], 1 + trace], -1
            ),
        ],
        axis=-2,
    )  # row k is 4 x_k times the quaternion, with x_k the k-th component
    diagonal = np.stack(
        [1 + 2 * m[..., 0, 0] - trace, 1 + 2 * m[..., 1, 1] - trace, 1 + 2 * m[..., 2, 2] - trace, 1 + trace], -1
    )
    best = np.argmax(diagonal, axis=-1)
    q = np.take_along_axis(candidates, best[..., None, None], axis=-2)[..., 0, :]
    return normalize(q)


# --------------------------------------------------------------------------- means and resampling


def mean_rotation(quats: np.ndarray) -> np.ndarray:
    """Means of unit quaternions over the first axis, ``[F, ..., 4] -> [..., 4]`` (e.g. one
    rotation per joint from ``[F, J, 4]``): each put on the first one's hemisphere, summed and
    normalised (good for rotations that stay well within 90 degrees of each other)."""
    quats = np.asarray(quats, dtype=np.float64)
    aligned = np.where(np.sum(quats * quats[:1], axis=-1, keepdims=True) < 0, -quats, quats)
    return _normalised_sum(aligned.sum(axis=0), quats[0])


def mean_rotations(quats: np.ndarray, lengths) -> np.ndarray:
    """:func:`mean_rotation` of each run of ``lengths`` consecutive quaternions of ``quats
    [sum(lengths), ..., 4]`` (clips laid end to end) -> ``[len(lengths), ..., 4]``, in a few calls
    for them all: each run on its own first quaternion's hemisphere. A run of none: the identity.
    (Run by run, the small calls held the GIL, and a ``preprocess --model`` run's model thread
    spent a sixth of its time in them.)"""
    quats = np.asarray(quats, dtype=np.float64)
    counts = np.asarray(lengths, dtype=np.int64)
    means = np.zeros((len(counts),) + quats.shape[1:])
    means[..., 3] = 1.0
    used = counts > 0
    if not used.any():
        return means
    starts = (np.cumsum(counts) - counts)[used]
    first = np.repeat(quats[starts], counts[used], axis=0)
    aligned = np.where(np.sum(quats * first, axis=-1, keepdims=True) < 0, -quats, quats)
    means[used] = _normalised_sum(np.add.reduceat(aligned, starts, axis=0), quats[starts])
    return means


def _normalised_sum(total: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """``total`` scaled to unit length; ``fallback`` where it is (nearly) zero."""
    norm = np.linalg.norm(total, axis=-1, keepdims=True)
    return np.where(norm > 1e-12, total / np.where(norm > 1e-12, norm, 1.0), fallback)


def smooth(quats: np.ndarray, sigma: float) -> np.ndarray:
    """Unit quaternions ``[F, ..., 4]`` smoothed over frames by a Gaussian of ``sigma`` frames
    (zero phase; the ends held): each frame put on its predecessor's hemisphere, the components
    filtered, then normalised. For rotations that change little between frames (a few degrees),
    where this equals filtering the rotation itself."""
    from scipy.ndimage import gaussian_filter1d  # here: SciPy takes a tenth of a second to import

    quats = np.array(quats, dtype=np.float64)
    if sigma <= 0 or len(quats) < 2:
        return quats
    flips = np.cumprod(np.where(np.sum(quats[1:] * quats[:-1], axis=-1) < 0, -1.0, 1.0), axis=0)
    quats[1:] *= flips[..., None]
    return normalize(gaussian_filter1d(quats, sigma, axis=0, mode="nearest"))


def spanning_positions(n_from: int, n_to: int) -> np.ndarray:
    """``n_to`` fractional frame positions spread evenly over frames ``0 .. n_from - 1`` (the
    first on the first frame, the last on the last): the positions that stretch or squeeze a
    sequence of ``n_from`` frames to ``n_to`` for :func:`resample`."""
    return np.linspace(0.0, n_from - 1, n_to)


def resample(values: np.ndarray, positions: np.ndarray, *, rotations: bool = True) -> np.ndarray:
    """``values [F, ...]`` (``F >= 2`` frames) at fractional frame ``positions [N]`` in
    ``[0, F - 1]``: ``[N, ...]``, each between its two neighbouring frames by slerp
    (``rotations=True``: unit quaternions ``[F, ..., 4]``) or linearly (``rotations=False``: any
    values, e.g. translations or DOF trajectories). The one time resampler of the package."""
    values = np.asarray(values)
    positions = np.asarray(positions, dtype=np.float64)
    i0 = np.minimum(np.floor(positions).astype(int), len(values) - 2)
    t = positions - i0
    if rotations:
        return slerp(values[i0], values[i0 + 1], t.reshape((-1,) + (1,) * (values.ndim - 2)))
    t = t.reshape((-1,) + (1,) * (values.ndim - 1))
    return (1 - t) * values[i0] + t * values[i0 + 1]


__all__ = [
    "about",
    "cross",
    "angle",
    "conjugate",
    "exp",
    "log",
    "mean_rotation",
    "mean_rotations",
    "mul",
    "normalize",
    "power",
    "resample",
    "rotate",
    "slerp",
    "smooth",
    "spanning_positions",
    "to_matrix",
]
