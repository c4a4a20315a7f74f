"""Commands of the decoupling method (Boehs et al.): ``decouple``, ``modulate``, ``mix``,
``blend``, ``train`` and ``calibrate``, and the body-model options other commands share."""

from __future__ import annotations

import argparse
import io
import sys

import numpy as np

from .._utils.files import atomic_write_all, open_input
from ..bvh import bvh_bytes, write_bvh
from ..decoupling.algebra import EXPONENT, GAIN
from ..decoupling.edits import blend, mix
from ..decoupling.training import train_body_model
from ..errors import MocapError
from .common import (
    DECOUPLE_SUFFIXES,
    PROG,
    add_body_model_option,
    add_map_option,
    default,
    finite,
    positive,
    read_all,
    read_for_model,
    read_motion,
    read_on_model,
)

__all__ = [
    "BODY_MODEL_FIX",
    "DECOUPLE_SUFFIXES",
    "add_feet_options",
    "add_model_options",
    "add_parsers",
    "body_model",
    "cmd_blend",
    "cmd_calibrate",
    "cmd_decouple",
    "cmd_mix",
    "cmd_modulate",
    "cmd_train",
]

BODY_MODEL_FIX = (
    "the body-mechanics model applies to its own skeleton only; train one on clips of this skeleton "
    "(`expressive-mocap train`), then calibrate it to a session if needed (`calibrate`)"
)


def add_model_options(p, calibrate: bool = True) -> None:
    """--model, --calibrate, --gain and --exponent: the body-mechanics model and activity index."""
    p.add_argument(
        "--model",
        metavar="MODEL.npz",
        help="body-mechanics model (default: the shipped one, trained on Bandai-Namco neutral locomotion)",
    )
    if calibrate:
        p.add_argument(
            "--calibrate",
            nargs="+",
            metavar="NEUTRAL",
            help="neutral clips of the same actor/session: calibrate the model to them first",
        )
        add_threshold_option(p)
    p.add_argument(
        "--gain",
        type=positive(float),
        default=GAIN,
        help=f"g of the activity index clip((tanh(a) g)^b, 0, 1) (default {GAIN:g})",
    )
    p.add_argument(
        "--exponent", type=positive(float), default=EXPONENT, help=f"b of the activity index (default {EXPONENT:g})"
    )
    add_map_option(p)
    add_body_model_option(p)


def add_feet_options(p, joints: bool = True) -> None:
    """--no-foot-lock, and --joints for the edits that take another motion's expression."""
    p.add_argument(
        "--no-foot-lock",
        action="store_true",
        help="leave the stance feet where the edit puts them (by default they are kept where the body-mechanics "
        "source has them during its contacts, with leg IK)",
    )
    if joints:
        from ..decoupling.feet import JOINT_GROUPS

        p.add_argument(
            "--joints",
            nargs="+",
            choices=JOINT_GROUPS,
            metavar="GROUP",
            help=f"take the expressive component of these joint groups only ({', '.join(JOINT_GROUPS)}); "
            "default: every joint as the activity index says, but not the legs when one clip stands and the other "
            "does not",
        )


def add_threshold_option(p) -> None:
    p.add_argument(
        "--no-threshold",
        action="store_true",
        help="calibrate only a constant rotation per joint, not each joint's activity threshold "
        "(by default raised above what the neutral clips still show)",
    )


def body_model(args):
    """The body-mechanics model of --model (default: the shipped one), calibrated with
    --calibrate NEUTRAL... when given."""
    from ..decoupling.body_model import BodyModel

    model = BodyModel.load(args.model)
    if getattr(args, "calibrate", None):
        for path in args.calibrate:
            if _is_model_file(path):
                raise MocapError(
                    f"--calibrate {path}: a model file; --calibrate takes neutral BVH clips, "
                    "and a calibrated model goes to --model"
                )
        model = model.calibrated(
            [read_for_model(path, model, BODY_MODEL_FIX, args) for path in args.calibrate],
            threshold=not args.no_threshold,
        )
    return model


def _is_model_file(path: str) -> bool:
    """A zip archive (what .npz model files are), by its first bytes."""
    try:
        with open_input(path) as handle:
            return handle.read(4) == b"PK\x03\x04"
    except OSError:
        return False  # the reader says why, with the file's name


def add_decouple(commands) -> None:
    p = commands.add_parser(
        "decouple", help="split a motion into body mechanics and expressiveness (BVH + activity per joint)"
    )
    p.add_argument("input", metavar="IN", help="BVH file (the model's skeleton)")
    p.add_argument(
        "-o",
        "--output",
        required=True,
        metavar="PREFIX",
        help="writes PREFIX_body.bvh, PREFIX_expressive.bvh, PREFIX_activity.csv "
        "(a .bvh ending is dropped from PREFIX)",
    )
    add_model_options(p)
    p.set_defaults(run=cmd_decouple)


