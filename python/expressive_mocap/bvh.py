"""Reading and writing BVH files.

The header (hierarchy, Frames, Frame Time) is parsed here; the MOTION number block, most of a
file's bytes, by the kernel ``parse_motion_block`` (Rust, or its NumPy twin). Every problem is a
:class:`~expressive_mocap.errors.BVHError` naming the file, the line and what was expected.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO, Iterable, Union

import numpy as np

from .backend import PARSE_ERRORS, kernels
from .errors import BVHError, MocapError
from .io import atomic_write
from .motion import Motion, Skeleton, canonical_channel

Source = Union[str, os.PathLike, bytes, bytearray, memoryview, BinaryIO]

_TOKEN = re.compile(r"[{}]|[^\s{}]+")
_MOTION = re.compile(rb"^[ \t]*MOTION[ \t]*\r?$", re.MULTILINE | re.IGNORECASE)
_FRAMES = re.compile(rb"[ \t]*Frames[ \t]*:[ \t]*(\S*)[ \t]*\r?$", re.IGNORECASE)
_FRAME_TIME = re.compile(rb"[ \t]*Frame[ \t]+Time[ \t]*:[ \t]*(\S*)[ \t]*\r?$", re.IGNORECASE)


@dataclass
class _Header:
    skeleton: Skeleton
    frames: int
    frame_time: float
    block_start: int  # byte offset of the number block
    block_line: int  # 1-based line number of the number block's first line


def _load(source: Source) -> tuple[bytes, str]:
    """The bytes of a source and a name for it in error messages."""
    if isinstance(source, (bytes, bytearray, memoryview)):
        return bytes(source), "<bytes>"
    if isinstance(source, (str, os.PathLike)):
        try:
            return Path(source).read_bytes(), str(source)
        except OSError as error:
            raise BVHError(source, None, f"cannot read the file: {error.strerror or error}") from None
    if hasattr(source, "read"):
        name = str(getattr(source, "name", "<file object>"))
        data = source.read()
        if isinstance(data, str):
            raise BVHError(name, None, "the file object is open in text mode: open it with 'rb'")
        return bytes(data), name
    raise TypeError(f"read_bvh: expected a path, bytes or a binary file object, got {type(source).__name__}")


class _Tokens:
    """Header tokens with their line numbers, consumed front to back."""

    def __init__(self, text: str, name: str):
        self.name = name
        self.items = [(t, n) for n, line in enumerate(text.split("\n"), 1) for t in _TOKEN.findall(line)]
        self.pos = 0
        self.last_line = text.count("\n") + 1

    def error(self, line: int | None, reason: str) -> BVHError:
        return BVHError(self.name, line, reason)

    def peek(self) -> tuple[str, int] | None:
        return self.items[self.pos] if self.pos < len(self.items) else None

    def next(self, expected: str) -> tuple[str, int]:
        item = self.peek()
        if item is None:
            raise self.error(self.last_line, f"unexpected end of the header: expected {expected}")
        self.pos += 1
        return item

    def expect(self, word: str) -> int:
        token, line = self.next(repr(word))
        if token.lower() != word.lower():
            raise self.error(line, f"expected {word!r}, found {token!r}")
        return line

    def number(self, what: str) -> float:
        token, line = self.next(what)
        try:
            value = float(token)
        except ValueError:
            raise self.error(line, f"expected {what}, found {token!r}") from None
        if not math.isfinite(value):
            raise self.error(line, f"expected {what} (a finite number), found {token!r}")
        return value

    def name_on_line(self, keyword_line: int, what: str) -> str:
        """The rest of the keyword's line up to '{' (names may contain spaces or ':')."""
        words = []
        while (item := self.peek()) is not None and item[1] == keyword_line and item[0] != "{":
            words.append(item[0])
            self.pos += 1
        if not words:
            raise self.error(keyword_line, f"expected the name of the {what}")
        return " ".join(words)


def _parse_hierarchy(tokens: _Tokens) -> Skeleton:
    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float] | None] = []
    channels: list[tuple[str, ...] | None] = []
    end_sites: list[tuple[int, list[float] | None]] = []
    opened_at: list[int] = []  # line of each joint's '{', for unbalanced-brace errors

    tokens.expect("HIERARCHY")
    root_line = tokens.expect("ROOT")
    # Stack of open blocks: a joint index, or ("site", index into end_sites).
    stack: list = []

    def open_joint(keyword_line: int, parent: int) -> None:
        names.append(tokens.name_on_line(keyword_line, "joint"))
        parents.append(parent)
        offsets.append(None)
        channels.append(None)
        opened_at.append(tokens.expect("{"))
        stack.append(len(names) - 1)

    open_joint(root_line, -1)
    while stack:
        if tokens.peek() is None:
            joint = next(j for j in reversed(stack) if isinstance(j, int))
            raise tokens.error(tokens.last_line, f"unbalanced braces: the '{{' of joint {names[joint]!r} at line {opened_at[joint]} is never closed")
        token, line = tokens.next("'}'")
        word = token.lower()
        top = stack[-1]
        if token == "}":
            if isinstance(top, int) and offsets[top] is None:
                raise tokens.error(line, f"joint {names[top]!r} has no OFFSET")
            if isinstance(top, tuple) and end_sites[top[1]][1] is None:
                raise tokens.error(line, "End Site has no OFFSET")
            stack.pop()
        elif isinstance(top, tuple):
            if word != "offset" or end_sites[top[1]][1] is not None:
                raise tokens.error(line, f"expected OFFSET or '}}' in an End Site, found {token!r}")
            end_sites[top[1]] = (end_sites[top[1]][0], [tokens.number("an OFFSET value") for _ in range(3)])
        elif word == "offset":
            if offsets[top] is not None:
                raise tokens.error(line, f"joint {names[top]!r} has a second OFFSET")
            offsets[top] = [tokens.number("an OFFSET value") for _ in range(3)]
        elif word == "channels":
            if channels[top] is not None:
                raise tokens.error(line, f"joint {names[top]!r} has a second CHANNELS line")
            count_token, count_line = tokens.next("the number of channels")
            if not count_token.isdigit() or int(count_token) > 6:
                raise tokens.error(count_line, f"expected a channel count from 0 to 6, found {count_token!r}")
            listed = []
            for _ in range(int(count_token)):
                name, name_line = tokens.next("a channel name")
                try:
                    listed.append(canonical_channel(name))
                except MocapError as error:
                    raise tokens.error(name_line, str(error)) from None
            if len(set(listed)) != len(listed):
                raise tokens.error(line, f"joint {names[top]!r} lists a channel twice: {' '.join(listed)}")
            channels[top] = tuple(listed)
        elif word == "joint":
            open_joint(line, top)
        elif word == "end":
            tokens.expect("Site")
            end_sites.append((top, None))
            tokens.expect("{")
            stack.append(("site", len(end_sites) - 1))
        elif word == "root":
            raise tokens.error(line, "several ROOT hierarchies in one file are not supported (a ROOT inside a joint)")
        else:
            raise tokens.error(line, f"expected OFFSET, CHANNELS, JOINT, End Site or '}}', found {token!r}")

    if (item := tokens.peek()) is not None:
        token, line = item
        if token.lower() == "root":
            raise tokens.error(line, "several ROOT hierarchies in one file are not supported: only the first ROOT can be read")
        if token == "}":
            raise tokens.error(line, "unbalanced braces: this '}' closes nothing")
        raise tokens.error(line, f"expected MOTION after the hierarchy, found {token!r}")
    return Skeleton(
        names=tuple(names),
        parents=np.array(parents),
        offsets=np.array(offsets, dtype=np.float64),
        channels=tuple(c or () for c in channels),
        end_sites=tuple((j, tuple(off)) for j, off in end_sites),
    )


