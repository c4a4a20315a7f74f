"""Reading and writing BVH files.

The header (hierarchy, Frames, Frame Time) is parsed here; the MOTION number block, most of a
file's bytes, by the kernel ``read_motion_blocks`` (Rust, or its NumPy twin). Every problem is a
:class:`~expressive_mocap.errors.BVHError` naming the file, the line and what was expected.

Text is UTF-8, with or without a byte-order mark; lines end in LF or CRLF (CR-only files, from
classic Mac OS, are refused with how to convert them). Numbers follow one grammar, header and
MOTION block alike (:mod:`expressive_mocap.tokens`), and tokens echoed in errors are cut to 40
bytes (:func:`~expressive_mocap.tokens.shown`).
"""

from __future__ import annotations

import errno
import os
import re
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from typing import BinaryIO, Iterable, Union

import numpy as np

from . import ops
from .errors import BVHError, MocapError, ParseError
from .files import MAX_INPUT_BYTES, atomic_write, open_input, read_input
from .motion import POSITION_CHANNELS, ROTATION_CHANNELS, Motion, Skeleton, canonical_channels
from .tokens import NUMBER_PATTERN, finite_number, shown

Source = Union[str, os.PathLike, bytes, bytearray, memoryview, BinaryIO]

_TOKEN = re.compile(r"[{}]|[^ \t\r\n\x0c{}]+")  # ASCII blanks, as in the MOTION block (tokens.py)
_KEYWORDS = frozenset(["}", "OFFSET", "CHANNELS", "JOINT", "ROOT"])  # already in upper case
_CHANNEL_NAMES = frozenset(c.lower() for c in POSITION_CHANNELS + ROTATION_CHANNELS)
_MOTION = re.compile(rb"^[ \t]*MOTION[ \t]*\r*$", re.MULTILINE | re.IGNORECASE)
_FRAMES = re.compile(rb"[ \t]*Frames[ \t]*:[ \t]*(\S*)[ \t]*\r*$", re.IGNORECASE)
_FRAME_TIME = re.compile(rb"[ \t]*Frame[ \t]+Time[ \t]*:[ \t]*(\S*)[ \t]*\r*$", re.IGNORECASE)


# Limits of the reader (README, "Limits"): within them, memory stays proportional to the file's
# size (a file under 1 MB never takes more than 100 MB); beyond them, a BVHError names the limit.
MAX_HEADER_BYTES = 4 << 20  # the hierarchy, HIERARCHY to MOTION (a 300-joint skeleton takes ~30 KB)
MAX_JOINTS = 10_000  # so also the depth of the hierarchy; read without recursion
MAX_CHANNELS = 6  # per joint: 3 positions and 3 rotations
# Frames x joints (decoded, 56 bytes a joint-frame; the NumPy twin peaks near 180) at most one per
# 3 bytes of the MOTION block (a joint's 3 channels take 6 or more), or this many for tiny blocks
# (a skeleton without channels).
BLOCK_BYTES_PER_JOINT_FRAME = 3
MIN_JOINT_FRAMES = 1 << 16
_COUNT = re.compile(r"[0-9]{1,18}")  # ASCII digits only: str.isdigit() also takes '²'
_COUNT_BYTES = re.compile(_COUNT.pattern.encode("ascii"))


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
            return read_input(source), str(source)
        except OSError as error:
            raise read_error(source, error) from None
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
        self.words: list[str] = []
        self.lines: list[int] = []
        for number, line in enumerate(text.split("\n"), 1):
            found = _TOKEN.findall(line)
            self.words += found
            self.lines += [number] * len(found)
        self.pos = 0
        self.last_line = text.count("\n") + 1

    def error(self, line: int | None, reason: str) -> BVHError:
        return BVHError(self.name, line, reason)

    def done(self) -> bool:
        return self.pos >= len(self.words)

    def next(self, expected: str) -> tuple[str, int]:
        pos = self.pos
        if pos >= len(self.words):
            raise self.error(self.last_line, f"unexpected end of the header: expected {expected}")
        self.pos = pos + 1
        return self.words[pos], self.lines[pos]

    def expect(self, word: str) -> int:
        token, line = self.next(repr(word))
        if token != word and token.lower() != word.lower():
            raise self.error(line, f"expected {word!r}, found {shown(token)}")
        return line

    def numbers(self, count: int, what: str) -> list[float]:
        start = self.pos
        if start + count > len(self.words):
            self.pos = len(self.words)
            self.next(what)  # raises the end-of-header error
        self.pos = start + count
        values = [finite_number(w) for w in self.words[start : start + count]]
        for k, value in enumerate(values, start):
            if value is None:
                raise self.error(self.lines[k], f"expected {what} (a finite number), found {shown(self.words[k])}")
        return values

    def name_on_line(self, keyword_line: int, what: str) -> str:
        """The rest of the keyword's line up to '{' (names may contain spaces or ':')."""
        start = pos = self.pos
        words, lines = self.words, self.lines
        while pos < len(words) and lines[pos] == keyword_line and words[pos] != "{":
            pos += 1
        if pos == start:
            raise self.error(keyword_line, f"expected the name of the {what}")
        self.pos = pos
        return words[start] if pos == start + 1 else " ".join(words[start:pos])


