"""Argument checks shared by the kernel wrappers: arrays coerced to the kernels' dtypes and
shapes, or an ArgumentError naming the argument."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations.orders import axes_of


def _array(name: str, value, dtype, kinds: str = "biuf") -> np.ndarray:
    """``value`` as a C-contiguous array of ``dtype``; an ArgumentError naming the argument when its
    dtype kind is not one of ``kinds`` (numbers; integers only where indices are expected)."""
    array = np.asarray(value)
    if array.dtype.kind not in kinds:
        wanted = "integers" if kinds == "iu" else "numbers"
        raise ArgumentError(f"argument `{name}`: expected an array of {wanted}, got dtype {array.dtype}")
    return np.ascontiguousarray(array, dtype=dtype)


def _f64(name: str, array, last: int) -> np.ndarray:
    array = _array(name, array, np.float64)
    if array.ndim < 2 or array.shape[-1] != last:
        raise ArgumentError(f"argument `{name}`: expected shape [..., J, {last}], got {list(array.shape)}")
    return array


def _orders(orders, joints: int) -> np.ndarray:
    """Orders as a ``[J, 3]`` uint8 array from one order ("ZXY") or one per joint."""
    if isinstance(orders, str):
        orders = [orders] * joints
    axes = np.array([axes_of(o) if isinstance(o, str) else o for o in orders], dtype=np.uint8)
    if axes.shape != (joints, 3):
        raise ArgumentError(f"argument `orders`: expected one order or {joints} orders, got {axes.shape[0]}")
    return axes


def _frames(array: np.ndarray) -> np.ndarray:
    """``[..., J, k]`` as ``[F, J, k]``, all leading dimensions folded into frames."""
    return array.reshape(-1, *array.shape[-2:])


def _float(name: str, array) -> np.ndarray:
    """``array`` as a C-contiguous float32 or float64 array (float32 kept, other numbers float64)."""
    array = np.asarray(array)
    return _array(name, array, np.float32 if array.dtype == np.float32 else np.float64)


__all__ = []
