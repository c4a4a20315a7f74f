"""Twin of ``rust/ik.rs``: two-bone inverse kinematics, vectorised over frames."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat

# Of the chain's length: the solver stops short of a fully straight knee (a knee straightened to
# the last 0.01% would flip). The Rust kernel's constant is the same.
REACH = 0.9999


def _about(axis: np.ndarray, radians: np.ndarray) -> np.ndarray:
    """Rotations ``[F, 4]`` by ``radians [F]`` about unit ``axis [F, 3]``."""
    return np.concatenate([axis * np.sin(radians / 2)[:, None], np.cos(radians / 2)[:, None]], axis=1)


def _unit(v: np.ndarray) -> np.ndarray:
    """Unit vectors along ``v [F, 3]``; +X where ``v`` is zero (its rotation angle is 0 then)."""
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(norm > 1e-12, v / np.where(norm > 1e-12, norm, 1.0), [1.0, 0.0, 0.0])


def _angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(np.sum(_unit(a) * _unit(b), axis=-1), -1.0, 1.0))


def _solve(
    root: np.ndarray,
    upper: np.ndarray,
    lower: np.ndarray,
    upper_bone: np.ndarray,
    lower_bone: np.ndarray,
    target: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """The solver itself (``expressive_mocap.body.ik.two_bone_ik`` says what it does)."""
    a = root
    b = a + quat.rotate(upper, upper_bone)
    c = b + quat.rotate(lower, lower_bone)
    thigh, shin = np.linalg.norm(upper_bone, axis=-1), np.linalg.norm(lower_bone, axis=-1)
    # Bounds relative to the chain's length: the same pose in centimetres or metres. Never
    # straighter than REACH, unless the chain already is: a target where its end is moves nothing.
    longest = np.maximum((thigh + shin) * REACH, np.linalg.norm(c - a, axis=1))
    reach = np.clip(np.linalg.norm(target - a, axis=1), np.abs(thigh - shin) + 1e-5 * (thigh + shin), longest)
    # Angles at the hip (between hip-ankle and thigh) and at the knee, now and wanted.
    hip_now, knee_now = _angle_between(c - a, b - a), _angle_between(a - b, c - b)
    hip_wanted = np.arccos(np.clip((shin**2 - thigh**2 - reach**2) / (-2 * thigh * reach), -1, 1))
    knee_wanted = np.arccos(np.clip((reach**2 - thigh**2 - shin**2) / (-2 * thigh * shin), -1, 1))
    bend_axis = _unit(np.cross(c - a, b - a))
    bend_hip = _about(bend_axis, hip_wanted - hip_now)
    bend_knee = _about(bend_axis, knee_wanted - knee_now)
    # Then turn the whole leg about the hip so the end points at the target.
    c_bent = a + quat.rotate(bend_hip, b - a) + quat.rotate(quat.mul(bend_knee, bend_hip), c - b)
    aim = _about(_unit(np.cross(c_bent - a, target - a)), _angle_between(c_bent - a, target - a))
    return quat.mul(aim, quat.mul(bend_hip, upper)), quat.mul(aim, quat.mul(bend_knee, quat.mul(bend_hip, lower)))


def two_bone_ik(root, upper, lower, upper_bone, lower_bone, target) -> tuple[np.ndarray, np.ndarray]:
    """New world rotations ``(upper, lower)`` ``[F, 4]`` (see ``expressive_mocap.body.ik.two_bone_ik``);
    every argument has a row a frame."""
    frames = len(root)
    for name, value, width in (
        ("root", root, 3),
        ("upper", upper, 4),
        ("lower", lower, 4),
        ("upper_bone", upper_bone, 3),
        ("lower_bone", lower_bone, 3),
        ("target", target, 3),
    ):
        if np.shape(value) != (frames, width):
            raise ArgumentError(f"argument `{name}`: expected shape [{frames}, {width}], got {list(np.shape(value))}")
    return _solve(root, upper, lower, upper_bone, lower_bone, target)


__all__ = ["two_bone_ik"]
