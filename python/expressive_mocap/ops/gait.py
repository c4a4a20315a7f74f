"""Wrappers of the gait kernels: foot contacts, air time, the decoupling method's dynamic
features, and whole clips' gait and pipeline passes."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from ..backend import kernels
from ..errors import ArgumentError
from ._args import _array
from .bvh_text import ChannelLayout, channel_layout


def foot_contacts(
    feet,
    frame_time: float,
    floor: float,
    height_threshold: float,
    speed_threshold: float,
    min_frames: int,
    causal: bool,
) -> np.ndarray:
    """Contact flags ``bool [F, S]`` from world positions ``feet [F, S, P, 3]`` (P points a
    foot: ankle, toe); thresholds in the positions' units (speed per second); runs shorter than
    ``min_frames`` are filtered (offline, or a causal hold when ``causal``)."""
    feet = _array("feet", feet, np.float64)
    return kernels().foot_contacts(
        feet,
        float(frame_time),
        float(floor),
        float(height_threshold),
        float(speed_threshold),
        int(min_frames),
        bool(causal),
    )


def air_time(contacts, frame_time: float) -> np.ndarray:
    """Seconds since each foot last left contact ``[F, S]`` from ``contacts bool [F, S]``."""
    return kernels().air_time(np.ascontiguousarray(contacts, dtype=bool), float(frame_time))


def clip_gradient(values, starts, frame_time) -> np.ndarray:
    """Per clip time derivative of rows ``values [N, ...]`` (clips begin at rows ``starts``, rising
    from 0; ``frame_time [N]`` each row's clip's seconds a frame), as ``np.gradient`` clip by clip:
    central differences, one-sided at a clip's ends, zero for a one-row clip."""
    values = _array("values", values, np.float64)
    if values.ndim == 0:
        raise ArgumentError("argument `values`: expected rows [N, ...], got a scalar")
    flat = values.reshape(len(values), int(np.prod(values.shape[1:])))  # not -1: no rows is fine
    starts = _array("starts", starts, np.int64, "iu")
    frame_time = _array("frame_time", frame_time, np.float64)
    return kernels().clip_gradient(flat, starts, frame_time).reshape(values.shape)


