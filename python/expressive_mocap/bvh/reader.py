"""Reading BVH files: :func:`read_bvh`, :func:`read_bvh_many` (many files, their number blocks
parsed in parallel), :func:`read_header` (the header alone, for readers of archives) and
:func:`read_summary` (the header of a file whose whole number block was checked, without NumPy
when the Rust kernels are in use: what ``expressive-mocap info`` says).

The header is parsed in Python (:mod:`.header`); the MOTION number block, most of a file's
bytes, by the kernel ``read_motion_blocks`` (Rust, or its NumPy twin). Every problem is a
:class:`~expressive_mocap.errors.BVHError` naming the file, the line and what was expected.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import TYPE_CHECKING, BinaryIO, Union

from .. import ops
from .._utils.files import read_beginning, read_input
from ..errors import BVHError, MocapError, ParseError
from .header import Header, parse_header, parse_tree_header
from .tree import Tree

if TYPE_CHECKING:
    from ..motion import Motion

__all__ = [
    "HEADER_PREFIX",
    "Source",
    "block_error",
    "read_bvh",
    "read_bvh_many",
    "read_error",
    "read_header",
    "read_summary",
]

Source = Union[str, os.PathLike, bytes, bytearray, memoryview, BinaryIO]


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


HEADER_PREFIX = 1 << 14  # bytes read first for a header: hierarchies are a few kilobytes (Bandai 3.4-4 KB)


def read_header(path: str | os.PathLike, beginning: tuple[bytes, int] | None = None) -> tuple[Header, bytes | None]:
    """The header of the BVH file at ``path`` and, only where it needed them, the file's bytes.

    The header is parsed from the file's first 16 KB when it fits there (the usual case): the
    caller then reads the MOTION block itself (``preprocess`` does, in Rust, in parallel), and
    ``None`` is returned for the bytes. A header that does not fit, or an error, is taken from the
    whole file, so the result and any error are those of :func:`read_bvh`. ``beginning``: those
    first bytes and the file's size, when the caller read them already. Raises BVHError.
    """
    name = str(path)
    try:
        data, size = read_beginning(path, HEADER_PREFIX) if beginning is None else beginning
        if len(data) == HEADER_PREFIX:  # maybe more: try the header from this beginning
            try:
                header = parse_header(data, name, size)
            except BVHError:
                header = None
            # The Frame Time line must have ended inside the beginning: a number cut by the
            # boundary of those bytes would otherwise be read short.
            if header is not None and header.block_start < len(data):
                return header, None
            data = read_input(path)
    except OSError as error:
        raise read_error(name, error) from None
    return parse_header(data, name), data


def read_summary(path: str | os.PathLike) -> Header[Tree]:
    """The header of the BVH file at ``path``, its hierarchy as a plain :class:`~.tree.Tree`,
    once its MOTION block has been checked: what :func:`read_bvh` refuses, this refuses with the
    same BVHError, without keeping a value (no NumPy with the Rust kernels)."""
    name = str(path)
    try:
        data = read_input(path)
    except OSError as error:
        raise read_error(name, error) from None
    header = parse_tree_header(data, name)
    try:
        ops.check_motion_block(data, header.block_start, header.frames, header.skeleton.n_channels)
    except ParseError as error:
        raise block_error(name, header, error) from None
    return header


def read_error(name: str | os.PathLike, error: OSError) -> BVHError:
    """The BVHError of a file that could not be read (Python's or the Rust kernel's OSError)."""
    return BVHError(name, None, f"cannot read the file: {error.strerror or error}")


def block_error(name: str, header: Header, error: Exception) -> BVHError:
    """The BVHError of a file whose MOTION block the kernels refused (their ParseError: a
    message and the line within the block)."""
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
    from concurrent.futures import ThreadPoolExecutor  # here: read_summary (`info`) has no use for it

    results: list = []
    with ThreadPoolExecutor(max_workers=1) as decoder:
        running = None
        for batch in _batches(sources, batch_bytes, results):
            if running is not None:
                _collect(running[0], running[1].result(), results)
            running = (batch, decoder.submit(_decode, batch))
        if running is not None:
            _collect(running[0], running[1].result(), results)
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


def _collect(batch: list, done: list, results: list) -> None:
    """Put each file's Motion, or its BVHError (``done``: what :func:`_decode` gave), in its place in ``results``."""
    from ..motion import Motion  # NumPy: not loaded by read_summary

    for (index, name, header, _), result in zip(batch, done):
        if isinstance(result, ParseError):
            results[index] = block_error(name, header, result)
        else:
            rotations, translations = result
            results[index] = Motion(header.skeleton, rotations, translations, header.frame_time)
