"""The kernels behind model-ready datasets (``ops.matrix_columns``, ``ops.clip_gradient``,
``ops.column_totals``): each against an independent computation (SciPy's matrices, NumPy's
gradient clip by clip, float64 sums), under both backends, and the two backends together."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from conftest import BACKENDS
from expressive_mocap import ops
from expressive_mocap.errors import ArgumentError

RNG = np.random.default_rng(11)


def test_matrix_columns_are_scipys_matrices_rounded_to_float32(backend):
    rotations = Rotation.random(5000, random_state=4)
    matrix = rotations.as_matrix()
    q = rotations.as_quat().reshape(50, 100, 4)  # any leading shape
    whole, six = ops.matrix_columns(q, 3), ops.matrix_columns(q, 2)
    assert whole.dtype == six.dtype == np.float32
    assert whole.shape == (50, 100, 9) and six.shape == (50, 100, 6)
    # Computed in float64 and rounded once: within half a float32 ulp below 1 (6e-8), and a hair.
    np.testing.assert_allclose(whole.reshape(-1, 9), matrix.reshape(-1, 9), atol=6e-8, rtol=0)
    first_two = np.concatenate([matrix[:, :, 0], matrix[:, :, 1]], axis=1)  # column after column
    np.testing.assert_allclose(six.reshape(-1, 6), first_two, atol=6e-8, rtol=0)


def per_clip_gradient(values, starts, frame_time):
    """NumPy's gradient of each clip on its own (zero for a clip of one row)."""
    out = np.zeros_like(values)
    ends = np.append(starts[1:], len(values))
    for a, b in zip(starts, ends):
        if b - a > 1:
            out[a:b] = np.gradient(values[a:b], frame_time[a], axis=0)
    return out


def test_clip_gradient_is_numpys_gradient_clip_by_clip(backend):
    values = RNG.normal(size=(400, 7, 3))
    starts = np.array([0, 1, 1, 5, 150, 399])  # a one-row clip, an empty one, a last one-row clip
    frame_time = np.repeat([1 / 30, 1 / 60, 1 / 60, 1 / 120, 1 / 30, 1 / 30], np.diff(np.append(starts, 400)))
    got = ops.clip_gradient(values, starts, frame_time)
    assert got.shape == values.shape
    np.testing.assert_allclose(got, per_clip_gradient(values, starts, frame_time), rtol=1e-12, atol=1e-9)
    # 1-D rows (a yaw angle a frame) keep their shape.
    yaw = values[:, 0, 0]
    np.testing.assert_allclose(ops.clip_gradient(yaw, starts, frame_time), got[:, 0, 0], rtol=0, atol=0)


@pytest.mark.parametrize("starts", [[1, 5], [0, 9, 5], [0, 401], [], [-1, 0]])
def test_clip_gradient_refuses_starts_that_do_not_fit(starts, backend):
    with pytest.raises(ArgumentError, match="starts"):
        ops.clip_gradient(np.zeros((400, 2)), np.array(starts, dtype=np.int64), np.ones(400))
    with pytest.raises(ArgumentError, match="frame_time"):
        ops.clip_gradient(np.zeros((400, 2)), np.array([0]), np.ones(399))


def test_column_totals_are_float64_sums_of_each_arrays_rows_and_squares(backend):
    arrays = [RNG.normal(50, 10, size=(n, 5, 3)).astype(np.float32) for n in (1, 9000, 0, 37)]
    sums, squares = ops.column_totals(arrays)
    assert sums.shape == squares.shape == (4, 5, 3) and sums.dtype == np.float64
    for k, array in enumerate(arrays):
        rows = array.astype(np.float64)
        np.testing.assert_allclose(sums[k], rows.sum(axis=0), rtol=1e-13, atol=1e-300)
        np.testing.assert_allclose(squares[k], (rows * rows).sum(axis=0), rtol=1e-13, atol=1e-300)
    # An array's sums are the same, bit for bit, whatever arrays come with it (batch-free statistics).
    alone = ops.column_totals(arrays[3:])
    np.testing.assert_array_equal(alone[0][0], sums[3])
    np.testing.assert_array_equal(alone[1][0], squares[3])
    with pytest.raises(ArgumentError, match="float32"):
        ops.column_totals([np.concatenate(arrays).astype(np.float64)])


@pytest.mark.skipif(len(BACKENDS) < 2, reason="the Rust extension is not built: nothing to compare")
def test_the_backends_agree():
    q = Rotation.random(3000, random_state=5).as_quat()
    values, starts, frame_time = RNG.normal(size=(3000, 12)), np.array([0, 700, 701, 2000]), np.full(3000, 0.02)
    arrays = [RNG.normal(size=(n, 12)).astype(np.float32) for n in (3000, 5, 20000)]
    results = {}
    for name in BACKENDS:
        with em.use_backend(name):
            results[name] = (
                ops.matrix_columns(q, 2),
                ops.clip_gradient(values, starts, frame_time),
                *ops.column_totals(arrays),
            )
    rust, twin = results["rust"], results["numpy"]
    np.testing.assert_array_equal(rust[0], twin[0])  # the same formula in float64, rounded once
    np.testing.assert_array_equal(rust[1], twin[1])  # the same differences and divisions
    np.testing.assert_allclose(rust[2], twin[2], rtol=1e-12)  # sums in another order
    np.testing.assert_allclose(rust[3], twin[3], rtol=1e-12)
