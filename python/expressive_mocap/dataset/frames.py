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
from ..heading import turn_by_yaw

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


def _origin(heading: np.ndarray) -> np.ndarray:
    """``[..., 3]`` heading origins on the floor from headings ``[..., 3]`` (x, z, yaw)."""
    return np.stack([heading[..., 0], np.zeros_like(heading[..., 0]), heading[..., 1]], axis=-1)


def to_window_frame(batch: dict, heading: np.ndarray, clip_heading: np.ndarray, where: str) -> None:
    """Turn in place the kinds of ``batch`` (``[B, T, ...]``) into each window's first frame's
    heading frame, from each frame's ``heading [B, T, 3]`` and, for ``where == "clip"``, each
    window's clip's first frame's ``clip_heading [B, 3]`` (the frame its positions are stored in)."""
    heading = np.asarray(heading, dtype=np.float64)
    first = heading[:, 0]
    stored = heading if where == "heading" else np.broadcast_to(np.asarray(clip_heading)[:, None], heading.shape)
    count, length = heading.shape[:2]
    turn = (stored[..., 2] - first[:, None, 2]).reshape(-1)  # [B * T]
    back = np.repeat(-first[:, 2], length)  # R_y(-yaw_0) per frame
    shift = turn_by_yaw((_origin(stored) - _origin(first)[:, None]).reshape(-1, 3), back).reshape(count, length, 3)
    for kind in MOVING_KINDS:
        if kind in batch:
            values = batch[kind]
            turned = turn_by_yaw(values.reshape(count * length, -1, 3), turn).reshape(values.shape)
            if kind == "positions":
                turned += shift[:, :, None, :]
            batch[kind] = turned.astype(values.dtype)
    if "heading" in batch:  # each frame's heading as seen from the window's first
        own = turn_by_yaw((_origin(heading) - _origin(first)[:, None]).reshape(-1, 3), back).reshape(count, length, 3)
        relative = np.stack([own[..., 0], own[..., 2], heading[..., 2] - first[:, None, 2]], axis=-1)
        batch["heading"] = relative.astype(batch["heading"].dtype)


__all__ = ["MOVING_KINDS", "STORED_FRAMES", "check_window_frame", "to_window_frame"]
