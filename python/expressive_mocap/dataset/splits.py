"""Train / validation / test splits of a dataset's clips, by clip or by any label field.

Clips are split in groups: by clip, each clip with its mirrored copy (``X@mirrored`` always goes
with ``X``); by a label field (``"take"``, ``"style"``, an actor column of a CSV...), every clip
of one value. Each group goes to a split by a hash of ``(seed, group key)`` mapped to [0, 1) and
cut at the cumulative fractions: the same seed gives the same split, and adding clips never moves
a group that was already there (the price: the fractions hold on average, not exactly, which
matters when there are few groups; an explicit ``held_out`` list is exact).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import ArgumentError, DatasetError
from .labels import Labels, base_name

DEFAULT_FRACTIONS = {"train": 0.8, "val": 0.1, "test": 0.1}


def unit_hash(seed: int, key: str) -> float:
    """A number in [0, 1) fixed by ``seed`` and ``key`` alone (BLAKE2b, not Python's salted hash)."""
    digest = hashlib.blake2b(f"{seed}\0{key}".encode(), digest_size=8).digest()
    return int.from_bytes(digest, "big") / 2.0**64


def group_keys(dataset, by: str = "clip", labels: Labels | None = None) -> list[str]:
    """Each clip's group key: its (unmirrored) name for ``by="clip"``, else its ``labels`` value of
    the field ``by``."""
    records = dataset.clips if hasattr(dataset, "clips") else [{"name": str(n)} for n in dataset]
    if by == "clip":
        return [base_name(r["name"], r) for r in records]
    if labels is None:
        raise ArgumentError(f"argument `labels`: splitting by {by!r} needs the clips' labels")
    if by not in labels.values:
        raise ArgumentError(f"argument `by`: no label field {by!r}; the labels have {', '.join(labels.fields)}")
    if len(labels) != len(records):
        raise ArgumentError(f"labels of {len(labels)} clips for a dataset of {len(records)}")
    keys = []
    for record, value in zip(records, labels.values[by]):
        if value is None:
            raise DatasetError(f"clip {record['name']!r} has no {by!r} label to split by")
        keys.append(value)
    return keys


def split(
    dataset,
    by: str = "clip",
    fractions: Mapping[str, float] | Sequence[float] | None = None,
    held_out: Mapping[str, Sequence[str]] | None = None,
    seed: int = 0,
    labels: Labels | None = None,
) -> dict[str, np.ndarray]:
    """``{split name: sorted clip indices}`` of ``dataset`` (a Dataset, or a list of clip names).

    ``fractions``: ``{"train": 0.8, "val": 0.1, "test": 0.1}`` (the default) or a sequence of
    three, summing to 1. ``held_out``: ``{"test": ["elderly"], "val": [...]}`` -- those group keys
    (clip names, or values of the field ``by``) go to those splits and every other group to
    ``"train"``; a key that is no group is an error (a typo would silently hold out nothing)."""
    keys = group_keys(dataset, by, labels)
    if held_out is not None:
        if fractions is not None:
            raise ArgumentError("give `fractions` or `held_out`, not both")
        where: dict[str, str] = {}
        for name, held in held_out.items():
            for key in held:
                if key in where:
                    raise ArgumentError(f"argument `held_out`: {key!r} is in {where[key]!r} and {name!r}")
                where[key] = name
        unknown = sorted(set(where) - set(keys))
        if unknown:
            raise ArgumentError(f"argument `held_out`: {unknown[:5]} are not {by} groups of this dataset")
        assigned = [where.get(k, "train") for k in keys]
        names = ["train", *held_out]
    else:
        cuts = _fractions(fractions)
        names = list(cuts)
        bounds = np.cumsum(list(cuts.values()))
        bounds[-1] = 1.0  # rounding
        cache: dict[str, str] = {}
        for key in keys:
            if key not in cache:
                cache[key] = names[int(np.searchsorted(bounds, unit_hash(seed, key), side="right"))]
        assigned = [cache[k] for k in keys]
    groups = np.array(assigned)
    return {name: np.flatnonzero(groups == name).astype(np.int64) for name in names}


def _fractions(fractions) -> dict[str, float]:
    if fractions is None:
        return dict(DEFAULT_FRACTIONS)
    if not isinstance(fractions, Mapping):
        values = list(fractions)
        if len(values) != 3:
            raise ArgumentError("argument `fractions`: three numbers (train, val, test) or a mapping")
        fractions = dict(zip(("train", "val", "test"), values))
    out = {str(k): float(v) for k, v in fractions.items()}
    if any(v < 0 for v in out.values()) or abs(sum(out.values()) - 1.0) > 1e-6:
        raise ArgumentError(f"argument `fractions`: non-negative and summing to 1, got {out}")
    return out


__all__ = ["DEFAULT_FRACTIONS", "group_keys", "split", "unit_hash"]