def column_totals(arrays: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The float64 sums of the rows of each of ``arrays`` (each ``[n_i, ...]``, one row shape) and
    of their squares, ``[len(arrays), ...]`` each: the increments of running normalisation
    statistics. Each array is summed on its own, so its sums do not depend on the arrays beside it."""
    if not arrays:
        raise ArgumentError("argument `arrays`: expected at least one array")
    shape = arrays[0].shape[1:]
    if any(np.asarray(a).dtype != np.float32 or a.shape[1:] != shape for a in arrays):
        raise ArgumentError(f"argument `arrays`: expected float32 arrays of rows shaped {list(shape)}")
    width = int(np.prod(shape, dtype=np.int64))
    flat = [np.ascontiguousarray(a).reshape(len(a), width) for a in arrays]
    sums, squares = kernels().column_totals(flat, width)
    return sums.reshape(len(arrays), *shape), squares.reshape(len(arrays), *shape)


def dynamic_features(
    points,
    thighs,
    contacts,
    reference,
    frame_time: float,
    height: float,
    hips_rest_height: float,
    floor: float,
    window: int,
) -> np.ndarray:
    """The 19 dynamic features ``[F, 19]`` from ``points [F, 3, 3]`` (hips, left and right upper
    leg, world), ``thighs [F, 2, 4]`` (local), ``contacts bool [F, 2]`` and the thighs'
    hemisphere ``reference [2, 4]``."""
    return kernels().dynamic_features(
        _array("points", points, np.float64),
        _array("thighs", thighs, np.float64),
        np.ascontiguousarray(contacts, dtype=bool),
        _array("reference", reference, np.float64),
        float(frame_time),
        float(height),
        float(hips_rest_height),
        float(floor),
        int(window),
    )


class GaitSettings(NamedTuple):
    """The thresholds of contact detection shared by the gait kernels (heights in actor heights,
    speed in actor heights per second, duration in seconds, floor as a toe-height percentile)."""

    height_threshold: float
    speed_threshold: float
    min_duration: float
    floor_percentile: float


def clip_gait_many(
    clips,
    roles,
    gait: GaitSettings,
    *,
    features: bool,
    contacts: bool,
    feature_floor: float | None = None,
    thigh_reference=None,
) -> list[tuple[np.ndarray | None, np.ndarray | None]]:
    """Gait arrays of many clips (in parallel with the Rust kernels): per clip ``(positions
    [F, J, 3] world, rotations [F, J, 4] local, frame_time, height, hips_rest_height)``, ``roles``
    the 7 gait joints; per clip ``(features [F, 19] or None, contacts bool [F, 2] or None)``."""
    return kernels().clip_gait_many(
        clips, [int(r) for r in roles], *gait, bool(features), bool(contacts), feature_floor, thigh_reference
    )


@dataclass(frozen=True)
class ClipInput:
    """One clip for :func:`clip_pipeline_many`: ``source`` its bytes or its path (read by the
    kernel), ``start`` where its MOTION block begins, its ``frames``, ``layout`` and
    ``frame_time``, and its body scale (``height``, ``hips_rest_height``)."""

    source: bytes | str
    start: int
    frames: int
    layout: ChannelLayout
    frame_time: float
    height: float
    hips_rest_height: float

    @classmethod
    def of(cls, source: bytes | str | os.PathLike, header, height: float, hips_rest_height: float) -> ClipInput:
        """The clip of a :class:`~expressive_mocap.bvh.Header` whose text is ``source``."""
        text = source if isinstance(source, bytes) else os.fspath(source)
        return cls(
            text,
            header.block_start,
            header.frames,
            channel_layout(header.skeleton),
            header.frame_time,
            height,
            hips_rest_height,
        )


@dataclass(frozen=True)
class FeatureRequest:
    """One causal feature array [F, 19] to compute: on ``floor`` (None: the toe-height
    percentile) with ``thigh_reference [2, 4]`` (None: the first frame's thighs)."""

    floor: float | None
    thigh_reference: np.ndarray | None = None


@dataclass(frozen=True)
class PipelineOutputs:
    """What :func:`clip_pipeline_many` keeps of each clip; float arrays in float32 if ``float32``.
    ``rotation_columns``: the rotations as quaternions (0) or as their matrices' first two
    columns (2, the 6D form) or whole matrices (3), as :func:`matrix_columns` gives them;
    ``velocities``: the world positions' time derivative, as :func:`clip_gradient` gives it."""

    positions: bool = False
    rotations: bool = False
    features: tuple[FeatureRequest, ...] = ()
    contacts: bool = False
    float32: bool = False
    rotation_columns: int = 0
    velocities: bool = False


def clip_pipeline_many(
    clips: Sequence[ClipInput],
    parents,
    roles,
    gait: GaitSettings,
    outputs: PipelineOutputs,
    max_bytes: int | None = None,
) -> list:
    """The whole per-clip work of many clips of one skeleton (``parents [J]``, ``roles`` its 7
    gait joints), clips in parallel with the Rust kernels: reading the file (a path, at most
    ``max_bytes``, default ``files.MAX_INPUT_BYTES``), MOTION block, FK, features, contacts.
    Per clip ``(positions or None, rotations or None, [features per request], contacts or
    None, velocities or None)``, or the ``ParseError`` / ``OSError`` of a clip whose block /
    file cannot be read."""
    parents = _array("parents", parents, np.int64, "iu")
    if outputs.rotation_columns not in (0, 2, 3):
        raise ArgumentError(
            "argument `rotation_columns`: expected 0 (quaternions), 2 (6d) or 3 (the whole matrix), "
            f"got {outputs.rotation_columns!r}"
        )
    features = tuple(
        FeatureRequest(
            f.floor, None if f.thigh_reference is None else _array("thigh_reference", f.thigh_reference, np.float64)
        )
        for f in outputs.features
    )
    outputs = replace(outputs, features=features)
    return kernels().clip_pipeline_many(
        list(clips), parents, [int(r) for r in roles], gait=GaitSettings(*gait), outputs=outputs, max_bytes=max_bytes
    )


__all__ = [
    "ClipInput",
    "FeatureRequest",
    "GaitSettings",
    "PipelineOutputs",
    "air_time",
    "clip_gait_many",
    "clip_gradient",
    "clip_pipeline_many",
    "column_totals",
    "dynamic_features",
    "foot_contacts",
]
