"""Batches of windows for training, without any framework: :class:`WindowReader` reads a set of
windows as one batch (augmented, normalised), :class:`Batches` iterates over an epoch's batches,
shuffled from a seed.

A batch is a dict: each kind read ``float32 [B, T, ...]`` (``contacts`` as 0/1), ``clip`` (clip
indices) ``[B]``, ``start`` (each window's first frame within its clip) ``[B]``, ``valid`` (frames
that are the clip's own, the rest padding) ``[B]``, ``labels`` ``{field: int64 [B]}`` when the
reader has labels, and when it augments what was drawn: ``angle``, ``speed``, ``mirrored``,
``noised`` ``[B]`` and ``dropped`` ``[B, J]``. The windows of a batch come
in the order of their rows, so that reading a kind is one gather of nearly sorted rows from its
memory-mapped array (``array[rows]``), whatever the shuffle picked.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from ..errors import ArgumentError, DatasetError
from .augment import (
    UNDEFINED_UNDER_ROTATION,
    Augment,
    add_noise,
    as_compose,
    drop_joints,
    interpolate,
    rotate_some,
    scale_rates,
)
from .format import MIRRORED
from .frames import check_window_frame, to_window_frame
from .labels import Labels
from .stats import Normaliser, float_kinds
from .transforms import Compose, Transform
from .windows import Windows

MAX_BATCH_BYTES = 4 << 30  # of one batch's arrays, float32 (a bound, not a tuning: real batches are MBs)


class WindowReader:
    """Reads windows of ``dataset`` (``kinds``: all by default) as batches: :meth:`read`.

    ``augment``: a :class:`~expressive_mocap.dataset.transforms.Compose` of transforms (or a list
    of them, one transform, or an :class:`~expressive_mocap.dataset.augment.Augment`), drawn per
    window from ``(seed, epoch, window index)``; ``normaliser``: a
    :class:`~expressive_mocap.dataset.stats.Normaliser` applied to the kinds it has statistics
    of (after augmentation, before noise); ``labels``: :class:`~expressive_mocap.dataset.labels.Labels`
    of the dataset's clips; ``frame``: ``"stored"`` (as the dataset holds them) or ``"window"``
    (each window in its first frame's heading frame, :mod:`~expressive_mocap.dataset.frames`,
    before the rotation augmentation); ``seed``: of the draws, when :meth:`read` is given none."""

    def __init__(
        self,
        dataset,
        windows: Windows,
        kinds: Sequence[str] | None = None,
        augment: Augment | Compose | Transform | Sequence[Transform] | None = None,
        normaliser: Normaliser | None = None,
        labels: Labels | None = None,
        frame: str = "stored",
        seed: int = 0,
    ):
        kinds = list(dataset.arrays) if kinds is None else list(kinds)
        if frame not in ("stored", "window"):
            raise ArgumentError(f"argument `frame`: 'stored' or 'window', got {frame!r}")
        if frame == "window":
            check_window_frame(dataset.manifest, dataset.arrays)
        self.frame, self.offsets, self.seed = frame, dataset.offsets, _seed(seed)
        self.heading = dataset.arrays.get("heading")
        unknown = [k for k in kinds if k not in dataset.arrays]
        if unknown:
            raise ArgumentError(f"argument `kinds`: {unknown} not in this dataset ({', '.join(dataset.arrays)})")
        if labels is not None and len(labels) != len(dataset):
            raise ArgumentError(f"labels of {len(labels)} clips for a dataset of {len(dataset)}")
        self.arrays = {k: dataset.arrays[k] for k in kinds}
        self.manifest = dataset.manifest
        self.roots = [i for i, p in enumerate(dataset.skeleton["parents"]) if p < 0]
        self.windows, self.normaliser, self.labels = windows, normaliser, labels
        self.augment = as_compose(augment)
        undefined = [k for k in UNDEFINED_UNDER_ROTATION if k in kinds]
        if self.augment is not None and self.augment.rotates and undefined:  # fail now, not in the first batch
            raise ArgumentError(f"rotation augmentation is not defined for {', '.join(undefined)}")
        names = list(dataset.skeleton["names"])
        dropout = self.augment.dropout if self.augment is not None else None
        self.droppable = dropout.droppable(names) if dropout is not None else np.zeros(len(names), dtype=bool)
        self.partner = mirror_partners(dataset, windows) if self.augment is not None and self.augment.mirrors else None

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
        """``array``'s rows ``rows`` (``[B, T]``, or ``[2, B, T]`` mixed at ``frac`` when resampled;
        windows at speed 1 then as read)."""
        values = array[rows.ravel()].reshape(rows.shape + array.shape[1:])
        if frac is not None:
            mixed = interpolate(kind, values[0], values[1], frac, self.manifest)
            mixed = scale_rates(kind, mixed, speeds)
            same = speeds == 1.0
            if same.any():
                mixed[same] = values[0][same]
            values = mixed
        return values.astype(np.float32, copy=False)

    def read(self, indices, epoch: int = 0, seed: int | None = None) -> dict:
        """The windows ``indices`` (of ``self.windows``) as one batch, in the order of their rows
        (``batch["window"]`` says which is which), augmented with the draws of ``(seed, epoch,
        window index)`` (``seed``: the reader's by default)."""
        if isinstance(epoch, bool) or not isinstance(epoch, (int, np.integer)):
            raise ArgumentError(
                f"argument `epoch`: a whole number (draws come from the seed, the epoch and each window's index), "
                f"got {type(epoch).__name__}"
            )
        w, length = self.windows, self.windows.length
        idx = np.asarray(indices, dtype=np.int64)
        self.check_batch(len(idx))
        augment = self.augment
        draws = None
        clips, offset = w.clip[idx], w.offset[idx]
        if augment is not None:
            draws = augment.draw(self.seed if seed is None else _seed(seed), int(epoch), idx, self.droppable)
            if self.partner is not None and draws.mirrored.any():
                clips = np.where(draws.mirrored, self.partner[clips], clips)
        start = self.offsets[clips] + offset
        order = np.argsort(start, kind="stable")
        idx, clips, offset, start = idx[order], clips[order], offset[order], start[order]
        end, count = self.offsets[clips + 1], len(idx)
        speeds = np.ones(count)
        if draws is not None:
            draws = draws.take(order)
            speeds = draws.speed
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
        if self.frame == "window":
            heading = batch.get("heading")
            if heading is None:
                heading = self._gather("heading", self.heading, rows, frac, speeds)
            clip_heading = np.asarray(self.heading[self.offsets[clips]])
            to_window_frame(batch, heading, clip_heading, self.manifest["options"]["positions"])
        if draws is not None:
            rotate_some(batch, draws.angle, self.manifest, self.roots)
        if self.normaliser is not None:
            for kind in batch:
                if kind in self.normaliser.mean:
                    batch[kind] = self.normaliser.normalise(kind, batch[kind], out=batch[kind])  # fresh arrays
        if draws is not None and augment is not None:
            if augment.noise is not None:
                add_noise(batch, draws, augment.noise)
            drop_joints(batch, draws.dropped)
        if w.padding == "zero" and np.any(valid < length):
            padded = steps >= valid[:, None]
            for kind in batch:
                batch[kind] = np.where(padded.reshape(padded.shape + (1,) * (batch[kind].ndim - 2)), 0, batch[kind])
        batch.update(window=idx, clip=clips, start=offset, valid=valid)
        if self.labels is not None:
            batch["labels"] = {f: c[clips] for f, c in self.labels.codes.items()}
        if draws is not None:
            batch.update(
                angle=draws.angle,
                speed=draws.speed,
                mirrored=draws.mirrored,
                noised=draws.noised,
                dropped=draws.dropped,
            )
        return batch


def mirror_partners(dataset, windows: Windows) -> np.ndarray:
    """For each clip of ``dataset``, its mirror image's index (``X`` <-> ``X@mirrored``; -1 when
    it has none); an error when a clip of ``windows`` has none, or one of another length."""
    names = list(dataset.names)
    index = {name: i for i, name in enumerate(names)}
    partner = np.full(len(names), -1, dtype=np.int64)
    for i, record in enumerate(dataset.clips):
        original = record.get("mirror_of") if isinstance(record.get("mirror_of"), str) else None
        if original is None and names[i].endswith(MIRRORED):
            original = names[i][: -len(MIRRORED)]
        if original is not None and original in index:
            partner[i], partner[index[original]] = index[original], i
    lengths = np.diff(dataset.offsets)
    for c in np.unique(windows.clip):
        if partner[c] < 0:
            raise ArgumentError(
                f"argument `augment`: Mirror reads each clip's mirror image, and clip {names[c]!r} has none "
                "(preprocess with --mirror)"
            )
        if lengths[c] != lengths[partner[c]]:
            raise DatasetError(
                f"clip {names[c]!r} and its mirror image have {lengths[c]} and {lengths[partner[c]]} frames"
            )
    return partner


def _seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ArgumentError(f"argument `seed`: a non-negative whole number, got {seed!r}")
    return int(seed)


class Batches:
    """An epoch's batches of ``batch_size`` windows, read by ``reader`` (a :class:`WindowReader`).

    ``batches.epoch(n)``: the batches of epoch ``n``, the windows shuffled (``shuffle=True``) by
    ``seed`` and ``n`` and each window's augmentation drawn from ``(seed, n, window index)``: the
    same seed gives the same batches and draws, whatever was read before and whatever the batch
    size. ``for batch in batches`` runs the
    next epoch (0, 1, ...). ``drop_last`` leaves out a last smaller batch."""

    def __init__(
        self, reader: WindowReader, batch_size: int = 256, shuffle: bool = True, seed: int = 0, drop_last: bool = False
    ):
        if isinstance(batch_size, bool) or not isinstance(batch_size, (int, np.integer)) or batch_size < 1:
            raise ArgumentError(f"argument `batch_size`: a positive whole number of windows, got {batch_size!r}")
        reader.check_batch(int(batch_size))
        seed = _seed(seed)
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
            yield self.reader.read(picked, number, self.seed)

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
    augment: Augment | Compose | Transform | Sequence[Transform] | None = None,
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
    reader = WindowReader(dataset, windows, kinds, augment, normaliser or None, labels, frame, seed)
    return Batches(reader, batch_size, shuffle, seed, drop_last)


__all__ = ["MAX_BATCH_BYTES", "Batches", "WindowReader", "window_batches"]
