"""The ``expressive-mocap`` command: a thin layer over the package's functions.

Bad input ends the command with a one-line message on stderr and a non-zero exit, never a
traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math
import os
import sys
import warnings
from pathlib import Path

import numpy as np

from . import __version__, backend
from .bvh import bvh_bytes, read_bvh, write_bvh
from .errors import ClipError, MocapError
from .files import atomic_write, atomic_write_all, file_kind, is_standard_output, open_input, output_target
from .motion import ORDERS, Motion

PROG = "expressive-mocap"


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage mistake is one line (and exit status 2), like every other error."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _finite(text: str) -> float:
    """A float option: "nan" and "inf" parse as floats, and are refused here, before any work."""
    value = float(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    return value


_finite.__name__ = "float"  # argparse's "invalid float value: 'x'"


def _positive(kind):
    def parse(text: str):
        value = kind(text)
        if not (math.isfinite(value) and value > 0):  # float("inf") and float("nan") parse
            raise argparse.ArgumentTypeError(f"must be positive and finite, got {text}")
        return value

    parse.__name__ = kind.__name__
    return parse


def cmd_info(args) -> int:
    failures = 0
    for path in args.files:
        try:
            motion = read_bvh(path)
        except MocapError as error:
            print(f"{PROG}: error: {error}", file=sys.stderr)
            failures += 1
            continue
        skeleton = motion.skeleton
        print(f"{path}")
        print(f"  joints    {skeleton.n_joints} (+{len(skeleton.end_sites)} End Sites), root {skeleton.names[0]}")
        print(f"  frames    {motion.n_frames} at {motion.fps:.6g} fps (frame time {motion.frame_time:.7g} s)")
        print(f"  duration  {motion.duration:.3f} s")
        print(f"  channels  {skeleton.n_channels} a frame: {skeleton.channel_layout()}")
        print(f"  rest pose height {skeleton.rest_height():.4g} (file units, Y extent incl. End Sites)")
    return 1 if failures else 0


def cmd_positions(args) -> int:
    kind = ".npz" if is_standard_output(args.output) else Path(args.output).suffix.lower()
    if kind not in (".npz", ".csv"):
        raise MocapError(f"-o {args.output}: positions writes .npz (every array) or .csv (positions, a row per frame), by the name's extension")
    motion = read_bvh(args.file)
    rotations, positions = motion.fk()
    if not np.isfinite(positions).all():  # offsets near 1e308 add up past float64
        frame, joint = np.argwhere(~np.isfinite(positions))[0, :2]
        raise MocapError(f"{args.file}: the position of {motion.skeleton.names[joint]} at frame {frame} is not finite (beyond float64): nothing written")
    if kind == ".csv":
        atomic_write(args.output, _positions_csv(motion, positions))
        print(f"wrote {args.output}: positions of {motion.skeleton.n_joints} joints x {motion.n_frames} frames (world, file units)")
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
    print(f"wrote {args.output}: positions and rotations of {motion.skeleton.n_joints} joints x {motion.n_frames} frames (world, x,y,z,w)")
    return 0


def _positions_csv(motion: Motion, positions: np.ndarray) -> bytes:
    """World positions as CSV: a header row, then per frame its time and x, y, z of every joint."""
    columns = ["time"] + [f"{name}_{axis}" for name in motion.skeleton.names for axis in "xyz"]
    table = np.column_stack([np.arange(motion.n_frames) * motion.frame_time, positions.reshape(motion.n_frames, -1)])
    text = io.StringIO()
    np.savetxt(text, table, fmt="%.9g", delimiter=",", header=",".join(columns), comments="")
    return text.getvalue().encode()


@contextlib.contextmanager
def _option(path: str, option: str, value):
    """An edit's MocapError, naming the file and the option it came from."""
    try:
        yield
    except MocapError as error:
        raise MocapError(f"{path}: {option} {value:g}: {str(error).removeprefix('resample: ').removeprefix('scaled: ')}") from None


def cmd_convert(args) -> int:
    motion = read_bvh(args.input)
    if args.fps:
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


def cmd_render(args) -> int:
    from .render import render

    motions = [read_bvh(path) for path in args.files]
    titles = [Path(p).stem for p in args.files]
    if args.decoupled or args.modulated:
        from .decouple import decompose

        if len(motions) != 1:
            raise MocapError("--decoupled and --modulated draw one file: give exactly one")
        parts = decompose(motions[0], _model(args), args.gain, args.exponent)
        if args.decoupled:
            motions, titles = [motions[0], parts.body_motion(), parts.expressive_motion()], ["original", "body mechanics", "expressive"]
        else:
            motions, titles = [parts.recompose(s) for s in (0.5, 1.0, 1.5)], ["50% expressive", "100% (original)", "150% expressive"]
    if args.start or args.end:
        motions = [m[args.start : args.end] for m in motions]
    options = {"poses": args.poses} if args.output.lower().endswith(".png") else {"speed": args.speed}
    played = render(motions, args.output, titles=titles, view=args.view, **options)
    print(f"wrote {args.output}" + (f": {played}" if played else ""))
    return 0


