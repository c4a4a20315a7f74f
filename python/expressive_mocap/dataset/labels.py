"""Labels of a dataset's clips: parsed from their names by a pattern, or read from a CSV file,
and turned into integer codes over a stable (sorted) vocabulary.

A pattern spells a clip's name with ``{field}`` placeholders, e.g. :data:`BANDAI` =
``"dataset-{dataset}_{content}_{style}_{take}"`` reads ``dataset-2_walk-left_normal_001`` as
dataset 2, content ``walk-left``, style ``normal``, take ``001``. Every field but the last is one
or more characters other than ``_`` (a ``-`` is fine); the last may be anything. The pattern is
matched against the name's last part (a folder prefix ``a/b/`` is ignored unless the pattern
itself has a ``/``) and a mirrored copy ``X@mirrored`` has the labels of ``X``.
"""

from __future__ import annotations

import csv
import os
import re
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import ArgumentError, DatasetError
from .format import MIRRORED

BANDAI = "dataset-{dataset}_{content}_{style}_{take}"
_FIELD = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)\}")


def base_name(name: str, record: Mapping | None = None) -> str:
    """The name of the clip a mirrored copy was made from (its record's ``mirror_of``, else the
    name without ``@mirrored``); any other clip's own name."""
    if record is not None and isinstance(record.get("mirror_of"), str):
        return record["mirror_of"]
    return name[: -len(MIRRORED)] if name.endswith(MIRRORED) else name


def compile_pattern(pattern: str) -> tuple[re.Pattern, list[str]]:
    """The regular expression of a ``{field}`` pattern and its field names, in order."""
    fields = _FIELD.findall(pattern)
    if not fields:
        raise ArgumentError(f"argument `pattern`: {pattern!r} has no {{field}} placeholder")
    if len(set(fields)) != len(fields):
        raise ArgumentError(f"argument `pattern`: {pattern!r} names a field twice")
    parts, last = [], 0
    for i, match in enumerate(_FIELD.finditer(pattern)):
        parts.append(re.escape(pattern[last : match.start()]))
        value = ".+" if i == len(fields) - 1 else "[^_/]+"
        parts.append(f"(?P<{match.group(1)}>{value})")
        last = match.end()
    parts.append(re.escape(pattern[last:]))
    return re.compile("".join(parts)), fields


class Labels:
    """Labels of clips: ``values[field]`` a list of strings per clip (None for a clip skipped),
    ``codes[field]`` int64 per clip (-1 when skipped), ``vocab[field]`` the sorted values, so a
    value's code is its place there; ``skipped`` the indices of clips without labels.

    ``Labels.from_names(names, pattern)`` or ``Labels.from_csv(path, names)``; ``names`` may be a
    :class:`~expressive_mocap.dataset.Dataset` (its clip records then name mirrored copies).
    ``vocab`` may be given to keep codes fixed across datasets (a value outside it is an error)."""

    def __init__(self, values: Mapping[str, Sequence[str | None]], vocab: Mapping[str, Sequence[str]] | None = None):
        self.values = {f: list(v) for f, v in values.items()}
        sizes = {len(v) for v in self.values.values()}
        if len(sizes) > 1:
            raise ArgumentError("every label field needs one value per clip")
        self.fields = list(self.values)
        self.vocab: dict[str, list[str]] = {}
        self.codes: dict[str, np.ndarray] = {}
        for field, column in self.values.items():
            found = sorted({v for v in column if v is not None})
            words = list(vocab[field]) if vocab is not None and field in vocab else found
            index = {v: i for i, v in enumerate(words)}
            unknown = [v for v in found if v not in index]
            if unknown:
                raise ArgumentError(f"label {field!r}: values {unknown[:5]} are not in the vocabulary given")
            self.vocab[field] = words
            self.codes[field] = np.array([-1 if v is None else index[v] for v in column], dtype=np.int64)
        first = next(iter(self.values.values()), [])
        self.skipped = [i for i, v in enumerate(first) if v is None]

    @classmethod
    def from_names(cls, names, pattern: str = BANDAI, skip: bool = False, vocab=None) -> Labels:
        """Labels parsed from clip names by ``pattern``. A name that does not match is an error
        naming it and the pattern, or (``skip=True``) a clip without labels."""
        regex, fields = compile_pattern(pattern)
        values: dict[str, list[str | None]] = {f: [] for f in fields}
        for name in _base_names(names):
            target = name if "/" in pattern else name.rsplit("/", 1)[-1]
            match = regex.fullmatch(target)
            if match is None and not skip:
                raise DatasetError(f"clip {name!r} does not match the label pattern {pattern!r}")
            for field in fields:
                values[field].append(None if match is None else match.group(field))
        return cls(values, vocab)

    @classmethod
    def from_csv(
        cls, path: str | os.PathLike, names, clip_column: str = "clip", skip: bool = False, vocab=None
    ) -> Labels:
        """Labels from a CSV file with a header: ``clip_column`` names a clip, every other column is
        a label field. A clip missing from the file is an error naming it (or, ``skip=True``, a clip
        without labels); a mirrored copy takes its original's row unless the file has its own."""
        with open(path, newline="", encoding="utf-8") as handle:
            reader = csv.DictReader(handle)
            header = reader.fieldnames or []
            if clip_column not in header:
                raise DatasetError(f"{path}: no column {clip_column!r} (columns: {', '.join(header)})")
            fields = [c for c in header if c != clip_column]
            rows: dict[str, dict] = {}
            for line in reader:
                rows[line[clip_column]] = line
        values: dict[str, list[str | None]] = {f: [] for f in fields}
        for name, base in zip(_names(names), _base_names(names)):
            row: dict | None = rows[name] if name in rows else rows.get(base)
            if row is None and not skip:
                raise DatasetError(f"clip {name!r} has no row in {path} (column {clip_column!r})")
            for field in fields:
                values[field].append(None if row is None else row[field])
        return cls(values, vocab)

    def __len__(self) -> int:
        return len(next(iter(self.values.values()), []))

    def decode(self, field: str, codes) -> list[str]:
        """The values of integer ``codes`` of ``field``."""
        return [self.vocab[field][int(c)] for c in np.ravel(codes)]

    def __repr__(self) -> str:
        sizes = ", ".join(f"{f} ({len(v)})" for f, v in self.vocab.items())
        return f"Labels({len(self)} clips; {sizes})"


def _names(names) -> list[str]:
    return list(names.names) if hasattr(names, "names") and hasattr(names, "clips") else [str(n) for n in names]


def _base_names(names) -> list[str]:
    if hasattr(names, "names") and hasattr(names, "clips"):
        return [base_name(r["name"], r) for r in names.clips]
    return [base_name(str(n)) for n in names]


__all__ = ["BANDAI", "Labels", "base_name", "compile_pattern"]
