"""Commands of the exaggeration method (Davis & Kannappan): ``rank``, ``exaggerate``,
``validate`` and ``models`` (the shipped ones)."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..bvh import write_bvh
from ..errors import ArgumentError, ClipError, MocapError
from ..exaggeration import exaggerate, swap_test, train
from ..motion import Motion
from .common import (
    add_body_model_option,
    add_map_option,
    default,
    finite,
    joint_map,
    positive,
    read_all,
    read_motion,
    read_on_model,
)

__all__ = ["EXAGGERATION_MODEL_FIX", "add_parsers", "cmd_exaggerate", "cmd_models", "cmd_rank", "cmd_validate"]

EXAGGERATION_MODEL_FIX = (
    "an exaggeration model applies to its own skeleton only; train one on clips of this skeleton "
    "(`expressive-mocap rank --level ... -o MODEL.npz`)"
)
FEET = ("left", "right")  # train's foot: 0 or 1


def _add_training_options(p, model: bool = False) -> None:
    """--level K FILE... and the options of :func:`~expressive_mocap.exaggerate.train`."""
    p.add_argument(
        "--level",
        action="append",
        nargs="+",
        metavar=("K", "FILE"),
        help="an intensity K and its BVH files, one per person (person i = the i-th file of every level); "
        "repeat per intensity",
    )
    add_body_model_option(p)
    if model:
        p.add_argument(
            "--model", metavar="MODEL.npz", help="a model saved by `rank -o MODEL.npz` instead of --level files"
        )
    share, energy = default(train, "share"), default(train, "energy")
    degree, samples = default(train, "degree"), default(train, "samples")
    p.add_argument(
        "--share",
        type=positive(float),
        default=share,
        help=f"expressiveness share of the key features (default {share:g})",
    )
    p.add_argument(
        "--energy", type=positive(float), default=energy, help=f"basis share of sum(s^2) (default {energy:g})"
    )
    p.add_argument("--rank", type=positive(int), help="number of basis vectors (default: by --energy)")
    p.add_argument(
        "--map",
        metavar="MAP.json|MAP.toml",
        help="joint map (role -> joint name) of the clips' skeleton where its names and topology fall short; "
        "the model records the map it finds",
    )
    p.add_argument(
        "--degree",
        type=int,
        default=degree,
        help=f"degree of the intensity-to-coefficient mappings (default {degree}: lines)",
    )
    p.add_argument(
        "--samples",
        type=positive(int),
        default=samples,
        help=f"samples per time-normalised cycle T (default {samples})",
    )
    cycle = default(train, "cycle")
    p.add_argument(
        "--cycle",
        default=cycle,
        help=f"cycles of each clip: {cycle} (default: their mean is the performance, predictability is measured over "
        "every one), middle (the paper's single cycle), first, whole (not a walk), gesture (a gesture's strokes, "
        "else the span its hand moves in), or an index",
    )
    foot = FEET[default(train, "foot")]
    p.add_argument(
        "--foot",
        choices=FEET,
        default=foot,
        help=f"walking cycles run from one footstrike of this foot to the next (default {foot})",
    )
    p.add_argument(
        "--euler",
        action="store_true",
        help="DOFs are the Euler channels (relative to the mean) instead of rotation vectors",
    )


def _levels(args) -> tuple[list[list[Motion]], list[float], list[list[str]]]:
    """``--level K FILE...`` options -> people (person i = the i-th file of every level), the
    intensities in increasing order, and the file names per person."""
    if not args.level or len(args.level) < 2:
        raise MocapError("give at least two --level K FILE... options (one per intensity)")
    levels = []
    for values in args.level:
        try:
            k = finite(values[0])
        except (ValueError, argparse.ArgumentTypeError):
            raise MocapError(f"--level {values[0]}: the first value is the intensity, a finite number") from None
        if len(values) < 2:
            raise MocapError(f"--level {values[0]}: give at least one BVH file after the intensity")
        levels.append((k, values[1:]))
    levels.sort(key=lambda kv: kv[0])
    counts = {len(files) for _, files in levels}
    if len(counts) != 1:
        raise MocapError(
            f"every --level needs the same number of files (one per person); got {[len(f) for _, f in levels]}"
        )
    n = counts.pop()
    paths = [[files[i] for _, files in levels] for i in range(n)]
    people = read_all([path for person in paths for path in person], "clips", args=args)
    return [people[i * len(levels) : (i + 1) * len(levels)] for i in range(n)], [k for k, _ in levels], paths


def _train_from_args(args):
    """The model of --model, or trained on the --level files (with those files' names)."""
    from ..exaggeration import ExaggerationModel, train

    if getattr(args, "model", None):
        return ExaggerationModel.load(args.model), None
    people, levels, paths = _levels(args)
    cycle = int(args.cycle) if args.cycle.lstrip("-").isdigit() else args.cycle  # names are checked by train
    try:
        model = train(
            people,
            levels,
            samples=args.samples,
            share=args.share,
            energy=args.energy,
            rank=args.rank,
            degree=args.degree,
            representation="euler" if args.euler else "rotvec",
            cycle=cycle,
            foot=FEET.index(args.foot),
            joint_map=joint_map(args),
        )
    except ClipError as error:
        raise MocapError(f"{paths[error.person][error.level]}: {error}") from None
    return model, paths


def add_rank(commands) -> None:
    p = commands.add_parser(
        "rank", help="rank the expressive features of an action performed at several intensities (Davis & Kannappan)"
    )
    _add_training_options(p)
    p.add_argument(
        "-o",
        "--output",
        action="append",
        metavar="OUT.png|MODEL.npz",
        help="write the bar plot (.png) and/or the model (.npz); repeatable",
    )
    p.add_argument("--top", type=positive(int), default=20, help="DOFs listed (default 20)")
    p.set_defaults(run=cmd_rank)


def cmd_rank(args) -> int:
    outputs = args.output or []
    bad = [o for o in outputs if not o.lower().endswith((".png", ".npz"))]
    if bad:
        raise MocapError(f"-o {bad[0]}: outputs must end in .png (the plot) or .npz (the model)")
    model, paths = _train_from_args(args)
    for i, person in enumerate(paths):
        print(f"person {i}: " + " < ".join(Path(p).name for p in person))
    print(model.table(top=args.top))
    for out in outputs:
        if out.lower().endswith(".png"):
            levels = ", ".join(f"{k:g}" for k in model.levels)
            model.plot(out, title=f"expressiveness of {len(paths)} person(s), intensities {levels}")
        else:
            model.save(out)
        print(f"wrote {out}")
    return 0


def add_exaggerate(commands) -> None:
    p = commands.add_parser(
        "exaggerate", help="exaggerate or diminish a motion with a shipped model or one from `rank -o MODEL.npz`"
    )
    p.add_argument(
        "--model",
        metavar="MODEL.npz",
        help="exaggeration model (default: the shipped model that fits the input best; `expressive-mocap models` "
        "lists them)",
    )
    p.add_argument("--action", help="without --model: choose among the shipped models of this action only")
    p.add_argument("--axis", help="without --model: choose among the shipped models of this style axis only")
    p.add_argument("--input", required=True, metavar="IN.bvh", help="the motion (same skeleton and action)")
    p.add_argument(
        "--from",
        dest="current",
        type=finite,
        metavar="K0",
        help="its current intensity (default: estimated by least squares over the key DOFs' mapped coefficients, "
        "each weighted by how well the mapping predicts it; printed with its uncertainty and fit residual, with a "
        "warning when outside the trained range)",
    )
    p.add_argument(
        "--to",
        type=finite,
        required=True,
        metavar="K1",
        help="target intensity (beyond the trained range extrapolates)",
    )
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    margin, fade, blend = (default(exaggerate, name) for name in ("margin", "fade", "blend"))
    p.add_argument(
        "--margin",
        type=finite,
        default=margin,
        help=f"DOFs stay within the training range widened by this share of its width (default {margin:g})",
    )
    p.add_argument(
        "--fade", type=finite, default=fade, help=f"cross-fade at cycle boundaries, seconds (default {fade:g})"
    )
    reference = default(exaggerate, "reference")
    p.add_argument(
        "--reference",
        choices=["model", "own"],
        default=reference,
        help="rotations measured from the training mean pose (default) or the motion's own",
    )
    p.add_argument(
        "--baseline",
        metavar="BASELINE.bvh",
        help="a clip of the same actor and action at a known intensity (--baseline-level): its difference from the "
        "model at that intensity is removed before the current intensity is estimated and from the clamping range",
    )
    p.add_argument("--baseline-level", type=finite, metavar="K", help="the intensity of --baseline")
    p.add_argument(
        "--estimate-offsets",
        action="store_true",
        help="let the estimate read each DOF's mean over the cycle too (default: only how it varies, so the "
        "actor's own posture does not move it)",
    )
    p.add_argument("--no-foot-lock", action="store_true", help="do not pin the stance feet with leg IK during contacts")
    p.add_argument(
        "--no-timing",
        action="store_true",
        help="keep the input's timing (default: the cycles' duration and the hips' travel over them change with the "
        "intensity as the model's timing mappings say, so the output may have another number of frames)",
    )
    p.add_argument(
        "--blend",
        type=finite,
        default=blend,
        help=f"foot locking eases in and out over this many seconds (default {blend:g})",
    )
    add_map_option(p)
    add_body_model_option(p)
    p.set_defaults(run=cmd_exaggerate)


def cmd_exaggerate(args) -> int:
    from ..exaggeration import ExaggerationModel, exaggerate

    if (args.baseline is None) != (args.baseline_level is None):
        raise ArgumentError("--baseline and --baseline-level go together: a clip of the same actor and its intensity")
    if args.model and (args.action or args.axis):
        raise ArgumentError("--action and --axis choose among the shipped models: give them without --model")
    original = read_motion(args.input, args)
    model, carried = (ExaggerationModel.load(args.model), None) if args.model else _shipped_for(args, original)
    motion, back = carried or read_on_model(args.input, model, EXAGGERATION_MODEL_FIX, args, original)
    baseline = None
    if args.baseline is not None:
        baseline, _ = read_on_model(args.baseline, model, EXAGGERATION_MODEL_FIX, args)
    out, report = exaggerate(
        model,
        motion,
        args.to,
        current=args.current,
        margin=args.margin,
        fade=args.fade,
        lock_feet=not args.no_foot_lock,
        blend=args.blend,
        reference=args.reference,
        baseline=baseline,
        baseline_level=args.baseline_level,
        estimate_offsets=args.estimate_offsets,
        timing=not args.no_timing,
    )
    timing = report.timing
    # On the model's skeleton the edit locked the feet itself; carried back from its body, they
    # are locked again on the file's own skeleton, held as the edit holds them.
    on_model = original.skeleton.names == motion.skeleton.names
    held = None if args.no_foot_lock or on_model else _held(original, timing, joint_map(args))
    if timing is not None:  # carried back onto the input retimed alike, frame for frame
        from ..exaggeration.timing import retime_like

        original = held[0] if held is not None else retime_like(original, timing)
        _, back = read_on_model(args.input, model, EXAGGERATION_MODEL_FIX, args, original)
    written = back(out)
    if held is not None:
        written = _locked(held, written, args.blend)
    write_bvh(written, args.output)
    print(report.text())
    if not on_model:  # edited on the model's body: say what the file got
        print(on_own_skeleton(original, written))
    print(f"wrote {args.output}")
    return 0


def _shipped_for(args, original: Motion) -> tuple:
    """The shipped model that fits the input best (among ``--action``, ``--axis``), said; with
    the input carried onto it when the choice was read there (None: carry it onto the model)."""
    from ..exaggeration.zoo import candidates, choose

    if args.baseline is not None:
        raise ArgumentError("--baseline needs --model: a baseline is measured against one model")
    models = candidates(args.action, args.axis)
    # Every shipped model is of the canonical skeleton: the input is carried onto it once.
    carried = read_on_model(args.input, models[0].load(), EXAGGERATION_MODEL_FIX, args, original)
    shipped, model, ranked = choose(carried[0], models, explicit=args.action is not None)
    others = ", ".join(f"{s.name} {r:.2f}" for s, r in ranked if s is not shipped)
    styles = " < ".join(f"{style} {k}" for k, style in enumerate(shipped.styles, start=1))
    residual = next(r for s, r in ranked if s is shipped)
    print(
        f"model: the shipped {shipped.name} ({styles}), fit residual {residual:.2f}"
        + (f"; others: {others}" if others else "")
    )
    return model, (carried if shipped is models[0] else None)


def _held(original: Motion, timing, user_map) -> tuple:
    """What the foot lock holds on ``original``'s own skeleton: (the input at the edit's
    ``timing``, its contacts there, its ankles held still through them or None when not
    retimed, its roles). Retimed, the input's own feet slide where its travel was stretched:
    holding them there slid a retimed exaggeration's stance feet 3.6x the input's."""
    from ..body.body import Body
    from ..body.contacts import foot_contacts
    from ..body.conventions import upright
    from ..exaggeration.timing import held_still

    contacts = foot_contacts(upright(original))  # read Y up, as the edit's own are
    roles = Body.of(original.skeleton, user_map).roles
    if timing is None:
        return original, contacts, None, roles
    return (*held_still(original, contacts, roles, timing), roles)


def _locked(held: tuple, written: Motion, blend: float) -> Motion:
    """``written`` (an edit carried back onto the skeleton of ``held``: see :func:`_held`) with its
    stance feet locked there as the edit locks them on the model's body: eased in and out over
    ``blend`` seconds, the swing left as the edit made it. (The decoupling edits' planting also
    moves the swing toward the next contact: on an exaggerated walk that took 6 of the knees' 19
    extra degrees.) A leg that is not two bones from hip to ankle is left as it is."""
    from ..exaggeration.footlock import lock_stance_feet

    motion, contacts, ankles, roles = held
    try:
        return lock_stance_feet(motion, written, contacts, roles, int(round(blend * motion.fps)), ankles)[0]
    except ArgumentError:
        return written


def on_own_skeleton(original: Motion, written: Motion) -> str:
    """What an edit carried back onto the input's own skeleton did, measured on the file written
    (``written``, frame for frame with ``original``), in that skeleton's joint names: the largest
    change of each joint's rotation and the stance feet's speed through the input's contacts."""
    from ..body.contacts import foot_contacts
    from ..body.conventions import upright
    from ..exaggeration.edit import stance_foot_speed
    from ..rotations import quat

    angles = np.degrees(quat.angle(quat.mul(quat.conjugate(original.rotations), written.rotations))).max(axis=0)
    changes = sorted(zip(original.skeleton.names, angles), key=lambda nv: -nv[1])
    moved = ", ".join(f"{n} {v:.1f}" for n, v in changes if v >= 0.05)[:600] or "none"
    before, after = upright(original), upright(written)  # contacts and speeds are read along Y
    contacts = foot_contacts(before)
    speeds = stance_foot_speed(before, contacts), stance_foot_speed(after, contacts)
    return (
        f"on {original.skeleton.n_joints}-joint skeleton of the input, as written: "
        f"largest change per joint (degrees): {moved}\n"
        f"stance-foot speed {speeds[0]:.3g} -> {speeds[1]:.3g} (file units/s, through the input's contacts)"
    )


def add_validate(commands) -> None:
    p = commands.add_parser(
        "validate", help="the swap test (with random and best same-size sets) and the leave-one-person-out warp"
    )
    _add_training_options(p, model=True)
    draws, seed = default(swap_test, "draws"), default(swap_test, "seed")
    p.add_argument(
        "--draws", type=positive(int), default=draws, help=f"random same-size sets averaged (default {draws})"
    )
    p.add_argument("--seed", type=int, default=seed, help=f"random seed (default {seed})")
    p.set_defaults(run=cmd_validate)


def cmd_validate(args) -> int:
    from ..exaggeration import leave_one_out, rank_agreement, swap_test, timing_validation, validation_table
    from ..exaggeration.validation import timing_table

    model, paths = _train_from_args(args)
    if paths:
        for i, person in enumerate(paths):
            print(f"person {i}: " + " < ".join(Path(p).name for p in person))
    swaps = swap_test(model, draws=args.draws, seed=args.seed)
    several = model.trajectories.shape[0] > 1
    warps = leave_one_out(model) if several else []
    share = model.settings.share
    ratio = "||swap - heaviest|| / ||lightest - heaviest||"
    print(f"swap test at share {share:g}: {ratio} over DOF trajectories and joint positions")
    print(validation_table(swaps, warps, rank_agreement(model) if several else None))
    if several and model.has_timing:
        print("")
        print("over joint positions in time (2 s), without and with the timing swapped / warped:")
        print(timing_table(timing_validation(model)))
    return 0


def add_models(commands) -> None:
    p = commands.add_parser("models", help="list the shipped exaggeration models, their training and validation")
    p.set_defaults(run=cmd_models)


def cmd_models(args) -> int:
    from ..exaggeration.zoo import index_records

    records = index_records()
    if not records:
        print("this installation ships no exaggeration model")
        return 0
    print("Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0): takes 1-8 of each style trained, the later held out")
    header = ("action", "axis", "styles (1 < 2 < 3)", "swap", "warp", "estimate", "chosen")
    print("{:<20} {:<7} {:<28} {:>5} {:>5} {:>9} {:>7}  shipped".format(*header))
    for r in records:
        shipped = "yes" if r["shipped"] else "no (" + "; ".join(f.split(" (")[0] for f in r["failed"]) + ")"
        print(
            f"{r['action']:<20} {r['axis']:<7} {' < '.join(r['styles']):<28} {r['swap_ratio']:>5.2f} "
            f"{r['warp_ratio_worst']:>5.2f} {100 * r['estimate_within']:>8.0f}% "
            f"{100 * r['chosen_right']:>6.0f}%  {shipped}"
        )
    print("swap: the paper's swap test over DOFs; warp: leave one person out, the worst; estimate: held-out takes")
    print("within 0.3 of their intensity; chosen: held-out takes whose best fit is their own action's model.")
    print("The card: expressive_mocap/data/exaggeration/MODEL_CARD.md; rebuilt by benches/build_models.py.")
    return 0


def add_parsers(commands) -> None:
    """The subparsers of this module's commands, in the order ``--help`` lists them."""
    for add in (add_rank, add_exaggerate, add_validate, add_models):
        add(commands)
