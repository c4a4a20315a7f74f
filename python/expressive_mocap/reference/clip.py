"""Twin of ``rust/clip.rs``: the whole per-clip work of preprocessing (MOTION block, FK,
features, contacts), as the composition of the other kernels' twins, clip by clip."""

from __future__ import annotations

import os
from types import SimpleNamespace

import numpy as np

from .._utils import files
from ..bvh.header import repeated_header
from ..errors import ArgumentError
from .fk import forward_kinematics
from .forms import clip_gradient, matrix_entries
from .gait import GAIT_ROLES, clip_gait_many
from .motion_block import read_motion_blocks


def clip_pipeline_many(clips, parents, roles, gait, outputs, max_bytes: int | None = None) -> list:
    """Per clip (``source``, ``start``, ``frames``, ``layout``, ``frame_time``, ``height``,
    ``hips_rest_height``: see ``expressive_mocap.ops.ClipInput``; ``source``: the bytes, or a
    path read here with :func:`~expressive_mocap._utils.files.read_input`: a regular file of at most
    ``max_bytes``, by default ``files.MAX_INPUT_BYTES``): ``(positions [F, J, 3] or None,
    rotations [F, J, 4] or None (or their matrices' first ``outputs.rotation_columns`` columns),
    [features [F, 19] per ``outputs.features`` request], contacts bool [F, 2] or None,
    velocities [F, J, 3] or None)``, float32 if ``outputs.float32``; a ``ParseError`` or ``OSError`` in
    the place of a clip whose block or file cannot be read (or is refused: not a regular file,
    or over the bound). ``gait``: the four thresholds (``expressive_mocap.ops.GaitSettings``)."""
    if outputs.rotation_columns not in (0, 2, 3):
        raise ArgumentError(
            "argument `rotation_columns`: expected 0 (quaternions), 2 (6d) or 3 (the whole matrix), "
            f"got {outputs.rotation_columns}"
        )
    roles = [int(r) for r in roles]
    if len(roles) != 7:
        raise ArgumentError(f"argument `roles`: expected 7 joint indices {GAIT_ROLES}, got {len(roles)}")
    parents = np.asarray(parents)
    thresholds = (gait.height_threshold, gait.speed_threshold, gait.min_duration, gait.floor_percentile)
    dtype = np.float32 if outputs.float32 else np.float64
    out: list[tuple | Exception] = []  # per clip its outputs, or the error that stopped it
    for clip in clips:
        source = clip.source
        if isinstance(source, (str, os.PathLike)):
            try:
                source = files.read_input(source, files.MAX_INPUT_BYTES if max_bytes is None else max_bytes)
            except OSError as error:
                out.append(OSError(error.errno, error.strerror) if error.errno is not None else error)
                continue
        if clip.start > len(source):
            raise ArgumentError("argument `start`: past the end of the clip's text")
        (decoded,) = read_motion_blocks(
            [SimpleNamespace(data=source, start=clip.start, frames=clip.frames, layout=clip.layout)]
        )
        if isinstance(decoded, Exception):
            out.append(decoded)
            continue
        local, translations = decoded
        _, world = forward_kinematics(local, translations, parents)
        gait_clip = (world, local, clip.frame_time, clip.height, clip.hips_rest_height)
        wanted = []  # features were asked for: the kernel gives them, never None
        for f in outputs.features:
            features, _ = clip_gait_many([gait_clip], roles, *thresholds, True, False, f.floor, f.thigh_reference)[0]
            assert features is not None
            wanted.append(features)
        found = clip_gait_many([gait_clip], roles, *thresholds, False, True)[0][1] if outputs.contacts else None
        velocities = (
            clip_gradient(world, np.array([0]), np.full(len(world), clip.frame_time)) if outputs.velocities else None
        )
        rotations = local if outputs.rotation_columns == 0 else matrix_entries(local, outputs.rotation_columns)
        out.append(
            (
                world.astype(dtype) if outputs.positions else None,
                rotations.astype(dtype) if outputs.rotations else None,
                [f.astype(dtype) for f in wanted],
                found,
                None if velocities is None else velocities.astype(dtype),
            )
        )
    return out


def repeated_headers(paths, template: bytes, joints: int, count: int, max_bytes: int | None = None) -> list:
    """Per file of ``paths`` (regular files of at most ``max_bytes``, by default
    ``files.MAX_INPUT_BYTES``), read from its first ``count`` bytes: ``(frames, frame_time,
    block_start)`` when it repeats ``template`` (:func:`repeated_header`), else ``(first bytes,
    size)`` to read in full, or the ``OSError`` of a file that cannot be read."""
    out: list = []
    for path in paths:
        try:
            data, size = files.read_beginning(path, count, files.MAX_INPUT_BYTES if max_bytes is None else max_bytes)
        except OSError as error:
            out.append(OSError(error.errno, error.strerror) if error.errno is not None else error)
            continue
        found = repeated_header(data, size, len(data) < count, template, joints)
        out.append((data, size) if found is None else found)
    return out


__all__ = [
    "clip_pipeline_many",
    "repeated_headers",
]