def _check_text(data: bytes, name: str) -> None:
    if not data.strip():
        raise BVHError(name, None, "the file is empty: expected a BVH file starting with HIERARCHY")
    head = data[:4096]
    if b"\0" in head:
        raise BVHError(name, None, f"binary data (a NUL byte at offset {head.index(0)}): not a BVH text file")
    if not data.lstrip()[:9].upper().startswith(b"HIERARCHY"):
        first = data.lstrip().split(b"\n", 1)[0][:40].decode("utf-8", "replace")
        line = data[: len(data) - len(data.lstrip())].count(b"\n") + 1
        raise BVHError(name, line, f"expected 'HIERARCHY' at the start of a BVH file, found {first!r}")


def _line_at(data: bytes, offset: int) -> int:
    return data.count(b"\n", 0, offset) + 1


def _next_content_line(data: bytes, position: int) -> tuple[int, int]:
    """Start and end (exclusive, before the newline) of the first non-blank line from ``position``."""
    while position < len(data):
        end = data.find(b"\n", position)
        end = len(data) if end < 0 else end
        if data[position:end].strip():
            return position, end
        position = end + 1
    return len(data), len(data)


def _parse_header(data: bytes, name: str) -> _Header:
    _check_text(data, name)
    motion = _MOTION.search(data)
    hierarchy_end = motion.start() if motion else len(data)
    try:
        text = data[:hierarchy_end].decode("utf-8")
    except UnicodeDecodeError as error:
        raise BVHError(name, _line_at(data, error.start), "bytes that are not UTF-8 text: not a BVH text file") from None
    skeleton = _parse_hierarchy(_Tokens(text, name))
    if motion is None:
        raise BVHError(name, text.count("\n") + 1, "missing MOTION section after the hierarchy")

    # The two lines after MOTION: "Frames: N" and "Frame Time: t" (blank lines skipped).
    position = motion.end() + 1
    values = []
    for pattern, what in ((_FRAMES, "'Frames: N'"), (_FRAME_TIME, "'Frame Time: seconds'")):
        start, end = _next_content_line(data, position)
        match = pattern.match(data, start, end)
        line = _line_at(data, start)
        if match is None:
            found = data[start:end].strip()[:40].decode("utf-8", "replace")
            raise BVHError(name, line, f"expected {what} after MOTION, found {found!r}" if found else f"missing {what} after MOTION")
        values.append((match.group(1).decode("utf-8", "replace"), line))
        position = end + 1

    (frames_text, frames_line), (time_text, time_line) = values
    if not frames_text.isdigit():
        raise BVHError(name, frames_line, f"expected a whole number of frames after 'Frames:', found {frames_text!r}")
    try:
        frame_time = float(time_text)
    except ValueError:
        frame_time = math.nan
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise BVHError(name, time_line, f"expected a positive number of seconds after 'Frame Time:', found {time_text!r}")
    return _Header(skeleton, int(frames_text), frame_time, min(position, len(data)), time_line + 1)