def _parse_hierarchy(tokens: _Tokens) -> tuple[Skeleton, list[int]]:
    """The skeleton, and the owner of each OFFSET in file order (joint j, or -1 - k for End Site k)."""
    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float] | None] = []
    channels: list[tuple[str, ...] | None] = []
    end_sites: list[tuple[int, list[float] | None]] = []
    opened_at: list[int] = []  # line of each joint's '{', for unbalanced-brace errors
    offset_owners: list[int] = []

    tokens.expect("HIERARCHY")
    root_line = tokens.expect("ROOT")
    # Stack of open blocks: a joint index, or -1 - (index into end_sites) for an End Site.
    stack: list[int] = []

    first_line: dict[str, int] = {}  # of each joint name

    def open_joint(keyword_line: int, parent: int) -> None:
        if len(names) == MAX_JOINTS:
            raise tokens.error(keyword_line, f"more than {MAX_JOINTS} joints: the reader's limit (see Limits in the README)")
        name = tokens.name_on_line(keyword_line, "joint")
        if name in first_line:
            raise tokens.error(keyword_line, f"joint name {shown(name)} appears more than once (first at line {first_line[name]})")
        first_line[name] = keyword_line
        names.append(name)
        parents.append(parent)
        offsets.append(None)
        channels.append(None)
        opened_at.append(tokens.expect("{"))
        stack.append(len(names) - 1)

    open_joint(root_line, -1)
    while stack:
        if tokens.done():
            joint = next(j for j in reversed(stack) if j >= 0)
            raise tokens.error(tokens.last_line, f"unbalanced braces: the '{{' of joint {shown(names[joint])} at line {opened_at[joint]} is never closed")
        token, line = tokens.next("'}'")
        top = stack[-1]
        word = token if token in _KEYWORDS else token.upper()
        if word == "}":
            if top >= 0 and offsets[top] is None:
                raise tokens.error(line, f"joint {shown(names[top])} has no OFFSET")
            if top < 0 and end_sites[-1 - top][1] is None:
                raise tokens.error(line, "End Site has no OFFSET")
            stack.pop()
        elif top < 0:
            if word != "OFFSET" or end_sites[-1 - top][1] is not None:
                raise tokens.error(line, f"expected OFFSET or '}}' in an End Site, found {shown(token)}")
            end_sites[-1 - top] = (end_sites[-1 - top][0], tokens.numbers(3, "an OFFSET value"))
            offset_owners.append(top)
        elif word == "OFFSET":
            if offsets[top] is not None:
                raise tokens.error(line, f"joint {shown(names[top])} has a second OFFSET")
            offsets[top] = tokens.numbers(3, "an OFFSET value")
            offset_owners.append(top)
        elif word == "CHANNELS":
            if channels[top] is not None:
                raise tokens.error(line, f"joint {shown(names[top])} has a second CHANNELS line")
            count_token, count_line = tokens.next("the number of channels")
            if not _COUNT.fullmatch(count_token) or int(count_token) > MAX_CHANNELS:
                raise tokens.error(count_line, f"expected a channel count from 0 to {MAX_CHANNELS}, found {shown(count_token)}")
            listed = tuple(tokens.words[tokens.pos : tokens.pos + int(count_token)])
            if len(listed) < int(count_token):
                tokens.pos = len(tokens.words)
                tokens.next("a channel name")  # raises the end-of-header error
            tokens.pos += len(listed)
            try:
                channels[top] = canonical_channels(listed)
            except MocapError as error:
                bad = next(k for k, n in enumerate(listed) if n.lower() not in _CHANNEL_NAMES)
                raise tokens.error(tokens.lines[tokens.pos - len(listed) + bad], str(error)) from None
            if len(set(channels[top])) != len(listed):  # canonical names: "Xrotation" and "XROTATION" are one
                raise tokens.error(line, f"joint {shown(names[top])} lists a channel twice: {' '.join(listed)}")
        elif word == "JOINT":
            open_joint(line, top)
        elif word == "END":
            tokens.expect("Site")
            end_sites.append((top, None))
            tokens.expect("{")
            stack.append(-len(end_sites))
        elif word == "ROOT":
            raise tokens.error(line, "several ROOT hierarchies in one file are not supported (a ROOT inside a joint)")
        else:
            raise tokens.error(line, f"expected OFFSET, CHANNELS, JOINT, End Site or '}}', found {shown(token)}")

    if not tokens.done():
        token, line = tokens.next("MOTION")
        if token.upper() == "ROOT":
            raise tokens.error(line, "several ROOT hierarchies in one file are not supported: only the first ROOT can be read")
        if token == "}":
            raise tokens.error(line, "unbalanced braces: this '}' closes nothing")
        raise tokens.error(line, f"expected MOTION after the hierarchy, found {shown(token)}")
    try:
        skeleton = Skeleton(
            names=tuple(names),
            parents=np.array(parents),
            offsets=np.array(offsets, dtype=np.float64),
            channels=tuple(c or () for c in channels),
            end_sites=tuple((j, tuple(off)) for j, off in end_sites),
        )
    except MocapError as error:  # the checks above should catch everything first, with a line
        raise tokens.error(None, str(error)) from None
    return skeleton, offset_owners