def cmd_decouple(args) -> int:
    from ..decoupling.algebra import decompose

    model = body_model(args)
    motion, back = read_on_model(args.input, model, BODY_MODEL_FIX, args)
    parts = decompose(motion, model, args.gain, args.exponent)
    prefix = str(args.output)
    if prefix.lower().endswith(".bvh"):  # -o out.bvh means the prefix out, not out.bvh_body.bvh
        prefix = prefix[:-4]
    names = motion.skeleton.names  # the activity is the model's, per joint of its skeleton
    table = io.StringIO()
    np.savetxt(table, parts.activity, fmt="%.5f", delimiter=",", header=",".join(names), comments="")
    files = {}
    # The body mechanics stand where the input stands; the expressive part is no stance of its own.
    body, expressive = back(parts.body_motion(), plant_feet=True), back(parts.expressive_motion())
    for suffix, part in zip(DECOUPLE_SUFFIXES[:2], (body, expressive)):
        try:
            files[prefix + suffix] = bvh_bytes(part)
        except MocapError as error:
            raise MocapError(f"cannot write {prefix + suffix}: {error}") from None
    files[prefix + DECOUPLE_SUFFIXES[2]] = table.getvalue().encode()
    atomic_write_all(files)  # the three belong together: all of them or none
    print(f"wrote {prefix}_body.bvh, {prefix}_expressive.bvh (E* on the mean body pose), {prefix}_activity.csv")
    print("mean activity per joint (0 = body mechanics only, 1 = fully expressive):")
    for name, value in zip(names, parts.activity.mean(axis=0)):
        print(f"  {name:<16} {value:6.3f} {'#' * int(round(value * 40))}")
    _note_held(parts, model)
    return 0


def _note_held(parts, model) -> None:
    """Name the joints held active through the clip when the model is not calibrated to its actor."""
    held = parts.held_joints()
    if held and model.calibration is None:
        print(
            f"note: {', '.join(held)} are active through most of the clip; if that is this actor's habitual "
            "posture rather than the motion's style, calibrate to the actor to read it as body mechanics "
            "(--calibrate with a few of their neutral clips, or `expressive-mocap calibrate`)"
        )


def add_modulate(commands) -> None:
    p = commands.add_parser(
        "modulate", help="scale the expressiveness of a motion (1 = unchanged, 0 = body mechanics only)"
    )
    p.add_argument("input", metavar="IN", help="BVH file")
    p.add_argument("--scale", type=finite, required=True, help="expressiveness factor, e.g. 0.5 or 1.5")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    add_model_options(p)
    add_feet_options(p, joints=False)
    p.set_defaults(run=cmd_modulate)


def cmd_modulate(args) -> int:
    from ..body.take import Take
    from ..decoupling.algebra import decompose
    from ..decoupling.edits import modulate

    model = body_model(args)
    motion, back = read_on_model(args.input, model, BODY_MODEL_FIX, args)
    take = Take.of(motion)
    parts = decompose(take, model, args.gain, args.exponent)
    edited = modulate(take, args.scale, model, plant_feet=not args.no_foot_lock, parts=parts)
    out = back(edited, plant_feet=not args.no_foot_lock)
    write_bvh(out, args.output)
    print(f"wrote {args.output}: expressiveness x {args.scale:g}")
    _note_held(parts, model)
    return 0


def add_mix(commands) -> None:
    p = commands.add_parser("mix", help="body mechanics of one motion with the expressiveness of another")
    p.add_argument("--body", required=True, metavar="X.bvh", help="source of the body mechanics and root trajectory")
    p.add_argument("--expressive", required=True, metavar="Y.bvh", help="source of the expressive component")
    align, offset = default(mix, "align"), default(mix, "offset")
    p.add_argument(
        "--align",
        choices=["time", "index", "resample"],
        default=align,
        help="time: Y resampled to X's frame rate, then frame by frame (holding its last frame); index: frame by "
        f"frame whatever the rates; resample: stretched to X's length (default: {align})",
    )
    p.add_argument(
        "--offset",
        type=int,
        default=offset,
        help=f"with --align time or index: Y frame (at X's rate) used at X frame 0 (default {offset})",
    )
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    add_model_options(p)
    add_feet_options(p)
    p.set_defaults(run=cmd_mix)


