"""The package's exceptions: every error caused by bad input or bad arguments is a
:class:`MocapError` (a ``ValueError``), raised from Python and from the Rust kernels alike, and the
command line turns exactly these into its one-line messages. The subclasses say what was wrong:

- :class:`ArgumentError`: an argument of a function or command (a shape, a dtype, a value);
  :class:`ArgumentTypeError` when its kind is wrong (also a ``TypeError``);
- :class:`BVHError`: a BVH file, naming the file and the line; :class:`ParseError`: a MOTION
  number block, before the file is known (turned into a BVHError by the reader);
- :class:`ModelError`: a model file or a model that cannot be used as asked;
- :class:`DatasetError`: a preprocessed dataset folder;
- :class:`ClipError`: one clip among several given together.
"""

from __future__ import annotations

import os


class MocapError(ValueError):
    """Base class of every error expressive-mocap raises on bad input."""


class ArgumentError(MocapError):
    """A bad argument: its name, what was expected and what was given."""


class ArgumentTypeError(ArgumentError, TypeError):
    """An argument of the wrong kind (an array of another dtype or memory order): an
    :class:`ArgumentError`, and a ``TypeError`` as Python's own type checks raise."""


class ModelError(MocapError):
    """A model file that cannot be read, or a model that does not fit what it is asked to do."""


class DatasetError(MocapError):
    """A dataset folder that is not ours to write, or whose files its manifest does not vouch for."""


class ParseError(MocapError):
    """A MOTION number block that cannot be read: ``args == (message, line_in_block)``, the line
    counted from the block's first (0-based); the reader adds the file and the header's lines."""


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


__all__ = [
    "ArgumentError",
    "ArgumentTypeError",
    "BVHError",
    "ClipError",
    "DatasetError",
    "MocapError",
    "ModelError",
    "ParseError",
]