def cmd_footsteps(args) -> int:
    from .features import cadence, contact_intervals, default_floor, foot_contacts, footstrikes
    from .roles import JointRoles, actor_height

    motion = read_bvh(args.file)
    roles = JointRoles.find(motion.skeleton)
    names = roles.names(motion.skeleton)
    height = actor_height(motion.skeleton, roles)
    floor = args.floor if args.floor is not None else (0.0 if args.causal else default_floor(motion.positions(), roles))
    contacts = foot_contacts(
        motion, roles, floor=floor, causal=args.causal, height_threshold=args.height_threshold, speed_threshold=args.speed_threshold
    )
    dt = motion.frame_time
    print(f"{args.file}: {motion.n_frames} frames at {motion.fps:.6g} fps ({motion.duration:.2f} s)")
    print(f"  actor height {height:.4g}, floor at {floor:.4g} (file units)")
    print(
        f"  contact: height < {args.height_threshold:g} x height = {args.height_threshold * height:.3g} and "
        f"speed < {args.speed_threshold:g} x height/s = {args.speed_threshold * height:.3g}/s, "
        f"{'causal hold' if args.causal else 'offline filter'} of 0.1 s"
    )
    for side, intervals in zip(("left", "right"), contact_intervals(contacts, dt)):
        print(f"{side} foot ({names[f'{side}_foot']}, {names[f'{side}_toe']}): {len(intervals)} contact{'s' * (len(intervals) != 1)}")
        for i in intervals:
            print(f"  frames {i.start:5d}-{i.end:<5d} {i.start * dt:8.3f}-{(i.end + 1) * dt:.3f} s  ({i.seconds:.3f} s)")
    strikes = footstrikes(contacts)
    steps_per_second = cadence(contacts, dt)
    left = int(np.count_nonzero(strikes[:, 1] == 0))
    rate = f"cadence {steps_per_second:.2f} steps/s" if np.isfinite(steps_per_second) else "cadence: too few steps"
    print(f"summary: {len(strikes)} steps ({left} left, {len(strikes) - left} right), {rate}")
    if args.plot:
        from .render import plot_contacts

        title = f"{Path(args.file).name}: foot contacts ({len(strikes)} steps, {rate})"
        plot_contacts(contacts, dt, args.plot, title=title)
        print(f"wrote {args.plot}")
    return 0


# Every file demo writes in its folder (cmd_demo, _demo_decoupling), checked before any work.
DEMO_FILES = ("walk.bvh", "walk_wave.bvh", "walk.png", "walk.gif", "walk_wave_body.bvh", "walk_wave_expressive.bvh",
              "walk_wave_x0.5.bvh", "walk_wave_x1.5.bvh", "decouple.png", "modulate.png", "decouple.gif")


def cmd_demo(args) -> int:
    from .demo import walk_and_wave
    from .features import cadence, foot_contacts, footstrikes
    from .render import render
    from .roles import JointRoles, actor_height

    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    print(f"expressive-mocap {__version__}, kernels: {backend.get_backend()}")
    pair = walk_and_wave(seconds=args.seconds, speed=args.speed, side=args.wave)
    bvh_path, wave_path = out / "walk.bvh", out / "walk_wave.bvh"
    write_bvh(pair.walk, bvh_path)
    write_bvh(pair.waving, wave_path)
    again, waving = read_bvh(bvh_path), read_bvh(wave_path)
    drift = float(np.abs(again.positions() - pair.walk.positions()).max())
    print(f"procedural walk at {args.speed} m/s on the Bandai-Namco dataset-2 skeleton: {again.n_frames} frames -> {bvh_path}")
    cmd_info(argparse.Namespace(files=[str(bvh_path)]))
    roles = JointRoles.find(again.skeleton)
    print(f"  actor height {actor_height(again.skeleton, roles):.4g} cm (hips rest height + spine-to-head chain: the rest pose is not upright)")
    print(f"  read back: largest joint position difference {drift:.2e} cm")
    hips = again.positions()[:, roles.hips]
    print(f"  hips travelled {np.linalg.norm(hips[-1, [0, 2]] - hips[0, [0, 2]]) / 100:.2f} m in {again.duration:.2f} s")
    contacts = foot_contacts(again, roles)
    strikes = footstrikes(contacts)
    left = int(np.count_nonzero(strikes[:, 1] == 0))
    print(f"  footsteps: {len(strikes)} ({left} left, {len(strikes) - left} right), cadence {cadence(contacts, again.frame_time):.2f} steps/s")
    changed = [again.skeleton.names[j] for j in range(again.skeleton.n_joints) if not np.array_equal(again.rotations[:, j], waving.rotations[:, j])]
    print(f"the same walk waving the {args.wave} arm -> {wave_path} (joints that differ: {', '.join(changed)})")
    titles = ["procedural walk", f"waving the {args.wave} arm"]
    render([again, waving], out / "walk.png", titles=titles)
    seconds = int(again.fps * 1.5)
    render([again[:seconds], waving[:seconds]], out / "walk.gif", titles=titles, view="front")
    print(f"pictures: {out / 'walk.png'}, {out / 'walk.gif'}")
    _demo_decoupling(waving, changed, out)
    return 0


