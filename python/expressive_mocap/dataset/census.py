"""The header scan of a source before any clip is processed (:func:`take_census`): how many clips
of each skeleton (joint names and parents) and of each frame rate it holds, from the clips'
headers alone. A run keeps the skeleton most clips share (:meth:`Census.majority`), not the first
clip's, and under ``--canonical`` resamples every clip to the rate most clips share
(:meth:`Census.common_rate`) when they do not all share one."""

from __future__ import annotations

from collections import Counter
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

from ..bvh import parse_header, read_header
from ..bvh.header import Header
from ..bvh.reader import HEADER_PREFIX
from ..errors import BVHError
from .derive import RATE_TOLERANCE, Options
from .heads import headers_ahead
from .sources import Item, Source, member_beginning

# Files whose headers are read in one kernel call: their first bytes are held until parsed
# (16 KB each: 4 MB), so an archive of any size is scanned in bounded memory.
SCAN_CHUNK = 256


def snapped(fps: float) -> float:
    """A clip's frame rate as a dataset names it: the whole number of frames a second a file's
    rounded frame time stands for (0.0333333 s: 30, 0.008333 s: 120), else 6 significant digits."""
    whole = round(fps)
    if whole >= 1 and abs(fps - whole) <= RATE_TOLERANCE * fps:
        return float(whole)
    return float(f"{fps:.6g}")


def rates_of(clips: list[dict]) -> Counter:
    """The frame rates (:func:`snapped`) of a dataset's clip records -> how many clips (mirror
    images not counted: they are their clip's rate)."""
    return Counter(snapped(clip["fps"]) for clip in clips if "mirror_of" not in clip)


def dataset_rate(clips: list[dict]) -> float | None:
    """The rate every clip of a dataset is stored at, or None: clips of several rates (or none)."""
    rates = rates_of(clips)
    return next(iter(rates)) if len(rates) == 1 else None


def shape_of(header: Header) -> tuple:
    """A header's hierarchy as the dataset compares them: (joint names, parents)."""
    return tuple(header.skeleton.names), tuple(header.skeleton.parents.tolist())


@dataclass
class Census:
    """What the headers of a source's clips say: clips per hierarchy (``shapes``: (names,
    parents) -> count, in the order first met) and per frame rate (``rates``: :func:`snapped`
    fps -> count); ``unread``: clips whose header could not be read here (the run says why)."""

    shapes: Counter = field(default_factory=Counter)
    rates: Counter = field(default_factory=Counter)
    unread: int = 0
    first_only: bool = False  # a tar stream: only its first readable clip was scanned

    @property
    def clips(self) -> int:
        return sum(self.shapes.values()) + self.unread

    def majority(self) -> tuple | None:
        """The hierarchy most clips share, (names, parents); on a tie the one met first (the
        first clip's by name in a folder, a glob or a zip). None when no header was read."""
        if not self.shapes:
            return None
        most = max(self.shapes.values())
        return next(shape for shape, count in self.shapes.items() if count == most)

    def resampling(self, shaping: Options) -> Options:
        """``shaping`` for an archive retargeted onto one body (``--canonical``): as given when it
        names a rate (``--fps``) or every clip shares one, else resampling every clip to the rate
        most clips share (:meth:`common_rate`; a tar's: its first clip's, whatever the others')."""
        if shaping.fps is not None or (len(self.rates) < 2 and not self.first_only):
            return shaping
        return replace(shaping, fps=self.common_rate())

    def common_rate(self) -> float | None:
        """The frame rate most clips share; on a tie the higher (no clip loses frames to it).
        None when no header was read."""
        if not self.rates:
            return None
        return max(self.rates, key=lambda rate: (self.rates[rate], rate))


def take_census(source: Source) -> Census:
    """The census of ``source``'s clips from their headers: a folder's or a glob's files from
    their first 16 KB (one kernel call for a few hundred files that repeat a header), a zip's
    members from their first decompressed 16 KB. A tar is a stream, read once: scanning it would
    decompress it all a second time (9.1 s for dataset-2's tar.xz, against 0.14 s for its
    folder), so only its first readable clip is (``first_only``): its skeleton and rate are the
    dataset's, as they are in archive order."""
    census = Census(first_only=source.items is None)
    items = source.items if source.items is not None else iter(source)
    for header in _headers(items):
        if header is None:
            census.unread += 1
            continue
        census.shapes[shape_of(header)] += 1
        census.rates[snapped(1.0 / header.frame_time)] += 1
        if census.first_only:
            break
    return census


def _headers(items: Iterable[Item]):
    """Each item's header, or None where it cannot be read."""
    chunk: list[Item] = []
    for item in items:
        if item.is_file:
            chunk.append(item)
            if len(chunk) == SCAN_CHUNK:
                yield from _file_headers(chunk)
                chunk = []
            continue
        try:
            if item.refused is not None:
                yield None
            elif item.smpl_model is not None:  # a parameter file: its header is the BVH it becomes
                yield parse_header(item.smpl_bvh(), item.source)
            elif item.data is not None:
                yield parse_header(item.data, item.source)
            else:
                yield _member_header(item)
        except BVHError:
            yield None
    yield from _file_headers(chunk)


def _file_headers(chunk: list[Item]):
    known = headers_ahead(chunk)
    for k, item in enumerate(chunk):
        found = known.get(k)
        if isinstance(found, Header):
            yield found
            continue
        try:
            yield read_header(item.path, found if isinstance(found, tuple) else None)[0]  # type: ignore[arg-type]
        except BVHError:
            yield None


def _member_header(item: Item) -> Header:
    """A zip member's header from its first decompressed bytes (the whole member when the header
    does not end in them)."""
    data, size = member_beginning(item, HEADER_PREFIX)
    if len(data) < size:
        try:
            header = parse_header(data, item.source, size)
            if header.block_start < len(data):  # the Frame Time line ended inside them
                return header
        except BVHError:
            pass
        data, size = member_beginning(item, None)
    return parse_header(data, item.source)


__all__ = ["SCAN_CHUNK", "Census", "dataset_rate", "rates_of", "shape_of", "snapped", "take_census"]