# Archives repeat a few hierarchies, some with different numbers (Bandai-Namco's Hips offset
# changes from clip to clip). A hierarchy is cached under its exact text, and under its text with
# the OFFSET numbers cut out: a file of a known shape then only converts its numbers. Anything
# unusual takes the full parse, whose errors name the line.
# A number is cut out only whole: "0}" stays in the shape (found by fuzz_bvh.py: "OFFSET 0 0 0}"
# cached a shape that a later "OFFSET 0 0 0" without its brace matched, and was read).
# Only tokens of the number grammar are cut out: anything else takes the full parse and its error.
_OFFSET_NUMBERS = re.compile(rf"(?<=OFFSET)[ \t]+({NUMBER_PATTERN})[ \t]+({NUMBER_PATTERN})[ \t]+({NUMBER_PATTERN})(?=[ \t]*\r*$)", re.MULTILINE)
_SHAPES: dict[tuple[str, ...], tuple[Skeleton, np.ndarray, np.ndarray]] = {}
_HIERARCHIES: dict[str, Skeleton] = {}
_MAX_SHAPES = 64


def _skeleton(text: str, name: str) -> Skeleton:
    exact = _HIERARCHIES.get(text)
    if exact is not None:
        return exact
    parts = _OFFSET_NUMBERS.split(text)
    shape = tuple(parts[0::4])
    cached = _SHAPES.get(shape)
    if cached is not None:
        template, joint_rows, site_rows = cached
        try:
            offsets = np.array([parts[1::4], parts[2::4], parts[3::4]], dtype=np.float64).T
        except ValueError:
            offsets = None
        if offsets is not None and np.isfinite(offsets).all():
            return _remember(text, template.with_offsets(offsets[joint_rows], offsets[site_rows]))
    skeleton, owners = _parse_hierarchy(_Tokens(text, name))
    if len(owners) == len(shape) - 1:  # every OFFSET was cut out: the shape says it all
        owners = np.array(owners)
        joint_rows, site_rows = np.flatnonzero(owners >= 0), np.flatnonzero(owners < 0)
        if len(_SHAPES) >= _MAX_SHAPES:
            _SHAPES.clear()
        _SHAPES[shape] = (skeleton, joint_rows[np.argsort(owners[joint_rows])], site_rows[np.argsort(-1 - owners[site_rows])])
    return _remember(text, skeleton)


