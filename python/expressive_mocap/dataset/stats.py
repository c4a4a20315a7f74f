"""Normalisation statistics of a dataset's float kinds, gathered while its batches are written:
per kind the row count and the float64 sums of the rows and of their squares (each clip's
summed in the kernel thread, :func:`.derive.sums`), carried from batch to batch in the journal
(so a resumed run goes on from them), turned into a mean and a population std at the end.

Sums of squares lose precision when a channel's mean is far larger than its spread; in float64
that costs about ``1e-16 * (mean / std)^2`` of the std: ``1e-10`` for world positions a
kilometre from the origin moving by a metre. Channels whose std is under :data:`MIN_STD` get
1.0, so that dividing by it is always safe.
"""

from __future__ import annotations

import numpy as np

MIN_STD = 1e-8


def merged(total: dict, batch: dict) -> dict:
    """``total`` (kind -> ``[rows, sums, squares]``, as JSON lists or arrays) with a batch's added."""
    out = {kind: [n, np.asarray(s1), np.asarray(s2)] for kind, (n, s1, s2) in total.items()}
    for kind, (n, s1, s2) in batch.items():
        if kind in out:
            out[kind] = [out[kind][0] + n, out[kind][1] + s1, out[kind][2] + s2]
        else:
            out[kind] = [n, np.asarray(s1, dtype=np.float64), np.asarray(s2, dtype=np.float64)]
    return out


def as_json(total: dict) -> dict:
    """The running sums as JSON values (floats round-trip exactly)."""
    return {kind: [int(n), np.asarray(s1).tolist(), np.asarray(s2).tolist()] for kind, (n, s1, s2) in total.items()}


def statistics(total: dict) -> dict:
    """``{kind: {"mean", "std", "frames"}}`` (nested lists shaped like one row) of the running sums."""
    out = {}
    for kind, (n, s1, s2) in total.items():
        s1, s2 = np.asarray(s1, dtype=np.float64), np.asarray(s2, dtype=np.float64)
        mean = s1 / max(n, 1)
        std = np.sqrt(np.maximum(s2 / max(n, 1) - mean * mean, 0.0))
        std = np.where(std < MIN_STD, 1.0, std)
        out[kind] = {"mean": mean.tolist(), "std": std.tolist(), "frames": int(n)}
    return out


__all__ = ["MIN_STD", "as_json", "merged", "statistics"]