def _motion_from(header: _Header, values: np.ndarray) -> Motion:
    rotations, translations = header.skeleton.decode(values)
    return Motion(header.skeleton, rotations, translations, header.frame_time)


def _block_error(name: str, header: _Header, error: Exception) -> BVHError:
    message, line_in_block = error.args
    return BVHError(name, header.block_line + line_in_block, message)


def read_bvh(source: Source) -> Motion:
    """Read a BVH file from a path, bytes, or a binary file object.

    Raises :class:`~expressive_mocap.errors.BVHError` (naming the file and line) on malformed
    input: rotations come out as unit quaternions, translations as offsets or position channels.
    """
    data, name = _load(source)
    header = _parse_header(data, name)
    if header.skeleton.n_channels == 0:
        values = np.zeros((header.frames, 0))
    else:
        try:
            values = kernels().parse_motion_block(data, header.block_start, header.frames, header.skeleton.n_channels)
        except PARSE_ERRORS as error:
            raise _block_error(name, header, error) from None
    return _motion_from(header, values)


def read_bvh_many(sources: Iterable[Source], errors: str = "raise") -> list:
    """Read many files; the number blocks are parsed in parallel (Rust) across files.

    ``errors="raise"`` raises the first file's :class:`BVHError`; ``errors="return"`` puts the
    error in that file's place in the returned list instead.
    """
    if errors not in ("raise", "return"):
        raise MocapError(f"errors must be 'raise' or 'return', got {errors!r}")
    results: list = []
    pending = []  # (index in results, name, header, data)
    for source in sources:
        try:
            data, name = _load(source)
            header = _parse_header(data, name)
        except BVHError as error:
            if errors == "raise":
                raise
            results.append(error)
            continue
        pending.append((len(results), name, header, data))
        results.append(None)
    to_parse = [p for p in pending if p[2].skeleton.n_channels > 0]
    blocks = [(data, h.block_start, h.frames, h.skeleton.n_channels) for _, _, h, data in to_parse]
    parsed = kernels().parse_motion_blocks(blocks) if blocks else []
    for index, name, header, _ in pending:
        if header.skeleton.n_channels == 0:
            results[index] = _motion_from(header, np.zeros((header.frames, 0)))
    for (index, name, header, _), values in zip(to_parse, parsed):
        if isinstance(values, Exception):
            error = _block_error(name, header, values)
            if errors == "raise":
                raise error
            results[index] = error
        else:
            results[index] = _motion_from(header, values)
    return results


