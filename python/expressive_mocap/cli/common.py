"""What the command modules share: the parser class, option types, reading inputs, and the
defaults of the domain functions (typed once, in the domain code)."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING, Any, Callable

from ..errors import MocapError

if TYPE_CHECKING:
    from ..motion import Motion

__all__ = [
    "DECOUPLE_SUFFIXES",
    "DEMO_FILES",
    "PROG",
    "Parser",
    "add_body_model_option",
    "add_map_option",
    "default",
    "finite",
    "joint_map",
    "positive",
    "read_all",
    "read_for_model",
    "read_motion",
    "read_on_model",
]

PROG = "expressive-mocap"

# The files `decouple -o PREFIX` writes, and every file `demo` writes in its folder: the outputs
# checked before any work (cli.__init__), named here so checking them loads no command's code.
DECOUPLE_SUFFIXES = ("_body.bvh", "_expressive.bvh", "_activity.csv")
DEMO_FILES = (
    "walk.bvh",
    "walk_wave.bvh",
    "walk.png",
    "walk.gif",
    "walk_wave_body.bvh",
    "walk_wave_expressive.bvh",
    "walk_wave_x0.5.bvh",
    "walk_wave_x1.5.bvh",
    "decouple.png",
    "modulate.png",
    "decouple.gif",
)


class Parser(argparse.ArgumentParser):
    """argparse, but a usage mistake is one line (and exit status 2), like every other error."""

    def error(self, message: str):  # type: ignore[override]  # argparse's returns NoReturn
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def finite(text: str) -> float:
    """A float option: "nan" and "inf" parse as floats, and are refused here, before any work."""
    value = float(text)
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    return value


finite.__name__ = "float"  # argparse's "invalid float value: 'x'"


def positive(kind: Callable[[str], Any]) -> Callable[[str], Any]:
    """An option type: ``kind`` (int or float) of the text, positive and finite."""

    def parse(text: str):
        value = kind(text)
        if not (math.isfinite(value) and value > 0):  # float("inf") and float("nan") parse
            raise argparse.ArgumentTypeError(f"must be positive and finite, got {text}")
        return value

    parse.__name__ = kind.__name__
    return parse


def default(function: Callable, name: str) -> Any:
    """The default of ``function``'s parameter ``name``: an option's default is the domain code's."""
    import inspect  # here: only parsers of the methods' options ask, and `info` starts faster without it

    return inspect.signature(function).parameters[name].default


def add_map_option(p) -> None:
    """--map: a joint map file, for a file of another skeleton than the model's."""
    p.add_argument(
        "--map",
        metavar="MAP.json|MAP.toml",
        help="joint map (role -> joint name) for roles the names and topology of another skeleton do not find",
    )


def add_body_model_option(p) -> None:
    """--body-model: the SMPL-family body model an .npz parameter file (AMASS) is read with."""
    p.add_argument(
        "--body-model",
        metavar="SMPL.npz",
        help="the SMPL-family body model (your own .npz: v_template, shapedirs, J_regressor, kintree_table) "
        "that SMPL/AMASS parameter files (.npz inputs) are read with",
    )


def read_motion(path: str, args, fps: float | None = None) -> Motion:
    """The motion of an input file: a BVH file, or an SMPL-family parameter file (``.npz``, AMASS)
    read with ``args.body_model`` (``fps``: the frame rate of one without ``mocap_framerate``)."""
    from pathlib import Path

    if Path(path).suffix.lower() == ".npz":
        smpl_model = getattr(args, "body_model", None)
        if not smpl_model:
            raise MocapError(f"{path}: an .npz parameter file (SMPL/AMASS) needs --body-model SMPL.npz")
        from ..skeletons.smpl import read_smpl

        return read_smpl(path, smpl_model, fps=fps)
    from ..bvh import read_bvh

    return read_bvh(path)


def joint_map(args) -> dict | None:
    """The joint map of ``--map``, if given."""
    from ..body import read_joint_map

    path = getattr(args, "map", None)
    return read_joint_map(path) if path else None


def read_for_model(path: str, model, fix: str, args) -> Motion:
    """An input file (:func:`read_motion`) that the model can take, on the model's skeleton: a
    motion of another humanoid skeleton is put on the canonical body the shipped models know
    (see :func:`read_on_model` for the way back); a skeleton that cannot be is an error naming
    the file and ``fix``."""
    return read_on_model(path, model, fix, args)[0]


def read_on_model(
    path: str, model, fix: str, args, motion: Motion | None = None
) -> tuple[Motion, Callable[..., Motion]]:
    """An input file (:func:`read_motion`) on the model's skeleton, and how to carry an edit of
    it back to the file's own skeleton (the identity when the file is on the model's skeleton
    already; otherwise :class:`~expressive_mocap.skeletons.canonical.Carried`). ``args``: the
    command's (its ``--map`` and ``--body-model``). ``motion``: the file's motion when already
    read, or changed (an edit that retimed it carries back onto it retimed alike)."""
    from ..skeletons.canonical import carried_for  # here: building the parser reads no BVH

    user_map = joint_map(args)
    motion = read_motion(path, args) if motion is None else motion
    try:
        carried = carried_for(motion, model, user_map)
    except MocapError as error:
        try:
            model.check_skeleton(motion)
        except MocapError as refused:
            raise MocapError(f"{path}: {refused}: {fix} ({error})") from None
        raise
    if carried is None:  # the model's own skeleton: only its axes may differ (a Z-up file)
        from ..body.conventions import upright_and_back

        upright, turn_back = upright_and_back(motion)
        # Its feet were planted on the model's skeleton, which is the file's: nothing to redo.
        return upright, lambda edited, plant_feet=False: turn_back(edited)
    return carried.body, carried.back


def read_all(paths: list[str], what: str, quiet: bool = False, args=None) -> list[Motion]:
    """Input files (:func:`read_motion`, with ``args``' ``--body-model``) read one after the
    other, with a progress bar on stderr (see progress.Progress)."""
    from .._utils.progress import Progress

    with Progress(len(paths), f"reading {what}", "files", enabled=bool(paths) and not quiet) as bar:
        motions = []
        for path in paths:
            motions.append(read_motion(path, args))
            bar.update()
    return motions
