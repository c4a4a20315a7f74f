"""Twin of ``rust/parse.rs`` and ``rust/format.rs``: the MOTION number block as text <-> array.

The fast path is ``np.loadtxt``; when it fails (or the counts do not match) a line-by-line
scan finds the first bad line and reports it exactly as the Rust kernel does.
"""

from __future__ import annotations

import io
import math
import re
import warnings
from typing import NoReturn

import numpy as np

from .._utils.tokens import BLANKS, NOT_FINITE_BYTES, NUMBER_BYTES, shown
from ..errors import ArgumentError, ParseError
from .rotations import euler_to_quat

# The Rust parser's grammar (expressive_mocap._utils.tokens): numbers separated by ASCII blanks, one
# frame a line. Python's own split() also splits at other control characters, so the twin
# tokenises with these explicitly to accept and refuse exactly the same files.
_PLAIN = b"0123456789+-.eE\n" + BLANKS.encode("ascii")
_BLANKS = re.compile(b"[" + re.escape(BLANKS.encode("ascii")) + b"]+")


def _tokens(line: bytes) -> list[bytes]:
    return [t for t in _BLANKS.split(line) if t]


def parse_motion_block(data: bytes, start: int, frames: int, channels: int) -> np.ndarray:
    """Parse ``frames`` lines of ``channels`` finite numbers from ``data[start:]`` -> ``[frames, channels]``."""
    if start > len(data):
        raise ArgumentError("argument `start`: past the end of `data`")
    block = data[start:]
    if channels == 0:
        # Frame lines of a skeleton without channels are blank, still one line a frame.
        lines = block.split(b"\n")
        for index, line in enumerate(lines):
            if _tokens(line):
                raise ParseError("expected 0 values (the hierarchy has no CHANNELS)", index)
        if frames > len(lines):
            _raise_truncated(block, frames, len(lines))
        return np.zeros((frames, 0))
    if block.translate(None, _PLAIN):  # anything but plain numbers and blanks: check line by line
        _raise_first_problem(block, frames, channels)
    if b"\r" in block:  # a blank like a space (loadtxt would end a line at a lone CR)
        block = block.replace(b"\r", b" ")
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # loadtxt warns on an empty block; counts are checked below
            values = np.loadtxt(io.BytesIO(block), dtype=np.float64, ndmin=2, comments=None)
    except ValueError:
        values = None
    if values is None or values.shape != (frames, channels) or not np.isfinite(values).all():
        if frames == 0 and values is not None and values.size == 0:
            return np.zeros((0, channels))
        _raise_first_problem(block, frames, channels)
    return values


def decode_channels(values, rotation_columns, orders, position_columns, offsets) -> tuple[np.ndarray, np.ndarray]:
    """Channel values ``[F, C]`` -> local rotations ``[F, J, 4]`` and translations ``[F, J, 3]``.

    ``rotation_columns [J, 3]``: column of each angle in the joint's order (-1: none, angle 0);
    ``orders [J, 3]``; ``position_columns [J, 3]``: column of x, y, z (-1 keeps the offset);
    ``offsets [J, 3]``.
    """
    values = np.asarray(values, dtype=np.float64)
    for name, columns in (("rotation_columns", rotation_columns), ("position_columns", position_columns)):
        if columns.shape != offsets.shape or ((columns < -1) | (columns >= values.shape[1])).any():
            raise ArgumentError(f"argument `{name}`: expected [J, 3] columns in -1..{values.shape[1] - 1}")
    # A trailing zero column lets missing channels (-1) read as 0.
    padded = np.concatenate([values, np.zeros((len(values), 1))], axis=1)
    rotations = euler_to_quat(padded[:, rotation_columns], orders)
    translations = np.where(position_columns >= 0, padded[:, position_columns], offsets)
    return rotations, translations


def read_motion_blocks(blocks: list) -> list:
    """Parse and decode many blocks: per block (``data``, ``start``, ``frames``, ``layout``: see
    ``expressive_mocap.ops.MotionBlock``) a ``(rotations, translations)`` pair or a ``ParseError``."""
    results: list[tuple[np.ndarray, np.ndarray] | ParseError] = []
    for block in blocks:
        layout = block.layout
        try:
            values = parse_motion_block(block.data, block.start, block.frames, layout.channels)
            results.append(
                decode_channels(values, layout.rotation_columns, layout.orders, layout.position_columns, layout.offsets)
            )
        except ParseError as error:
            results.append(error)
    return results


def check_motion_block(data: bytes, start: int, frames: int, channels: int) -> None:
    """Raise what :func:`parse_motion_block` raises for this block, or return None."""
    parse_motion_block(data, start, frames, channels)


def _raise_first_problem(block: bytes, frames: int, channels: int) -> NoReturn:
    lines = block.split(b"\n")
    found = 0
    for index, line in enumerate(lines):
        tokens = _tokens(line)
        if not tokens:
            continue
        for token in tokens:
            if NUMBER_BYTES.fullmatch(token):
                finite = math.isfinite(float(token))
            elif NOT_FINITE_BYTES.fullmatch(token):
                finite = False
            else:
                raise ParseError(f"{shown(token)} is not a number", index)
            if not finite:
                raise ParseError(f"{shown(token)} is not a finite number (NaN and infinity are not allowed)", index)
        if len(tokens) != channels:
            raise ParseError(f"expected {channels} values (the CHANNELS of the hierarchy), found {len(tokens)}", index)
        if found == frames:
            raise ParseError(f"more frame lines than Frames says ({frames})", index)
        found += 1
    if found < frames:
        _raise_truncated(block, frames, found)
    raise ParseError("the MOTION block could not be parsed", 0)


def _raise_truncated(block: bytes, frames: int, found: int) -> None:
    """Fewer frame lines than ``frames``: point at the last line of the block, where the missing
    frames should have been."""
    lines = block.count(b"\n") + (1 if block and not block.endswith(b"\n") else 0)
    raise ParseError(
        f"truncated MOTION block: Frames says {frames}, but only {found} frame lines follow", max(lines - 1, 0)
    )


def format_motion_block(values: np.ndarray, decimals: int | None = None) -> bytes:
    """Text of ``values [F, C]``, one frame a line; ``decimals=None`` is the shortest exact text."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim != 2 or values.shape[1] == 0:
        raise ArgumentError(f"argument `values`: expected shape [F, C] with C >= 1, got {list(values.shape)}")
    bad = np.argwhere(~np.isfinite(values))
    if len(bad):
        f, c = bad[0]
        raise ArgumentError(f"argument `values`: frame {f}, channel {c} is {values[f, c]}")
    out = io.StringIO()
    if decimals is None:
        values = values + 0.0  # -0.0 -> 0.0, as the Rust kernel writes it
        for row in values.tolist():
            out.write(" ".join(np.format_float_positional(v, trim="-") for v in row))
            out.write("\n")
    else:
        np.savetxt(out, values, fmt=f"%.{int(decimals)}f", delimiter=" ")
    return out.getvalue().encode("ascii")


__all__ = [
    "decode_channels",
    "format_motion_block",
    "check_motion_block",
    "parse_motion_block",
    "read_motion_blocks",
]