def _number(value: float, decimals: int | None) -> str:
    if decimals is None:
        return np.format_float_positional(value + 0.0, trim="-")
    return f"{value:.{decimals}f}"


def bvh_bytes(motion: Motion, decimals: int | None = None) -> bytes:
    """The text of a BVH file for ``motion``, in its skeleton's channel layout.

    ``decimals=None`` writes the shortest text that reads back to the same float64 values;
    an integer writes that many digits after the point (6 is common in exported files).
    """
    skeleton = motion.skeleton
    sites: dict[int, list] = {}
    for joint, offset in skeleton.end_sites:
        sites.setdefault(joint, []).append(offset)
    lines = ["HIERARCHY"]

    def offset_line(indent: str, offset) -> str:
        return f"{indent}OFFSET {' '.join(_number(v, decimals) for v in offset)}"

    def close(joint: int, depth: int) -> None:
        for offset in sites.get(joint, []):
            inner = "\t" * (depth + 1)
            lines.extend([f"{inner}End Site", f"{inner}{{", offset_line(inner + "\t", offset), f"{inner}}}"])
        lines.append("\t" * depth + "}")

    open_joints: list[int] = []
    for j, parent in enumerate(skeleton.parents.tolist()):
        while open_joints and open_joints[-1] != parent:
            close(open_joints.pop(), len(open_joints))
        if parent >= 0 and not open_joints:
            raise MocapError("joints must be in depth-first order (each subtree contiguous) to be written as BVH")
        indent = "\t" * len(open_joints)
        lines.append(f"{indent}{'ROOT' if parent < 0 else 'JOINT'} {skeleton.names[j]}")
        lines.append(f"{indent}{{")
        lines.append(offset_line(indent + "\t", skeleton.offsets[j]))
        lines.append(f"{indent}\tCHANNELS {len(skeleton.channels[j])} {' '.join(skeleton.channels[j])}".rstrip())
        open_joints.append(j)
    while open_joints:
        close(open_joints.pop(), len(open_joints))
    lines += ["MOTION", f"Frames: {motion.n_frames}", f"Frame Time: {_number(motion.frame_time, None)}", ""]
    header = "\n".join(lines).encode("utf-8")
    if skeleton.n_channels == 0 or motion.n_frames == 0:
        return header + b"\n" * motion.n_frames
    return header + kernels().format_motion_block(motion.channel_values(), decimals)


def write_bvh(motion: Motion, path: str | os.PathLike, decimals: int | None = None) -> None:
    """Write ``motion`` as a BVH file at ``path``, atomically (a complete file or none).

    See :func:`bvh_bytes` for ``decimals``.
    """
    atomic_write(path, bvh_bytes(motion, decimals))
