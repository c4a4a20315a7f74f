"""Writing BVH files: :func:`bvh_bytes` (the text) and :func:`write_bvh` (atomically to a file)."""

from __future__ import annotations

import os

import numpy as np

from .. import ops
from .._utils.files import atomic_write
from .._utils.kept import Kept
from ..errors import MocapError
from ..motion import Motion, Skeleton
from .channels import encode

__all__ = ["bvh_bytes", "write_bvh"]


def _number(value: float, decimals: int | None) -> str:
    if decimals is None:
        return np.format_float_positional(value + 0.0, trim="-")
    return f"{value:.{decimals}f}"


_MAX_INDENT = 16  # tabs: deeper joints are not indented further, so a deep chain's header stays linear


def _hierarchy(skeleton: Skeleton, decimals: int | None) -> str:
    """The HIERARCHY part of a file, kept per skeleton content: retargeting onto one body writes
    it once per clip."""
    key = (skeleton.content_key, skeleton.end_sites, decimals)
    return _HIERARCHIES.get(key, lambda: _written_hierarchy(skeleton, decimals))


_HIERARCHIES: Kept[str] = Kept(64)


def _written_hierarchy(skeleton: Skeleton, decimals: int | None) -> str:
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
    return "\n".join(lines)


def bvh_bytes(motion: Motion, decimals: int | None = None) -> bytes:
    """The text of a BVH file for ``motion``, in its skeleton's channel layout.

    ``decimals=None`` writes the shortest text that reads back to the same float64 values;
    an integer writes that many digits after the point (6 is common in exported files).
    """
    skeleton = motion.skeleton
    lines = [_hierarchy(skeleton, decimals)]
    lines += ["MOTION", f"Frames: {motion.n_frames}", f"Frame Time: {_number(motion.frame_time, None)}", ""]
    header = "\n".join(lines).encode("utf-8")
    if skeleton.n_channels == 0 or motion.n_frames == 0:
        return header + b"\n" * motion.n_frames
    values = encode(skeleton, motion.rotations, motion.translations)
    if not np.isfinite(values).all():  # "inf"/"nan" in a file is refused by every reader, ours too
        frame, column = (int(i) for i in np.argwhere(~np.isfinite(values))[0])
        joint = int(np.searchsorted(np.cumsum([len(cs) for cs in skeleton.channels]), column, side="right"))
        channel = skeleton.channels[joint][column - sum(len(cs) for cs in skeleton.channels[:joint])]
        value = values[frame, column]
        raise MocapError(
            f"frame {frame}, {skeleton.names[joint]} {channel} is {value}: a BVH file holds finite numbers only"
        )
    return header + ops.format_motion_block(values, decimals)


def write_bvh(motion: Motion, path: str | os.PathLike, decimals: int | None = None) -> None:
    """Write ``motion`` as a BVH file at ``path``, atomically (a complete file or none; see
    :func:`expressive_mocap._utils.files.atomic_write_all` for what ``path`` may be). A non-finite value
    is refused, naming ``path``, the frame and the channel, before anything is written.

    See :func:`bvh_bytes` for ``decimals``.
    """
    if not isinstance(motion, Motion):
        got = f"an array {list(motion.shape)}" if isinstance(motion, np.ndarray) else f"a {type(motion).__name__}"
        # The likely slip: Decomposition.body / .expressive are rotation arrays, its motions come from methods.
        raise MocapError(
            f"write_bvh needs a Motion, got {got}; for a Decomposition use parts.body_motion(), "
            "parts.expressive_motion() or parts.recompose(scale)"
        )
    try:
        data = bvh_bytes(motion, decimals)
    except MocapError as error:
        raise MocapError(f"cannot write {path}: {error}") from None
    atomic_write(path, data)
