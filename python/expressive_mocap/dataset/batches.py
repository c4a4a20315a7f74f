"""Batches of windows for training, without any framework: :class:`WindowReader` reads a set of
windows as one batch (augmented, normalised), :class:`Batches` iterates over an epoch's batches,
shuffled from a seed.

A batch is a dict: each kind read ``float32 [B, T, ...]`` (``contacts`` as 0/1), ``clip`` (clip
indices) ``[B]``, ``start`` (each window's first frame within its clip) ``[B]``, ``valid`` (frames
that are the clip's own, the rest padding) ``[B]``, ``labels`` ``{field: int64 [B]}`` when the
reader has labels, and ``angle``/``speed`` ``[B]`` when it augments. The windows of a batch come
in the order of their rows, so that reading a kind is one gather of nearly sorted rows from its
memory-mapped array (``array[rows]``), whatever the shuffle picked.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from ..errors import ArgumentError
from .augment import UNDEFINED_UNDER_ROTATION, Augment, interpolate, rotate_window_kinds, scale_rates
from .frames import check_window_frame, to_window_frame
from .labels import Labels
from .stats import Normaliser, float_kinds
from .windows import Windows

MAX_BATCH_BYTES = 4 << 30  # of one batch's arrays, float32 (a bound, not a tuning: real batches are MBs)


class WindowReader:
    """Reads windows of ``dataset`` (``kinds``: all by default) as batches: :meth:`read`.

    ``augment``: an :class:`~expressive_mocap.dataset.augment.Augment`; ``normaliser``: a
    :class:`~expressive_mocap.dataset.stats.Normaliser` applied to the kinds it has statistics
    of (after augmentation, before noise); ``labels``: :class:`~expressive_mocap.dataset.labels.Labels`
    of the dataset's clips; ``frame``: ``"stored"`` (as the dataset holds them) or ``"window"``
    (each window in its first frame's heading frame, :mod:`~expressive_mocap.dataset.frames`,
    before the rotation augmentation)."""

    def __init__(
        self,
        dataset,
        windows: Windows,
        kinds: Sequence[str] | None = None,
        augment: Augment | None = None,
        normaliser: Normaliser | None = None,
        labels: Labels | None = None,
        frame: str = "stored",
    ):
        kinds = list(dataset.arrays) if kinds is None else list(kinds)
        if frame not in ("stored", "window"):
            raise ArgumentError(f"argument `frame`: 'stored' or 'window', got {frame!r}")
        if frame == "window":
            check_window_frame(dataset.manifest, dataset.arrays)
        self.frame, self.offsets = frame, dataset.offsets
        self.heading = dataset.arrays.get("heading")
        unknown = [k for k in kinds if k not in dataset.arrays]
        if unknown:
            raise ArgumentError(f"argument `kinds`: {unknown} not in this dataset ({', '.join(dataset.arrays)})")
        if labels is not None and len(labels) != len(dataset):
            raise ArgumentError(f"labels of {len(labels)} clips for a dataset of {len(dataset)}")
        self.arrays = {k: dataset.arrays[k] for k in kinds}
        self.manifest = dataset.manifest
        self.roots = [i for i, p in enumerate(dataset.skeleton["parents"]) if p < 0]
        self.windows, self.augment, self.normaliser, self.labels = windows, augment, normaliser, labels
        undefined = [k for k in UNDEFINED_UNDER_ROTATION if k in kinds]
        if augment is not None and augment.rotate and undefined:  # fail now, not in the first batch
            raise ArgumentError(f"rotation augmentation is not defined for {', '.join(undefined)}")

    def check_batch(self, count: int) -> None:
        """Refuse (ArgumentError) a batch of ``count`` windows over :data:`MAX_BATCH_BYTES` in
        float32: a window far longer than the clips, padded, is a raw MemoryError otherwise."""
        frame = sum(4 * int(np.prod(array.shape[1:], dtype=np.int64)) for array in self.arrays.values())
        size = count * self.windows.length * frame
        if size > MAX_BATCH_BYTES:
            raise ArgumentError(
                f"a batch of {count} windows of {self.windows.length:,} frames takes {size / 2**30:,.1f} GiB, more "
                f"than the {MAX_BATCH_BYTES / 2**30:g} GiB a batch may: a shorter `length` or a smaller `batch_size`"
            )

    def _gather(self, kind: str, array, rows: np.ndarray, frac, speeds: np.ndarray) -> np.ndarray:
        """``array``'s rows ``rows`` (``[B, T]``, or ``[2, B, T]`` mixed at ``frac`` when resampled)."""
        values = array[rows.ravel()].reshape(rows.shape + array.shape[1:])
        if frac is not None:
            values = interpolate(kind, values[0], values[1], frac, self.manifest)
            values = scale_rates(kind, values, speeds)
        return values.astype(np.float32, copy=False)

    def read(self, indices, rng: np.random.Generator | None = None) -> dict:
        """The windows ``indices`` (of ``self.windows``) as one batch, in the order of their rows
        (``batch["window"]`` says which is which); ``rng`` draws the augmentation."""
        w, length = self.windows, self.windows.length
        idx = np.asarray(indices, dtype=np.int64)
        self.check_batch(len(idx))
        idx = idx[np.argsort(w.start[idx], kind="stable")]
        start, end, count = w.start[idx], w.end[idx], len(idx)
        augment = self.augment if self.augment is not None and self.augment.active else None
        speeds, angles = np.ones(count), np.zeros(count)
        if augment is not None:
            if rng is None:
                raise ArgumentError("argument `rng`: augmentation draws from a generator")
            speeds, angles = augment.speeds(rng, count), augment.angles(rng, count)
        steps = np.arange(length)
        remaining = end - start  # frames of the clip from the window's first
        if np.all(speeds == 1.0):
            rows, frac = np.minimum(start[:, None] + steps, end[:, None] - 1), None
            valid = np.minimum(remaining, length)
        else:
            at = steps * speeds[:, None]
            base = np.minimum(np.floor(at).astype(np.int64), (remaining - 1)[:, None])
            frac = np.where(base + 1 <= (remaining - 1)[:, None], at - base, 0.0)
            frac = np.minimum(frac, 1.0)
            after = np.minimum(base + 1, (remaining - 1)[:, None])
            rows = start[:, None] + np.stack([base, after])  # [2, B, T]: each half in row order
            valid = np.minimum(length, (remaining - 1) // speeds + 1).astype(np.int64)
        batch: dict = {}
        try:
            for kind, array in self.arrays.items():
                batch[kind] = self._gather(kind, array, rows, frac, speeds)
        except MemoryError:
            raise ArgumentError(
                f"a batch of {count} windows of {length:,} frames does not fit in memory: a shorter `length` or a "
                "smaller `batch_size`"
            ) from None
        clips = w.clip[idx]
        if self.frame == "window":
            heading = batch.get("heading")
            if heading is None:
                heading = self._gather("heading", self.heading, rows, frac, speeds)
            clip_heading = np.asarray(self.heading[self.offsets[clips]])
            to_window_frame(batch, heading, clip_heading, self.manifest["options"]["positions"])
        if np.any(angles):
            rotate_window_kinds(batch, angles, self.manifest, self.roots)
        if self.normaliser is not None:
            for kind in batch:
                if kind in self.normaliser.mean:
                    batch[kind] = self.normaliser.normalise(kind, batch[kind], out=batch[kind])  # fresh arrays
        for kind in batch:
            sigma = augment.noise_of(kind) if augment is not None and kind != "contacts" else 0.0
            if sigma and rng is not None:
                noise = rng.standard_normal(batch[kind].shape, dtype=np.float32)
                batch[kind] = np.add(batch[kind], np.multiply(noise, sigma, out=noise), out=noise)
        if w.padding == "zero" and np.any(valid < length):
            padded = steps >= valid[:, None]
            for kind in batch:
                batch[kind] = np.where(padded.reshape(padded.shape + (1,) * (batch[kind].ndim - 2)), 0, batch[kind])
        batch.update(window=idx, clip=clips, start=w.offset[idx], valid=valid)
        if self.labels is not None:
            batch["labels"] = {f: c[clips] for f, c in self.labels.codes.items()}
        if augment is not None:
            batch.update(angle=angles, speed=speeds)
        return batch


class Batches:
    """An epoch's batches of ``batch_size`` windows, read by ``reader`` (a :class:`WindowReader`).

    ``batches.epoch(n)``: the batches of epoch ``n``, the windows shuffled (``shuffle=True``) by
    ``seed`` and ``n`` and each batch's augmentation drawn from ``(seed, n, batch number)``: the
    same seed gives the same batches, whatever was read before. ``for batch in batches`` runs the
    next epoch (0, 1, ...). ``drop_last`` leaves out a last smaller batch."""

    def __init__(
        self, reader: WindowReader, batch_size: int = 256, shuffle: bool = True, seed: int = 0, drop_last: bool = False
    ):
        if isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
            raise ArgumentError(f"argument `batch_size`: a positive whole number of windows, got {batch_size!r}")
        reader.check_batch(int(batch_size))
        self.reader, self.batch_size, self.shuffle, self.seed, self.drop_last = (
            reader,
            batch_size,
            shuffle,
            seed,
            drop_last,
        )
        self.next_epoch = 0

    def __len__(self) -> int:
        n = len(self.reader.windows)
        return n // self.batch_size if self.drop_last else -(-n // self.batch_size)

    def epoch(self, number: int) -> Iterator[dict]:
        n = len(self.reader.windows)
        order = np.random.default_rng([self.seed, number]).permutation(n) if self.shuffle else np.arange(n)
        for b in range(len(self)):
            picked = order[b * self.batch_size : (b + 1) * self.batch_size]
            yield self.reader.read(picked, np.random.default_rng([self.seed, number, b, 1]))

    def __iter__(self) -> Iterator[dict]:
        number, self.next_epoch = self.next_epoch, self.next_epoch + 1
        return self.epoch(number)


def window_batches(
    dataset,
    length: int,
    stride: int | None = None,
    batch_size: int = 256,
    kinds: Sequence[str] | None = None,
    clips=None,
    padding: str = "drop",
    augment: Augment | None = None,
    normalise: bool | Normaliser = False,
    labels: Labels | None = None,
    shuffle: bool = True,
    seed: int = 0,
    drop_last: bool = False,
    frame: str = "stored",
) -> Batches:
    """Batches of ``length``-frame windows of ``dataset``'s ``clips`` (indices, e.g. a split's; all
    by default) in one call. ``normalise=True`` uses the dataset's statistics
    (:meth:`Normaliser.of <expressive_mocap.dataset.stats.Normaliser.of>`)."""
    windows = Windows(dataset, length, stride, padding, clips)
    kinds = list(dataset.arrays) if kinds is None else list(kinds)
    floats = [k for k in float_kinds(dataset) if k in kinds]
    normaliser = Normaliser.of(dataset, floats) if normalise is True else normalise
    reader = WindowReader(dataset, windows, kinds, augment, normaliser or None, labels, frame)
    return Batches(reader, batch_size, shuffle, seed, drop_last)


__all__ = ["MAX_BATCH_BYTES", "Batches", "WindowReader", "window_batches"]
