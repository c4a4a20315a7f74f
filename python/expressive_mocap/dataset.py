"""A preprocessed dataset on disk: its fixed file names, the manifest that vouches for them, the
lock a run holds on its folder, and the reader (:func:`load_dataset`).

A dataset folder holds, by fixed names only, ``manifest.json``, ``offsets.npy`` and one
``{kind}.npy`` per kind kept (see :data:`KINDS`), plus ``.lock`` (the run's advisory lock) and,
while a run is unfinished, ``.partial/`` (its journal and growing data files). Nothing here ever
opens or deletes a path a manifest names: names come from this module, so a tampered manifest
cannot point a reader or ``--overwrite`` outside the folder.

The manifest records each file's size and modification time as written. :func:`load_dataset`
checks them, the ``.npy`` headers (dtype, shape, row count) and the clips' offsets against the
manifest, so a dataset that another process rewrote, a half-copied one, or one whose files do
not belong together is refused with a one-line error instead of being read as data.
"""

from __future__ import annotations

import json
import os
import socket
import stat
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from .errors import MocapError

FORMAT = "expressive-mocap dataset"
VERSION = 2  # 2: the manifest records each file's size and mtime; clips keyed by name
KINDS = ("positions", "rotations", "features", "contacts", "activity", "body", "expressive")
MANIFEST = "manifest.json"
OFFSETS = "offsets.npy"
PARTIAL = ".partial"
LOCK = ".lock"
JOURNAL = "journal.jsonl"  # in .partial: one line per batch written
RUN = "run.json"  # in .partial: the options of the interrupted run
MAX_MANIFEST_BYTES = 256 << 20  # ~1 M clips with their failures


def data_file(kind: str) -> str:
    """The one file name of a kind's array."""
    if kind not in KINDS:
        raise MocapError(f"unknown kind {kind!r}; choose from {', '.join(KINDS)}")
    return f"{kind}.npy"


OWN_FILES = frozenset([MANIFEST, OFFSETS, *map(data_file, KINDS)])  # what a finished dataset may hold
PARTIAL_FILES = OWN_FILES | {JOURNAL, RUN}  # what .partial may hold (and atomic writes' temporaries)


# ----------------------------------------------------------------------------- the lock


