"""The ``info`` command: what a BVH file holds, from its header and a check of its whole number
block, without NumPy when the Rust kernels are in use (a tenth of a second, most of it Python's
own start-up); an SMPL/AMASS parameter file is read whole."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import MocapError
from .common import PROG, add_body_model_option, read_motion

if TYPE_CHECKING:
    from ..bvh.tree import Tree
    from ..motion import Skeleton

__all__ = ["add_parsers", "cmd_info"]


def add_parsers(commands) -> None:
    p = commands.add_parser("info", help="joints, frames, fps, duration, channel layout and rest height of BVH files")
    p.add_argument("files", nargs="+", metavar="FILE", help="BVH files (or SMPL/AMASS .npz files, with --body-model)")
    add_body_model_option(p)
    p.set_defaults(run=cmd_info)


def cmd_info(args) -> int:
    failures = 0
    for path in args.files:
        try:
            lines = _described(path, args)
        except MocapError as error:
            print(f"{PROG}: error: {error}", file=sys.stderr)
            failures += 1
            continue
        print("\n".join(lines))
    return 1 if failures else 0


def _described(path: str, args) -> list[str]:
    """The lines ``info`` prints for one file."""
    from ..bvh.tree import channel_summary, vertical_extent

    skeleton: Skeleton | Tree
    if Path(path).suffix.lower() == ".npz":
        motion = read_motion(path, args)
        skeleton, frames, frame_time = motion.skeleton, motion.n_frames, motion.frame_time
    else:
        from ..bvh.reader import read_summary

        header = read_summary(path)
        skeleton, frames, frame_time = header.skeleton, header.frames, header.frame_time
    heights = [float(offset[1]) for offset in skeleton.offsets]
    height = vertical_extent([int(p) for p in skeleton.parents], heights, skeleton.end_sites)
    return [
        f"{path}",
        f"  joints    {len(skeleton.names)} (+{len(skeleton.end_sites)} End Sites), root {skeleton.names[0]}",
        f"  frames    {frames} at {1.0 / frame_time:.6g} fps (frame time {frame_time:.7g} s)",
        f"  duration  {max(frames - 1, 0) * frame_time:.3f} s",
        f"  channels  {sum(map(len, skeleton.channels))} a frame: {channel_summary(skeleton.channels)}",
        f"  rest pose height {height:.4g} (file units, Y extent incl. End Sites)",
    ]
