"""The header of a BVH file from its bytes: the text checks (encoding, line endings), the
hierarchy (:mod:`.hierarchy`), the MOTION line, ``Frames`` and ``Frame Time``, and where the
number block starts.

Text is UTF-8, with or without a byte-order mark; lines end in LF or CRLF (CR-only files, from
classic Mac OS, are refused with how to convert them). Numbers follow one grammar, header and
MOTION block alike (:mod:`expressive_mocap._utils.tokens`), and tokens echoed in errors are cut to 40
bytes (:func:`~expressive_mocap._utils.tokens.shown`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, TypeVar

from .._utils.tokens import finite_number, shown
from ..errors import BVHError
from .tree import COUNT_PATTERN, Tree, parse_tree

if TYPE_CHECKING:
    from ..motion import Skeleton

__all__ = [
    "BLOCK_BYTES_PER_JOINT_FRAME",
    "MAX_HEADER_BYTES",
    "MIN_JOINT_FRAMES",
    "Header",
    "header_template",
    "parse_header",
    "parse_tree_header",
    "repeated_header",
]

_MOTION = re.compile(rb"^[ \t]*MOTION[ \t]*\r*$", re.MULTILINE | re.IGNORECASE)
_FRAMES = re.compile(rb"[ \t]*Frames[ \t]*:[ \t]*(\S*)[ \t]*\r*$", re.IGNORECASE)
_FRAME_TIME = re.compile(rb"[ \t]*Frame[ \t]+Time[ \t]*:[ \t]*(\S*)[ \t]*\r*$", re.IGNORECASE)
_COUNT_BYTES = re.compile(COUNT_PATTERN.encode("ascii"))

# Limits of the reader (docs/safety.md, "Limits"): within them, memory stays proportional to the file's
# size (a file under 1 MB never takes more than 100 MB); beyond them, a BVHError names the limit.
MAX_HEADER_BYTES = 4 << 20  # the hierarchy, HIERARCHY to MOTION (a 300-joint skeleton takes ~30 KB)
# Frames x joints (decoded, 56 bytes a joint-frame; the NumPy twin peaks near 180) at most one per
# 3 bytes of the MOTION block (a joint's 3 channels take 6 or more), or this many for tiny blocks
# (a skeleton without channels).
BLOCK_BYTES_PER_JOINT_FRAME = 3
MIN_JOINT_FRAMES = 1 << 16


# The hierarchy as read: a Skeleton (:func:`parse_header`), or its plain Tree (:func:`parse_tree_header`).
S = TypeVar("S", "Skeleton", Tree)


@dataclass
class Header(Generic[S]):
    """What a BVH file's header says, and where its number block starts."""

    skeleton: S
    frames: int
    frame_time: float
    block_start: int  # byte offset of the number block
    block_line: int  # 1-based line number of the number block's first line


_BOM = b"\xef\xbb\xbf"  # UTF-8 byte-order mark: some exporters start files with it


def _check_text(data: bytes, name: str) -> int:
    """Refuse empty and binary files and CR-only line endings early, looking at the first few
    kilobytes only. Returns where the text starts: 3 after a UTF-8 byte-order mark, else 0."""
    bom = len(_BOM) if data.startswith(_BOM) else 0
    head = data[bom:4096]
    start = len(head) - len(head.lstrip())
    if start == len(head) and not data[bom + len(head) :].strip():
        raise BVHError(name, None, "the file is empty: expected a BVH file starting with HIERARCHY")
    if b"\0" in head:
        raise BVHError(name, None, f"binary data (a NUL byte at offset {head.index(0)}): not a BVH text file")
    if _cr_only(head, bom + len(head) == len(data)):
        # Lines are LF or CRLF in both MOTION parsers and in preprocess, which hands a file's
        # path and byte offsets to the Rust kernel: reading CR-only text would take a copy.
        raise BVHError(
            name,
            1,
            "CR-only line endings (classic Mac OS): expected LF or CRLF; convert the file first, "
            "e.g. tr '\\r' '\\n' < old.bvh > new.bvh",
        )
    if not head[start : start + 9].upper().startswith(b"HIERARCHY"):
        end = data.find(b"\n", bom + start)
        first = memoryview(data)[bom + start : len(data) if end < 0 else end]
        raise BVHError(
            name,
            head.count(b"\n", 0, start) + 1,
            f"expected 'HIERARCHY' at the start of a BVH file, found {shown(first)}",
        )
    return bom


