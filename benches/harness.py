"""The speed benchmarks' one timing harness: how benches/ times, repeats, checks and names the machine.

    from harness import Best, Stopwatch, check, check_close, check_equal, median, rotated, timed

    seconds, motions = timed(em.read_bvh_many, paths, collect=True)   # one call: (seconds, result)
    check_equal(len(motions), len(paths), "clips read")                  # raises CheckFailed if not
    with Stopwatch() as watch:                                           # a block of code
        run()
    watch.seconds
    best = Best()                                                        # best of rounds, per label
    for r in range(rounds):
        for label in rotated(labels, r):                                 # the order rotated each round
            best.time(label, cases[label])

Every script in benches/ checks its result before it reports a time (``check``, ``check_equal``,
``check_close``): a check that fails raises :class:`CheckFailed` (also under ``python -O``), so a
wrong result never turns into a figure. Times come from one clock, :data:`clock`
(``time.perf_counter``). Machines here drift by +-30 %: compare only figures of one run, and
alternate what is compared (``rotated``).
"""

from __future__ import annotations

import compileall
import gc
import importlib.util
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

__all__ = [
    "Best",
    "CheckFailed",
    "Stopwatch",
    "byte_compile",
    "check",
    "check_close",
    "check_equal",
    "clock",
    "commit",
    "cpu_name",
    "log",
    "median",
    "memory_gib",
    "peak_rss",
    "ratio_median",
    "repeat",
    "rotated",
    "timed",
]

T = TypeVar("T")
HERE = Path(__file__).resolve().parent

clock = time.perf_counter  # the one clock of every timing here

# ----------------------------------------------------------------------------- timing


def timed(fn: Callable[..., T], *args: Any, collect: bool = False, **kwargs: Any) -> tuple[float, T]:
    """``(seconds, result)`` of one call ``fn(*args, **kwargs)``. ``collect``: collect garbage first,
    so one stage's litter is not billed to the next."""
    if collect:
        gc.collect()
    start = clock()
    result = fn(*args, **kwargs)
    return clock() - start, result


class Stopwatch:
    """Wall time of a ``with`` block: ``seconds`` once it is left, ``elapsed()`` while it runs."""

    def __init__(self) -> None:
        self.start = clock()
        self.seconds = math.nan

    def __enter__(self) -> Stopwatch:
        self.start = clock()
        return self

    def __exit__(self, *exc: object) -> None:
        self.seconds = clock() - self.start

    def elapsed(self) -> float:
        return clock() - self.start


def repeat(fn: Callable[[], object], times: int, warmup: int = 0) -> list[float]:
    """Seconds of each of ``times`` calls of ``fn()``, after ``warmup`` untimed calls."""
    for _ in range(warmup):
        fn()
    return [timed(fn)[0] for _ in range(times)]


class Best(dict):
    """The best (shortest) time of each label over rounds: ``best.time(label, fn, *args)`` times one
    call, keeps the shorter of it and the label's best so far, and returns the call's result."""

    def time(self, label: str, fn: Callable[..., T], *args: Any, **kwargs: Any) -> T:
        seconds, result = timed(fn, *args, **kwargs)
        self[label] = min(self.get(label, math.inf), seconds)
        return result


def rotated(items: Sequence[T], round_: int) -> list[T]:
    """``items`` started at ``round_ % len(items)``: each round runs them in another order, so a
    machine's drift during a round falls on all of them alike."""
    k = round_ % len(items) if items else 0
    return list(items[k:]) + list(items[:k])


def median(values: Iterable[float]) -> float:
    """The median, or NaN for no values."""
    values = list(values)
    return statistics.median(values) if values else float("nan")


def ratio_median(num: Sequence[float], den: Sequence[float]) -> float:
    """Median of per-round ratios ``num[r] / den[r]``: each ratio from runs of the same round."""
    return median(a / b for a, b in zip(num, den))


