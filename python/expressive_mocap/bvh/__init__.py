"""Reading and writing BVH files.

:func:`read_bvh` / :func:`read_bvh_many` read files into :class:`~expressive_mocap.motion.Motion`
objects, :func:`write_bvh` / :func:`bvh_bytes` write them back. The parts: :mod:`.tree` (header
tokens and the joint tree), :mod:`.hierarchy` (its skeleton), :mod:`.header` (the whole header from
a file's bytes), :mod:`.reader`, :mod:`.writer` and :mod:`.channels` (the MOTION block's channel layout).
"""

from typing import TYPE_CHECKING

from .._utils.lazy import lazy_exports

# Each name loads on first use (PEP 562): read_summary (``expressive-mocap info``) needs no NumPy.
_LAZY = {
    "BLOCK_BYTES_PER_JOINT_FRAME": "header",
    "HEADER_PREFIX": "reader",
    "Header": "header",
    "MAX_CHANNELS": "tree",
    "MAX_HEADER_BYTES": "header",
    "MAX_JOINTS": "tree",
    "MIN_JOINT_FRAMES": "header",
    "Source": "reader",
    "block_error": "reader",
    "bvh_bytes": "writer",
    "parse_header": "header",
    "read_bvh": "reader",
    "read_bvh_many": "reader",
    "read_error": "reader",
    "read_header": "reader",
    "read_summary": "reader",
    "write_bvh": "writer",
}

if TYPE_CHECKING:  # what the names are, for type checkers and editors
    from .header import BLOCK_BYTES_PER_JOINT_FRAME, MAX_HEADER_BYTES, MIN_JOINT_FRAMES, Header, parse_header
    from .reader import (
        HEADER_PREFIX,
        Source,
        block_error,
        read_bvh,
        read_bvh_many,
        read_error,
        read_header,
        read_summary,
    )
    from .tree import MAX_CHANNELS, MAX_JOINTS
    from .writer import bvh_bytes, write_bvh

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

__all__ = [
    "BLOCK_BYTES_PER_JOINT_FRAME",
    "HEADER_PREFIX",
    "Header",
    "MAX_CHANNELS",
    "MAX_HEADER_BYTES",
    "MAX_JOINTS",
    "MIN_JOINT_FRAMES",
    "Source",
    "block_error",
    "bvh_bytes",
    "parse_header",
    "read_bvh",
    "read_bvh_many",
    "read_error",
    "read_header",
    "read_summary",
    "write_bvh",
]
