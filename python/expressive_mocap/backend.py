"""Choosing between the Rust kernels and their NumPy twins.

One setting picks the implementation of every kernel: the environment variable
``EXPRESSIVE_MOCAP_BACKEND`` (``rust``, ``numpy`` or ``auto``, read at import) or
:func:`set_backend` / :func:`use_backend` from Python. ``auto`` (the default) uses Rust when the
compiled extension is importable and NumPy otherwise, so the package works without it.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from types import ModuleType

from . import reference
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
    return "rust" if kernels() is _core else "numpy"


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
        return reference
    if _core is None:
        raise MocapError(
            f"the Rust backend was requested ({ENV_VAR}={_selected}) but the compiled extension "
            "expressive_mocap._core is not installed; reinstall with `pip install .` or use 'numpy'"
        )
    return _core


__all__ = [
    "BACKENDS",
    "ENV_VAR",
    "get_backend",
    "kernels",
    "rust_available",
    "set_backend",
    "use_backend",
]