# ----------------------------------------------------------------------------- checks


class CheckFailed(AssertionError):
    """A benchmark's result is wrong: no time is reported for it."""


def check(condition: object, message: str) -> None:
    """Raise :class:`CheckFailed` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise CheckFailed(message)


def check_equal(actual: object, expected: object, what: str) -> None:
    """``actual == expected`` (counts, names, shapes), else :class:`CheckFailed` naming ``what``."""
    if actual != expected:
        raise CheckFailed(f"{what}: got {actual!r}, expected {expected!r}")


def check_close(actual, expected, what: str, *, atol: float = 0.0, rtol: float = 0.0) -> float:
    """Every ``|actual - expected| <= atol + rtol * |expected|`` (same shapes, NaN equal to NaN),
    else :class:`CheckFailed` naming ``what`` and the worst value. Returns the largest absolute
    difference."""
    a, b = np.asarray(actual), np.asarray(expected)
    if a.shape != b.shape:
        raise CheckFailed(f"{what}: shape {list(a.shape)}, expected {list(b.shape)}")
    if a.size == 0:
        return 0.0
    if a.dtype == bool or b.dtype == bool:
        a, b = a.astype(np.int8), b.astype(np.int8)
    diff = np.abs(a.astype(np.float64) - b.astype(np.float64))
    both_nan = np.isnan(a) & np.isnan(b)
    bad = ~both_nan & ~(diff <= atol + rtol * np.abs(b))
    if bad.any():
        worst = np.unravel_index(np.argmax(np.where(bad, np.nan_to_num(diff, nan=np.inf), -1.0)), a.shape)
        raise CheckFailed(
            f"{what}: {int(bad.sum())} of {a.size} values differ by more than atol {atol:g} + rtol {rtol:g}; "
            f"at {tuple(int(i) for i in worst)}: {a[worst]!r} against {b[worst]!r}"
        )
    return float(np.where(both_nan, 0.0, diff).max())


# ----------------------------------------------------------------------------- machine, process


def log(message: str) -> None:
    """Progress on stderr, so a child's stdout stays its one JSON line."""
    print(message, file=sys.stderr, flush=True)


def peak_rss() -> int:
    """This process's RSS high-water mark in bytes (VmHWM). Not ``ru_maxrss``: on Linux that
    survives exec, so a child would report the (large) parent's peak from before the exec."""
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmHWM:"))


def cpu_name() -> str:
    """The CPU's model name (/proc/cpuinfo), else what ``platform`` knows."""
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            names = [line.split(":", 1)[1].strip() for line in cpuinfo if line.startswith("model name")]
    except OSError:
        names = []
    return names[0] if names else platform.processor() or platform.machine()


def byte_compile(*packages: Path) -> dict[str, int]:
    """Each package's modules (its folder given) compiled to bytecode where it lacks it, as pip leaves an installed
    wheel, so that no child process timed compiles source at its start (an editable checkout under
    PYTHONDONTWRITEBYTECODE compiled ours at every start: 60 ms of each process). Returns how many
    modules of each were compiled now."""
    compiled = {}
    for folder in packages:
        stale = [p for p in folder.rglob("*.py") if not Path(importlib.util.cache_from_source(str(p))).exists()]
        compileall.compile_dir(folder, quiet=1)
        compiled[folder.name] = len(stale)
    return compiled


def memory_gib() -> float:
    """The machine's memory (MemTotal) in GiB."""
    with open("/proc/meminfo") as meminfo:
        return next(int(line.split()[1]) for line in meminfo if line.startswith("MemTotal")) / 2**20


def commit(repo: str | os.PathLike = HERE) -> str:
    """``git describe --always --dirty`` of the checkout holding ``repo``, or "?" without git."""
    try:
        return subprocess.run(
            ["git", "-C", str(repo), "describe", "--always", "--dirty"], capture_output=True, text=True
        ).stdout.strip()
    except OSError:
        return "?"
