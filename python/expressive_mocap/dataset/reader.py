"""Reading a finished dataset: :func:`load_dataset` opens a folder written by
:func:`~expressive_mocap.dataset.preprocess` as a :class:`Dataset` of :class:`Clip` s, after
checking its files against its manifest (:func:`~expressive_mocap.dataset.format.verify`)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Literal

import numpy as np

from ..errors import DatasetError
from .format import MANIFEST, OFFSETS, PARTIAL, data_file, read_manifest, verify


class Clip(Mapping):
    """One clip of a :class:`Dataset`: a mapping kind -> its rows of that kind's array (views, no
    copy), e.g. ``clip["positions"]`` or ``clip.positions`` ``[frames, J, 3]``; ``name``,
    ``index`` (position in the dataset), ``start`` (first row), ``frames`` and ``record`` (the
    manifest's record: source, fps, frame_time...)."""

    def __init__(self, dataset: Dataset, index: int):
        self.index = index
        self.record = dataset.clips[index]
        self.name: str = self.record["name"]
        self.start, end = int(dataset.offsets[index]), int(dataset.offsets[index + 1])
        self.frames = end - self.start
        self._arrays = {k: a[self.start : end] for k, a in dataset.arrays.items()}

    def __getitem__(self, kind: str) -> np.ndarray:
        try:
            return self._arrays[kind]
        except KeyError:
            raise KeyError(f"{kind!r}: this dataset's kinds are {', '.join(self._arrays)}") from None

    def __getattr__(self, kind: str) -> np.ndarray:
        if kind.startswith("_") or kind not in self._arrays:
            raise AttributeError(f"a Clip has no attribute {kind!r}; its kinds are {', '.join(self._arrays)}")
        return self._arrays[kind]

    def __iter__(self):
        return iter(self._arrays)

    def __len__(self) -> int:
        return len(self._arrays)

    __eq__ = object.__eq__  # a view: Mapping's item-by-item == would compare arrays
    __hash__ = object.__hash__

    def __repr__(self) -> str:
        return f"Clip({self.name!r}, {self.frames} frames, kinds {', '.join(self._arrays)})"


class Dataset(Sequence):
    """A preprocessed dataset: a sequence of :class:`Clip` s, ``ds[3]``, ``ds[-1]`` or
    ``ds["walk_001"]`` (by name), ``len(ds)`` clips, ``for clip in ds``, ``"walk_001" in ds``.

    Whole arrays (memory-mapped, the rows of every clip in order) by kind: ``ds.positions`` or
    ``ds.arrays["positions"]``; ``ds.kinds`` lists them. Also ``offsets [C + 1]`` (clip ``i`` is
    rows ``offsets[i]:offsets[i + 1]``), ``clips`` (manifest records), ``names``, ``failures``,
    ``manifest``, ``skeleton``.

    Formerly ``ds["positions"]`` was the whole array; it still is when no clip has that name,
    with a DeprecationWarning.
    """

    def __init__(self, folder: str | os.PathLike, mmap: bool = True, check_times: bool = True):
        folder = Path(folder)
        path = folder / MANIFEST
        if not path.exists():
            hint = " (an interrupted run: rerun preprocess to finish it)" if (folder / PARTIAL).exists() else ""
            raise DatasetError(f"{folder} is not a finished expressive-mocap dataset: no manifest.json{hint}")
        self.folder = folder
        self.manifest = read_manifest(path)
        verify(folder, self.manifest, check_times)
        try:
            self.offsets = np.load(folder / OFFSETS)
            mode: Literal["r"] | None = "r" if mmap else None
            self.arrays = {k: np.load(folder / data_file(k), mmap_mode=mode) for k in self.manifest["kinds"]}
        except (OSError, ValueError) as error:  # changed after the checks: a run redoing it, say
            raise DatasetError(
                f"{folder}: its files changed while it was read ({type(error).__name__}: {error}); another run "
                "redoing it with --overwrite? Read it again once that run is done"
            ) from None
        self.clips = self.manifest["clips"]
        self.names = [c["name"] for c in self.clips]
        self.failures = self.manifest["failures"]
        self.skeleton = self.manifest["skeleton"]
        self._index = {n: i for i, n in enumerate(self.names)}

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(self.arrays)

    def __getitem__(self, which: int | str) -> Clip:  # type: ignore[override]  # by number or name, no slices
        if isinstance(which, str) and which not in self._index and which in self.arrays:
            import warnings

            warnings.warn(
                f"ds[{which!r}] as the whole array is deprecated: use ds.{which} or ds.arrays[{which!r}] "
                "(ds[...] is a clip)",
                DeprecationWarning,
                stacklevel=2,
            )
            return self.arrays[which]
        return self.clip(which)

    def __getattr__(self, kind: str) -> np.ndarray:
        arrays = self.__dict__.get("arrays", {})
        if kind not in arrays:
            raise AttributeError(f"a Dataset has no attribute {kind!r}; its kinds are {', '.join(arrays)}")
        return arrays[kind]

    def __len__(self) -> int:
        return len(self.clips)

    def __iter__(self):
        return (Clip(self, i) for i in range(len(self)))

    def __contains__(self, name) -> bool:
        return name in self._index

    def __repr__(self) -> str:
        kinds, frames = ", ".join(self.arrays), int(self.offsets[-1])
        return f"Dataset({len(self)} clips, {frames:,} frames, kinds {kinds}; {len(self.failures)} failures)"

    def clip(self, which: int | str) -> Clip:
        """One clip, by index (negative counts from the end) or name."""
        if isinstance(which, str):
            if which not in self._index:
                raise KeyError(f"no clip named {which!r} in {self.folder}")
            return Clip(self, self._index[which])
        if not isinstance(which, (int, np.integer)) or isinstance(which, bool):
            raise TypeError(f"a dataset is indexed by clip number or name, not {type(which).__name__}")
        i = int(which) + (len(self) if which < 0 else 0)
        if not 0 <= i < len(self):
            raise IndexError(f"clip {int(which)} of a dataset of {len(self)} clips")
        return Clip(self, i)


def load_dataset(folder: str | os.PathLike, mmap: bool = True, check_times: bool = True) -> Dataset:
    """Open the dataset written by :func:`~expressive_mocap.dataset.preprocess` in ``folder``
    (arrays memory-mapped unless ``mmap=False``), after checking its files against its manifest
    (:func:`~expressive_mocap.dataset.format.verify`; ``check_times=False`` skips the modification
    times, for a copy that did not keep them)."""
    return Dataset(folder, mmap, check_times)


__all__ = ["Clip", "Dataset", "load_dataset"]
