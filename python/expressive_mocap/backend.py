"""Choosing between the Rust kernels and their NumPy twins.

One setting picks the implementation of every kernel: the environment variable
``EXPRESSIVE_MOCAP_BACKEND`` (``rust``, ``numpy`` or ``auto``, read at import) or
:func:`set_backend` / :func:`use_backend` from Python. ``auto`` (the default) uses Rust when the
compiled extension is importable and NumPy otherwise, so the package works without it.
"""

from __future__ import annotations

import atexit
import contextlib
import functools
import os
import threading
from collections.abc import Iterator
from types import ModuleType
from typing import Any, cast

from .errors import MocapError

_core: ModuleType | None
try:
    from . import _core
except ImportError:  # the extension was not built: NumPy twins only
    _core = None

ENV_VAR = "EXPRESSIVE_MOCAP_BACKEND"
BACKENDS = ("auto", "rust", "numpy")


def _checked(name: str, source: str = "set_backend") -> str:
    name = name.strip().lower()
    if name not in BACKENDS:
        raise MocapError(f"backend must be one of {', '.join(BACKENDS)}, got {name!r} (from {source})")
    return name


# The environment's choice, checked when a kernel is first needed rather than at import: a bad
# value is then an error of the command that uses it, not a traceback of `import expressive_mocap`.
_selected = os.environ.get(ENV_VAR, "auto") or "auto"


def rust_available() -> bool:
    """True when the compiled Rust extension is importable."""
    return _core is not None


def set_backend(name: str) -> None:
    """Use ``"rust"``, ``"numpy"`` or ``"auto"`` kernels from now on."""
    global _selected
    _selected = _checked(name)
    kernels()  # fail now, not at the first call, if Rust was asked for and is missing


def get_backend() -> str:
    """The backend in use: ``"rust"`` or ``"numpy"``."""
    return "rust" if kernels() is _counted else "numpy"


@contextlib.contextmanager
def use_backend(name: str) -> Iterator[None]:
    """Run a block with the given backend, then restore the previous choice."""
    global _selected
    previous = _selected
    set_backend(name)
    try:
        yield
    finally:
        _selected = previous


def kernels() -> ModuleType:
    """The module whose functions implement the kernels under the current choice."""
    global _selected
    if _selected not in BACKENDS:
        _selected = _checked(_selected, f"the environment variable {ENV_VAR}")
    if _selected == "numpy" or (_selected == "auto" and _core is None):
        from . import reference  # here: the NumPy twins load only when they are used

        return reference
    if _core is None:
        raise MocapError(
            f"the Rust backend was requested ({ENV_VAR}={_selected}) but the compiled extension "
            "expressive_mocap._core is not installed; reinstall with `pip install .` or use 'numpy'"
        )
    return cast(ModuleType, _counted)


class _InRust:
    """The Rust extension's functions, each call counted while it runs: the interpreter's exit
    waits until none is (:func:`_wait_at_exit`). A daemon thread (the preprocess pipeline's, a
    user's) still in a kernel when Python finalises would come back to a dying interpreter, which
    ends it with a forced unwind through Rust frames: the process aborted with "FATAL: exception
    not rethrown" (exit 134), now and then, after ``preprocess --max-batches``."""

    def __init__(self, module: ModuleType):
        self._module = module
        self._running = 0
        self._idle = threading.Condition()

    def __getattr__(self, name: str) -> Any:
        value = getattr(self._module, name)
        if not callable(value) or isinstance(value, type):
            return value

        @functools.wraps(value)
        def counted(*args, **kwargs):
            with self._idle:
                self._running += 1
            try:
                return value(*args, **kwargs)
            finally:
                with self._idle:
                    self._running -= 1
                    self._idle.notify_all()

        setattr(self, name, counted)  # wrapped once
        return counted

    def wait_idle(self, timeout: float) -> bool:
        """Wait until no call is under way (at most ``timeout`` seconds); whether none is."""
        with self._idle:
            return self._idle.wait_for(lambda: self._running == 0, timeout)


# Seconds the interpreter's exit waits for kernel calls under way (a batch's: 0.1-3 s); bounded,
# so that a call that never ends cannot keep the process alive.
EXIT_WAIT = 30.0

_counted = _InRust(_core) if _core is not None else None


@atexit.register
def _wait_at_exit() -> None:
    if _counted is not None:
        _counted.wait_idle(EXIT_WAIT)


__all__ = [
    "BACKENDS",
    "ENV_VAR",
    "get_backend",
    "kernels",
    "rust_available",
    "set_backend",
    "use_backend",
]
