"""Typed records of the JSON objects a model file holds (a body model's settings and training
report): frozen dataclasses read with :func:`read_record` and written back with
:func:`record_json`, so that a file loaded and saved again holds the same JSON.

A record's fields are each an ``int``, ``float``, ``str``, ``bool`` or another record, all
optional: None where the file has no such entry (a file of an older version), and then not
written. Fields are written in the order the dataclass declares them, the order training writes
them in; entries this version does not know are kept in the record's ``extra`` (its last field)
and written back after the known ones."""

from __future__ import annotations

import sys
from dataclasses import Field, fields, is_dataclass
from typing import Any, TypeVar, cast

from ..errors import ModelError

R = TypeVar("R")

# JSON values each annotation accepts (a float may be written as an integer; true is no number),
# and how a message names them.
_SCALARS: dict[str, tuple[type, ...]] = {"int": (int,), "float": (int, float), "str": (str,), "bool": (bool,)}
_NAMES = {"int": "an integer", "float": "a number", "str": "text", "bool": "true or false"}


def _kind(cls: type, f: Field) -> str:
    """The annotation of ``f`` without ``| None``: a scalar's name or a record class's."""
    kinds = [part.strip() for part in str(f.type).split("|") if part.strip() != "None"]
    if len(kinds) != 1:
        raise TypeError(f"{cls.__name__}.{f.name}: a record field is one kind or None, not {f.type}")
    return kinds[0]


def _typed(cls: type, f: Field, value: Any, where: str) -> Any:
    if value is None:
        return None
    kind = _kind(cls, f)
    if kind in _SCALARS:
        accepted = _SCALARS[kind]
        if not isinstance(value, accepted) or (isinstance(value, bool) and bool not in accepted):
            raise ModelError(f"{where} must be {_NAMES[kind]}, got {value!r}")
        return value  # as written (an integer stays one), so it is written back alike
    return read_record(getattr(sys.modules[cls.__module__], kind), value, where)


def read_record(cls: type[R], value: Any, where: str) -> R:
    """``value`` (a JSON object) as a record of the dataclass ``cls``: missing entries None, unknown
    ones in ``extra``; a :class:`ModelError` naming the entry (``where``: the object's place, as
    ``"model.npz: report"``) when one is of the wrong kind."""
    if not isinstance(value, dict):
        raise ModelError(f"{where} must be a JSON object, got {type(value).__name__}")
    known = {f.name: f for f in fields(cls) if f.name != "extra"}  # type: ignore[arg-type]
    typed = {k: _typed(cls, known[k], v, f"{where}.{k}") for k, v in value.items() if k in known}
    return cast(Any, cls)(**typed, extra={k: v for k, v in value.items() if k not in known})


def record_json(record: Any) -> dict[str, Any]:
    """The JSON object of a record :func:`read_record` reads back: its fields that are not None,
    in their order, records as objects, then its ``extra`` entries."""
    out: dict[str, Any] = {}
    for f in fields(record):
        value = getattr(record, f.name)
        if f.name != "extra" and value is not None:
            out[f.name] = record_json(value) if is_dataclass(value) else value
    out.update(record.extra)
    return out


__all__ = ["read_record", "record_json"]
