"""Twin of ``rust/decouple.rs``: the per-joint algebra of decoupling, in NumPy."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat


def _check(name: str, first: np.ndarray, second: np.ndarray) -> None:
    if first.ndim != 3 or first.shape[-1] != 4 or first.shape != second.shape:
        raise ArgumentError(
            f"argument `{name}`: expected shape {list(first.shape)} (quaternions [F, J, 4]), got {list(second.shape)}"
        )


def decouple_rotations(original: np.ndarray, body: np.ndarray, gain: float = 2.0, exponent: float = 4.0):
    """``E = O B^-1``, ``A = clip((tanh(angle(E)) gain)^exponent, 0, 1)``, ``E* = E^A``,
    ``B' = E*^-1 O``: returns ``(E*, B', A)``."""
    _check("body", original, body)
    for name, value in (("gain", gain), ("exponent", exponent)):
        if not (np.isfinite(value) and value > 0):
            raise ArgumentError(f"argument `{name}`: must be a positive number, got {value}")
    expressive = quat.mul(original, quat.conjugate(body))
    activity = np.clip((np.tanh(quat.angle(expressive)) * gain) ** exponent, 0.0, 1.0)
    return (*_filtered(original, body, activity), activity)


def decouple_with_activity(original: np.ndarray, body: np.ndarray, activity: np.ndarray):
    """``E* = (O B^-1)^A`` and ``B' = E*^-1 O`` for a given activity ``A [F, J]`` in [0, 1]."""
    _check("body", original, body)
    if np.shape(activity) != original.shape[:2]:
        raise ArgumentError(
            f"argument `activity`: expected shape {list(original.shape[:2])} (one value per rotation of `original`), "
            f"got {list(np.shape(activity))}"
        )
    if not np.all((activity >= 0.0) & (activity <= 1.0)):
        raise ArgumentError("argument `activity`: expected values in [0, 1]")
    return _filtered(original, body, activity)


def _filtered(original: np.ndarray, body: np.ndarray, activity: np.ndarray):
    filtered = quat.power(quat.mul(original, quat.conjugate(body)), activity)
    return filtered, quat.mul(quat.conjugate(filtered), original)


def compose_rotations(expressive: np.ndarray, body: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """``expressive^scale * body``."""
    _check("expressive", body, expressive)
    if not np.isfinite(scale):
        raise ArgumentError(f"argument `scale`: must be a finite number, got {scale}")
    return quat.mul(expressive if scale == 1.0 else quat.power(expressive, scale), body)


__all__ = [
    "compose_rotations",
    "decouple_rotations",
    "decouple_with_activity",
]