def _demo_decoupling(waving: Motion, arm: list[str], out: Path) -> None:
    """Decouple the waving walk with the shipped model, modulate it, draw both."""
    from .decouple import decompose
    from .model import BodyModel
    from .render import render

    parts = decompose(waving, BodyModel.load())
    names = waving.skeleton.names
    on_arm = [names.index(n) for n in arm]
    elsewhere = [j for j in range(2, len(names)) if j not in on_arm]
    print("decoupled with the shipped body-mechanics model (trained on Bandai-Namco neutral locomotion):")
    print(f"  mean activity on the waving arm ({', '.join(arm)}): {parts.activity[:, on_arm].mean():.2f}; on the other 17 joints: {parts.activity[:, elsewhere].mean():.3f}")
    write_bvh(parts.body_motion(), out / "walk_wave_body.bvh")
    write_bvh(parts.expressive_motion(), out / "walk_wave_expressive.bvh")
    for scale in (0.5, 1.5):
        write_bvh(parts.recompose(scale), out / f"walk_wave_x{scale:g}.bvh")
    print(f"  wrote walk_wave_body.bvh, walk_wave_expressive.bvh, walk_wave_x0.5.bvh, walk_wave_x1.5.bvh in {out}")
    clip = slice(0, int(waving.fps * 1.5))
    render([waving, parts.body_motion(), parts.expressive_motion()], out / "decouple.png", ["original", "body mechanics", "expressive"], view="front", poses=4)
    render([parts.recompose(s) for s in (0.5, 1.0, 1.5)], out / "modulate.png", ["50% expressive", "100% (original)", "150% expressive"], view="front", poses=4)
    render([waving[clip], parts.body_motion()[clip], parts.expressive_motion()[clip]], out / "decouple.gif", ["original", "body mechanics", "expressive"], view="front")
    print(f"pictures: {out / 'decouple.png'}, {out / 'modulate.png'}, {out / 'decouple.gif'}")


def _model(args):
    """The body-mechanics model of --model (default: the shipped one), calibrated with
    --calibrate NEUTRAL... when given."""
    from .model import BodyModel

    model = BodyModel.load(args.model)
    if getattr(args, "calibrate", None):
        for path in args.calibrate:
            if _is_model_file(path):
                raise MocapError(f"--calibrate {path}: a model file; --calibrate takes neutral BVH clips, and a calibrated model goes to --model")
        model = model.calibrated([_read_for_model(path, model) for path in args.calibrate])
    return model


def _is_model_file(path: str) -> bool:
    """A zip archive (what .npz model files are), by its first bytes."""
    try:
        with open_input(path) as handle:
            return handle.read(4) == b"PK\x03\x04"
    except OSError:
        return False  # the reader says why, with the file's name


BODY_MODEL_FIX = ("the body-mechanics model applies to its own skeleton only; train one on clips of this skeleton "
                  "(`expressive-mocap train`), then calibrate it to a session if needed (`calibrate`)")
EXAGGERATION_MODEL_FIX = ("an exaggeration model applies to its own skeleton only; train one on clips of this skeleton "
                          "(`expressive-mocap rank --level ... -o MODEL.npz`)")


def _read_for_model(path: str, model, fix: str = BODY_MODEL_FIX) -> Motion:
    """A BVH file that the model can take: another skeleton is an error naming the file and
    what to do about it."""
    motion = read_bvh(path)
    try:
        model.check_skeleton(motion)
    except MocapError as error:
        raise MocapError(f"{path}: {error}: {fix}") from None
    return motion


