"""Twin of ``rust/features.rs``: the 19 dynamic features per frame of the decoupling method
(Boehs et al.).

Y is up. The heading frame of a frame turns the world about Y so that the character's forward
direction (``(left upper leg - right upper leg) x up``, flattened) becomes +Z and its left +X.
"""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat
from .footsteps import air_time

N_FEATURES = 19


def heading_yaw(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Yaw angles ``[F]`` (radians about +Y, 0 = facing +Z) from the upper-leg positions
    ``[F, 3]``. A frame whose legs line up with Y (no horizontal direction) keeps the previous
    frame's yaw (0 at the first frame)."""
    across = left - right
    # forward = across x up, with up = +Y: (-across_z, 0, across_x)
    fx, fz = -across[:, 2], across[:, 0]
    yaw = np.arctan2(fx, fz)
    degenerate = np.hypot(fx, fz) <= 1e-9 * np.maximum(np.linalg.norm(across, axis=1), 1e-300)
    if degenerate.any():
        frames = np.arange(len(yaw))
        # Carry the last good yaw forward (causal).
        last_good = np.maximum.accumulate(np.where(degenerate, -1, frames))
        yaw = np.where(last_good >= 0, yaw[np.maximum(last_good, 0)], 0.0)
    return yaw


def _check(points, thighs, contacts, reference, frame_time, height, hips_rest_height, window):
    frames = len(points)
    if points.ndim != 3 or points.shape[1:] != (3, 3):
        raise ArgumentError(
            f"argument `points`: expected shape [F, 3, 3] (hips, left and right upper leg), got {list(points.shape)}"
        )
    if thighs.shape != (frames, 2, 4):
        raise ArgumentError(f"argument `thighs`: expected shape [{frames}, 2, 4], got {list(thighs.shape)}")
    if contacts.shape != (frames, 2):
        raise ArgumentError(f"argument `contacts`: expected shape [{frames}, 2], got {list(contacts.shape)}")
    if reference.shape != (2, 4):
        raise ArgumentError(f"argument `reference`: expected shape [2, 4], got {list(reference.shape)}")
    for name, value in (("frame_time", frame_time), ("height", height), ("hips_rest_height", hips_rest_height)):
        if not (np.isfinite(value) and value > 0):
            raise ArgumentError(f"argument `{name}`: must be positive, got {value}")
    if int(window) < 1:
        raise ArgumentError(f"argument `window`: must be at least 1, got {window}")


def dynamic_features(
    points: np.ndarray,
    thighs: np.ndarray,
    contacts: np.ndarray,
    reference: np.ndarray,
    frame_time: float,
    height: float,
    hips_rest_height: float,
    floor: float,
    window: int,
) -> np.ndarray:
    """Features ``[F, 19]`` per frame, each from frames ``<= t`` only.

    ``points [F, 3, 3]``: world positions of the hips, left and right upper leg;
    ``thighs [F, 2, 4]``: local rotations of the left and right upper leg (x, y, z, w);
    ``contacts bool [F, 2]``: left, right foot; ``reference [2, 4]``: each thigh rotation is
    kept on this quaternion's hemisphere. Columns: hips velocity in the heading frame / height
    (3; 0 at frame 0), its mean over the last ``window`` frames (3), contacts (2), air time in
    seconds (2), (hips height - floor) / hips_rest_height (1), thigh rotations (2 x 4).
    """
    points = np.asarray(points, dtype=np.float64)
    thighs = np.asarray(thighs, dtype=np.float64)
    contacts = np.asarray(contacts, dtype=bool)
    reference = np.asarray(reference, dtype=np.float64)
    _check(points, thighs, contacts, reference, frame_time, height, hips_rest_height, window)
    frames, window = len(points), int(window)
    hips = points[:, 0]
    world_velocity = np.zeros((frames, 3))
    world_velocity[1:] = (hips[1:] - hips[:-1]) / frame_time / height
    # Remove the heading: rotate by -yaw about Y.
    velocity = quat.rotate(quat.about("Y", -np.degrees(heading_yaw(points[:, 1], points[:, 2]))), world_velocity)
    # Causal running mean over the last `window` frames (fewer at the start).
    sums = np.cumsum(velocity, axis=0)
    before = np.zeros_like(sums)
    before[window:] = sums[:-window]
    counts = np.minimum(np.arange(1, frames + 1), window)[:, None]
    mean = (sums - before) / counts
    sign = np.where(np.sum(thighs * reference, axis=-1, keepdims=True) < 0, -1.0, 1.0)
    out = np.empty((frames, N_FEATURES))
    out[:, 0:3] = velocity
    out[:, 3:6] = mean
    out[:, 6:8] = contacts
    out[:, 8:10] = air_time(contacts, frame_time) if frames else np.zeros((0, 2))
    out[:, 10] = (hips[:, 1] - floor) / hips_rest_height
    out[:, 11:19] = (thighs * sign).reshape(frames, 8)
    return out


__all__ = [
    "N_FEATURES",
    "dynamic_features",
    "heading_yaw",
]
