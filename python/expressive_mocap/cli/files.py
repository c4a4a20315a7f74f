"""Commands on BVH files: ``positions`` and ``convert`` (``info``: :mod:`.info`; ``render``: :mod:`.pictures`)."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np

from .._utils.files import atomic_write, is_standard_output
from ..bvh import write_bvh
from ..errors import MocapError
from ..motion import Motion
from ..rotations.orders import ORDERS
from .common import add_body_model_option, positive, read_motion

__all__ = ["add_parsers", "cmd_convert", "cmd_positions"]


def add_positions(commands) -> None:
    p = commands.add_parser("positions", help="world positions and rotations of every joint, to an .npz file")
    p.add_argument("file", metavar="FILE", help="BVH file (or an SMPL/AMASS .npz, with --body-model)")
    add_body_model_option(p)
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="OUT.npz|OUT.csv",
        help=".npz: arrays positions [F,J,3], rotations [F,J,4] (x,y,z,w), joints, parents, frame_time; "
        ".csv: time and x,y,z of every joint, a row per frame",
    )
    p.set_defaults(run=cmd_positions)


def cmd_positions(args) -> int:
    kind = ".npz" if is_standard_output(args.output) else Path(args.output).suffix.lower()
    if kind not in (".npz", ".csv"):
        raise MocapError(
            f"-o {args.output}: positions writes .npz (every array) or .csv (positions, a row per frame), "
            "by the name's extension"
        )
    motion = read_motion(args.file, args)
    rotations, positions = motion.fk()
    if not np.isfinite(positions).all():  # offsets near 1e308 add up past float64
        frame, joint = np.argwhere(~np.isfinite(positions))[0, :2]
        raise MocapError(
            f"{args.file}: the position of {motion.skeleton.names[joint]} at frame {frame} is not finite "
            "(beyond float64): nothing written"
        )
    joints, frames = motion.skeleton.n_joints, motion.n_frames
    if kind == ".csv":
        atomic_write(args.output, _positions_csv(motion, positions))
        print(f"wrote {args.output}: positions of {joints} joints x {frames} frames (world, file units)")
        return 0
    buffer = io.BytesIO()
    np.savez(
        buffer,
        positions=positions,
        rotations=rotations,
        joints=np.array(motion.skeleton.names),
        parents=motion.skeleton.parents,
        frame_time=np.float64(motion.frame_time),
    )
    atomic_write(args.output, buffer.getvalue())
    print(f"wrote {args.output}: positions and rotations of {joints} joints x {frames} frames (world, x,y,z,w)")
    return 0


def _positions_csv(motion: Motion, positions: np.ndarray) -> bytes:
    """World positions as CSV: a header row, then per frame its time and x, y, z of every joint."""
    columns = ["time"] + [f"{name}_{axis}" for name in motion.skeleton.names for axis in "xyz"]
    times = np.arange(motion.n_frames) * motion.frame_time
    table = np.column_stack([times, positions.reshape(motion.n_frames, -1)])
    text = io.StringIO()
    np.savetxt(text, table, fmt="%.9g", delimiter=",", header=",".join(columns), comments="")
    return text.getvalue().encode()


def add_convert(commands) -> None:
    p = commands.add_parser(
        "convert", help="rewrite a BVH file, optionally resampled, scaled or in another rotation order"
    )
    p.add_argument("input", metavar="IN", help="BVH file, or an SMPL/AMASS parameter file (.npz, with --body-model)")
    p.add_argument(
        "-o", "--output", required=True, metavar="OUT.bvh", help="where to write (atomically; - for standard output)"
    )
    add_body_model_option(p)
    p.add_argument(
        "--fps",
        type=positive(float),
        help="resample to this frame rate (slerp); for an .npz without mocap_framerate, its frame rate",
    )
    p.add_argument("--scale", type=positive(float), help="multiply every length, e.g. 0.01 for cm to m")
    p.add_argument(
        "--order", type=str.upper, choices=ORDERS, help="write every joint's rotation channels in this order"
    )
    p.add_argument(
        "--decimals", type=int, help="digits after the point (default: the shortest text that reads back exactly)"
    )
    p.set_defaults(run=cmd_convert)


@contextlib.contextmanager
def _option(path: str, option: str, value):
    """An edit's MocapError, naming the file and the option it came from."""
    try:
        yield
    except MocapError as error:
        reason = str(error).removeprefix("resample: ").removeprefix("scaled: ")
        raise MocapError(f"{path}: {option} {value:g}: {reason}") from None


def cmd_convert(args) -> int:
    if args.body_model and Path(args.input).suffix.lower() != ".npz":
        raise MocapError(
            f"--body-model {args.body_model}: only for an SMPL/AMASS parameter file (.npz), not {args.input}"
        )
    motion = read_motion(args.input, args, fps=args.fps)
    if args.fps and abs(args.fps - motion.fps) > 1e-9 * args.fps:
        with _option(args.input, "--fps", args.fps):
            motion = motion.resample(fps=args.fps)
    if args.scale:
        with _option(args.input, "--scale", args.scale):
            motion = motion.scaled(args.scale)
    if args.order:
        motion = motion.with_rotation_order(args.order)
    write_bvh(motion, args.output, decimals=args.decimals)
    print(f"wrote {args.output}: {motion.n_frames} frames at {motion.fps:.6g} fps")
    return 0


def add_parsers(commands) -> None:
    """The subparsers of this module's commands, in the order ``--help`` lists them."""
    for add in (add_positions, add_convert):
        add(commands)
