"""The ``expressive-mocap`` command: a thin layer over the package's functions.

Each group of commands is a module that adds its subparsers next to its command functions
(:mod:`.info`, :mod:`.files`, :mod:`.pictures`, :mod:`.skeletons`, :mod:`.decoupling`, :mod:`.exaggeration`,
:mod:`.data`, :mod:`.demo`); this one builds the parser and runs a command: outputs are checked
before any work, and bad input ends the command with a one-line message on stderr and a non-zero
exit, never a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
import warnings
from pathlib import Path

from .. import __version__, backend
from .._utils.files import file_kind, is_standard_output, output_target
from ..errors import MocapError
from .common import DECOUPLE_SUFFIXES, DEMO_FILES, PROG, Parser

__all__ = ["COMMANDS", "DEMO_FILES", "PROG", "build_parser", "main"]

# Each group's module and its commands, in the order ``--help`` lists them. A command line
# builds only its command's group: the others import what their commands need (the methods,
# training, pictures), a third of the CLI's start-up time, for nothing.
COMMANDS = {
    "info": ("info",),
    "files": ("positions", "convert"),
    "pictures": ("render",),
    "skeletons": ("skeleton", "retarget", "fit"),
    "decoupling": ("decouple", "modulate", "mix", "blend", "train", "calibrate"),
    "exaggeration": ("rank", "exaggerate", "validate", "models"),
    "data": ("footsteps", "preprocess"),
    "demo": ("demo",),
}


def _command_of(argv: list[str]) -> str | None:
    """The command a command line names (its first word that is not an option or the value of
    ``--backend``), or None."""
    words = iter(argv)
    for word in words:
        if word == "--backend":
            next(words, None)
        elif not word.startswith("-"):
            return word
    return None


def build_parser(command: str | None = None, commands_needed: bool = True) -> argparse.ArgumentParser:
    """The command line's parser: every command's, or only those of ``command``'s group (as
    :func:`main` builds it for a command line naming one), or none when not ``commands_needed``
    (``--version`` alone: no command's code is loaded)."""
    parser = Parser(prog=PROG, description="Find, measure and edit the expressive part of motion capture (BVH files).")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument(
        "--backend",
        choices=backend.BACKENDS,
        help=f"kernels to use (default: ${backend.ENV_VAR} or auto = Rust when built)",
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser, required=True)
    groups = [group for group, names in COMMANDS.items() if command in names]
    if not groups and commands_needed:
        groups = list(COMMANDS)
    for group in groups:
        importlib.import_module(f".{group}", __name__).add_parsers(commands)
    # --backend is also taken after the command (`info FILE --backend numpy`); SUPPRESS keeps a
    # command without it from overwriting the value given before the command.
    for subparser in commands.choices.values():
        subparser.add_argument(
            "--backend",
            choices=backend.BACKENDS,
            default=argparse.SUPPRESS,
            help="kernels to use (as before the command)",
        )
    return parser


# Commands whose one output may be standard output (`-o -` or `-o /dev/stdout`): a BVH or .npz
# streamed as it is; their report lines then go to stderr. Pictures pick their format from the
# name, decouple writes three files and demo/preprocess a folder, so they take none.
_STREAMING = ("convert", "positions", "retarget", "fit", "modulate", "mix", "blend", "exaggerate", "calibrate", "train")
_MAKE_FOLDERS = ("demo", "preprocess")  # their OUT is a folder, made if new


def _output_paths(args) -> list[str]:
    """The files a command will write, as given (``-o``, ``--plot``; decouple's three)."""
    outputs = args.output if isinstance(getattr(args, "output", None), list) else [getattr(args, "output", None)]
    outputs = [o for o in [*outputs, getattr(args, "plot", None)] if o is not None]
    if args.command == "decouple" and not is_standard_output(outputs[0]):  # `-o -` is refused, not "-_body.bvh"
        outputs = [f"{outputs[0]}{suffix}" for suffix in DECOUPLE_SUFFIXES]
    return [str(o) for o in outputs]


def _check_outputs(args) -> None:
    """Refuse, before any work, an output whose folder is missing or unwritable, or that is
    anything but a regular file or a new one (a folder, FIFO, socket, device, or a symlink to
    one: :func:`expressive_mocap._utils.files.output_target`): files go where they are asked to (``-o``,
    ``--plot``), never next to an input, and the folders of ``demo`` and ``preprocess`` are
    created only inside an existing one. ``-`` is standard output for the commands that stream."""
    for output in _output_paths(args):
        if is_standard_output(output):
            if args.command not in _STREAMING:
                raise MocapError(
                    f"cannot write {output}: {args.command} does not write to standard output "
                    f"(these do: {', '.join(_STREAMING)})"
                )
            continue
        path = Path(output)
        if args.command in _MAKE_FOLDERS:
            if path.exists() and not path.is_dir():
                raise MocapError(f"cannot write {output}: it is {file_kind(path.stat().st_mode)}, not a folder")
            folder = path if path.is_dir() else path.parent
            if path.is_dir() and args.command == "demo":
                for name in DEMO_FILES:
                    output_target(path / name)
        else:
            folder = output_target(path).parent  # a symlink to a regular file is written through
            _refuse_an_input(args, output)
        if not folder.is_dir():
            what = "is not a folder" if folder.exists() else "does not exist"
            raise MocapError(f"cannot write {output}: the folder {folder} {what}")
        if not os.access(folder, os.W_OK):
            raise MocapError(f"cannot write {output}: the folder {folder} is not writable")


# Attributes of a command's arguments that are not inputs.
_NOT_INPUTS = ("output", "plot", "command", "run", "backend")
_POSITIONAL = ("input", "source", "file", "files", "first", "second")  # the others are named as options


def _refuse_an_input(args, output: str) -> None:
    """Refuse an output that is, or resolves to (a symlink, a hard link), a file the command reads:
    writing it would replace the input before, or while, it is read."""
    for name, value in vars(args).items():
        if name in _NOT_INPUTS:
            continue
        for given in value if isinstance(value, list) else [value]:
            if isinstance(given, (str, os.PathLike)) and os.path.isfile(given) and _same_file(output, given):
                option = "the input" if name in _POSITIONAL else f"--{name.replace('_', '-')}"
                raise MocapError(
                    f"cannot write {output}: it is {option} {given} of this command; choose another output"
                )


def _same_file(a, b) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:  # a new output: no file yet, so not an input
        return False


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"{PROG}: warning: {message}", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    """Run the command line ``argv`` (default: the process's); returns the exit status."""
    words = sys.argv[1:] if argv is None else argv
    command = _command_of(words)
    args = build_parser(command, commands_needed=command is not None or "--version" not in words).parse_args(argv)
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
    except MocapError as error:  # bad input or arguments, from Python or the Rust kernels
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 1
    except OSError as error:  # the system's (a full disk, a permission): one line too, not a traceback
        print(f"{PROG}: error: {error}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
