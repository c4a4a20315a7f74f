"""Twin of ``rust/clip.rs``: the whole per-clip work of preprocessing (MOTION block, FK,
features, contacts), as the composition of the other kernels' twins, clip by clip."""

from __future__ import annotations

import os

import numpy as np

from .. import files
from .fk import forward_kinematics
from .gait import GAIT_ROLES, clip_gait_many
from .motion_block import read_motion_blocks


def clip_pipeline_many(
    clips,
    parents,
    roles,
    height_threshold: float,
    speed_threshold: float,
    min_duration: float,
    floor_percentile: float,
    positions: bool,
    rotations: bool,
    features,
    contacts: bool,
    float32: bool,
    max_bytes: int | None = None,
) -> list:
    """Per clip ``(source, start, frames, channels, rotation_columns, orders, position_columns,
    offsets, frame_time, height, hips_rest_height)`` (``source``: the bytes, or a path read
    here with :func:`~expressive_mocap.files.read_input`: a regular file of at most ``max_bytes``,
    by default ``files.MAX_INPUT_BYTES``): ``(positions [F, J, 3] or None, rotations [F, J, 4] or
    None, [features [F, 19] per (floor, thigh_reference) request], contacts bool [F, 2] or
    None)``, float32 if asked; a ``ParseError`` or ``OSError`` in the place of a clip whose
    block or file cannot be read (or is refused: not a regular file, or over the bound)."""
    roles = [int(r) for r in roles]
    if len(roles) != 7:
        raise ValueError(f"argument `roles`: expected 7 joint indices {GAIT_ROLES}, got {len(roles)}")
    parents = np.asarray(parents)
    dtype = np.float32 if float32 else np.float64
    out = []
    for source, start, frames, channels, *layout, frame_time, height, hips_rest_height in clips:
        if isinstance(source, (str, os.PathLike)):
            try:
                source = files.read_input(source, files.MAX_INPUT_BYTES if max_bytes is None else max_bytes)
            except OSError as error:
                out.append(OSError(error.errno, error.strerror) if error.errno is not None else error)
                continue
        if start > len(source):
            raise ValueError("argument `start`: past the end of the clip's text")
        (decoded,) = read_motion_blocks([(source, start, frames, channels, *layout)])
        if isinstance(decoded, Exception):
            out.append(decoded)
            continue
        local, translations = decoded
        _, world = forward_kinematics(local, translations, parents)
        clip = (world, local, frame_time, height, hips_rest_height)
        wanted = [clip_gait_many([clip], roles, height_threshold, speed_threshold, min_duration, floor_percentile, True, False, floor, reference)[0][0]
                  for floor, reference in features]
        found = clip_gait_many([clip], roles, height_threshold, speed_threshold, min_duration, floor_percentile, False, True)[0][1] if contacts else None
        out.append((world.astype(dtype) if positions else None, local.astype(dtype) if rotations else None, [f.astype(dtype) for f in wanted], found))
    return out
