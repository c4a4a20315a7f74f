"""Train / validation / test splits of a dataset's clips, by clip or by any label field.

Clips are split in groups: by clip, each clip with its mirrored copy (``X@mirrored`` always goes
with ``X``); by a label field (``"take"``, ``"style"``, an actor column of a CSV...), every clip
of one value. Groups are ordered by a hash of ``(seed, group key)`` (the same seed, the same
order, on any machine) and dealt out in that order by ``method``:

- ``"rank"`` (the default): each split gets its fraction of the groups, rounded (largest
  remainders), and at least one group when its fraction is not 0 and there are enough groups, so
  10 contents split 0.8/0.1/0.1 are 8/1/1. Adding groups moves at most a few at the boundaries.
- ``"hash"``: a group goes where its hash, in [0, 1), falls between the cumulative fractions:
  adding clips never moves a group already there, and the fractions hold on average only (10
  groups may leave a split empty).

An explicit ``held_out`` list names the groups of each split instead.
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
    method: str = "rank",
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
        hashes = {key: unit_hash(seed, key) for key in keys}
        if method == "hash":
            bounds = np.cumsum(list(cuts.values()))
            bounds[-1] = 1.0  # rounding
            where = {key: names[int(np.searchsorted(bounds, h, side="right"))] for key, h in hashes.items()}
        elif method == "rank":
            order = sorted(hashes, key=lambda key: (hashes[key], key))
            counts = group_counts(len(order), list(cuts.values()))
            where = dict(zip(order, np.repeat(names, counts)))
        else:
            raise ArgumentError(f"argument `method`: 'rank' or 'hash', got {method!r}")
        assigned = [str(where[k]) for k in keys]
    groups = np.array(assigned)
    return {name: np.flatnonzero(groups == name).astype(np.int64) for name in names}


def group_counts(groups: int, fractions: Sequence[float]) -> np.ndarray:
    """How many of ``groups`` each split gets: its fraction rounded by largest remainders, then
    one taken from the largest split for each empty split whose fraction is not 0 (while groups
    last)."""
    share = np.asarray(fractions, dtype=np.float64) * groups
    counts = np.floor(share).astype(np.int64)
    for i in np.argsort(-(share - counts), kind="stable")[: groups - int(counts.sum())]:
        counts[i] += 1
    for i in np.flatnonzero((counts == 0) & (share > 0)):
        donor = int(np.argmax(counts))
        if counts[donor] > 1:
            counts[donor] -= 1
            counts[i] += 1
    return counts


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


__all__ = ["DEFAULT_FRACTIONS", "group_counts", "group_keys", "split", "unit_hash"]
