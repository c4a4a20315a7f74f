"""A map-style dataset of windows for PyTorch's ``DataLoader``, without importing torch.

:class:`WindowDataset` has ``__len__`` and ``__getitem__`` (one window as a dict of NumPy arrays,
which ``default_collate`` stacks into tensors) and ``__getitems__`` (a whole batch read with one
gather per kind, as :class:`~expressive_mocap.dataset.batches.WindowReader` does). It pickles
as its folder and settings only: each ``DataLoader`` worker reopens the memory-mapped arrays on
first use, so the workers share the page cache instead of copying arrays.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from .augment import Augment
from .batches import WindowReader
from .labels import BANDAI, Labels
from .stats import Normaliser, float_kinds
from .transforms import Compose, Transform
from .windows import Windows


class WindowDataset:
    """The ``length``-frame windows (``stride``, ``padding`` as in
    :class:`~expressive_mocap.dataset.windows.Windows`) of the dataset in ``folder``, of its clips
    ``clips`` (indices, e.g. a split's; all by default), ``kinds`` (all by default).

    ``augment``: a :class:`~expressive_mocap.dataset.transforms.Compose` of transforms (or a
    list of them, or an :class:`~expressive_mocap.dataset.augment.Augment`), drawn per window
    from ``(seed, epoch, index)``: the same whether a window is fetched alone or in a batch (call
    :meth:`set_epoch` each epoch for fresh draws); ``normalise``: True for the dataset's statistics, or a
    :class:`~expressive_mocap.dataset.stats.Normaliser`; ``labels``: a name pattern (``"bandai"``
    for :data:`~expressive_mocap.dataset.labels.BANDAI`) or :class:`~expressive_mocap.dataset.labels.Labels`.

    An item: each kind ``float32 [T, ...]``, ``clip``, ``start``, ``valid`` (int64), ``labels``
    ``{field: int64}``, and when augmenting ``angle``, ``speed``, ``mirrored``, ``noised`` and
    ``dropped`` ``[J]``."""

    def __init__(
        self,
        folder: str | os.PathLike,
        length: int,
        stride: int | None = None,
        padding: str = "drop",
        kinds: Sequence[str] | None = None,
        clips: Sequence[int] | np.ndarray | None = None,
        augment: Augment | Compose | Transform | Sequence[Transform] | None = None,
        normalise: bool | Normaliser = False,
        labels: str | Labels | None = None,
        seed: int = 0,
        check_times: bool = True,
        frame: str = "stored",
    ):
        self.folder = os.fspath(folder)
        self.length, self.stride, self.padding, self.check_times = length, stride, padding, check_times
        self.kinds = None if kinds is None else list(kinds)
        self.clips = None if clips is None else np.asarray(clips, dtype=np.int64)
        self.augment, self.seed, self.epoch, self.frame = augment, seed, 0, frame
        self.labels = BANDAI if labels == "bandai" else labels
        self._reader: WindowReader | None = None
        self._dataset: Any = None
        self.normaliser: Normaliser | None = None
        if isinstance(normalise, Normaliser):
            self.normaliser = normalise
        reader = self.reader  # opens the dataset: errors now, not in a worker
        if normalise is True:
            floats = [k for k in float_kinds(self._dataset) if k in reader.arrays]
            self.normaliser = reader.normaliser = Normaliser.of(self._dataset, floats)

    @property
    def reader(self) -> WindowReader:
        """The reader, opening the dataset (memory-mapped) on first use in this process."""
        if self._reader is None:
            from .reader import load_dataset

            dataset = load_dataset(self.folder, check_times=self.check_times)
            windows = Windows(dataset, self.length, self.stride, self.padding, self.clips)
            labels = Labels.from_names(dataset, self.labels) if isinstance(self.labels, str) else self.labels
            self._reader = WindowReader(
                dataset, windows, self.kinds, self.augment, self.normaliser, labels, self.frame, self.seed
            )
            self._dataset = dataset
        return self._reader

    def set_epoch(self, epoch: int) -> None:
        """Draw the next epoch's augmentation (workers started after this see it)."""
        self.epoch = int(epoch)

    def __len__(self) -> int:
        return len(self.reader.windows)

    def __getitem__(self, index) -> dict:
        """Window ``index`` as an item; or, for a list of indices, those windows as one batch
        (``[B, T, ...]`` arrays in the order of their rows, ``window`` naming them): the fast
        path for ``DataLoader(ds, batch_size=None, sampler=BatchSampler(...))``, nothing to
        collate."""
        if not isinstance(index, (int, np.integer)):
            wanted = np.asarray(index, dtype=np.int64) % max(len(self), 1)
            return self.reader.read(wanted, self.epoch, self.seed)
        if not -len(self) <= index < len(self):
            raise IndexError(f"window {index} of {len(self)}")
        index = int(index) % len(self)
        return _item(self.reader.read([index], self.epoch, self.seed), 0)

    def __getitems__(self, indices: Sequence[int]) -> list[dict]:
        """The windows ``indices`` read as one batch, returned one dict per index, in order."""
        wanted = np.asarray(indices, dtype=np.int64) % max(len(self), 1)
        batch = self.reader.read(wanted, self.epoch, self.seed)
        place = _places(wanted, batch["window"])
        return [_item(batch, int(j)) for j in place]

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_reader"] = state["_dataset"] = None  # reopened in each worker: memory maps are not pickled
        return state

    def __repr__(self) -> str:
        return f"WindowDataset({self.folder!r}, {len(self)} windows of {self.length} frames)"


def _places(wanted: np.ndarray, got: np.ndarray) -> np.ndarray:
    """For each ``wanted`` window index, a position in ``got`` holding it (``got`` a permutation
    of ``wanted``, repeats allowed)."""
    order_wanted, order_got = np.argsort(wanted, kind="stable"), np.argsort(got, kind="stable")
    place = np.empty(len(wanted), dtype=np.int64)
    place[order_wanted] = order_got
    return place


def _item(batch: dict, j: int) -> dict:
    item = {}
    for key, value in batch.items():
        if key == "window":
            continue
        item[key] = {f: v[j] for f, v in value.items()} if key == "labels" else value[j]
    return item


__all__ = ["WindowDataset"]
