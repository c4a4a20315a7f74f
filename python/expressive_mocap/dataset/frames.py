"""Windows seen from their own first frame: a window's positions, velocities and accelerations
re-expressed in the heading frame of its first frame (origin on the floor under the hips then, Y
up, +Z the body's facing then), so that every window starts at the origin facing +Z wherever the
clip was. It needs positions stored in a heading frame and the ``heading`` kind, which says where
each frame's heading frame is in the (harmonised) world: ``preprocess --positions heading`` or
``--positions clip``, with ``--keep ...,heading``.

With ``h_t = (x_t, z_t, yaw_t)`` a frame's heading and ``o_t = (x_t, 0, z_t)``, a point ``p``
stored in the heading frame of ``h_s`` (``s = t`` for ``heading``, the clip's first frame for
``clip``) is ``R_y(yaw_s) p + o_s`` in the world, so in the window's first frame ``0`` it is
``R_y(yaw_s - yaw_0) p + R_y(-yaw_0) (o_s - o_0)``; directions (velocities, accelerations) take the
turn alone. ``root_velocity`` is in each frame's own heading frame already, and rotations stay as
stored (local; the root's in the file's world).
"""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from .heading import turn_by_yaw

MOVING_KINDS = ("positions", "velocities", "accelerations")
STORED_FRAMES = ("heading", "clip")  # the --positions frames a window's frame can be found from


def check_window_frame(manifest, kinds) -> None:
    """Raise ArgumentError unless windows of a dataset of ``manifest`` and ``kinds`` can be turned
    into their first frame's heading frame."""
    where = (manifest.get("options") or {}).get("positions", "world")
    if where not in STORED_FRAMES:
        raise ArgumentError(
            f"window frames need positions stored in a heading frame (preprocess --positions heading or clip), "
            f"this dataset's are {where!r}"
        )
    if "heading" not in kinds:
        raise ArgumentError("window frames need the `heading` kind: preprocess with --keep ...,heading")


def turn_headings(heading: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Headings ``[B, T, 3]`` (x, z, yaw) turned about +Y by ``angles [B]``: each origin turned
    about the world's, each yaw plus the angle."""
    count, length = heading.shape[:2]
    origin = np.stack([heading[..., 0], np.zeros_like(heading[..., 0]), heading[..., 1]], axis=-1)
    turned = turn_by_yaw(origin.reshape(-1, 3), np.repeat(angles, length)).reshape(count, length, 3)
    return np.stack([turned[..., 0], turned[..., 2], heading[..., 2] + angles[:, None]], axis=-1)


def to_window_frame(batch: dict, heading: np.ndarray, clip_heading: np.ndarray, where: str) -> None:
    """Turn in place the kinds of ``batch`` (``[B, T, ...]``) into each window's first frame's
    heading frame, from each frame's ``heading [B, T, 3]`` and, for ``where == "clip"``, each
    window's clip's first frame's ``clip_heading [B, 3]`` (the frame its positions are stored in)."""
    heading = np.asarray(heading, dtype=np.float64)
    first = heading[:, :1] * [1.0, 1.0, 0.0]  # the first frame's origin (its yaw is turned off below)
    back = -heading[:, 0, 2]  # R_y(-yaw_0)
    stored = heading if where == "heading" else np.broadcast_to(np.asarray(clip_heading)[:, None], heading.shape)
    seen = turn_headings(stored - first, back)  # each stored frame from the window's first
    count, length = heading.shape[:2]
    for kind in MOVING_KINDS:
        if kind in batch:
            values = batch[kind]
            turned = turn_by_yaw(values.reshape(count * length, -1, 3), seen[..., 2].reshape(-1)).reshape(values.shape)
            if kind == "positions":
                turned[..., 0] += seen[..., 0, None]
                turned[..., 2] += seen[..., 1, None]
            batch[kind] = turned.astype(values.dtype)
    if "heading" in batch:  # each frame's heading as seen from the window's first
        own = seen if where == "heading" else turn_headings(heading - first, back)
        batch["heading"] = own.astype(batch["heading"].dtype)


__all__ = ["MOVING_KINDS", "STORED_FRAMES", "check_window_frame", "to_window_frame", "turn_headings"]
