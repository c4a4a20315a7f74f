"""Two-bone inverse kinematics (a leg: upper leg, lower leg, foot), on arrays of frames.

Used by the demo to plant its feet on a footstep plan and by the exaggeration's foot locking to
keep a stance foot where the input had it.
"""

from __future__ import annotations

import numpy as np

from . import quat

REACH = 0.9999  # of the chain's length: the solver stops short of a fully straight knee


def _about(axis: np.ndarray, radians: np.ndarray) -> np.ndarray:
    """Rotations ``[F, 4]`` by ``radians [F]`` about unit ``axis [F, 3]``."""
    return np.concatenate([axis * np.sin(radians / 2)[:, None], np.cos(radians / 2)[:, None]], axis=1)


def _unit(v: np.ndarray) -> np.ndarray:
    """Unit vectors along ``v [F, 3]``; +X where ``v`` is zero (its rotation angle is 0 then)."""
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(norm > 1e-12, v / np.where(norm > 1e-12, norm, 1.0), [1.0, 0.0, 0.0])


def _angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(np.sum(_unit(a) * _unit(b), axis=-1), -1.0, 1.0))


def two_bone_ik(
    root: np.ndarray,
    upper: np.ndarray,
    lower: np.ndarray,
    upper_bone: np.ndarray,
    lower_bone: np.ndarray,
    target: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations of a two-bone chain turned so that its end reaches ``target``.

    Args:
        root: float[F, 3], the chain's first joint (the hip) in world space.
        upper, lower: float[F, 4] (x, y, z, w), world rotations of the first joint (thigh) and the
            second (shin).
        upper_bone: float[3] or [F, 3], the second joint's offset in the first joint's frame (the
            knee's local translation).
        lower_bone: float[3] or [F, 3], the end's offset in the second joint's frame (the ankle's
            local translation).
        target: float[F, 3], where the end should be.

    Returns:
        The new world rotations ``(upper, lower)``, each ``[F, 4]``. The chain bends in its own
        current plane (after D. Holden's two-joint IK) and then turns about the root to aim at the
        target; each bone keeps its twist. A target out of reach is approached as closely as
        ``REACH`` x the chain's length allows (a target nearer than the bones' difference, as that).
    """
    a = root
    b = a + quat.rotate(upper, upper_bone)
    c = b + quat.rotate(lower, lower_bone)
    thigh, shin = np.linalg.norm(upper_bone, axis=-1), np.linalg.norm(lower_bone, axis=-1)
    # Bounds relative to the chain's length: the same pose in centimetres or metres.
    reach = np.clip(
        np.linalg.norm(target - a, axis=1), np.abs(thigh - shin) + 1e-5 * (thigh + shin), (thigh + shin) * REACH
    )
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


__all__ = ["REACH", "two_bone_ik"]
