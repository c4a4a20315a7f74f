"""Reading and writing BVH files.

:func:`read_bvh` / :func:`read_bvh_many` read files into :class:`~expressive_mocap.motion.Motion`
objects, :func:`write_bvh` / :func:`bvh_bytes` write them back. The parts: :mod:`.hierarchy`
(header tokens and the joint tree), :mod:`.header` (the whole header from a file's bytes),
:mod:`.reader`, :mod:`.writer` and :mod:`.channels` (the MOTION block's channel layout).
"""

from .header import BLOCK_BYTES_PER_JOINT_FRAME, MAX_HEADER_BYTES, MIN_JOINT_FRAMES, Header, parse_header
from .hierarchy import MAX_CHANNELS, MAX_JOINTS
from .reader import HEADER_PREFIX, Source, block_error, read_bvh, read_bvh_many, read_error, read_header
from .writer import bvh_bytes, write_bvh

__all__ = [
    "BLOCK_BYTES_PER_JOINT_FRAME",
    "HEADER_PREFIX",
    "MAX_CHANNELS",
    "MAX_HEADER_BYTES",
    "MAX_JOINTS",
    "MIN_JOINT_FRAMES",
    "Header",
    "Source",
    "block_error",
    "bvh_bytes",
    "parse_header",
    "read_bvh",
    "read_bvh_many",
    "read_error",
    "read_header",
    "write_bvh",
]
