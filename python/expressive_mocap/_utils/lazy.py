"""Names of a package that load on first use (PEP 562), so importing it stays cheap: one
mechanism for the package and its subpackages."""

from __future__ import annotations

import importlib
from typing import Any, Callable


def lazy_exports(package: str, names: dict[str, str], namespace: dict[str, Any]) -> tuple[Callable, Callable]:
    """A module's ``(__getattr__, __dir__)`` for ``names`` (name -> its module, relative to
    ``package``): a name is imported when first asked for, then kept in ``namespace`` (the
    module's globals), so later look-ups skip the function."""

    def __getattr__(name: str) -> Any:
        if name in names:
            value = getattr(importlib.import_module(f".{names[name]}", package), name)
            namespace[name] = value
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(names))

    return __getattr__, __dir__


__all__ = ["lazy_exports"]
