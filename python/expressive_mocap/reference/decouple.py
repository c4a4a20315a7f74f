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
    return split_rotations(original, body, gain, exponent, np.ones(original.shape[1]), 0.0, 0.0)


def split_rotations(
    original: np.ndarray,
    body: np.ndarray,
    gain: float,
    exponent: float,
    scale: np.ndarray,
    body_sigma: float,
    activity_sigma: float,
):
    """One clip's ``(E*, B', A)`` with ``B`` smoothed over ``body_sigma`` frames (each joint's
    quaternions on their predecessor's hemisphere, filtered, normalised) and ``A``, read from
    ``angle(O B^-1) / scale [J]``, over ``activity_sigma`` frames (Gaussians, the ends held; 0: none)."""
    _check("body", original, body)
    if np.shape(scale) != original.shape[1:2]:
        raise ArgumentError(
            f"argument `scale`: expected shape {list(original.shape[1:2])} (one value per joint of `original`), "
            f"got {list(np.shape(scale))}"
        )
    for name, value in (("gain", gain), ("exponent", exponent), *(("scale", v) for v in np.ravel(scale))):
        if not (np.isfinite(value) and value > 0):
            raise ArgumentError(f"argument `{name}`: must be a positive number, got {value}")
    for name, value in (("body_sigma", body_sigma), ("activity_sigma", activity_sigma)):
        if not (np.isfinite(value) and value >= 0):
            raise ArgumentError(f"argument `{name}`: must be a number >= 0, got {value}")
    smooth = len(original) > 1
    if body_sigma > 0 and smooth:
        body = quat.smooth(body, body_sigma)
    expressive = quat.mul(original, quat.conjugate(body))  # E = O B^-1
    activity = np.clip((np.tanh(quat.angle(expressive) / scale) * gain) ** exponent, 0.0, 1.0)
    if activity_sigma > 0 and smooth:
        from scipy.ndimage import gaussian_filter1d  # here: SciPy takes a tenth of a second to import

        activity = np.clip(gaussian_filter1d(activity, activity_sigma, axis=0, mode="nearest"), 0.0, 1.0)
    filtered = quat.power(expressive, activity)  # E* = E^A
    return filtered, quat.mul(quat.conjugate(filtered), original), activity  # B' = E*^-1 O


def compose_rotations(expressive: np.ndarray, body: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """``expressive^scale * body``."""
    _check("expressive", body, expressive)
    if not np.isfinite(scale):
        raise ArgumentError(f"argument `scale`: must be a finite number, got {scale}")
    return quat.mul(expressive if scale == 1.0 else quat.power(expressive, scale), body)


__all__ = [
    "compose_rotations",
    "decouple_rotations",
    "split_rotations",
]