def _remember(text: str, skeleton: Skeleton) -> Skeleton:
    """Keep the skeleton of this exact hierarchy text: many clips share one (skeletons are immutable)."""
    if len(_HIERARCHIES) >= _MAX_SHAPES:
        _HIERARCHIES.clear()
    _HIERARCHIES[text] = skeleton
    return skeleton


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
        raise BVHError(name, 1, "CR-only line endings (classic Mac OS): expected LF or CRLF; convert the file first, e.g. tr '\\r' '\\n' < old.bvh > new.bvh")
    if not head[start : start + 9].upper().startswith(b"HIERARCHY"):
        end = data.find(b"\n", bom + start)
        first = memoryview(data)[bom + start : len(data) if end < 0 else end]
        raise BVHError(name, head.count(b"\n", 0, start) + 1, f"expected 'HIERARCHY' at the start of a BVH file, found {shown(first)}")
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
    55 ms of the 76 ms that parsing them took; with this, 16 ms of 37 ms), so candidates are found with ``bytes.find`` in lower-cased
    windows (every MOTION line contains "motion") and only their lines are matched. The first
    window ends after the first upper-case MOTION, usually the line. Each byte is lowered,
    searched for newlines and matched at most a bounded number of times: linear on any input."""
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


def parse_header(data: bytes, name: str, size: int | None = None) -> _Header:
    """The header of the BVH text ``data``; ``size``: the whole file's length when ``data`` is
    only its beginning (see :func:`read_header`)."""
    text_start = _check_text(data, name)
    motion = _find_motion_line(data)
    hierarchy_end = motion.start() if motion else len(data)
    if hierarchy_end > MAX_HEADER_BYTES:
        where = "the hierarchy" if motion else "the hierarchy (no MOTION line found)"
        raise BVHError(name, None, f"{where} is longer than {MAX_HEADER_BYTES} bytes: the reader's limit (see Limits in the README)")
    try:
        text = data[text_start:hierarchy_end].decode("utf-8")  # without the byte-order mark: lines are the same
    except UnicodeDecodeError as error:
        raise BVHError(name, _line_at(data, text_start + error.start), "bytes that are not UTF-8 text: not a BVH text file") from None
    skeleton = _skeleton(text, name)
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
            raise BVHError(name, line, f"expected {what} after MOTION, found {shown(found)}" if found else f"missing {what} after MOTION")
        values.append((match.group(1), line))
        position = end + 1

    (frames_text, frames_line), (time_text, time_line) = values
    if not _COUNT_BYTES.fullmatch(frames_text):
        raise BVHError(name, frames_line, f"expected a whole number of frames (at most 18 digits) after 'Frames:', found {shown(frames_text)}")
    frames, block_start = int(frames_text), min(position, len(data))
    block_bytes = (len(data) if size is None else size) - block_start
    if frames * skeleton.n_joints > max(block_bytes // BLOCK_BYTES_PER_JOINT_FRAME, MIN_JOINT_FRAMES):
        raise BVHError(
            name,
            frames_line,
            f"Frames: {frames} x {skeleton.n_joints} joints is more than the {block_bytes}-byte MOTION block can hold (the reader's "
            f"limit: one joint-frame per {BLOCK_BYTES_PER_JOINT_FRAME} bytes of the block, or {MIN_JOINT_FRAMES}; see Limits in the README)",
        )
    frame_time = finite_number(time_text.decode("utf-8", "replace"))
    if frame_time is None or frame_time <= 0:
        raise BVHError(name, time_line, f"expected a positive number of seconds after 'Frame Time:', found {shown(time_text)}")
    return _Header(skeleton, frames, frame_time, block_start, time_line + 1)


HEADER_PREFIX = 1 << 14  # bytes read first for a header: hierarchies are a few kilobytes (Bandai 3.4-4 KB)


def read_header(path: str | os.PathLike) -> tuple[_Header, bytes | None]:
    """The header of the BVH file at ``path`` and, only where it needed them, the file's bytes.

    The header is parsed from the file's first 16 KB when it fits there (the usual case): the
    caller then reads the MOTION block itself (``preprocess`` does, in Rust, in parallel), and
    ``None`` is returned for the bytes. A header that does not fit, or an error, is taken from the
    whole file, so the result and any error are those of :func:`read_bvh`. Raises BVHError.
    """
    name = str(path)
    try:
        with open_input(path) as handle:
            data = handle.read(HEADER_PREFIX)
            if len(data) == HEADER_PREFIX:  # maybe more: try the header from this beginning
                size = os.fstat(handle.fileno()).st_size
                try:
                    header = parse_header(data, name, size)
                except BVHError:
                    header = None
                # The Frame Time line must have ended inside the beginning: a number cut by the
                # boundary of those bytes would otherwise be read short.
                if header is not None and header.block_start < len(data):
                    return header, None
                data += handle.read(MAX_INPUT_BYTES + 1 - len(data))
                if len(data) > MAX_INPUT_BYTES:
                    raise OSError(errno.EFBIG, f"more than the {MAX_INPUT_BYTES:,} bytes read at most", name)
    except OSError as error:
        raise read_error(name, error) from None
    return parse_header(data, name), data


def read_error(name: str | os.PathLike, error: OSError) -> BVHError:
    """The BVHError of a file that could not be read (Python's or the Rust kernel's OSError)."""
    return BVHError(name, None, f"cannot read the file: {error.strerror or error}")


def block_error(name: str, header: _Header, error: Exception) -> BVHError:
    message, line_in_block = error.args
    return BVHError(name, header.block_line + line_in_block, message)


def read_bvh(source: Source) -> Motion:
    """Read a BVH file from a path, bytes, or a binary file object.

    Raises :class:`~expressive_mocap.errors.BVHError` (naming the file and line) on malformed
    input: rotations come out as unit quaternions, translations as offsets or position channels.
    """
    data, name = _load(source)
    results: list = [None]
    _collect(batch := [(0, name, parse_header(data, name), data)], _decode(batch), results)
    if isinstance(results[0], BVHError):
        raise results[0]
    return results[0]


def read_bvh_many(sources: Iterable[Source], errors: str = "raise", batch_bytes: int = 32 << 20) -> list:
    """Read many files; their number blocks are parsed and decoded in parallel (Rust).

    Files are taken in batches of about ``batch_bytes``: while the kernels work on one batch
    (without the GIL), the next one is read and its headers parsed, and a batch's bytes are
    dropped once decoded. ``errors="raise"`` raises the first bad file's :class:`BVHError`;
    ``errors="return"`` puts the error in that file's place in the returned list instead.
    """
    if errors not in ("raise", "return"):
        raise MocapError(f"errors must be 'raise' or 'return', got {errors!r}")
    results: list = []
    with ThreadPoolExecutor(max_workers=1) as decoder:
        running = None
        for batch in _batches(sources, batch_bytes, results):
            if running is not None:
                _collect(*running, results)
            running = (batch, decoder.submit(_decode, batch))
        if running is not None:
            _collect(*running, results)
    if errors == "raise":
        first_error = next((r for r in results if isinstance(r, BVHError)), None)
        if first_error is not None:
            raise first_error
    return results


def _batches(sources: Iterable[Source], batch_bytes: int, results: list):
    """Load sources and parse their headers, yielding ``(index, name, header, data)`` batches;
    a source that fails here gets its BVHError in ``results`` at once."""
    batch, size = [], 0
    for source in sources:
        try:
            data, name = _load(source)
            header = parse_header(data, name)
        except BVHError as error:
            results.append(error)
            continue
        batch.append((len(results), name, header, data))
        results.append(None)
        size += len(data)
        if size >= batch_bytes:
            yield batch
            batch, size = [], 0
    if batch:
        yield batch


def _decode(batch: list) -> list:
    """The kernel's (rotations, translations) or ParseError for each file of a batch."""
    return ops.read_motion_blocks([(data, h) for _, _, h, data in batch])