def _window(text: str) -> tuple[int, int]:
    """``"A:B"`` -> ``(A, B)`` output frames."""
    try:
        start, end = (int(part) for part in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected START:END frames, got {text!r}") from None
    if start < 0 or end < start:
        raise argparse.ArgumentTypeError(f"expected 0 <= START <= END, got {text!r}")
    return start, end


DECOUPLE_SUFFIXES = ("_body.bvh", "_expressive.bvh", "_activity.csv")


def cmd_decouple(args) -> int:
    from .decouple import decompose

    model = _model(args)
    motion = _read_for_model(args.input, model)
    parts = decompose(motion, model, args.gain, args.exponent)
    prefix = str(args.output)
    if prefix.lower().endswith(".bvh"):  # -o out.bvh means the prefix out, not out.bvh_body.bvh
        prefix = prefix[:-4]
    names = motion.skeleton.names
    table = io.StringIO()
    np.savetxt(table, parts.activity, fmt="%.5f", delimiter=",", header=",".join(names), comments="")
    files = {}
    for suffix, part in zip(DECOUPLE_SUFFIXES[:2], (parts.body_motion(), parts.expressive_motion())):
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
    return 0


def cmd_modulate(args) -> int:
    from .decouple import modulate

    model = _model(args)
    out = modulate(_read_for_model(args.input, model), args.scale, model, args.gain, args.exponent)
    write_bvh(out, args.output)
    print(f"wrote {args.output}: expressiveness x {args.scale:g}")
    return 0


def cmd_mix(args) -> int:
    from .decouple import mix

    model = _model(args)
    out = mix(_read_for_model(args.body, model), _read_for_model(args.expressive, model), model, args.align, args.offset, args.gain, args.exponent)
    write_bvh(out, args.output)
    print(f"wrote {args.output}: body mechanics of {args.body}, expressiveness of {args.expressive}")
    return 0


def cmd_blend(args) -> int:
    from .decouple import blend, blend_alignment

    first, second = read_bvh(args.first), read_bvh(args.second)
    expressive_window = None if args.naive else args.expressive_window or args.body_window
    if args.naive:
        out = blend(first, second, None, args.body_window)
    else:
        out = blend(first, second, _model(args), args.body_window, expressive_window, args.gain, args.exponent)
    write_bvh(out, args.output)
    a = blend_alignment(first, second, args.body_window, expressive_window)
    print(f"wrote {args.output}: {out.n_frames} frames")
    print(f"  {args.second} continues the path of {first.skeleton.names[a.joint]} from frame {a.anchor}: turned {a.turn:.1f} degrees "
          f"about the vertical and moved {np.linalg.norm(a.shift):.4g} (file units) on the floor")
    return 0


def cmd_calibrate(args) -> int:
    from .model import BodyModel

    model = BodyModel.load(args.model)
    model = model.calibrated([_read_for_model(path, model) for path in args.neutral])
    model.save(args.output)
    angles = model.calibration_angles()
    largest = sorted(angles.items(), key=lambda kv: -kv[1])[:5]
    print(f"wrote {args.output}: the model calibrated on {len(args.neutral)} neutral clip(s); largest corrections:")
    for name, degrees in largest:
        print(f"  {name:<16} {degrees:6.1f} degrees")
    return 0


def _read_all(paths: list[str], what: str, quiet: bool = False) -> list[Motion]:
    """BVH files read one after the other, with a progress bar on stderr (see progress.Progress)."""
    from .progress import Progress

    with Progress(len(paths), f"reading {what}", "files", enabled=bool(paths) and not quiet) as bar:
        motions = []
        for path in paths:
            motions.append(read_bvh(path))
            bar.update()
    return motions


def cmd_train(args) -> int:
    from .model import poor_fit, train_model
    from .progress import line_log
    from .train import format_report

    neutral = _read_all(args.neutral, "neutral clips", args.quiet)
    unlabelled = _read_all(args.unlabelled or [], "unlabelled clips", args.quiet)
    model = train_model(
        neutral, unlabelled, hidden=args.hidden, regression_hidden=args.regression_hidden, unlabelled_frames=args.unlabelled_frames,
        seed=args.seed, max_iter=args.max_iter, log=line_log(not args.quiet),
    )
    print(format_report(model.report))
    problem = poor_fit(model.report)
    if problem and not args.allow_poor:
        raise MocapError(f"not writing {args.output}: the model is of no use: {problem}; train on more neutral clips "
                         "(see `train --help`), or pass --allow-poor to write it anyway")
    model.save(args.output)
    if problem:
        print(f"{PROG}: warning: {args.output} is a poor model: {problem}", file=sys.stderr)
    print(f"wrote {args.output}")
    return 0


def _levels(args) -> tuple[list[list[Motion]], list[float], list[list[str]]]:
    """``--level K FILE...`` options -> people (person i = the i-th file of every level), the
    intensities in increasing order, and the file names per person."""
    if not args.level or len(args.level) < 2:
        raise MocapError("give at least two --level K FILE... options (one per intensity)")
    levels = []
    for values in args.level:
        try:
            k = _finite(values[0])
        except (ValueError, argparse.ArgumentTypeError):
            raise MocapError(f"--level {values[0]}: the first value is the intensity, a finite number") from None
        if len(values) < 2:
            raise MocapError(f"--level {values[0]}: give at least one BVH file after the intensity")
        levels.append((k, values[1:]))
    levels.sort(key=lambda kv: kv[0])
    counts = {len(files) for _, files in levels}
    if len(counts) != 1:
        raise MocapError(f"every --level needs the same number of files (one per person); got {[len(f) for _, f in levels]}")
    n = counts.pop()
    paths = [[files[i] for _, files in levels] for i in range(n)]
    people = _read_all([path for person in paths for path in person], "clips")
    return [people[i * len(levels) : (i + 1) * len(levels)] for i in range(n)], [k for k, _ in levels], paths


def _train_from_args(args):
    from .exaggerate import ExaggerationModel, train

    if getattr(args, "model", None):
        return ExaggerationModel.load(args.model), None
    people, levels, paths = _levels(args)
    cycle = int(args.cycle) if args.cycle.lstrip("-").isdigit() else args.cycle  # names are checked by train
    try:
        model = train(
            people, levels, samples=args.samples, share=args.share, energy=args.energy, rank=args.rank, degree=args.degree,
            representation="euler" if args.euler else "rotvec", cycle=cycle, foot=("left", "right").index(args.foot),
        )
    except ClipError as error:
        raise MocapError(f"{paths[error.person][error.level]}: {error}") from None
    return model, paths


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
            model.plot(out, title=f"expressiveness of {len(paths)} person(s), intensities {', '.join(f'{k:g}' for k in model.levels)}")
        else:
            model.save(out)
        print(f"wrote {out}")
    return 0


def cmd_exaggerate(args) -> int:
    from .exaggerate import ExaggerationModel, exaggerate

    model = ExaggerationModel.load(args.model)
    motion = _read_for_model(args.input, model, EXAGGERATION_MODEL_FIX)
    out, report = exaggerate(
        model, motion, args.to, current=args.current, margin=args.margin, fade=args.fade, lock_feet=not args.no_foot_lock, blend=args.blend,
        reference=args.reference,
    )
    write_bvh(out, args.output)
    print(report.text())
    print(f"wrote {args.output}")
    return 0


def cmd_validate(args) -> int:
    from .exaggerate import leave_one_out, rank_agreement, swap_test, validation_table

    model, paths = _train_from_args(args)
    if paths:
        for i, person in enumerate(paths):
            print(f"person {i}: " + " < ".join(Path(p).name for p in person))
    swaps = swap_test(model, draws=args.draws, seed=args.seed)
    several = model.trajectories.shape[0] > 1
    warps = leave_one_out(model) if several else []
    print(f"swap test at share {model.settings.get('share', 0.9):g}: ||swap - heaviest|| / ||lightest - heaviest|| over DOF trajectories and joint positions")
    print(validation_table(swaps, warps, rank_agreement(model) if several else None))
    return 0


def _add_training_options(p, model: bool = False) -> None:
    p.add_argument("--level", action="append", nargs="+", metavar=("K", "FILE"),
                   help="an intensity K and its BVH files, one per person (person i = the i-th file of every level); repeat per intensity")
    if model:
        p.add_argument("--model", metavar="MODEL.npz", help="a model saved by `rank -o MODEL.npz` instead of --level files")
    p.add_argument("--share", type=_positive(float), default=0.9, help="expressiveness share of the key features (default 0.9)")
    p.add_argument("--energy", type=_positive(float), default=0.99, help="basis share of sum(s^2) (default 0.99)")
    p.add_argument("--rank", type=_positive(int), help="number of basis vectors (default: by --energy)")
    p.add_argument("--degree", type=int, default=1, help="degree of the intensity-to-coefficient mappings (default 1: lines)")
    p.add_argument("--samples", type=_positive(int), default=50, help="samples per time-normalised cycle T (default 50)")
    p.add_argument("--cycle", default="all", help="cycles of each clip: all (default: their mean is the performance, predictability is measured over "
                   "every one), middle (the paper's single cycle), first, whole (not a walk), or an index")
    p.add_argument("--foot", choices=["left", "right"], default="left", help="walking cycles run from one footstrike of this foot to the next (default left)")
    p.add_argument("--euler", action="store_true", help="DOFs are the Euler channels (relative to the mean) instead of rotation vectors")


def cmd_preprocess(args) -> int:
    from .preprocess import preprocess

    summary = preprocess(args.source, args.output, args.keep, args.model, batch_mb=args.batch_mb,
                         max_batches=args.max_batches, model_float32=args.model_float32, cluster=args.dask, overwrite=args.overwrite,
                         progress=not args.quiet)
    print("\n".join(summary.lines()))
    if summary.finished and summary.clips_ok == 0:  # a dataset of nothing is not a success
        found = f"none of its {summary.clips_failed} clips could be read (see the failures above)" if summary.clips_failed else "it holds no .bvh clips"
        raise MocapError(f"{args.source}: {found}; {args.output} holds no data")
    return 0


def _add_model_options(p, calibrate: bool = True) -> None:
    p.add_argument("--model", metavar="MODEL.npz", help="body-mechanics model (default: the shipped one, trained on Bandai-Namco neutral locomotion)")
    if calibrate:
        p.add_argument("--calibrate", nargs="+", metavar="NEUTRAL", help="neutral clips of the same actor/session: calibrate the model to them first")
    p.add_argument("--gain", type=_positive(float), default=2.0, help="g of the activity index clip((tanh(a) g)^b, 0, 1) (default 2)")
    p.add_argument("--exponent", type=_positive(float), default=4.0, help="b of the activity index (default 4)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog=PROG, description="Find, measure and edit the expressive part of motion capture (BVH files).")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("--backend", choices=backend.BACKENDS, help=f"kernels to use (default: ${backend.ENV_VAR} or auto = Rust when built)")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser, required=True)

    p = commands.add_parser("info", help="joints, frames, fps, duration, channel layout and rest height of BVH files")
    p.add_argument("files", nargs="+", metavar="FILE", help="BVH files")
    p.set_defaults(run=cmd_info)

    p = commands.add_parser("positions", help="world positions and rotations of every joint, to an .npz file")
    p.add_argument("file", metavar="FILE", help="BVH file")
    p.add_argument("-o", "--output", required=True, metavar="OUT.npz|OUT.csv", help=".npz: arrays positions [F,J,3], rotations [F,J,4] (x,y,z,w), joints, parents, frame_time; .csv: time and x,y,z of every joint, a row per frame")
    p.set_defaults(run=cmd_positions)

    p = commands.add_parser("convert", help="rewrite a BVH file, optionally resampled, scaled or in another rotation order")
    p.add_argument("input", metavar="IN", help="BVH file")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write (atomically; - for standard output)")
    p.add_argument("--fps", type=_positive(float), help="resample to this frame rate (slerp)")
    p.add_argument("--scale", type=_positive(float), help="multiply every length, e.g. 0.01 for cm to m")
    p.add_argument("--order", type=str.upper, choices=ORDERS, help="write every joint's rotation channels in this order")
    p.add_argument("--decimals", type=int, help="digits after the point (default: the shortest text that reads back exactly)")
    p.set_defaults(run=cmd_convert)

    p = commands.add_parser("render", help="stick figures side by side: poses as PNG or an animated GIF")
    p.add_argument("files", nargs="+", metavar="FILE", help="BVH files, one panel each")
    p.add_argument("-o", "--output", required=True, metavar="OUT.png|OUT.gif", help="picture to write")
    p.add_argument("--view", choices=["side", "front"], default="side",
                   help="camera, relative to the walker's heading: side (walking to the right) or front (default: side)")
    p.add_argument("--poses", type=_positive(int), default=8, help="poses per panel in a PNG (default: 8)")
    p.add_argument("--speed", type=_positive(float), default=1.0, help="GIF playback speed, 1 = real time (default: 1)")
    p.add_argument("--start", type=int, default=0, help="first frame (default: 0)")
    p.add_argument("--end", type=int, help="frame to stop before (default: the end)")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--decoupled", action="store_true", help="one file: original | body mechanics | expressive")
    what.add_argument("--modulated", action="store_true", help="one file: expressiveness at 50%% | 100%% | 150%%")
    _add_model_options(p)
    p.set_defaults(run=cmd_render)

    p = commands.add_parser("decouple", help="split a motion into body mechanics and expressiveness (BVH + activity per joint)")
    p.add_argument("input", metavar="IN", help="BVH file (the model's skeleton)")
    p.add_argument("-o", "--output", required=True, metavar="PREFIX", help="writes PREFIX_body.bvh, PREFIX_expressive.bvh, PREFIX_activity.csv (a .bvh ending is dropped from PREFIX)")
    _add_model_options(p)
    p.set_defaults(run=cmd_decouple)

    p = commands.add_parser("modulate", help="scale the expressiveness of a motion (1 = unchanged, 0 = body mechanics only)")
    p.add_argument("input", metavar="IN", help="BVH file")
    p.add_argument("--scale", type=_finite, required=True, help="expressiveness factor, e.g. 0.5 or 1.5")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    _add_model_options(p)
    p.set_defaults(run=cmd_modulate)

    p = commands.add_parser("mix", help="body mechanics of one motion with the expressiveness of another")
    p.add_argument("--body", required=True, metavar="X.bvh", help="source of the body mechanics and root trajectory")
    p.add_argument("--expressive", required=True, metavar="Y.bvh", help="source of the expressive component")
    p.add_argument("--align", choices=["index", "resample"], default="index", help="Y frame by frame (holding its last frame) or resampled to X's length (default: index)")
    p.add_argument("--offset", type=int, default=0, help="with --align index: Y frame used at X frame 0 (default 0)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    _add_model_options(p)
    p.set_defaults(run=cmd_mix)

    p = commands.add_parser("blend", help="blend from one motion to another, body mechanics and expressiveness on their own windows")
    p.add_argument("first", metavar="P", help="BVH file to blend from")
    p.add_argument("second", metavar="Q", help="BVH file to blend to (starts at the earlier window's start)")
    p.add_argument("--body-window", type=_window, required=True, metavar="A:B", help="output frames over which the body mechanics go from P to Q")
    p.add_argument("--expressive-window", type=_window, metavar="C:D", help="output frames over which the expressiveness goes from P to Q (default: the body window)")
    p.add_argument("--naive", action="store_true", help="blend whole poses over the body window (no decoupling), for comparison")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    _add_model_options(p)
    p.set_defaults(run=cmd_blend)

    p = commands.add_parser(
        "train", help="train a body-mechanics model on neutral clips of one skeleton",
        description="Train a body-mechanics model on neutral clips of one skeleton. How much data: on Bandai-Namco locomotion "
        "(benches/NEUTRAL_DATA.md) 2 clips (~7 s) gave a model worse than the mean pose, which train refuses; 4 clips (~16 s) "
        "predicted held-out poses with 0.15x the mean pose's error, 16 clips (~70 s) 0.07x, 99 clips (~8 min) 0.05x. Give at "
        "least a minute of neutral walking and running, in several clips (the test split is by clip).",
    )
    p.add_argument("neutral", nargs="+", metavar="NEUTRAL", help="neutral clips (no gestures, head forward, limbs moving with the body); 70/30 split by clip")
    p.add_argument("--unlabelled", nargs="+", metavar="CLIP", help="any clips of the same skeleton: frames for the denoising autoencoder")
    p.add_argument("-o", "--output", required=True, metavar="MODEL.npz", help="the model file")
    p.add_argument("--hidden", type=_positive(int), default=300, help="autoencoder code units H (default 300)")
    p.add_argument("--regression-hidden", type=_positive(int), default=300, help="regression hidden units (default 300)")
    p.add_argument("--unlabelled-frames", type=_positive(int), default=40_000, help="frames drawn from the unlabelled clips (default 40000)")
    p.add_argument("--max-iter", type=_positive(int), default=400, help="L-BFGS iterations per stage (default 400)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--allow-poor", action="store_true", help="write the model even if it predicts held-out poses no better than the mean pose")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    p.set_defaults(run=cmd_train)

    p = commands.add_parser("calibrate", help="calibrate the body-mechanics model to an actor or capture session")
    p.add_argument("neutral", nargs="+", metavar="NEUTRAL", help="neutral clips (walks, runs, standing) of that actor/session")
    p.add_argument("-o", "--output", required=True, metavar="CAL.npz", help="the calibrated model, for --model")
    p.add_argument("--model", metavar="MODEL.npz", help="model to calibrate (default: the shipped one)")
    p.set_defaults(run=cmd_calibrate)

    p = commands.add_parser("rank", help="rank the expressive features of an action performed at several intensities (Davis & Kannappan)")
    _add_training_options(p)
    p.add_argument("-o", "--output", action="append", metavar="OUT.png|MODEL.npz", help="write the bar plot (.png) and/or the model (.npz); repeatable")
    p.add_argument("--top", type=_positive(int), default=20, help="DOFs listed (default 20)")
    p.set_defaults(run=cmd_rank)

    p = commands.add_parser("exaggerate", help="exaggerate or diminish a motion with a model from `rank -o MODEL.npz`")
    p.add_argument("--model", required=True, metavar="MODEL.npz", help="exaggeration model")
    p.add_argument("--input", required=True, metavar="IN.bvh", help="the motion (same skeleton and action)")
    p.add_argument("--from", dest="current", type=_finite, metavar="K0",
                   help="its current intensity (default: estimated by least squares over the key DOFs' mapped coefficients, each weighted "
                   "by how well the mapping predicts it; printed with its uncertainty and fit residual, with a warning when outside the trained range)")
    p.add_argument("--to", type=_finite, required=True, metavar="K1", help="target intensity (beyond the trained range extrapolates)")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write")
    p.add_argument("--margin", type=_finite, default=0.1, help="DOFs stay within the training range widened by this share of its width (default 0.1)")
    p.add_argument("--fade", type=_finite, default=0.15, help="cross-fade at cycle boundaries, seconds (default 0.15)")
    p.add_argument("--reference", choices=["model", "own"], default="model", help="rotations measured from the training mean pose (default) or the motion's own")
    p.add_argument("--no-foot-lock", action="store_true", help="do not pin the stance feet with leg IK during contacts")
    p.add_argument("--blend", type=_finite, default=0.1, help="foot locking eases in and out over this many seconds (default 0.1)")
    p.set_defaults(run=cmd_exaggerate)

    p = commands.add_parser("validate", help="the swap test (with random and best same-size sets) and the leave-one-person-out warp")
    _add_training_options(p, model=True)
    p.add_argument("--draws", type=_positive(int), default=200, help="random same-size sets averaged (default 200)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.set_defaults(run=cmd_validate)

    p = commands.add_parser(
        "footsteps",
        help="foot contacts of a walk: contact intervals per foot, step count and cadence, optionally a gait diagram",
        description="Foot contacts after Lee et al. 2002: a foot (ankle or toe) touches when it is both low and slow; "
        "contacts and flights shorter than 0.1 s are absorbed (offline) or held off (--causal). "
        "Prints each foot's contact intervals in frames and seconds, then the steps and the cadence.",
    )
    p.add_argument("file", metavar="FILE", help="BVH file (joints found by name: Bandai-Namco, CMU or Mixamo)")
    p.add_argument("--plot", metavar="OUT.png", help="also write a gait diagram: one row per foot, a bar per contact")
    p.add_argument("--causal", action="store_true", help="streaming detector: frame t sees frames <= t only (hold filter, floor 0)")
    p.add_argument("--height-threshold", type=_positive(float), default=0.05, metavar="X", help="contact below X x actor height above the floor (default: 0.05)")
    p.add_argument("--speed-threshold", type=_positive(float), default=0.5, metavar="X", help="contact below X x actor height per second (default: 0.5)")
    p.add_argument("--floor", type=_finite, metavar="Y", help="floor height in file units (default: 5th percentile of toe heights; 0 with --causal)")
    p.set_defaults(run=cmd_footsteps)

    p = commands.add_parser(
        "preprocess",
        help="a whole archive of BVH clips (folder, glob, .zip, .tar.gz/.xz) into a dataset of arrays: positions, features, contacts, activity",
        description="Parse every clip, run FK, dynamic features, foot contacts and optionally the decomposition, in batches "
        "(parallel Rust parsing and FK), into OUT: one memory-mappable .npy per kind, offsets.npy and manifest.json "
        "(load with expressive_mocap.preprocess.load_dataset(OUT)). Bad clips are listed with their errors; an interrupted "
        "run resumes where it stopped when run again.",
    )
    p.add_argument("source", metavar="SRC", help="a folder (*.bvh, recursive), a quoted glob, a .zip or a .tar/.tar.gz/.tar.xz")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="dataset folder")
    p.add_argument("--keep", metavar="KINDS", help="comma-separated: positions,rotations,features,contacts,activity,body,expressive "
                   "(default: positions,features,contacts, plus activity with --model)")
    p.add_argument("--model", nargs="?", const="", metavar="MODEL.npz", help="decompose with this body-mechanics model (no value: the shipped one)")
    p.add_argument("--model-float32", action="store_true", help="run the network in float32: ~2x faster, activity within ~2e-5 of float64")
    p.add_argument("--dask", nargs="?", const="local", metavar="ADDRESS", help="run the batches on a Dask cluster at ADDRESS "
                   "(no value: a local cluster of 2 worker processes on 127.0.0.1); needs pip install 'expressive-mocap[distributed]'")
    p.add_argument("--batch-mb", type=_positive(float), default=64.0, help="MB of BVH text read per batch (default 64)")
    p.add_argument("--max-batches", type=_positive(int), metavar="N", help="stop after N batches (rerun to resume)")
    p.add_argument("--overwrite", action="store_true", help="redo OUT if it already holds a finished dataset")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(run=cmd_preprocess)

    p = commands.add_parser("demo", help="generate a procedural walk and a waving one (no download), write, read and draw them")
    p.add_argument("-o", "--output", default="expressive-mocap-demo", metavar="DIR", help="folder for the outputs (default: ./expressive-mocap-demo)")
    p.add_argument("--speed", type=_positive(float), default=1.2, help="walking speed in m/s (default: 1.2)")
    p.add_argument("--seconds", type=_positive(float), default=4.0, help="length of the walk (default: 4)")
    p.add_argument("--wave", choices=["left", "right"], default="right", help="arm that waves in walk_wave.bvh (default: right)")
    p.set_defaults(run=cmd_demo)
    # --backend is also taken after the command (`info FILE --backend numpy`); SUPPRESS keeps a
    # command without it from overwriting the value given before the command.
    for command in commands.choices.values():
        command.add_argument("--backend", choices=backend.BACKENDS, default=argparse.SUPPRESS, help="kernels to use (as before the command)")
    return parser


# Commands whose one output may be standard output (`-o -` or `-o /dev/stdout`): a BVH or .npz
# streamed as it is; their report lines then go to stderr. Pictures pick their format from the
# name, decouple writes three files and demo/preprocess a folder, so they take none.
_STREAMING = ("convert", "positions", "modulate", "mix", "blend", "exaggerate", "calibrate", "train")


def _output_paths(args) -> list[str]:
    """The files a command will write, as given (``-o``, ``--plot``; decouple's three)."""
    outputs = args.output if isinstance(getattr(args, "output", None), list) else [getattr(args, "output", None)]
    outputs = [o for o in [*outputs, getattr(args, "plot", None)] if o is not None]
    if args.run is cmd_decouple and not is_standard_output(outputs[0]):  # `-o -` is refused, not "-_body.bvh"
        outputs = [f"{outputs[0]}{suffix}" for suffix in DECOUPLE_SUFFIXES]
    return [str(o) for o in outputs]


def _check_outputs(args) -> None:
    """Refuse, before any work, an output whose folder is missing or unwritable, or that is
    anything but a regular file or a new one (a folder, FIFO, socket, device, or a symlink to
    one: :func:`expressive_mocap.files.output_target`): files go where they are asked to (``-o``,
    ``--plot``), never next to an input, and the folders of ``demo`` and ``preprocess`` are
    created only inside an existing one. ``-`` is standard output for the commands that stream."""
    makes_folder = args.run in (cmd_demo, cmd_preprocess)  # their OUT is a folder, made if new
    for output in _output_paths(args):
        if is_standard_output(output):
            if args.command not in _STREAMING:
                raise MocapError(f"cannot write {output}: {args.command} does not write to standard output (these do: {', '.join(_STREAMING)})")
            continue
        path = Path(output)
        if makes_folder:
            if path.exists() and not path.is_dir():
                raise MocapError(f"cannot write {output}: it is {file_kind(path.stat().st_mode)}, not a folder")
            folder = path if path.is_dir() else path.parent
            if path.is_dir() and args.run is cmd_demo:
                for name in DEMO_FILES:
                    output_target(path / name)
        else:
            folder = output_target(path).parent  # a symlink to a regular file is written through
        if not folder.is_dir():
            what = "is not a folder" if folder.exists() else "does not exist"
            raise MocapError(f"cannot write {output}: the folder {folder} {what}")
        if not os.access(folder, os.W_OK):
            raise MocapError(f"cannot write {output}: the folder {folder} is not writable")


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    with warnings.catch_warnings():  # the package's warnings as one line each, like its errors
        warnings.showwarning = _show_warning
        return _run(args)


def _run(args) -> int:
    try:
        if args.backend:
            backend.set_backend(args.backend)
        backend.kernels()  # a bad $EXPRESSIVE_MOCAP_BACKEND fails here, in one line
        _check_outputs(args)
        # Streaming an output (`-o -`): standard output carries the data alone, reports go to stderr.
        streaming = any(is_standard_output(output) for output in _output_paths(args))
        with contextlib.redirect_stdout(sys.stderr) if streaming else contextlib.nullcontext():
            return args.run(args)
    except BrokenPipeError:
        # The reader went away (`| head`): stop quietly, and keep Python from complaining at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1
    except (MocapError, OSError) as error:
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
