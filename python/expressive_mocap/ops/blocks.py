"""Checking a MOTION number block without reading it into an array: what a summary of a file
(``expressive-mocap info``) needs, without loading NumPy when the Rust kernels are in use."""

from __future__ import annotations

from ..backend import kernels
from ..errors import ArgumentError


def check_motion_block(data: bytes, start: int, frames: int, channels: int) -> None:
    """Raise the :class:`~expressive_mocap.errors.ParseError` that parsing ``frames`` lines of
    ``channels`` numbers from ``data[start:]`` would raise, or return None when they parse."""
    for name, value in (("start", start), ("frames", frames), ("channels", channels)):
        if not isinstance(value, int) or value < 0:
            raise ArgumentError(f"argument `{name}`: expected a whole number >= 0, got {value!r}")
    kernels().check_motion_block(bytes(data), start, frames, channels)


__all__ = ["check_motion_block"]