def _collect(batch: list, decoded: Future | list, results: list) -> None:
    """Put each file's Motion, or its BVHError, in its place in ``results``."""
    if isinstance(decoded, Future):
        decoded = decoded.result()
    for (index, name, header, _), result in zip(batch, decoded):
        if isinstance(result, ParseError):
            results[index] = block_error(name, header, result)
        else:
            results[index] = Motion(header.skeleton, *result, header.frame_time)


def _number(value: float, decimals: int | None) -> str:
    if decimals is None:
        return np.format_float_positional(value + 0.0, trim="-")
    return f"{value:.{decimals}f}"


_MAX_INDENT = 16  # tabs: deeper joints are not indented further, so a deep chain's header stays linear


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
            inner = "\t" * min(depth + 1, _MAX_INDENT)
            lines.extend([f"{inner}End Site", f"{inner}{{", offset_line(inner + "\t", offset), f"{inner}}}"])
        lines.append("\t" * min(depth, _MAX_INDENT) + "}")

    open_joints: list[int] = []
    for j, parent in enumerate(skeleton.parents.tolist()):
        while open_joints and open_joints[-1] != parent:
            close(open_joints.pop(), len(open_joints))
        if parent >= 0 and not open_joints:
            raise MocapError("joints must be in depth-first order (each subtree contiguous) to be written as BVH")
        indent = "\t" * min(len(open_joints), _MAX_INDENT)
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
    values = motion.channel_values()
    if not np.isfinite(values).all():  # "inf"/"nan" in a file is refused by every reader, ours too
        frame, column = (int(i) for i in np.argwhere(~np.isfinite(values))[0])
        joint = np.searchsorted(np.cumsum([len(cs) for cs in skeleton.channels]), column, side="right")
        channel = skeleton.channels[joint][column - sum(len(cs) for cs in skeleton.channels[:joint])]
        raise MocapError(f"frame {frame}, {skeleton.names[joint]} {channel} is {values[frame, column]}: a BVH file holds finite numbers only")
    return header + ops.format_motion_block(values, decimals)


def write_bvh(motion: Motion, path: str | os.PathLike, decimals: int | None = None) -> None:
    """Write ``motion`` as a BVH file at ``path``, atomically (a complete file or none; see
    :func:`expressive_mocap.files.atomic_write_all` for what ``path`` may be). A non-finite value
    is refused, naming ``path``, the frame and the channel, before anything is written.

    See :func:`bvh_bytes` for ``decimals``.
    """
    if not isinstance(motion, Motion):
        got = f"an array {list(motion.shape)}" if isinstance(motion, np.ndarray) else f"a {type(motion).__name__}"
        # The likely slip: Decomposition.body / .expressive are rotation arrays, its motions come from methods.
        raise MocapError(f"write_bvh needs a Motion, got {got}; for a Decomposition use parts.body_motion(), "
                         "parts.expressive_motion() or parts.recompose(scale)")
    try:
        data = bvh_bytes(motion, decimals)
    except MocapError as error:
        raise MocapError(f"cannot write {path}: {error}") from None
    atomic_write(path, data)
