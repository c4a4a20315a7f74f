"""Wrappers of the BVH text kernels: a skeleton's channel layout, MOTION blocks parsed and
formatted, headers repeated."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._utils.kept import Kept
from ..backend import kernels
from ..errors import ArgumentError
from ._args import _array


@dataclass(frozen=True)
class ChannelLayout:
    """Where each joint's numbers sit in a frame of ``channels`` values (see
    :meth:`Skeleton.layout`): ``rotation_columns``, ``orders``, ``position_columns`` and rest
    ``offsets``, each ``[J, 3]``. Built by :func:`channel_layout`."""

    channels: int
    rotation_columns: np.ndarray
    orders: np.ndarray
    position_columns: np.ndarray
    offsets: np.ndarray


def channel_layout(skeleton) -> ChannelLayout:
    """The :class:`ChannelLayout` of a :class:`~expressive_mocap.motion.Skeleton`, kept per
    skeleton content: the clips of an archive with one hierarchy share one (the kernels copy the
    layout's index arrays: nothing writes to them)."""

    def layout() -> ChannelLayout:
        rotation_columns, orders, position_columns = skeleton.layout()
        return ChannelLayout(skeleton.n_channels, rotation_columns, orders, position_columns, skeleton.offsets)

    return _LAYOUTS.get(skeleton.content_key, layout)


_LAYOUTS: Kept[ChannelLayout] = Kept(64)


@dataclass(frozen=True)
class MotionBlock:
    """A MOTION number block to read: ``data[start:]`` holds ``frames`` lines laid out as ``layout``."""

    data: bytes
    start: int
    frames: int
    layout: ChannelLayout


def read_motion_blocks(blocks: Sequence[tuple[bytes, Any]]) -> list:
    """Parse and decode many MOTION blocks (in parallel across blocks with the Rust kernels):
    per ``(data, header)`` (a :class:`~expressive_mocap.bvh.Header`: where its block starts,
    how many frames, its skeleton) a ``(rotations [F, J, 4], translations [F, J, 3])`` pair, or
    the :class:`~expressive_mocap.errors.ParseError` of a malformed block in its place."""
    return kernels().read_motion_blocks(
        [MotionBlock(data, h.block_start, h.frames, channel_layout(h.skeleton)) for data, h in blocks]
    )


def format_motion_block(values, decimals: int | None = None) -> bytes:
    """Text of the MOTION number block of channel values ``[F, C]`` (finite numbers);
    ``decimals=None`` is the shortest text that reads back exactly."""
    values = _array("values", values, np.float64)
    if values.ndim != 2:
        raise ArgumentError(f"argument `values`: expected shape [F, C], got {list(values.shape)}")
    return kernels().format_motion_block(values, decimals)


def repeated_headers(paths: Sequence[str | os.PathLike], template: bytes, joints: int, count: int) -> list:
    """The headers of files that repeat one already read, ``template`` its bytes through its
    MOTION line (``joints`` joints), each file read from its first ``count`` bytes, in parallel
    with the Rust kernels and without the GIL: per path ``(frames, frame_time, block_start)``,
    or ``(first bytes, size)`` of a file that is anything else (for the full reader), or the
    ``OSError`` of a file that cannot be read or is refused."""
    return kernels().repeated_headers([os.fspath(p) for p in paths], bytes(template), int(joints), int(count))


__all__ = [
    "ChannelLayout",
    "MotionBlock",
    "channel_layout",
    "format_motion_block",
    "read_motion_blocks",
    "repeated_headers",
]
