"""Train / validation / test splits of a dataset's clips, by performance, by clip or by any label
field.

Clips are split in groups, and a mirrored copy ``X@mirrored`` always goes with ``X``:

- ``"performance"`` (the default): the repetitions of one performance together. A Bandai clip
  ``dataset-{dataset}_{content}_{style}_{take}`` is one take of a performance (same actor,
  content and style); its takes are near copies of each other, so that a split by clip or by
  take puts the same performance in train and test and measures memory, not generalisation.
  With ``labels=`` a performance is the clips whose labels agree on every field but ``take``.
  When no labels are given and some clip names are not Bandai names, those clips are groups of
  their own, with a warning (pass ``by="clip"`` to say that is meant).
- ``"clip"``: each clip alone (with its mirrored copy).
- a label field (``"content"``, ``"style"``, ``"take"``, an actor column of a CSV...): every clip
  of one value; the labels are parsed from Bandai names when ``labels=`` is not given.

Groups are ordered by a hash of ``(seed, group key)`` (the same seed, the same
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
import warnings
from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import ArgumentError, DatasetError
from .format import MIRRORED
from .labels import BANDAI, Labels, base_name, compile_pattern

DEFAULT_FRACTIONS = {"train": 0.8, "val": 0.1, "test": 0.1}
PERFORMANCE = "performance"
REPEAT_FIELD = "take"  # the field that tells the repetitions of one performance apart


def unit_hash(seed: int, key: str) -> float:
    """A number in [0, 1) fixed by ``seed`` and ``key`` alone (BLAKE2b, not Python's salted hash)."""
    digest = hashlib.blake2b(f"{seed}\0{key}".encode(), digest_size=8).digest()
    return int.from_bytes(digest, "big") / 2.0**64


def group_keys(dataset, by: str = PERFORMANCE, labels: Labels | None = None) -> list[str]:
    """Each clip's group key: its (unmirrored) name for ``by="clip"``; for ``"performance"`` its
    labels but the take, joined by ``_`` (``"2_walk_normal"``); else its ``labels`` value of the
    field ``by`` (labels parsed from Bandai names when not given)."""
    records = _records(dataset)
    if by == "clip":
        return [base_name(r["name"], r) for r in records]
    if by == PERFORMANCE and labels is None:
        return _performances(records)
    if labels is None:
        if by not in compile_pattern(BANDAI)[1]:
            raise ArgumentError(f"argument `labels`: splitting by {by!r} needs the clips' labels")
        labels = _bandai_labels(records, by)
    if len(labels) != len(records):
        raise ArgumentError(f"labels of {len(labels)} clips for a dataset of {len(records)}")
    if by == PERFORMANCE:
        if REPEAT_FIELD not in labels.values:
            raise ArgumentError(
                f"argument `by`: a performance is the clips whose labels agree on all but {REPEAT_FIELD!r}, and "
                f"these labels have no such field ({', '.join(labels.fields)}): by one of them, or by='clip'"
            )
        fields = [f for f in labels.fields if f != REPEAT_FIELD]
        columns = [labels.values[f] for f in fields]
        keys = []
        for i, record in enumerate(records):
            values = [column[i] for column in columns]
            if any(v is None for v in values):
                raise DatasetError(f"clip {record['name']!r} has no labels to find its performance")
            keys.append("_".join(str(v) for v in values))
        return keys
    if by not in labels.values:
        raise ArgumentError(f"argument `by`: no label field {by!r}; the labels have {', '.join(labels.fields)}")
    keys = []
    for record, value in zip(records, labels.values[by]):
        if value is None:
            raise DatasetError(f"clip {record['name']!r} has no {by!r} label to split by")
        keys.append(value)
    return keys


def _records(dataset) -> list:
    return dataset.clips if hasattr(dataset, "clips") else [{"name": str(n)} for n in dataset]


def _bandai_labels(records, by: str) -> Labels:
    try:
        return Labels.from_names([base_name(r["name"], r) for r in records])
    except DatasetError as error:
        raise DatasetError(f"{error}: splitting by {by!r} without `labels=` reads them from Bandai names") from None


def _performances(records) -> list[str]:
    """Performance keys from Bandai names (the name without its take); a clip whose name is not
    one keeps its own name, with a warning."""
    regex, _ = compile_pattern(BANDAI)
    keys, odd = [], []
    for record in records:
        name = base_name(record["name"], record)
        match = regex.fullmatch(name.rsplit("/", 1)[-1])
        if match is None:
            odd.append(name)
            keys.append(name)
        else:
            keys.append("_".join(match.group(f) for f in ("dataset", "content", "style")))
    if odd:
        warnings.warn(
            f"split: {len(odd)} of {len(records)} clip names (e.g. {odd[0]!r}) are not Bandai names {BANDAI!r}, so "
            "their repetitions cannot be found: each is a group of its own. Pass by='clip' if clips are "
            "independent, or labels= with a 'take' field (by='performance') or by=<a label field>",
            stacklevel=3,
        )
    return keys


def split(
    dataset,
    by: str = PERFORMANCE,
    fractions: Mapping[str, float] | Sequence[float] | None = None,
    held_out: Mapping[str, Sequence[str]] | None = None,
    seed: int = 0,
    labels: Labels | None = None,
    method: str = "rank",
    mirrored: bool = True,
) -> dict[str, np.ndarray]:
    """``{split name: sorted clip indices}`` of ``dataset`` (a Dataset, or a list of clip names),
    grouped ``by`` ``"performance"`` (the default: every take of one dataset, content and style
    together), ``"clip"`` or a label field (``"content"``: unseen actions; ``"style"``).

    ``fractions``: ``{"train": 0.8, "val": 0.1, "test": 0.1}`` (the default) or a sequence of
    three, summing to 1. ``held_out``: ``{"test": ["elderly"], "val": [...]}`` -- those group keys
    (clip names, or values of the field ``by``) go to those splits and every other group to
    ``"train"``; a key that is no group is an error (a typo would silently hold out nothing).
    ``mirrored=False`` leaves the mirrored copies out of every split (for a
    :class:`~expressive_mocap.dataset.transforms.Mirror` augmentation, which reads them)."""
    if not isinstance(by, str):
        raise ArgumentError(f"argument `by`: 'performance', 'clip' or a label field, got {by!r}")
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
    if not mirrored:
        copies = [_is_copy(r) for r in _records(dataset)]
        groups[np.array(copies, dtype=bool)] = ""
    return {name: np.flatnonzero(groups == name).astype(np.int64) for name in names}


def _is_copy(record) -> bool:
    return isinstance(record.get("mirror_of"), str) or str(record["name"]).endswith(MIRRORED)


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


__all__ = ["DEFAULT_FRACTIONS", "PERFORMANCE", "group_counts", "group_keys", "split", "unit_hash"]