class FolderLock:
    """An advisory lock (``flock``) on ``folder/.lock``, held while a run writes the folder: a
    second run on the same folder fails at once, saying which process holds it. The lock goes
    with the process (a killed run leaves no stale lock); the file stays, as deleting a lock file
    others may be waiting on would let two runs lock two different files. Works between
    processes of one machine and on local file systems; over NFS it depends on the server."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.path = folder / LOCK
        self.handle: int | None = None

    def __enter__(self) -> FolderLock:
        import fcntl

        try:  # O_NOFOLLOW: a link planted at .lock must not make us write into its target
            handle = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0), 0o666)
        except OSError as error:
            raise MocapError(f"cannot lock {self.path}: {error.strerror or error}") from None
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(handle)
            os.close(handle)
            raise MocapError(f"{self.folder} is being written by another run ({holder}); wait for it to end or stop it") from None
        except OSError as error:
            os.close(handle)
            raise MocapError(f"cannot lock {self.path}: {error.strerror or error}") from None
        record = {"pid": os.getpid(), "host": socket.gethostname(), "since": time.strftime("%Y-%m-%d %H:%M:%S"),
                  "command": " ".join(sys.argv)[:500]}
        os.ftruncate(handle, 0)
        os.pwrite(handle, json.dumps(record).encode(), 0)
        self.handle = handle
        return self

    def __exit__(self, *exc) -> None:
        if self.handle is not None:
            os.close(self.handle)  # releases the flock
            self.handle = None


def _holder(handle: int) -> str:
    """Who holds the lock, from what it wrote into the lock file."""
    try:
        record = json.loads(os.pread(handle, 4096, 0))
        return f"process {record['pid']} on {record['host']} since {record['since']}: {record['command']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "a process that has not said which yet"


# ----------------------------------------------------------------------------- the manifest


def read_manifest(path: Path) -> dict:
    """The manifest at ``path``, checked as far as it speaks of itself: our format and version,
    fixed file names, kinds and shapes consistent with the frame count, clips with unique names
    and contiguous rows. A :class:`MocapError` naming the file otherwise."""
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_MANIFEST_BYTES:
            raise ValueError("not a regular file of at most 256 MiB")
        manifest = json.loads(path.read_bytes())
    except (OSError, ValueError) as error:
        raise MocapError(f"{path}: not a readable dataset manifest ({error})") from None
    problem = _manifest_problem(manifest)
    if problem:
        raise MocapError(f"{path}: {problem}")
    return manifest


def _manifest_problem(manifest) -> str | None:
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        return f"not an {FORMAT} manifest"
    if manifest.get("version") not in (1, VERSION):
        return f"a dataset of format version {manifest.get('version')!r}; this version reads {VERSION}"
    kinds, rows, clips = manifest.get("kinds"), manifest.get("frames"), manifest.get("clips")
    if not isinstance(kinds, dict) or not isinstance(rows, int) or rows < 0 or not isinstance(clips, list):
        return "lacks its kinds, frame count or clips"
    for kind, entry in kinds.items():
        if kind not in KINDS or not isinstance(entry, dict) or entry.get("file") != data_file(kind):
            return f"names a file its format does not have ({kind!r}: {str(entry)[:80]})"
        shape = entry.get("shape")
        if not isinstance(shape, list) or not shape or shape[0] != rows or not all(isinstance(n, int) and n >= 0 for n in shape):
            return f"{kind}: shape {shape} does not hold the {rows} frames of the dataset"
    start, names = 0, set()
    for clip in clips:
        if not isinstance(clip, dict) or not isinstance(clip.get("name"), str) or not isinstance(clip.get("frames"), int):
            return f"a clip record is not a name and a frame count: {str(clip)[:80]}"
        if clip["name"] in names:
            return f"the clip name {clip['name']!r} is there twice"
        if clip.get("start") != start or clip["frames"] < 0:
            return f"clip {clip['name']!r} does not start where the one before it ends (row {start})"
        names.add(clip["name"])
        start += clip["frames"]
    if start != rows:
        return f"its clips hold {start} frames, not the {rows} it says"
    return None


def file_record(folder: Path, names) -> dict:
    """``{name: {"bytes", "mtime_ns"}}`` of files in ``folder``, as written, for the manifest."""
    record = {}
    for name in names:
        info = os.stat(folder / name)
        record[name] = {"bytes": info.st_size, "mtime_ns": info.st_mtime_ns}
    return record


def verify(folder: Path, manifest: dict, check_times: bool = True) -> None:
    """Check the files of the dataset in ``folder`` against its (already read) ``manifest``:
    each a regular file of the recorded size (and modification time, unless ``check_times`` is
    False: a copy that did not keep times), an ``.npy`` header of the recorded dtype and shape
    whose rows fill the file exactly, and offsets that are the clips' rows. A one-line
    :class:`MocapError` naming the file otherwise."""
    recorded = manifest.get("files", {}) if manifest["version"] >= 2 else None
    names = [OFFSETS] + [data_file(k) for k in manifest["kinds"]]
    if recorded is not None and sorted(recorded) != sorted(names):
        raise MocapError(f"{folder / MANIFEST}: records files {sorted(recorded)}, expected {sorted(names)}")
    for name in names:
        path = folder / name
        try:
            info = os.lstat(path)
        except OSError as error:
            raise MocapError(f"{path}: part of the dataset, cannot be read: {error.strerror or error}") from None
        if not stat.S_ISREG(info.st_mode):
            raise MocapError(f"{path}: part of the dataset, is not a regular file")
        if recorded is not None:
            expected = recorded[name]
            if info.st_size != expected["bytes"]:
                raise MocapError(f"{path}: {info.st_size:,} bytes, the manifest says {expected['bytes']:,}: the file was changed after the dataset was written")
            if check_times and info.st_mtime_ns != expected["mtime_ns"]:
                raise MocapError(f"{path}: modified after the dataset was written (a copy that did not keep modification "
                                 "times? load with check_times=False)")
    for kind, entry in manifest["kinds"].items():
        _check_npy(folder / data_file(kind), np.dtype(entry["dtype"]), tuple(entry["shape"]))
    clips = manifest["clips"]
    _check_npy(folder / OFFSETS, np.dtype(np.int64), (len(clips) + 1,))
    offsets = np.load(folder / OFFSETS)
    expected_offsets = np.array([c["start"] for c in clips] + [manifest["frames"]], dtype=np.int64)
    if not np.array_equal(offsets, expected_offsets):
        raise MocapError(f"{folder / OFFSETS}: the clips' rows differ from the manifest's")


def _check_npy(path: Path, dtype: np.dtype, shape: tuple) -> None:
    """The ``.npy`` file at ``path`` holds a C-ordered ``dtype`` array of ``shape`` that fills it."""
    try:
        with open(path, "rb") as handle:
            version = np.lib.format.read_magic(handle)
            if version not in ((1, 0), (2, 0)):
                raise ValueError(f".npy format version {version}")
            reader = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            found_shape, fortran, found_dtype = reader(handle)
            header_end = handle.tell()
        size = os.stat(path).st_size
    except (OSError, ValueError) as error:
        raise MocapError(f"{path}: not a readable .npy file ({error})") from None
    if found_dtype != dtype or tuple(found_shape) != shape or fortran:
        raise MocapError(f"{path}: holds {found_dtype} {list(found_shape)}, the manifest says {dtype} {list(shape)}")
    expected = header_end + int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if size != expected:
        raise MocapError(f"{path}: {size:,} bytes where a {dtype} array of shape {list(shape)} takes {expected:,}")


# ----------------------------------------------------------------------------- the folder's state


def finished_manifest(out: Path) -> dict | None:
    """The manifest of the finished dataset in ``out``, None when there is none, after refusing a
    folder that is not ours to write: not a folder, a ``.partial`` that is not a real folder
    (a link would make us write elsewhere), or a non-empty folder that holds neither a dataset
    nor an unfinished run (the user's own files are never replaced)."""
    if not out.exists():
        return None
    if not out.is_dir():
        raise MocapError(f"{out}: not a folder (a dataset is a folder)")
    partial = out / PARTIAL
    if partial.is_symlink() or (partial.exists() and not partial.is_dir()):
        raise MocapError(f"{partial}: not a folder of ours (a link or a file); move it away")
    if (out / MANIFEST).exists():
        return read_manifest(out / MANIFEST)
    if partial.exists():
        if not (partial / RUN).is_file():
            raise MocapError(f"{partial} is not an unfinished run of ours (no {RUN}); move it away")
        if not (partial / MANIFEST).exists():  # a run not yet moving its files into place
            clash = sorted(OWN_FILES & set(os.listdir(out)))
            if clash:
                raise MocapError(f"{out} holds {', '.join(clash)} beside an unfinished run, without a manifest: "
                                 "not ours to replace; move them away")
        return None
    foreign = sorted(set(os.listdir(out)) - {LOCK})
    if foreign:
        shown = ", ".join(foreign[:5]) + (f" and {len(foreign) - 5} more" if len(foreign) > 5 else "")
        raise MocapError(f"{out} is not empty ({shown}) and holds no dataset: choose a new or empty folder")
    return None


def remove_dataset(out: Path) -> None:
    """Unmake the finished dataset in ``out`` (its manifest already read and checked): the
    manifest first, so no reader sees old and new files mixed, then its files by their fixed
    names; anything else in the folder stays."""
    (out / MANIFEST).unlink()
    for name in sorted(OWN_FILES - {MANIFEST}):
        (out / name).unlink(missing_ok=True)


def remove_partial(out: Path) -> None:
    """Delete ``out/.partial``: the files a run writes there, by their fixed names (and the
    temporaries of its atomic writes), then the folder; a file of someone else's stops it."""
    partial = out / PARTIAL
    if not partial.is_dir() or partial.is_symlink():
        return
    for name in os.listdir(partial):
        temporary = name.endswith(".tmp") and any(name.startswith(f".{own}.") for own in PARTIAL_FILES)
        if name in PARTIAL_FILES or temporary:
            (partial / name).unlink(missing_ok=True)
    try:
        partial.rmdir()
    except OSError:
        raise MocapError(f"{partial} holds files this package did not write ({', '.join(sorted(os.listdir(partial))[:5])}); "
                         "left in place: move them away") from None


# ----------------------------------------------------------------------------- reading


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
            raise MocapError(f"{folder} is not a finished expressive-mocap dataset: no manifest.json{hint}")
        self.folder = folder
        self.manifest = read_manifest(path)
        verify(folder, self.manifest, check_times)
        self.offsets = np.load(folder / OFFSETS)
        self.clips = self.manifest["clips"]
        self.names = [c["name"] for c in self.clips]
        self.failures = self.manifest["failures"]
        self.skeleton = self.manifest["skeleton"]
        mode = "r" if mmap else None
        self.arrays = {k: np.load(folder / data_file(k), mmap_mode=mode) for k in self.manifest["kinds"]}
        self._index = {n: i for i, n in enumerate(self.names)}

    @property
    def kinds(self) -> tuple[str, ...]:
        return tuple(self.arrays)

    def __getitem__(self, which: int | str) -> Clip:
        if isinstance(which, str) and which not in self._index and which in self.arrays:
            import warnings

            warnings.warn(f'ds[{which!r}] as the whole array is deprecated: use ds.{which} or ds.arrays[{which!r}] '
                          "(ds[...] is a clip)", DeprecationWarning, stacklevel=2)
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
        return f"Dataset({len(self)} clips, {int(self.offsets[-1]):,} frames, kinds {', '.join(self.arrays)}; {len(self.failures)} failures)"

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
    """Open the dataset written by :func:`~expressive_mocap.preprocess.preprocess` in ``folder``
    (arrays memory-mapped unless ``mmap=False``), after checking its files against its manifest
    (:func:`verify`; ``check_times=False`` skips the modification times, for a copy that did not
    keep them)."""
    return Dataset(folder, mmap, check_times)