def _cr_only(head: bytes, whole: bool) -> bool:
    """Whether the first line break of ``head`` (the file's beginning, or ``whole`` file) is
    CR alone: CRs not followed by LF ("\r\r\n", from converting twice, is a CRLF)."""
    breaks = re.search(rb"[\r\n]", head)
    if breaks is None or breaks[0] == b"\n":
        return False
    after = head[breaks.start() :].lstrip(b"\r")[:1]
    return after != b"\n" and (after != b"" or whole)  # CRs up to the end of a part: maybe LF next


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


def _find_motion_line(data: bytes) -> re.Match | None:
    """The first line that is MOTION (any case): ``_MOTION.search(data)``, 3.5x faster.

    The case-insensitive regex tries every byte of the hierarchy (on dataset-2's 2,902 headers:
    55 ms of the 76 ms that parsing them took; with this, 16 ms of 37 ms), so candidates are found
    with ``bytes.find`` in lower-cased windows (every MOTION line contains "motion") and only their
    lines are matched. The first window ends after the first upper-case MOTION, usually the line.
    Each byte is lowered, searched for newlines and matched at most a bounded number of times: linear on any input."""
    exact = data.find(b"MOTION")
    start, end = 0, exact + 6 if exact >= 0 else 1 << 12
    line_start, scanned, tried = 0, 0, -1
    while True:
        lower = data[start:end].lower()
        position = lower.find(b"motion")
        while position >= 0:
            newline = data.rfind(b"\n", scanned, start + position)
            scanned = start + position
            if newline >= 0:
                line_start = newline + 1
            if line_start != tried:  # each line is matched once, however many candidates it holds
                tried = line_start
                match = _MOTION.match(data, line_start)
                if match is not None:
                    return match
            position = lower.find(b"motion", position + 1)
        if end >= len(data):
            return None
        start, end = end - 5, 4 * end  # the next window repeats 5 bytes: a candidate may cross the end


# The Python reader's line patterns, in their plainest form (see rust/heads.rs): a token ends
# at Rust's ASCII whitespace (space, tab, LF, FF, CR).
_TOKEN = rb"([^ \t\n\x0c\r]*)[ \t]*\r*"
_FRAMES_LINE = re.compile(rb"Frames:[ \t]*" + _TOKEN)
_FRAME_TIME_LINE = re.compile(rb"Frame Time:[ \t]*" + _TOKEN)
_COUNT = re.compile(rb"[0-9]{1,18}")
_PLAIN = re.compile(rb"[0-9]+(?:\.[0-9]+)?")


