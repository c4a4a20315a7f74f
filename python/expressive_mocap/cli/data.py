"""Commands on captured data: ``footsteps`` (one walk) and ``preprocess`` (a whole archive)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..body.contacts import HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD
from ..dataset import preprocess
from ..errors import MocapError
from .common import PROG, add_body_model_option, default, finite, positive, read_motion

__all__ = ["add_parsers", "cmd_footsteps", "cmd_preprocess"]


def add_footsteps(commands) -> None:
    p = commands.add_parser(
        "footsteps",
        help="foot contacts of a walk: contact intervals per foot, step count and cadence, optionally a gait diagram",
        description="Foot contacts after Lee et al. 2002: a foot (ankle or toe) touches when it is both low and slow; "
        f"contacts and flights shorter than {MIN_DURATION:g} s are absorbed (offline) or held off (--causal). "
        "Prints each foot's contact intervals in frames and seconds, then the steps and the cadence.",
    )
    p.add_argument(
        "file", metavar="FILE", help="BVH file of any humanoid skeleton (see `skeleton`), or an SMPL/AMASS .npz"
    )
    add_body_model_option(p)
    p.add_argument("--map", metavar="MAP.json|MAP.toml", help="joint map for roles the names and topology do not find")
    p.add_argument("--plot", metavar="OUT.png", help="also write a gait diagram: one row per foot, a bar per contact")
    p.add_argument(
        "--causal", action="store_true", help="streaming detector: frame t sees frames <= t only (hold filter, floor 0)"
    )
    p.add_argument(
        "--height-threshold",
        type=positive(float),
        default=HEIGHT_THRESHOLD,
        metavar="X",
        help=f"contact below X x actor height above the floor (default: {HEIGHT_THRESHOLD:g})",
    )
    p.add_argument(
        "--speed-threshold",
        type=positive(float),
        default=SPEED_THRESHOLD,
        metavar="X",
        help=f"contact below X x actor height per second (default: {SPEED_THRESHOLD:g})",
    )
    p.add_argument(
        "--floor",
        type=finite,
        metavar="Y",
        help="floor height in file units (default: 5th percentile of toe heights; 0 with --causal)",
    )
    p.set_defaults(run=cmd_footsteps)


def cmd_footsteps(args) -> int:
    from ..body.contacts import cadence, contact_intervals, floor_of, foot_contacts, footstrikes
    from ..body.conventions import upright
    from ..body.take import Take

    motion = upright(read_motion(args.file, args))  # contacts are read along Y: a Z-up file is turned first
    take = Take.of(motion, _joint_map(args.map) if args.map else None)
    roles, height = take.body.roles, take.body.actor_height
    names = roles.names(motion.skeleton)
    floor = args.floor if args.floor is not None else (0.0 if args.causal else floor_of(take))
    contacts = foot_contacts(
        take,
        floor=floor,
        causal=args.causal,
        height_threshold=args.height_threshold,
        speed_threshold=args.speed_threshold,
    )
    dt = motion.frame_time
    print(f"{args.file}: {motion.n_frames} frames at {motion.fps:.6g} fps ({motion.duration:.2f} s)")
    print(f"  actor height {height:.4g}, floor at {floor:.4g} (file units)")
    print(
        f"  contact: height < {args.height_threshold:g} x height = {args.height_threshold * height:.3g} and "
        f"speed < {args.speed_threshold:g} x height/s = {args.speed_threshold * height:.3g}/s, "
        f"{'causal hold' if args.causal else 'offline filter'} of {MIN_DURATION:g} s"
    )
    for side, intervals in zip(("left", "right"), contact_intervals(contacts, dt)):
        count = f"{len(intervals)} contact{'s' * (len(intervals) != 1)}"
        print(f"{side} foot ({names[f'{side}_foot']}, {names[f'{side}_toe']}): {count}")
        for i in intervals:
            print(
                f"  frames {i.start:5d}-{i.end:<5d} {i.start * dt:8.3f}-{(i.end + 1) * dt:.3f} s  ({i.seconds:.3f} s)"
            )
    strikes = footstrikes(contacts)
    steps_per_second = cadence(contacts, dt)
    left = int(np.count_nonzero(strikes[:, 1] == 0))
    rate = f"cadence {steps_per_second:.2f} steps/s" if np.isfinite(steps_per_second) else "cadence: too few steps"
    print(f"summary: {len(strikes)} steps ({left} left, {len(strikes) - left} right), {rate}")
    if args.plot:
        from ..viz.render import plot_contacts

        title = f"{Path(args.file).name}: foot contacts ({len(strikes)} steps, {rate})"
        plot_contacts(contacts, dt, args.plot, title=title)
        print(f"wrote {args.plot}")
    return 0


def add_preprocess(commands) -> None:
    p = commands.add_parser(
        "preprocess",
        help="a whole archive of BVH clips (folder, glob, .zip, .tar.gz/.xz) into a dataset of arrays: "
        "positions, features, contacts, activity",
        description="Parse every clip, run FK, dynamic features, foot contacts and optionally the decomposition, "
        "in batches (parallel Rust parsing and FK), into OUT: one memory-mappable .npy per kind, offsets.npy and "
        "manifest.json (load with expressive_mocap.dataset.load_dataset(OUT)). Bad clips are listed with their "
        "errors; an interrupted run resumes where it stopped when run again.",
    )
    p.add_argument(
        "source", metavar="SRC", help="a folder (*.bvh, recursive), a quoted glob, a .zip or a .tar/.tar.gz/.tar.xz"
    )
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="dataset folder")
    p.add_argument(
        "--keep",
        metavar="KINDS",
        help="comma-separated: positions,rotations,features,contacts,activity,body,expressive,"
        "velocities,accelerations,root_velocity,angular_velocities,heading "
        "(default: positions,features,contacts, plus activity with --model)",
    )
    p.add_argument(
        "--rotations",
        default="quaternion",
        metavar="FORM",
        help="the form of the rotations kind: quaternion (default), 6d, matrix, axis-angle, euler[:ORDER]",
    )
    p.add_argument(
        "--positions",
        default="world",
        choices=("world", "root", "heading", "clip"),
        help="the frame of the positions (and velocities): world (as in the files, default), root (minus the "
        "root joint's), heading (each frame on the floor under the hips facing +Z), clip (the first frame's heading)",
    )
    p.add_argument("--fps", type=positive(float), metavar="F", help="resample every clip to F frames per second first")
    p.add_argument(
        "--mirror", action="store_true", help="also store each clip mirrored left for right, as NAME@mirrored"
    )
    add_body_model_option(p)
    p.add_argument(
        "--model",
        nargs="?",
        const="",
        metavar="MODEL.npz",
        help="decompose with this body-mechanics model (no value: the shipped one)",
    )
    p.add_argument(
        "--model-float32",
        action="store_true",
        help="run the network in float32: ~2x faster, activity within ~2e-5 of float64",
    )
    p.add_argument(
        "--dask",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="run the batches on a Dask cluster at ADDRESS (no value: a local cluster of 2 worker processes on "
        "127.0.0.1); needs pip install 'expressive-mocap[distributed]'",
    )
    batch_mb = default(preprocess, "batch_mb")
    p.add_argument(
        "--batch-mb",
        type=positive(float),
        default=batch_mb,
        help=f"MB of BVH text read per batch (default {batch_mb:g})",
    )
    p.add_argument("--max-batches", type=positive(int), metavar="N", help="stop after N batches (rerun to resume)")
    p.add_argument(
        "--canonical",
        action="store_true",
        help="take clips of any humanoid skeleton, each retargeted onto the canonical body (the Bandai-Namco "
        "22-joint skeleton, cm), its own skeleton and joint map kept in the manifest; without it one dataset "
        "holds one skeleton",
    )
    p.add_argument(
        "--map",
        metavar="MAP.json|MAP.toml",
        help="with --canonical: joint map (role -> joint name) for roles the names and topology do not find",
    )
    p.add_argument("--overwrite", action="store_true", help="redo OUT if it already holds a finished dataset")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(run=cmd_preprocess)


def cmd_preprocess(args) -> int:
    from ..dataset import preprocess

    summary = preprocess(
        args.source,
        args.output,
        args.keep,
        args.model,
        batch_mb=args.batch_mb,
        max_batches=args.max_batches,
        model_float32=args.model_float32,
        cluster=args.dask,
        overwrite=args.overwrite,
        progress=not args.quiet,
        canonical=args.canonical,
        joint_map=_joint_map(args.map),
        rotations=args.rotations,
        positions=args.positions,
        fps=args.fps,
        mirror=args.mirror,
        smpl_model=args.body_model,
    )
    print("\n".join(summary.lines()))
    if summary.finished and summary.clips_ok == 0:  # a dataset of nothing is not a success
        if summary.clips_failed:
            found = f"none of its {summary.clips_failed} clips could be read (see the failures above)"
        else:
            found = "it holds no .bvh clips" + (
                " or .npz parameter files" if args.body_model else _npz_hint(args.source)
            )
        raise MocapError(f"{args.source}: {found}; {args.output} holds no data")
    if summary.finished and summary.most_failed:  # a dataset of the few clips that worked: not what was asked
        ok = summary.clips_ok - summary.clips_mirrored
        hint = (
            " (of other skeletons: see --canonical above)" if summary.other_skeletons else " (see the failures above)"
        )
        print(
            f"{PROG}: error: {summary.clips_failed} of the {ok + summary.clips_failed} clips of "
            f"{args.source} failed{hint}; {args.output} holds the {ok} that worked",
            file=sys.stderr,
        )
        return 1
    return 0


def _npz_hint(source: str) -> str:
    """For a folder of ``.npz`` files read without --body-model: what they need."""
    folder = Path(source)
    if folder.is_dir() and next(folder.rglob("*.npz"), None) is not None:
        return " (its .npz files are read as SMPL/AMASS parameters with --body-model SMPL.npz)"
    return ""


def _joint_map(path: str | None) -> dict | None:
    from ..body import read_joint_map

    return read_joint_map(path) if path else None


def add_parsers(commands) -> None:
    """The subparsers of this module's commands, in the order ``--help`` lists them."""
    for add in (add_footsteps, add_preprocess):
        add(commands)
