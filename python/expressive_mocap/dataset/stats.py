"""Normalisation statistics of a dataset's float kinds: per channel mean and std over all rows.

Written: gathered while a run's batches are written, per kind the row count and the float64 sums
of the rows and of their squares (each clip's summed in the kernel thread, row after row,
:func:`.derive.totals`, then added clip by clip in the dataset's order: the same whatever the
batches, bit for bit),
carried from batch to batch in the journal (so a resumed run goes on from them), turned into
``manifest["stats"][kind] = {"mean", "std", "frames"}`` at the end (:func:`statistics`: nested
lists shaped like one row, the population std). Sums of squares lose precision when a channel's
mean is far larger than its spread; in float64 that costs about ``1e-16 * (mean / std)^2`` of the
std: ``1e-10`` for world positions a kilometre from the origin moving by a metre.

Read: :meth:`Normaliser.of` takes them from the manifest, or computes the same from the data for
a dataset that has none (:func:`compute_stats`: float64, streaming over rows in chunks, Chan's
parallel merge of per-chunk means and squared deviations, so neither memory nor precision
depends on the dataset's size).

Channels whose std is under :data:`MIN_STD`, or under :data:`MIN_RELATIVE_STD` of their root mean
square, get 1.0, so that dividing by it is always safe (and a constant channel reads the same
whatever the batches: its sums of squares carry rounding of that order).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from ..errors import ArgumentError

MIN_STD = 1e-8  # a channel whose std is below this is recorded with std 1.0 (dividing stays safe)
# ... or below this share of its root mean square: float32 values vary that little by rounding
# only, and the float64 sums of squares a std comes from are not that precise either (a constant
# channel read 0 or 1e-8 depending on how its clips were batched).
MIN_RELATIVE_STD = 1e-5
CHUNK_ROWS = 65536


def merged(total: dict, increments: list) -> dict:
    """``total`` (kind -> ``[rows, sums, squares]``, as JSON lists or arrays) with ``increments``
    (``(kind, (rows, sums, squares))`` of each clip, in the dataset's order) added one by one: the
    same float64 additions in the same order whatever the batches, so the same sums bit for bit."""
    out = {
        kind: [n, np.asarray(s1, dtype=np.float64), np.asarray(s2, dtype=np.float64)]
        for kind, (n, s1, s2) in total.items()
    }
    for kind, (n, s1, s2) in increments:
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
        std = _safe(np.sqrt(np.maximum(s2 / max(n, 1) - mean * mean, 0.0)), mean)
        out[kind] = {"mean": mean.tolist(), "std": std.tolist(), "frames": int(n)}
    return out


def _safe(std: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """``std`` with 1.0 for the channels that do not vary (:data:`MIN_STD`, :data:`MIN_RELATIVE_STD`)."""
    rms = np.sqrt(mean * mean + std * std)
    return np.where(std < np.maximum(MIN_STD, MIN_RELATIVE_STD * rms), 1.0, std)


def float_kinds(dataset) -> list[str]:
    """The kinds of ``dataset`` stored as floating point (those statistics are for)."""
    return [k for k, a in dataset.arrays.items() if np.issubdtype(a.dtype, np.floating)]


def compute_stats(dataset, kinds: Iterable[str] | None = None, chunk_rows: int = CHUNK_ROWS) -> dict:
    """``{kind: {"mean", "std", "frames"}}`` (the manifest's format) computed from ``dataset``'s
    arrays over all rows, in float64, ``chunk_rows`` rows at a time."""
    if chunk_rows < 1:
        raise ArgumentError(f"argument `chunk_rows`: expected a positive count, got {chunk_rows}")
    stats = {}
    for kind in float_kinds(dataset) if kinds is None else kinds:
        array = dataset.arrays[kind]
        n, mean, m2 = 0, np.zeros(array.shape[1:]), np.zeros(array.shape[1:])
        for start in range(0, len(array), chunk_rows):
            chunk = np.asarray(array[start : start + chunk_rows], dtype=np.float64)
            k = len(chunk)
            chunk_mean = chunk.mean(axis=0)
            chunk_m2 = ((chunk - chunk_mean) ** 2).sum(axis=0)
            delta = chunk_mean - mean
            total = n + k
            mean = mean + delta * (k / total)
            m2 = m2 + chunk_m2 + delta**2 * (n * k / total)
            n = total
        std = _safe(np.sqrt(m2 / n), mean) if n else np.ones_like(mean)
        stats[kind] = {"mean": mean.tolist(), "std": std.tolist(), "frames": n}
    return stats


_FLOAT32_MAX = float(np.finfo(np.float32).max)  # normalised batches are float32


def _check_finite(kind: str, name: str, values: np.ndarray, good: np.ndarray) -> None:
    """An ArgumentError naming the first channel of ``values`` that is not ``good``: a std of inf
    normalised every value to 0, and one of 1e-300 to inf."""
    if not np.all(good):
        channel = tuple(int(i) for i in np.argwhere(~good)[0])
        where = f" of channel {channel}" if channel else ""
        bounds = f"at least {MIN_STD:g} and " if name == "std" else ""
        raise ArgumentError(
            f"stats of {kind!r}: {name}{where} is {values[~good].flat[0]!r}; expected {bounds}at most "
            f"{_FLOAT32_MAX:.3g} in magnitude (statistics edited by hand?)"
        )


class Normaliser:
    """``(x - mean) / std`` per channel of each kind, and back.

    ``Normaliser(stats)`` from ``{kind: {"mean", "std", ...}}``; ``Normaliser.of(dataset)`` from
    its manifest's statistics, computed from its arrays when the manifest has none. Arrays of a
    kind may carry any leading axes (``[T, ...]``, ``[B, T, ...]``): the statistics broadcast
    over them. Results are float32 (float64 in, float64 out)."""

    def __init__(self, stats: Mapping[str, Mapping]):
        self.mean: dict[str, np.ndarray] = {}
        self.std: dict[str, np.ndarray] = {}
        self.frames: dict[str, int] = {}
        for kind, entry in stats.items():
            mean, std = np.asarray(entry["mean"], dtype=np.float64), np.asarray(entry["std"], dtype=np.float64)
            if mean.shape != std.shape:
                raise ArgumentError(f"stats of {kind!r}: mean {list(mean.shape)} and std {list(std.shape)} differ")
            _check_finite(kind, "mean", mean, np.abs(mean) <= _FLOAT32_MAX)
            _check_finite(kind, "std", std, (std >= MIN_STD) & (std <= _FLOAT32_MAX))
            self.mean[kind], self.std[kind] = mean, std
            self.frames[kind] = int(entry.get("frames", 0))
        self._cache: dict[tuple[str, np.dtype], tuple[np.ndarray, np.ndarray]] = {}

    @classmethod
    def of(cls, dataset, kinds: Iterable[str] | None = None, chunk_rows: int = CHUNK_ROWS) -> Normaliser:
        """The statistics of ``dataset`` (``kinds``: its float kinds by default): the manifest's
        where it has them, computed from the arrays for the kinds it lacks."""
        wanted = float_kinds(dataset) if kinds is None else list(kinds)
        recorded = dataset.manifest.get("stats") or {}
        missing = [k for k in wanted if k not in recorded]
        computed = compute_stats(dataset, missing, chunk_rows) if missing else {}
        return cls({k: recorded[k] if k in recorded else computed[k] for k in wanted})

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(self.mean)

    def to_dict(self) -> dict:
        """The statistics in the manifest's format."""
        return {
            k: {"mean": self.mean[k].tolist(), "std": self.std[k].tolist(), "frames": self.frames[k]} for k in self.mean
        }

    def _stats(self, kind: str, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if kind not in self.mean:
            raise KeyError(f"no statistics of {kind!r}; this normaliser has {', '.join(self.mean) or 'none'}")
        dtype = np.dtype(np.float64 if values.dtype == np.float64 else np.float32)
        key = (kind, dtype)
        if key not in self._cache:
            self._cache[key] = (self.mean[kind].astype(dtype), self.std[kind].astype(dtype))
        mean, std = self._cache[key]
        if values.shape[values.ndim - mean.ndim :] != mean.shape:
            raise ArgumentError(f"{kind}: rows of shape {list(mean.shape)} expected, got {list(values.shape)}")
        return mean, std

    def normalise(self, kind: str, values, out: np.ndarray | None = None) -> np.ndarray:
        """``(values - mean) / std`` of ``kind`` (into ``out``, which may be ``values``)."""
        values = np.asarray(values)
        mean, std = self._stats(kind, values)
        if out is None:
            return (values - mean) / std
        np.subtract(values, mean, out=out)
        return np.divide(out, std, out=out)

    def denormalise(self, kind: str, values) -> np.ndarray:
        """``values * std + mean`` of ``kind``: the inverse of :meth:`normalise`."""
        values = np.asarray(values)
        mean, std = self._stats(kind, values)
        return values * std + mean

    def __getstate__(self) -> dict:
        return {"stats": self.to_dict()}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["stats"])  # type: ignore[misc]

    def __repr__(self) -> str:
        return f"Normaliser({', '.join(self.mean)})"


__all__ = [
    "MIN_RELATIVE_STD",
    "MIN_STD",
    "Normaliser",
    "as_json",
    "compute_stats",
    "float_kinds",
    "merged",
    "statistics",
]