def cmd_mix(args) -> int:
    from ..decoupling.edits import mix

    model = body_model(args)
    body, back = read_on_model(args.body, model, BODY_MODEL_FIX, args)
    expressive = read_for_model(args.expressive, model, BODY_MODEL_FIX, args)  # any skeleton: on the model's body
    out = back(
        mix(
            body,
            expressive,
            model,
            args.align,
            args.offset,
            args.gain,
            args.exponent,
            joints=args.joints,
            plant_feet=not args.no_foot_lock,
        ),
        plant_feet=not args.no_foot_lock,
    )
    write_bvh(out, args.output)
    print(f"wrote {args.output}: body mechanics of {args.body}, expressiveness of {args.expressive}")
    _say_resampled(args.expressive, expressive, body, args.align)
    return 0


def _say_resampled(path: str, motion, to, align: str) -> None:
    """The note of what ``--align time`` resampled, if anything."""
    from ..decoupling.edits import at_rate_of

    if at_rate_of(motion, to, align) is not motion:
        print(f"  {path} resampled from {motion.fps:.6g} to {to.fps:.6g} fps to play in its own time (--align time)")


def _window(text: str) -> tuple[int, int]:
    """``"A:B"`` -> ``(A, B)`` output frames."""
    try:
        start, end = (int(part) for part in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected START:END frames, got {text!r}") from None
    if start < 0 or end < start:
        raise argparse.ArgumentTypeError(f"expected 0 <= START <= END, got {text!r}")
    return start, end


def add_blend(commands) -> None:
    p = commands.add_parser(
        "blend", help="blend from one motion to another, body mechanics and expressiveness on their own windows"
    )
    p.add_argument("first", metavar="P", help="BVH file to blend from")
    p.add_argument("second", metavar="Q", help="BVH file to blend to (starts at the earlier window's start)")
    p.add_argument(
        "--body-window",
        type=_window,
        required=True,
        metavar="A:B",
        help="output frames over which the body mechanics go from P to Q",
    )
    p.add_argument(
        "--expressive-window",
        type=_window,
        metavar="C:D",
        help="output frames over which the expressiveness goes from P to Q (default: the body window)",
    )
    p.add_argument(
        "--naive", action="store_true", help="blend whole poses over the body window (no decoupling), for comparison"
    )
    p.add_argument(
        "--align",
        choices=["time", "index"],
        default=default(blend, "align"),
        help="time: Q resampled to P's frame rate first; index: Q's frames as they are (default: time)",
    )
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    add_model_options(p)
    add_feet_options(p)
    p.set_defaults(run=cmd_blend)


def cmd_blend(args) -> int:
    from ..decoupling.edits import blend_alignment

    expressive_window = None if args.naive else args.expressive_window or args.body_window
    if args.naive and args.joints:
        raise MocapError(
            "--joints: the naive blend takes whole poses, not joints' expression; drop --naive or --joints"
        )
    if args.naive:
        first, second = read_motion(args.first, args), read_motion(args.second, args)
        out = blend(first, second, None, args.body_window, align=args.align)
    else:
        model = body_model(args)
        first, back = read_on_model(args.first, model, BODY_MODEL_FIX, args)
        second = read_for_model(args.second, model, BODY_MODEL_FIX, args)
        out = back(
            blend(
                first,
                second,
                model,
                args.body_window,
                expressive_window,
                args.gain,
                args.exponent,
                joints=args.joints,
                plant_feet=not args.no_foot_lock,
                align=args.align,
            )
        )
    write_bvh(out, args.output)
    a = blend_alignment(first, second, args.body_window, expressive_window, align=args.align)
    print(f"wrote {args.output}: {out.n_frames} frames")
    _say_resampled(args.second, second, first, args.align)
    print(
        f"  {args.second} continues the path of {first.skeleton.names[a.joint]} from frame {a.anchor}: "
        f"turned {a.turn:.1f} degrees about the vertical and moved {np.linalg.norm(a.shift):.4g} (file units) "
        "on the floor"
    )
    return 0


def add_train(commands) -> None:
    p = commands.add_parser(
        "train",
        help="train a body-mechanics model on neutral clips of one skeleton",
        description="Train a body-mechanics model on neutral clips of one skeleton. How much data: on Bandai-Namco "
        "locomotion (experiments/NEUTRAL_DATA.md) 2 clips (~7 s) gave a model worse than the mean pose, which train "
        "refuses; 4 clips (~16 s) predicted held-out poses with 0.15x the mean pose's error, 16 clips (~70 s) 0.07x, "
        "99 clips (~8 min) 0.05x. Give at least a minute of neutral walking and running, in several clips (the test "
        "split is by clip).",
    )
    p.add_argument(
        "neutral",
        nargs="+",
        metavar="NEUTRAL",
        help="neutral clips (no gestures, head forward, limbs moving with the body); 70/30 split by clip",
    )
    p.add_argument(
        "--unlabelled",
        nargs="+",
        metavar="CLIP",
        help="any clips of the same skeleton: frames for the denoising autoencoder",
    )
    p.add_argument("-o", "--output", required=True, metavar="MODEL.npz", help="the model file")
    for option, name, kind, what in (
        ("--hidden", "hidden", positive(int), "autoencoder code units H"),
        ("--regression-hidden", "regression_hidden", positive(int), "regression hidden units"),
        ("--unlabelled-frames", "unlabelled_frames", positive(int), "frames drawn from the unlabelled clips"),
        ("--max-iter", "max_iter", positive(int), "L-BFGS iterations per stage"),
        ("--seed", "seed", int, "random seed"),
    ):
        value = default(train_body_model, name)
        p.add_argument(option, type=kind, default=value, help=f"{what} (default {value})")
    p.add_argument(
        "--allow-poor",
        action="store_true",
        help="write the model even if it predicts held-out poses no better than the mean pose",
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    add_body_model_option(p)
    p.set_defaults(run=cmd_train)


def cmd_train(args) -> int:
    from .._utils.progress import line_log
    from ..decoupling.body_model import poor_fit
    from ..decoupling.training import format_report

    neutral = read_all(args.neutral, "neutral clips", args.quiet, args)
    unlabelled = read_all(args.unlabelled or [], "unlabelled clips", args.quiet, args)
    model = train_body_model(
        neutral,
        unlabelled,
        hidden=args.hidden,
        regression_hidden=args.regression_hidden,
        unlabelled_frames=args.unlabelled_frames,
        seed=args.seed,
        max_iter=args.max_iter,
        log=line_log(not args.quiet),
    )
    print(format_report(model.report))
    problem = poor_fit(model.report)
    if problem and not args.allow_poor:
        raise MocapError(
            f"not writing {args.output}: the model is of no use: {problem}; train on more neutral clips "
            "(see `train --help`), or pass --allow-poor to write it anyway"
        )
    model.save(args.output)
    if problem:
        print(f"{PROG}: warning: {args.output} is a poor model: {problem}", file=sys.stderr)
    print(f"wrote {args.output}")
    return 0


def add_calibrate(commands) -> None:
    p = commands.add_parser("calibrate", help="calibrate the body-mechanics model to an actor or capture session")
    p.add_argument(
        "neutral", nargs="+", metavar="NEUTRAL", help="neutral clips (walks, runs, standing) of that actor/session"
    )
    p.add_argument("-o", "--output", required=True, metavar="CAL.npz", help="the calibrated model, for --model")
    p.add_argument("--model", metavar="MODEL.npz", help="model to calibrate (default: the shipped one)")
    add_threshold_option(p)
    add_map_option(p)
    add_body_model_option(p)
    p.set_defaults(run=cmd_calibrate)


def cmd_calibrate(args) -> int:
    from ..decoupling.body_model import BodyModel

    uncalibrated = BodyModel.load(args.model)
    neutral = [read_for_model(path, uncalibrated, BODY_MODEL_FIX, args) for path in args.neutral]
    model = uncalibrated.calibrated(neutral, threshold=not args.no_threshold)
    model.save(args.output)
    angles = model.calibration_angles()
    largest = sorted(angles.items(), key=lambda kv: -kv[1])[:5]
    print(f"wrote {args.output}: the model calibrated on {len(args.neutral)} neutral clip(s); largest corrections:")
    for name, degrees in largest:
        print(f"  {name:<16} {degrees:6.1f} degrees")
    if model.activity_scale is not None:
        raised = sorted(((s, n) for n, s in zip(model.joint_names, model.activity_scale) if s > 1.0), reverse=True)[:5]
        print(
            "activity thresholds raised above the neutral clips' residue: "
            + (", ".join(f"{n} x{s:.2f}" for s, n in raised) if raised else "none")
        )
    if model.trunk is not None and uncalibrated.trunk is not None and model.trunk.scale > uncalibrated.trunk.scale:
        print(f"trunk lean threshold raised x{model.trunk.scale / uncalibrated.trunk.scale:.2f} above the model's own")
    return 0


def add_parsers(commands) -> None:
    """The subparsers of this module's commands, in the order ``--help`` lists them."""
    for add in (add_decouple, add_modulate, add_mix, add_blend, add_train, add_calibrate):
        add(commands)
