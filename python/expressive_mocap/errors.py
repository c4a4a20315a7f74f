"""The package's exceptions: one base, and one for malformed BVH files."""

from __future__ import annotations

import os


class MocapError(ValueError):
    """Base class of every error expressive-mocap raises on bad input."""


class BVHError(MocapError):
    """A BVH file that cannot be read. Names the file, the line (1-based) and what was expected.

    Attributes: ``source`` (path or a description such as ``<bytes>``), ``line`` (int or None),
    ``reason`` (the message without the location).
    """

    def __init__(self, source: str | os.PathLike, line: int | None, reason: str):
        self.source = str(source)
        self.line = line
        self.reason = reason
        where = f"{self.source}, line {line}" if line is not None else self.source
        super().__init__(f"{where}: {reason}")


class ClipError(MocapError):
    """A clip among several given together (the people and intensities of a training set) that
    cannot be used: ``person`` and ``level`` (indices) say which, so that a caller holding the
    file names can name its file."""

    def __init__(self, message: str, person: int, level: int):
        super().__init__(message)
        self.person = person
        self.level = level
