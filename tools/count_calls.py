"""How often one CLI command asks each skeleton finder and each kernel: what a Body per skeleton
and a Take per motion save.

    python tools/count_calls.py COMMAND [ARGS ...]      e.g. mix --body walk.bvh --expressive wave.bvh -o out.bvh

Runs ``expressive-mocap COMMAND ARGS`` in this process with counters on the three finders (the
roles by name, the joint map, the rest heights) and on every kernel the ``ops`` wrappers call,
then prints the counts (the command's own output is kept back). Run each command in a fresh
process: a Body found once is kept for the process.
"""

from __future__ import annotations

import collections
import contextlib
import importlib
import io
import sys
from collections.abc import Callable
from typing import Any

COUNTS: collections.Counter = collections.Counter()


class _Counted:
    """A kernel module whose every function call is counted under its name."""

    def __init__(self, kernels: Any):
        self._kernels = kernels

    def __getattr__(self, name: str) -> Any:
        value = getattr(self._kernels, name)
        if not callable(value):
            return value

        def counted(*args: Any, **kwargs: Any) -> Any:
            COUNTS[f"kernel {name}"] += 1
            return value(*args, **kwargs)

        return counted


def _count(label: str, function: Callable) -> Callable:
    def counted(*args: Any, **kwargs: Any) -> Any:
        COUNTS[label] += 1
        return function(*args, **kwargs)

    return counted


def instrument() -> None:
    """Counters on the finders and on the kernels of every ``ops`` module."""
    from expressive_mocap.body import body, jointmap, roles

    by_names = roles.JointRoles.by_names.__func__  # type: ignore[attr-defined]
    roles.JointRoles.by_names = classmethod(_count("finder roles", by_names))  # type: ignore[method-assign]
    run = jointmap._Finder.run
    jointmap._Finder.run = _count("finder map", run)  # type: ignore[method-assign]
    body.rest_heights = _count("finder heights", body.rest_heights)
    for name in ("arrays", "bvh_text", "gait", "mlp", "posing", "rotations"):
        module = importlib.import_module(f"expressive_mocap.ops.{name}")
        module.kernels = lambda real=module.kernels: _Counted(real())  # type: ignore[attr-defined]


def main(argv: list[str]) -> int:
    from expressive_mocap.cli import main as cli

    instrument()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        code = cli(argv)
    for label, count in sorted(COUNTS.items()):
        print(f"{label}: {count}")
    return code


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
