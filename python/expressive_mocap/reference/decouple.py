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
    trunk_joints=(),
    trunk_bones=(),
    trunk_scale: float = 1.0,
):
    """One clip's ``(E*, B', A)`` with ``B`` smoothed over ``body_sigma`` frames (each joint's
    quaternions on their predecessor's hemisphere, filtered, normalised) and ``A``, read from
    ``angle(O B^-1) / scale [J]``, over ``activity_sigma`` frames (Gaussians, the ends held; 0: none).
    ``trunk_joints`` (the chain from the hips up; empty: none) are at least as active as the
    angle between the chain's trunk lines (the ``trunk_bones [n, 3]`` each joint carries, summed
    as the chain turns them) in ``O`` and ``B``, divided by ``trunk_scale``, reads."""
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
    trunk_joints = [int(j) for j in trunk_joints]
    bones = np.asarray(trunk_bones, dtype=np.float64).reshape(-1, 3)
    _check_trunk(trunk_joints, bones, trunk_scale, original.shape[1])
    smooth = len(original) > 1
    if body_sigma > 0 and smooth:
        body = quat.smooth(body, body_sigma)
    expressive = quat.mul(original, quat.conjugate(body))  # E = O B^-1
    activity = np.clip((np.tanh(quat.angle(expressive) / scale) * gain) ** exponent, 0.0, 1.0)
    if trunk_joints:
        lean = trunk_lean(original, body, trunk_joints, bones)
        chain = np.clip((np.tanh(lean / trunk_scale) * gain) ** exponent, 0.0, 1.0)
        activity[:, trunk_joints] = np.maximum(activity[:, trunk_joints], chain[:, None])
    if activity_sigma > 0 and smooth:
        from scipy.ndimage import gaussian_filter1d  # here: SciPy takes a tenth of a second to import

        activity = np.clip(gaussian_filter1d(activity, activity_sigma, axis=0, mode="nearest"), 0.0, 1.0)
    filtered = quat.power(expressive, activity)  # E* = E^A
    return filtered, quat.mul(quat.conjugate(filtered), original), activity  # B' = E*^-1 O


def _check_trunk(joints: list[int], bones: np.ndarray, scale: float, n_joints: int) -> None:
    if not joints:
        return
    outside = [j for j in joints if not 0 <= j < n_joints]
    if outside:
        raise ArgumentError(f"argument `trunk_joints`: joint {outside[0]} is not one of the {n_joints} joints")
    if len(bones) != len(joints) or not np.all(np.isfinite(bones)) or np.linalg.norm(bones.sum(0)) <= 1e-12:
        raise ArgumentError(
            f"argument `trunk_bones`: expected one finite bone per trunk joint ({len(joints)}), "
            f"not all of zero length, got {bones.tolist()}"
        )
    if not (np.isfinite(scale) and scale > 0):
        raise ArgumentError(f"argument `trunk_scale`: must be a positive number, got {scale}")


def trunk_lean(original: np.ndarray, body: np.ndarray, joints: list[int], bones: np.ndarray) -> np.ndarray:
    """Per frame, the angle between the trunk lines of ``original`` and ``body``: the ``bones
    [n, 3]`` the chain ``joints`` carries, each turned by the chain down to its joint, summed."""
    lines = []
    for rotations in (original, body):
        turn = np.broadcast_to(np.array([0.0, 0.0, 0.0, 1.0]), rotations.shape[:1] + (4,))
        line = np.zeros(rotations.shape[:1] + (3,))
        for j, bone in zip(joints, np.asarray(bones, dtype=np.float64).reshape(-1, 3)):
            turn = quat.mul(turn, rotations[:, j])
            line = line + quat.rotate(turn, np.broadcast_to(bone, line.shape))
        lines.append(line)
    o, b = lines
    return np.arctan2(np.linalg.norm(np.cross(o, b), axis=-1), np.sum(o * b, axis=-1))


def compose_rotations(expressive: np.ndarray, body: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """``expressive^scale * body``."""
    _check("expressive", body, expressive)
    if not np.isfinite(scale):
        raise ArgumentError(f"argument `scale`: must be a finite number, got {scale}")
    return quat.mul(expressive if scale == 1.0 else quat.power(expressive, scale), body)


def split_rotations_many(
    originals: list,
    bodies: list,
    gain: float,
    exponent: float,
    scale: np.ndarray,
    body_sigmas: list,
    activity_sigmas: list,
    trunk_joints=(),
    trunk_bones=(),
    trunk_scale: float = 1.0,
) -> list:
    """:func:`split_rotations` of each clip, in order (each with its own smoothing widths)."""
    return [
        split_rotations(o, b, gain, exponent, scale, bs, a_s, trunk_joints, trunk_bones, trunk_scale)
        for o, b, bs, a_s in zip(originals, bodies, body_sigmas, activity_sigmas, strict=True)
    ]


__all__ = [
    "compose_rotations",
    "decouple_rotations",
    "split_rotations",
    "split_rotations_many",
    "trunk_lean",
]
