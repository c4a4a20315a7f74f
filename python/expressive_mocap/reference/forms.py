"""Twin of ``rust/forms.rs``: model-ready forms of a batch of clips (rotations as matrix columns,
time derivatives clip by clip, the column sums behind normalisation statistics)."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError


def matrix_entries(q: np.ndarray, columns: int) -> np.ndarray:
    """The rotation matrices of unit quaternions ``q [..., 4]`` in ``q``'s dtype: row after row
    (``columns=3``, 9 values) or their first two columns, column after column (``columns=2``, 6d).
    Written value by value into one array: building the matrix and picking from it took 5x as
    long on a dataset's rotations."""
    x, y, z, w = (q[..., k] for k in range(4))
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    entries = {
        (0, 0): lambda: 1 - 2 * (yy + zz),
        (1, 0): lambda: 2 * (xy + wz),
        (2, 0): lambda: 2 * (xz - wy),
        (0, 1): lambda: 2 * (xy - wz),
        (1, 1): lambda: 1 - 2 * (xx + zz),
        (2, 1): lambda: 2 * (yz + wx),
        (0, 2): lambda: 2 * (xz + wy),
        (1, 2): lambda: 2 * (yz - wx),
        (2, 2): lambda: 1 - 2 * (xx + yy),
    }
    if columns == 3:  # row after row
        order = [(r, c) for r in range(3) for c in range(3)]
    else:  # 6d: column after column
        order = [(r, c) for c in range(2) for r in range(3)]
    out = np.empty(q.shape[:-1] + (len(order),), dtype=q.dtype)
    for k, entry in enumerate(order):
        out[..., k] = entries[entry]()
    return out


def matrix_columns(quats: np.ndarray, columns: int) -> np.ndarray:
    """Unit quaternions ``[N, 4]`` as float32 rotation matrices, ``[N, 9]`` row after row
    (``columns`` 3) or ``[N, 6]`` their first two columns (2), computed in float64 and rounded."""
    if columns not in (2, 3):
        raise ArgumentError(f"argument `columns`: expected 2 (6d) or 3 (the whole matrix), got {columns}")
    return matrix_entries(np.asarray(quats, dtype=np.float64), columns).astype(np.float32)


def clip_gradient(values: np.ndarray, starts: np.ndarray, frame_time: np.ndarray, difference=np.subtract) -> np.ndarray:
    """Per clip ``np.gradient`` of rows ``values [N, ...]`` over time: clips begin at rows
    ``starts [C]`` (rising, the first 0), ``frame_time [N]`` each row's clip's. Central
    differences inside a clip, one-sided at its ends, zero for a one-row clip; no difference spans
    two clips. ``difference(a, b)`` is ``a - b`` (or, for rotations, the rotation vector from
    ``b`` to ``a``: the twin serves both; the kernel only differences)."""
    n = len(values)
    starts, frame_time = np.asarray(starts), np.asarray(frame_time, dtype=np.float64)
    if len(frame_time) != n:
        raise ArgumentError(f"argument `frame_time`: expected one value a row ({n}), got {len(frame_time)}")
    fits = len(starts) > 0 and starts[0] == 0 and bool(np.all(np.diff(starts) >= 0)) and starts[-1] <= n
    if not (fits or (n == 0 and len(starts) == 0)):
        raise ArgumentError(f"argument `starts`: expected rising row indices from 0 to at most {n}")
    out = np.zeros(values.shape[:1] + difference(values[:1], values[:1]).shape[1:])
    if n < 2:
        return out
    ends = np.append(starts[1:], n)
    starts, ends = starts[ends > starts], ends[ends > starts]  # a clip of no frames has no rows
    out[1:-1] = difference(values[2:], values[:-2])
    scale = 2.0 * frame_time
    single = ends - starts == 1
    first, last = starts[~single], ends[~single] - 1
    out[first] = difference(values[first + 1], values[first])
    out[last] = difference(values[last], values[last - 1])
    scale[first], scale[last] = frame_time[first], frame_time[last]
    out[starts[single]] = 0.0
    return out / scale.reshape((-1,) + (1,) * (out.ndim - 1))


def column_totals(arrays: list[np.ndarray], width: int) -> tuple[np.ndarray, np.ndarray]:
    """The float64 sums of the rows of each of ``arrays`` (each ``[n_i, width]``) and of their
    squares, ``([A, width], [A, width])``, each array on its own (so its sums are the same whatever
    arrays come with it)."""
    sums, squares = np.zeros((len(arrays), width)), np.zeros((len(arrays), width))
    for k, array in enumerate(arrays):
        if array.ndim != 2 or array.shape[1] != width:
            raise ArgumentError(f"argument `arrays`: expected shape [n, {width}] (array {k}), got {list(array.shape)}")
        sums[k] = array.sum(axis=0, dtype=np.float64)
        squares[k] = np.einsum("ij,ij->j", array, array, dtype=np.float64)
    return sums, squares
