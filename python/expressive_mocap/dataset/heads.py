"""A batch's headers read ahead (:func:`headers_ahead`): the files that repeat a header met in
the batch get it without being parsed, most of them in one kernel call without the GIL."""

from __future__ import annotations

from typing import cast

from .. import ops
from .._utils import files as inputs
from ..bvh import parse_header
from ..bvh.header import Header, header_template, repeated_header
from ..bvh.reader import HEADER_PREFIX
from ..errors import BVHError
from .sources import Item


def headers_ahead(batch: list[Item]) -> dict[int, object]:
    """The headers of the batch's files that repeat one of them, by index: a Header, or for a
    file that does not repeat one, its first bytes and size (for
    :func:`~expressive_mocap.bvh.read_header`), or the OSError reading it. One kernel call
    (``repeated_headers``: in parallel, without the GIL) reads every file against the first
    header that holds more than its beginning (a shorter file's header is read with the whole
    file); a file it does not match (another actor's skeleton) is parsed here once for each
    header it brings, and the files repeating that one are matched to it here (:func:`_others`).
    Each header's own first bytes are handed on too, so no file is read twice. Empty when there
    is none, or when the first header's own lines are not in the plainest form (see
    :func:`.header.repeated_header`)."""
    files = [k for k, item in enumerate(batch) if item.is_file]
    first = next((k for k in files if batch[k].size > HEADER_PREFIX), None)
    if first is None or len(files) < 2:
        return {}
    path = batch[first].path
    try:
        data, size = inputs.read_beginning(path, HEADER_PREFIX)  # type: ignore[arg-type]
        header = parse_header(data, str(path), size)
    except (OSError, BVHError):
        return {}  # its own error comes from the full reader, with the others'
    template = header_template(data, size, header) if len(data) == HEADER_PREFIX else None
    if template is None:
        return {}
    others = [k for k in files if k != first]
    paths = [str(batch[k].path) for k in others]
    found = ops.repeated_headers(paths, template, header.skeleton.n_joints, HEADER_PREFIX)
    known: dict[int, object] = {first: (data, size)}
    unmatched = []  # the files read but not matched: their first bytes and size
    for k, result in zip(others, found):
        if isinstance(result, tuple) and not isinstance(result[0], bytes):
            known[k] = _repeating(header, result)
        else:
            known[k] = result
            unmatched += [k] if isinstance(result, tuple) else []
    _others(batch, known, unmatched)
    return known


def _repeating(header: Header, timing: tuple) -> Header:
    """The header of a file that repeats ``header``'s hierarchy with its own ``timing``
    ``(frames, frame_time, block_start)``."""
    frames, frame_time, block_start = timing
    return Header(header.skeleton, frames, frame_time, block_start, header.block_line)


def _others(batch: list[Item], known: dict[int, object], unmatched: list[int]) -> None:
    """The ``unmatched`` files of ``known`` (first bytes and size: the kernel's template was
    not theirs) matched, in batch order, to the headers found among them: the first file of each
    other header is parsed (and keeps its bytes), the files repeating it get its header. A
    batch of an archive of three actors parses three headers, not two thirds of its files
    (18 us each, holding the GIL against the pipeline's other threads)."""
    templates: list[tuple[bytes, Header]] = []  # the other headers met so far
    for k in unmatched:
        data, size = cast(tuple[bytes, int], known[k])
        whole = len(data) < HEADER_PREFIX
        timings = (repeated_header(data, size, whole, t, h.skeleton.n_joints) for t, h in templates)
        match = next(((h, timing) for (_, h), timing in zip(templates, timings) if timing is not None), None)
        if match is not None:
            known[k] = _repeating(*match)
        elif not whole:  # (a file that short is read whole, as any)
            try:
                header = parse_header(data, batch[k].source, size)
            except BVHError:
                continue  # its own error comes from the full reader
            template = header_template(data, size, header)
            if template is not None:
                templates.append((template, header))


__all__ = ["headers_ahead"]