def repeated_header(data: bytes, size: int, whole: bool, template: bytes, joints: int) -> tuple | None:
    """``(frames, frame_time, block_start)`` of a file whose first bytes ``data`` (all of it when
    ``whole``; ``size`` the file's) are ``template`` (a header's bytes through its MOTION line, of
    ``joints`` joints) then ``Frames:`` and ``Frame Time:`` lines in their plainest form: the file's
    header is then the template's with these values, as :func:`parse_header` reads it. None for
    anything else, and for what :func:`~expressive_mocap.bvh.read_header` reads from the whole
    file or refuses: the full reader then reads it. The kernel ``repeated_headers`` (rust/heads.rs)
    reads files the same way, in parallel."""
    if whole or not template or not data.startswith(template):
        return None
    bom = 3 if data.startswith(b"\xef\xbb\xbf") else 0
    if b"\0" in data[len(template) : min(len(data), bom + 4096)]:
        return None
    values, position = [], len(template)
    for pattern in (_FRAMES_LINE, _FRAME_TIME_LINE):
        end = data.find(b"\n", position)
        match = pattern.fullmatch(data, position, end) if end >= 0 else None
        if match is None:
            return None
        values.append(match.group(1))
        position = end + 1
    frames_text, time_text = values
    if not (_COUNT.fullmatch(frames_text) and _PLAIN.fullmatch(time_text)):
        return None
    frames, frame_time = int(frames_text), float(time_text)
    if not (math.isfinite(frame_time) and frame_time > 0) or position >= len(data) or size < position:
        return None
    if frames * joints > max((size - position) // 3, 1 << 16):
        return None
    return frames, frame_time, position


def header_template(data: bytes, size: int, header: Header) -> bytes | None:
    """The bytes of ``header``'s file (its first ``data``, ``size`` its length) through its MOTION
    line, when the file's own Frames and Frame Time lines read through it as :func:`repeated_header`
    reads them (so files repeating them have ``header``'s skeleton and line numbers); else None."""
    motion = _find_motion_line(data)
    if motion is None or data[motion.end() : motion.end() + 1] != b"\n":
        return None
    template = data[: motion.end() + 1]
    found = repeated_header(data, size, False, template, header.skeleton.n_joints)
    return template if found == (header.frames, header.frame_time, header.block_start) else None


def parse_header(data: bytes, name: str, size: int | None = None) -> Header[Skeleton]:
    """The header of the BVH text ``data``; ``size``: the whole file's length when ``data`` is
    only its beginning (see :func:`~expressive_mocap.bvh.reader.read_header`)."""
    from .hierarchy import read_hierarchy  # NumPy: a summary of a file goes without (parse_tree_header)

    return _parse(data, name, size, read_hierarchy)


def parse_tree_header(data: bytes, name: str, size: int | None = None) -> Header[Tree]:
    """:func:`parse_header`, its hierarchy as a plain :class:`~.tree.Tree` (no NumPy)."""
    return _parse(data, name, size, lambda text, name: parse_tree(text, name)[0])


def _parse(data: bytes, name: str, size: int | None, read: Callable[[str, str], S]) -> Header[S]:
    # The header's parts in file order, each refused with its line: one function reads best.
    text_start = _check_text(data, name)
    motion = _find_motion_line(data)
    hierarchy_end = motion.start() if motion else len(data)
    if hierarchy_end > MAX_HEADER_BYTES:
        where = "the hierarchy" if motion else "the hierarchy (no MOTION line found)"
        raise BVHError(
            name,
            None,
            f"{where} is longer than {MAX_HEADER_BYTES} bytes: the reader's limit (see docs/safety.md, Limits)",
        )
    try:
        text = data[text_start:hierarchy_end].decode("utf-8")  # without the byte-order mark: lines are the same
    except UnicodeDecodeError as error:
        raise BVHError(
            name, _line_at(data, text_start + error.start), "bytes that are not UTF-8 text: not a BVH text file"
        ) from None
    skeleton = read(text, name)
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
            found = data[start:end].strip()
            raise BVHError(
                name,
                line,
                f"expected {what} after MOTION, found {shown(found)}" if found else f"missing {what} after MOTION",
            )
        values.append((match.group(1), line))
        position = end + 1

    (frames_text, frames_line), (time_text, time_line) = values
    if not _COUNT_BYTES.fullmatch(frames_text):
        raise BVHError(
            name,
            frames_line,
            f"expected a whole number of frames (at most 18 digits) after 'Frames:', found {shown(frames_text)}",
        )
    frames, block_start = int(frames_text), min(position, len(data))
    block_bytes = (len(data) if size is None else size) - block_start
    if frames * skeleton.n_joints > max(block_bytes // BLOCK_BYTES_PER_JOINT_FRAME, MIN_JOINT_FRAMES):
        raise BVHError(
            name,
            frames_line,
            f"Frames: {frames} x {skeleton.n_joints} joints is more than the {block_bytes}-byte MOTION block can hold "
            f"(the reader's limit: one joint-frame per {BLOCK_BYTES_PER_JOINT_FRAME} bytes of the block, "
            f"or {MIN_JOINT_FRAMES}; see docs/safety.md, Limits)",
        )
    frame_time = finite_number(time_text.decode("utf-8", "replace"))
    if frame_time is None or frame_time <= 0:
        raise BVHError(
            name, time_line, f"expected a positive number of seconds after 'Frame Time:', found {shown(time_text)}"
        )
    return Header(skeleton, frames, frame_time, block_start, time_line + 1)
