"""Preprocessing a whole archive of BVH clips into a dataset of arrays (``expressive-mocap preprocess``).

Per clip: parse, forward kinematics (world positions), dynamic features, foot contacts and,
with a body-mechanics model, the decomposition's activity per joint (optionally its body and
expressive rotations). Clips are read in batches. Python reads each clip's header from the
file's first bytes (:func:`~expressive_mocap.bvh.read_header`); everything else of a clip
(reading the file, its MOTION block, FK, features, contacts, float32 outputs) is one task of
one Rust call per batch, clips in parallel (``clip_pipeline_many``), then the network runs on
the whole batch. Header threads prepare the next batches while a kernel thread runs this one's
kernels and the main thread appends the previous one's rows to the output, so memory stays
bounded and both cores stay busy (the kernels release the GIL).

The output format: a folder ::

    OUT/manifest.json      clips (name, source, frames, fps, start row), failures with their
                           errors, the skeleton (joint names, parents), the kinds kept and their
                           shapes, the options, the package version; written last
    OUT/offsets.npy        int64 [C + 1]: clip i is rows offsets[i]:offsets[i + 1] of every kind
    OUT/positions.npy      float32 [N, J, 3]  world positions (file units)
    OUT/rotations.npy      float32 [N, J, 4]  local rotations (x, y, z, w)
    OUT/features.npy       float32 [N, 19]    dynamic_features (causal; FEATURE_NAMES)
    OUT/contacts.npy       bool    [N, 2]     foot_contacts (offline; left, right)
    OUT/activity.npy       float32 [N, J]     decomposition activity per joint (--model)
    OUT/body.npy, OUT/expressive.npy  float32 [N, J, 4]  B' and E* (--model)

(N = frames of all clips, rows in clip order.) Why NumPy ``.npy`` files and a JSON manifest:
they need nothing beyond NumPy, every array can be memory-mapped (``np.load(mmap_mode="r")``:
a 500 MB archive opens in milliseconds and a training loop reads only the rows it touches),
one concatenated array per kind is what batch samplers want (clip ``i`` is one slice), and
the whole dataset loads in one line: ``load_dataset(OUT)``. HDF5 or Zarr would add a
dependency for little gain here; ``.npz`` cannot be memory-mapped; Parquet does not hold
``[N, J, 3]`` tensors naturally.

Robustness: a clip that cannot be read or processed is listed in the manifest's failures with
its error and the run goes on. The run writes into ``OUT/.partial``: each batch's rows are
appended to the data files, then one line is appended to a journal; an interrupted run
restarts from the journal (the data files are cut back to the last journaled batch, finished
clips are skipped). At the end the data are synced to disk, the files renamed into ``OUT`` and
the manifest written last: a folder with a ``manifest.json`` is a complete dataset, never a
half-written one. (An interrupted process loses nothing; the journal is not synced per batch,
so after a power cut mid-run delete ``OUT/.partial`` and run again.)

Safety (:mod:`expressive_mocap.dataset`): a run holds an advisory lock on ``OUT/.lock`` from start
to end, so a second run on the same OUT fails at once naming the first; OUT must be new, empty,
or one of our datasets (finished or unfinished), never a folder of the user's own files; a rerun
over a finished dataset never rewrites it (``overwrite`` redoes it, deleting only the format's
own file names); clips are keyed by name, so a resumed run may spell SRC otherwise, and a
second clip of a name already taken is a failure; the manifest records each file's size and
mtime, and :func:`load_dataset` refuses files that do not match it.

Clips are taken in sorted path order from folders, globs and zips, in archive order from tars
(a compressed tar is read as a stream, once; reading it out of order would decompress it again
and again).
"""

from __future__ import annotations

import datetime
import glob as globlib
import errno
import io
import itertools
import json
import lzma
import os
import queue
import stat
import struct
import tarfile
import threading
import time
import zipfile
import zlib
from collections import Counter, deque
from concurrent.futures import CancelledError, Future, ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from . import ops
from .backend import get_backend
from .bvh import block_error, parse_header, read_error, read_header
from .dataset import (FORMAT, JOURNAL, KINDS, MANIFEST, OFFSETS, PARTIAL, RUN, VERSION, Dataset, FolderLock, data_file,
                      file_record, finished_manifest, load_dataset, read_manifest, remove_dataset, remove_partial, verify)
from .errors import BVHError, MocapError
from .decoupling.algebra import EXPONENT, GAIN
from .features import FEATURE_NAMES, FLOOR_PERCENTILE, HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD
from . import files as inputs
from .files import atomic_write
from .ops import decouple_rotations
from .progress import Progress
from .roles import JointRoles, actor_height, hips_rest_height

MODEL_KINDS = ("activity", "body", "expressive")
DEFAULT_KEEP = ("positions", "features", "contacts")  # + activity with a model
MB = 1e6
_HEADER_BYTES = 128  # room reserved at the start of each data file for its .npy header


# ----------------------------------------------------------------------------- sources


@dataclass(frozen=True)
class _Item:
    """One clip to read: ``name`` (path inside SRC without .bvh), ``source`` (where it came
    from, for the manifest and error messages), ``size`` in bytes (listed: for batching and
    progress only), and where its bytes are: a file ``path``, a ``member`` of the zip at
    ``path``, ``data`` (a tar member already read), or ``refused``: why a tar member was not
    read. Plain values only, so a batch of items can be sent to the workers of a cluster."""

    name: str
    source: str
    size: int
    path: str | None = None
    member: str | None = None
    data: bytes | None = None
    refused: str | None = None

    def header(self, outcome: dict):
        """The clip's BVH header and its text for the kernel: the file's path when the header
        came from the file's beginning (the kernel reads the rest), else the bytes. Sets
        ``outcome["bytes"]`` to the bytes read so far, also when the header then fails."""
        outcome["bytes"] = 0
        if self.refused is not None:
            raise BVHError(self.source, None, f"cannot read the archive member: {self.refused}")
        if self.data is None and self.member is None:
            header, data = read_header(self.path)
            if data is None:
                return header, self.path  # counted once the kernel has read the file
            outcome["bytes"] = len(data)
            return header, data
        data = self.data if self.data is not None else _member_bytes(self)
        outcome["bytes"] = len(data)
        return parse_header(data, self.source), data


# What reading one zip member can raise (a damaged, truncated or unsupported member).
_MEMBER_ERRORS = (zipfile.BadZipFile, zlib.error, lzma.LZMAError, OSError, EOFError, NotImplementedError, RuntimeError, ValueError)


def _member_bytes(item: _Item) -> bytes:
    """A zip member's bytes, checked before decompressing: not encrypted, at most
    ``files.MAX_INPUT_BYTES`` declared, and no more than that read whatever it declares (a 1 MB zip
    can hold a 1 GiB member). Any problem is that clip's BVHError."""
    try:
        info = _zip(item.path).getinfo(item.member)
        if info.flag_bits & 0x1:
            raise OSError(errno.EACCES, "encrypted: members are read without a password")
        if info.file_size > inputs.MAX_INPUT_BYTES:
            raise inputs.too_large(inputs.MAX_INPUT_BYTES, item.source, info.file_size)
        with _zip(item.path).open(info) as member:
            return inputs.read_at_most(member, inputs.MAX_INPUT_BYTES, item.source)
    except _MEMBER_ERRORS as error:  # a damaged member fails alone
        reason = error.strerror if isinstance(error, OSError) and error.strerror else error
        raise BVHError(item.source, None, f"cannot read the archive member: {reason}") from None


_ZIPS: dict[str, zipfile.ZipFile] = {}


def _zip(path: str) -> zipfile.ZipFile:
    """One open ZipFile per archive and process (each worker of a cluster opens its own)."""
    archive = _ZIPS.get(path)
    if archive is None:
        archive = _ZIPS[path] = zipfile.ZipFile(path)
    return archive


def _is_tar(path: Path) -> bool:
    return any(path.name.lower().endswith(s) for s in (".tar", ".tar.gz", ".tgz", ".tar.xz", ".txz", ".tar.bz2"))


def _clip_name(relative: str) -> str:
    return relative[:-4] if relative.lower().endswith(".bvh") else relative


def _listed_size(path: str) -> int:
    """The size of a regular file within the bound (a stat, no open: listing stays fast), 0 for
    anything else: a FIFO, device, dangling link or larger file is not read, its clip fails
    with the reason when read."""
    try:
        info = os.stat(path)
    except OSError:
        return 0
    return info.st_size if stat.S_ISREG(info.st_mode) and info.st_size <= inputs.MAX_INPUT_BYTES else 0


def _folder(root: Path) -> list[_Item]:
    """The ``*.bvh`` files below ``root`` (any case; symlinked folders are not followed), by name.
    os.walk + plain strings: an archive of thousands of files is listed in milliseconds."""
    prefix, items = os.path.join(str(root), ""), []
    for folder, _, names in os.walk(root):
        for name in names:
            if name.lower().endswith(".bvh"):
                path = os.path.join(folder, name)
                items.append(_Item(_clip_name(path[len(prefix):].replace(os.sep, "/")), path, _listed_size(path), path=path))
    return sorted(items, key=lambda i: i.name)


def _files(paths, root: Path) -> list[_Item]:
    items = [_Item(_clip_name(p.relative_to(root).as_posix()), str(p), _listed_size(str(p)), path=str(p)) for p in paths]
    return sorted(items, key=lambda i: i.name)


@dataclass
class _Source:
    """The clips of SRC: a folder (recursive ``*.bvh``), a glob, a .zip or a tar (read in place)."""

    description: str
    items: list[_Item] | None  # known up front (folders, globs, zips); None for a tar stream
    _stream: Callable[[], Iterator[_Item]] | None = None
    _close: Callable[[], None] | None = None

    def __iter__(self) -> Iterator[_Item]:
        return iter(self.items) if self.items is not None else self._stream()

    def close(self) -> None:
        if self._close is not None:
            self._close()


def open_source(src: str | os.PathLike) -> _Source:
    """The clips of ``src``: a folder (``*.bvh`` found recursively), a glob pattern
    (``"data/*_walk_*.bvh"``), a ``.zip`` or a ``.tar``/``.tar.gz``/``.tar.xz`` archive."""
    text = str(src)
    path = Path(src)
    if path.is_dir():
        return _Source(f"folder {path}", _folder(path))
    if path.is_file() and zipfile.is_zipfile(path):
        try:
            archive = _zip(str(path))
        except (zipfile.BadZipFile, OSError, ValueError) as error:  # found a zip's end, but not a readable directory
            raise MocapError(f"{path}: cannot read the zip archive ({type(error).__name__}: {error})") from None
        members = [m for m in archive.infolist() if not m.is_dir() and m.filename.lower().endswith(".bvh")]
        # A member over the bound is refused unread: it counts 0 towards the progress bar's total.
        items = [_Item(_clip_name(m.filename), f"{path}:{m.filename}", m.file_size if m.file_size <= inputs.MAX_INPUT_BYTES else 0,
                       path=str(path), member=m.filename) for m in members]
        return _Source(f"zip {path}", sorted(items, key=lambda i: i.name), _close=lambda: _ZIPS.pop(str(path)).close())
    if path.is_file() and _is_tar(path):
        return _Source(f"tar {path}", None, _stream=lambda: _tar_stream(path))
    if any(c in text for c in "*?["):
        # Anything but a folder: a FIFO or a device matched is that clip's failure, not skipped.
        matches = [Path(p) for p in globlib.glob(text, recursive=True) if p.lower().endswith(".bvh") and not os.path.isdir(p)]
        if not matches:
            raise MocapError(f"no .bvh files match {text}")
        # Clip names are paths below the pattern's last folder without wildcards.
        prefix = text[: min(text.index(c) for c in "*?[" if c in text)]
        root = Path(prefix) if prefix.endswith(os.sep) else Path(prefix).parent
        return _Source(f"glob {text}", _files(matches, root))
    if path.is_file():
        raise MocapError(f"{path}: not a folder, .zip or .tar(.gz/.xz) archive of BVH files")
    if path.exists():  # a FIFO, a device: never opened
        raise MocapError(f"{path}: {inputs.file_kind(path.stat().st_mode)}, not a folder, .zip or .tar(.gz/.xz) archive of BVH files")
    raise MocapError(f"{path}: no such folder or archive")


def _tar_stream(path: Path) -> Iterator[_Item]:
    """The .bvh members of a tar in archive order, each read as the stream passes it: only
    regular files of at most ``files.MAX_INPUT_BYTES`` (checked before reading), others are
    their clip's failure."""
    limit = inputs.MAX_INPUT_BYTES
    try:
        with tarfile.open(path, mode="r|*") as archive:
            for member in archive:
                if member.isdir() or not member.name.lower().endswith(".bvh"):
                    continue
                name, source = _clip_name(member.name), f"{path}:{member.name}"
                if not member.isfile():
                    yield _Item(name, source, 0, refused=f"{_tar_kind(member)}, not a regular file: only regular files are read")
                elif member.size > limit:
                    yield _Item(name, source, 0, refused=inputs.too_large(limit, source, member.size).strerror)
                else:
                    data = inputs.read_at_most(archive.extractfile(member), limit, source)
                    yield _Item(name, source, len(data), data=data)
    except (tarfile.TarError, EOFError, OSError) as error:
        raise MocapError(f"{path}: cannot read the tar archive ({type(error).__name__}: {error})") from None


def _tar_kind(member: tarfile.TarInfo) -> str:
    """What a tar member that is not a regular file is, in words (as files.file_kind)."""
    for test, kind in ((member.issym, "a symbolic link"), (member.islnk, "a hard link"), (member.isfifo, "a FIFO"),
                       (member.ischr, "a character device"), (member.isblk, "a block device")):
        if test():
            return kind
    return "a special file"


# ----------------------------------------------------------------------------- .npy files written in pieces


def _npy_header(dtype: np.dtype, shape: tuple) -> bytes:
    """A version 1.0 .npy header padded to exactly ``_HEADER_BYTES`` (64-byte aligned data)."""
    text = repr({"descr": np.lib.format.dtype_to_descr(dtype), "fortran_order": False, "shape": tuple(shape)}).encode("latin1")
    room = _HEADER_BYTES - 10 - len(text) - 1
    if room < 0:
        raise MocapError(f"array shape {shape} too long for the reserved .npy header")
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", _HEADER_BYTES - 10) + text + b" " * room + b"\n"


@dataclass
class _Kind:
    """How one kind of array is stored: dtype and the shape of one frame's row."""

    name: str
    dtype: np.dtype
    row: tuple[int, ...]
    description: str

    @property
    def row_bytes(self) -> int:
        return int(np.prod(self.row, dtype=np.int64)) * self.dtype.itemsize


def _kinds(keep: tuple[str, ...], joints: int) -> list[_Kind]:
    f32 = np.dtype(np.float32)
    table = {
        "positions": (f32, (joints, 3), "world positions [N, J, 3] (file units)"),
        "rotations": (f32, (joints, 4), "local rotations [N, J, 4] (x, y, z, w)"),
        "features": (f32, (len(FEATURE_NAMES),), "dynamic_features [N, 19] (causal defaults), columns FEATURE_NAMES"),
        "contacts": (np.dtype(bool), (2,), "foot_contacts [N, 2] (offline defaults; left, right)"),
        "activity": (f32, (joints,), "decomposition activity per joint [N, J] in [0, 1]"),
        "body": (f32, (joints, 4), "body-mechanics rotations B' [N, J, 4] (x, y, z, w)"),
        "expressive": (f32, (joints, 4), "filtered expressive rotations E* [N, J, 4] (x, y, z, w)"),
    }
    return [_Kind(k, *table[k]) for k in keep]


# ----------------------------------------------------------------------------- per-clip work


def decompose_many(rotations: list[np.ndarray], features: list[np.ndarray], model, float32: bool = False) -> list[dict[str, np.ndarray]]:
    """``decompose`` of many clips at once, from each clip's local ``rotations [F, J, 4]`` and
    model ``features [F, 19]``: one network call for all their frames (the network and the
    decoupling work frame by frame, so this is the per-clip result, with one kernel call that
    the Rust MLP spreads over its threads instead of a small call per clip). Returns per clip
    ``activity [F, J]``, ``body`` and ``expressive [F, J, 4]`` (float64). ``float32``: run the
    network in float32, about 2x faster (on 12,689 Bandai frames: activity within 2e-5, body
    rotations within 3e-6 of the float64 result)."""
    if not rotations:
        return []
    original = np.concatenate(rotations)
    inputs = np.concatenate(features)
    body = model.predict_from_features(original, inputs.astype(np.float32) if float32 else inputs)
    expressive, recovered, activity = decouple_rotations(original, body, GAIN, EXPONENT)
    cuts = np.cumsum([len(r) for r in rotations])[:-1]
    return [
        {"activity": a, "body": b, "expressive": e}
        for a, b, e in zip(np.split(activity, cuts), np.split(recovered, cuts), np.split(expressive, cuts))
    ]


# ----------------------------------------------------------------------------- the run


@dataclass
class Summary:
    """What a run did: clips ok / failed (this run and earlier ones it resumed), frames,
    bytes of BVH text read (what was read, not what files or archive members declare: a file
    read whole, a member's decompressed bytes; a clip refused or failing before its text was
    held counts 0), seconds in total and split into reading headers, kernels (reading
    and parsing the MOTION blocks, FK, features, contacts, model) and writing (headers and
    kernels summed over the threads or workers that ran them: they overlap)."""

    out: str
    clips_ok: int = 0
    clips_failed: int = 0
    clips_resumed: int = 0
    frames: int = 0
    bytes_read: int = 0
    seconds: float = 0.0
    headers_s: float = 0.0
    kernels_s: float = 0.0
    write_s: float = 0.0
    batches: int = 0
    finished: bool = False
    failures: list = field(default_factory=list)

    @property
    def mb_per_s(self) -> float:
        return self.bytes_read / MB / self.seconds if self.seconds > 0 else 0.0

    def lines(self) -> list[str]:
        state = "finished" if self.finished else "stopped early (rerun the same command to resume)"
        out = [
            f"{self.out}: {state}; {self.clips_ok} clips ok, {self.clips_failed} failed"
            + (f" ({self.clips_resumed} done by an earlier run)" if self.clips_resumed else ""),
            f"  {self.frames:,} frames, {self.bytes_read / MB:.1f} MB of BVH read this run in {self.seconds:.2f} s ({self.mb_per_s:.0f} MB/s)",
            f"  time: headers {self.headers_s:.2f} s, kernels (MOTION blocks, FK, features, contacts, model) {self.kernels_s:.2f} s, "
            f"writing {self.write_s:.2f} s (headers and kernels run in two threads or on a cluster's workers, overlapping the writing)",
        ]
        for failure in self.failures[:10]:
            out.append(f"  failed: {failure['error']}")
        if len(self.failures) > 10:
            out.append(f"  ... and {len(self.failures) - 10} more failures (see manifest.json)")
        return out


def _journal_entries(path: Path) -> list[dict]:
    """Complete lines of the journal; a torn last line (a crash mid-append) is cut off."""
    if not path.exists():
        return []
    data = path.read_bytes()
    entries, good = [], 0
    for line in data.split(b"\n"):
        if not line.strip():
            good += len(line) + 1
            continue
        try:
            entries.append(json.loads(line))
        except ValueError:
            break
        good += len(line) + 1
    if good < len(data):
        with open(path, "r+b") as handle:
            handle.truncate(min(good, len(data)))
    return entries


def _append_line(path: Path, record: dict) -> None:
    """One journal line, appended in one write after the batch's rows: a run that is killed
    leaves the journal ending at its last complete batch. (Not fsynced: after a power cut the
    run may need redoing; the finished dataset is synced before its manifest appears.)"""
    with open(path, "ab") as handle:
        handle.write(json.dumps(record).encode() + b"\n")


def _model_label(model) -> str | None:
    return None if model is None else "shipped" if model == "" else str(Path(model).resolve())


def preprocess(
    src: str | os.PathLike,
    out: str | os.PathLike,
    keep: tuple[str, ...] | list[str] | str | None = None,
    model: str | os.PathLike | None = None,
    *,
    batch_mb: float = 64.0,
    max_batches: int | None = None,
    model_float32: bool = False,
    cluster=None,
    overwrite: bool = False,
    progress: bool = True,
) -> Summary:
    """Preprocess every clip of ``src`` (folder, glob, .zip or tar) into the dataset folder ``out``.

    ``keep``: kinds to store (see :data:`KINDS`; a comma-separated string or a sequence;
    default positions, features, contacts, plus activity with a model). ``model``: a
    body-mechanics model file, or ``""`` for the shipped one (needed for activity, body,
    expressive). Clips are read in batches of about ``batch_mb`` MB of BVH text.
    ``max_batches``: stop after that many batches (the run resumes when called again with the
    same arguments). ``model_float32``: run the network in float32 (see :func:`decompose_many`).
    ``cluster``: run the batches on a Dask cluster instead of this process: a
    ``distributed.Client``, a scheduler address, or ``"local"`` (a LocalCluster of 2 worker
    processes on 127.0.0.1); needs the ``[distributed]`` extra. The batches are written in order
    as they come back, so the dataset is the one a single-machine run writes.
    ``overwrite``: redo a folder that already holds a finished dataset.
    Returns a :class:`Summary`.
    """
    started = time.perf_counter()
    out = Path(out)
    keep = _keep(keep, model)
    if any(k in MODEL_KINDS for k in keep) and model is None:
        raise MocapError(f"keeping {', '.join(k for k in keep if k in MODEL_KINDS)} needs a body-mechanics model (--model)")
    if batch_mb <= 0:
        raise MocapError(f"batch_mb must be positive, got {batch_mb}")
    body_model = _load_model(model) if model is not None else None
    # The source in one canonical form (a resumed run may spell it otherwise: relative, through a link).
    source = os.path.realpath(src) if Path(src).exists() else os.path.abspath(src)
    options = {"keep": list(keep), "model": _model_label(model), "model_float32": bool(model_float32), "source": source,
               "backend": get_backend()}

    finished_manifest(out)  # refuse a folder that is not ours before putting a lock file in it
    source = open_source(src)  # a bad SRC fails before OUT is touched
    try:
        out.mkdir(parents=True, exist_ok=True)
        with FolderLock(out):  # held to the end: a second run on OUT fails at once
            manifest = finished_manifest(out)  # again: another run may have changed it meanwhile
            if manifest is not None:
                if not overwrite:
                    return _already_finished(out, manifest, options, started)
                remove_partial(out)
                remove_dataset(out)
            return _run(source, out, keep, options, body_model, model, model_float32, batch_mb, max_batches, cluster, progress, started)
    finally:
        source.close()


def _already_finished(out: Path, manifest: dict, options: dict, started: float) -> Summary:
    """A rerun over a finished dataset never rewrites it. After a run killed between putting its
    manifest in place and removing ``.partial``, the same command finishes the cleanup and says
    what the dataset holds; otherwise redoing it needs ``overwrite``."""
    if not (out / PARTIAL).exists():
        raise MocapError(f"{out} already holds a finished dataset (manifest.json); use --overwrite to redo it")
    if manifest.get("options") != options:
        raise MocapError(f"{out} holds a finished dataset made with other options ({manifest.get('options')}); "
                         "use --overwrite to redo it with these")
    verify(out, manifest)
    remove_partial(out)
    return _summary_of(out, manifest, started)


def _summary_of(out: Path, manifest: dict, started: float) -> Summary:
    """The summary of a dataset an earlier run finished."""
    done = len(manifest["clips"]) + len(manifest["failures"])
    return Summary(str(out), clips_ok=len(manifest["clips"]), clips_failed=len(manifest["failures"]), clips_resumed=done,
                   failures=manifest["failures"], finished=True, seconds=time.perf_counter() - started)


def _run(source: _Source, out: Path, keep, options, body_model, model, model_float32, batch_mb, max_batches, cluster, progress, started) -> Summary:
    """The run itself, in ``out`` locked and free of other datasets: start or resume the journal
    in ``out/.partial``, process what it has not done, then move the finished files into place."""
    partial = out / PARTIAL
    partial.mkdir(exist_ok=True)
    if (partial / MANIFEST).exists():  # interrupted while moving the finished files into place
        return _summary_of(out, _move_into_place(out), started)

    summary = Summary(str(out))
    run_file = partial / RUN
    if run_file.exists():
        previous = json.loads(run_file.read_text())
        if previous.get("options") != options:
            raise MocapError(f"{partial} holds an interrupted run with other options ({previous.get('options')}); "
                             f"rerun with those, or delete {partial} to start again")
    else:
        atomic_write(run_file, json.dumps({"options": options}).encode())

    journal = partial / JOURNAL
    entries = _journal_entries(journal)
    done = Counter(name for e in entries for name in e["items"])
    clips = [c for e in entries for c in e["clips"]]
    failures = [f for e in entries for f in e["failures"]]
    taken = {c["name"] for c in clips} | {f["name"] for f in failures}  # a second clip of a name fails
    skeleton = next((e["skeleton"] for e in entries if e.get("skeleton")), None)
    rows = entries[-1]["rows"] if entries else 0
    summary.clips_resumed = sum(done.values())
    kinds = _kinds(keep, len(skeleton["names"])) if skeleton else None
    if kinds:
        _cut_data_files(partial, kinds, rows)

    client, close_client = _client(cluster) if cluster is not None else (None, lambda: None)
    syncer = ThreadPoolExecutor(max_workers=1)  # flushes each batch's rows to disk in the background
    try:
        if source.items is not None:
            todo = iter(list(_not_done(source.items, done)))
            total_bytes = sum(i.size for i in _not_done(source.items, done))
        else:
            todo, total_bytes = _not_done(source, done), None
        total_files = len(source.items) if source.items is not None else None
        bar = Progress(total_bytes, "preprocess", "B", enabled=progress)
        batch_number = len(entries)
        stopped: list[bool] = []
        flushes: list = []
        batches = _batched(todo, batch_mb * MB)
        if cluster is None:
            results = _local(batches, max_batches, stopped, keep, body_model, model_float32)
        else:
            results = _on_cluster(batches, max_batches, stopped, client, (keep, model, model_float32, get_backend()))
        for batch, outcomes, headers_s, kernels_s in results:
            record = {"batch": batch_number, "items": [item.name for item in batch], "clips": [], "failures": []}
            nbytes = sum(outcome.get("bytes", 0) for outcome in outcomes)  # bytes read, not sizes declared
            times = [time.perf_counter()]
            arrays, rows, skeleton = _collect(batch, outcomes, skeleton, keep, record, rows, taken)
            if "skeleton" in record:  # the first clip parsed: now the row shapes are known
                kinds = _kinds(keep, len(skeleton["names"]))
                _cut_data_files(partial, kinds, 0)
            for kind in kinds or ():
                if record["clips"]:
                    _append_rows(partial / data_file(kind.name), arrays[kind.name], kind.dtype)
            if record["clips"]:
                flushes.append(syncer.submit(_flush, [partial / data_file(kind.name) for kind in kinds]))
            _raise_failed_flush(flushes)  # before the journal vouches for rows the disk did not take
            record["rows"] = rows
            _append_line(journal, record)
            times.append(time.perf_counter())
            del outcomes, arrays
            clips += record["clips"]
            failures += record["failures"]
            frames = sum(c["frames"] for c in record["clips"])
            summary.headers_s += headers_s
            summary.kernels_s += kernels_s
            summary.write_s += times[1] - times[0]
            summary.frames += frames
            summary.bytes_read += nbytes
            summary.batches += 1
            summary.clips_ok += len(record["clips"])
            summary.clips_failed += len(record["failures"])
            summary.failures += record["failures"]
            batch_number += 1
            files = len(clips) + len(failures)
            bar.update(nbytes, f"{files}{f'/{total_files}' if total_files else ''} files, {sum(c['frames'] for c in clips):,} frames")
        if not stopped:
            t0 = time.perf_counter()
            syncer.shutdown()
            _raise_failed_flush(flushes, wait=True)
            _finish(out, kinds or [], clips, failures, skeleton, rows, options)
            summary.write_s += time.perf_counter() - t0
            summary.finished = True
        bar.close()
    finally:
        syncer.shutdown()
        close_client()
    summary.clips_ok, summary.clips_failed = len(clips), len(failures)
    summary.failures = failures
    summary.seconds = time.perf_counter() - started
    return summary


def _keep(keep, model) -> tuple[str, ...]:
    if keep is None:
        return DEFAULT_KEEP + (("activity",) if model is not None else ())
    if isinstance(keep, str):
        keep = [k.strip() for k in keep.split(",") if k.strip()]
    unknown = [k for k in keep if k not in KINDS]
    if unknown or not keep:
        raise MocapError(f"unknown kinds to keep: {', '.join(unknown) or '(none given)'}; choose from {', '.join(KINDS)}")
    return tuple(k for k in KINDS if k in keep)  # a fixed order, whatever the order given


def _load_model(model):
    from .decoupling.body_model import BodyModel

    return BodyModel.load(None if model == "" else model)


def _batched(items: Iterator[_Item], batch_bytes: float) -> Iterator[list[_Item]]:
    """Batches of about ``batch_bytes`` of BVH text. The first ones are smaller (1/8, 1/4,
    1/2 of it): nothing overlaps the parsing of the first batch, so a small one starts the
    pipeline sooner."""
    batch, size, limit = [], 0, batch_bytes / 8
    for item in items:
        batch.append(item)
        size += item.size
        if size >= limit:
            yield batch
            batch, size, limit = [], 0, min(2 * limit, batch_bytes)
    if batch:
        yield batch


def _local(batches, limit, stopped, keep, model, model_float32) -> Iterator[tuple]:
    """``(batch, outcomes, seconds reading headers, seconds in the kernels)`` of each batch in
    order, on this machine, up to ``limit`` batches (``stopped`` gets an entry if more were left).

    A pipeline of threads: header threads read the next batches' headers (from a zip: decompress
    them) and prepare the kernel's arguments (:func:`_prepare`), one kernel thread runs each
    batch's kernel call, whose Rust threads use every core, and the caller writes the batch
    before (and takes the next batches: a tar stream is decompressed there). Headers and writing are
    Python and hold the GIL, the kernels do not: separate threads keep the cores busy with
    kernels while they run. (When each thread did a whole batch, the threads fell into step,
    reading headers at the same time on one core and then running kernels at the same time:
    0.92 s for dataset-2 against 0.80 s.) Two header threads on two cores or more decompress
    two batches of a zip at once."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    in_flight = 3  # batches read ahead of the one being written: bounds memory
    running: deque = deque()
    header_pool, kernel_pool = _Workers(min(2, cores), "headers"), _Workers(1, "kernels")
    # Held during each kernel call. A stopped run waits for the call under way (it ends: its reads
    # never block) so that no thread is in Rust when the interpreter exits (one returning from
    # Rust then aborts the process: "FATAL: exception not rethrown"), but it does not wait for
    # a header thread (pure Python) or for batches not started.
    in_kernels, stopping = threading.Lock(), threading.Event()

    def compute(batch, prepared: Future):
        ready = prepared.result()
        with in_kernels:
            if stopping.is_set():
                raise CancelledError
            return _kernels(batch, ready, keep, model, model_float32)

    def submit_next() -> None:
        batch = next(batches, None)  # taken here, in order (a tar stream is read here)
        if batch is not None:
            running.append((batch, kernel_pool.submit(compute, batch, header_pool.submit(_prepare, batch, keep, model))))

    try:
        for _ in range(in_flight):
            submit_next()
        for count in itertools.count():
            if not running:
                return
            if limit is not None and count >= limit:
                stopped.append(True)
                return
            batch, computed = running.popleft()
            result = computed.result()
            submit_next()
            yield (batch, *result)
    finally:  # done, or stopped by Ctrl-C or an error: the batches read ahead are dropped
        header_pool.close()
        kernel_pool.close()
        with in_kernels:
            stopping.set()


class _Workers:
    """Daemon threads taking tasks in order (``submit`` returns a Future), for the pipeline of
    :func:`_local`. Not a ThreadPoolExecutor: that one runs all its queued tasks when closed and
    joins its threads at interpreter exit, so a Ctrl-C waited for the batches read ahead (5.5 s
    with a model) or for ever for a blocked read. ``close`` cancels the tasks not started; a
    running one ends on its own and nothing waits for it here."""

    def __init__(self, count: int, name: str):
        self._count = count
        self._tasks: queue.SimpleQueue = queue.SimpleQueue()
        for number in range(count):
            threading.Thread(target=self._work, name=f"preprocess-{name}-{number}", daemon=True).start()

    def submit(self, call, *args) -> Future:
        future: Future = Future()
        self._tasks.put((future, call, args))
        return future

    def _work(self) -> None:
        while (task := self._tasks.get()) is not None:
            future, call, args = task
            if future.set_running_or_notify_cancel():
                try:
                    future.set_result(call(*args))
                except BaseException as error:  # handed to whoever takes the result
                    future.set_exception(error)
            del task, future, call, args  # hold no batch while waiting for the next task

    def close(self) -> None:
        while True:
            try:
                task = self._tasks.get_nowait()
            except queue.Empty:
                break
            if task is not None:
                task[0].cancel()
        for _ in range(self._count):
            self._tasks.put(None)


def _client(cluster):
    """A Dask client for ``cluster`` (a Client, an address or "local") and how to close what was opened here."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise MocapError("running on a cluster needs Dask: pip install 'expressive-mocap[distributed]'") from None
    if isinstance(cluster, Client):
        return cluster, lambda: None
    if cluster == "local":
        local = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None)
        client = Client(local)

        def close():
            client.close()
            local.close()

        return client, close
    client = Client(str(cluster))
    return client, client.close


_MODELS: dict = {}


def _remote_batch(batch: list[_Item], keep, model, model_float32: bool, backend: str) -> tuple[list[dict], float, float]:
    """What a cluster's worker does with one batch: :func:`_compute`, with the model loaded
    once per worker process and the client's backend."""
    from .backend import use_backend

    if model is not None and model not in _MODELS:
        _MODELS[model] = _load_model(model)
    with use_backend(backend):
        return _compute(batch, keep, _MODELS.get(model), model_float32)


def _on_cluster(batches, limit, stopped, client, work) -> Iterator[tuple]:
    """As :func:`_local`, the batches run on a Dask cluster: a few per worker in flight,
    results taken back in order (memory stays bounded, the output is written in order)."""
    from collections import deque

    window = 2 * max(1, len(client.scheduler_info().get("workers", {})))
    running: deque = deque()
    for count, batch in enumerate(batches):
        if limit is not None and count >= limit:
            stopped.append(True)
            break
        running.append((batch, client.submit(_remote_batch, batch, *work, pure=False)))
        if len(running) >= window:
            done, future = running.popleft()
            yield (done, *future.result())
    while running:
        done, future = running.popleft()
        yield (done, *future.result())


def _compute(batch: list[_Item], keep: tuple[str, ...], model, model_float32: bool) -> tuple[list[dict], float, float]:
    """The work on one batch, one outcome per item: ``{"error": text}`` for a clip that failed,
    else ``frames``, ``fps``, ``frame_time`` and ``values`` (kind -> array as stored);
    ``skeleton`` (names, parents) for every clip whose header was read. Plain values, so a
    cluster's worker can send them back. Returns the outcomes and the seconds spent preparing
    (headers) and in the kernels. The two steps, :func:`_prepare` and :func:`_kernels`, are run
    by different threads on this machine."""
    return _kernels(batch, _prepare(batch, keep, model), keep, model, model_float32)


@dataclass
class _Group:
    """The clips of one hierarchy in a batch, ready for one kernel call: their indices in the
    batch, headers, the kernel's per-clip tuples, the skeleton's parents and gait joints."""

    indices: list[int]
    headers: list
    clips: list[tuple]
    parents: np.ndarray
    gait_joints: list[int]


@dataclass
class _Prepared:
    """A batch with its headers read: outcomes so far (errors, skeletons), its groups, seconds taken."""

    outcomes: list[dict]
    groups: list[_Group]
    seconds: float


def _prepare(batch: list[_Item], keep: tuple[str, ...], model) -> _Prepared:
    """The Python work before a batch's kernels: the clips' headers, from the files' first bytes
    (:func:`~expressive_mocap.bvh.read_header`; zip members are decompressed here, a tar's
    members come already read), each hierarchy's joint roles and each clip's body scale and
    channel layout."""
    start = time.perf_counter()
    outcomes: list[dict] = [{} for _ in batch]
    by_hierarchy: dict[tuple, list] = {}  # (names, parents) -> [(index, header, text for the kernel)]
    for k, item in enumerate(batch):
        try:
            header, text = item.header(outcomes[k])
        except BVHError as error:
            outcomes[k]["error"] = str(error)
            continue
        shape = (tuple(header.skeleton.names), tuple(header.skeleton.parents.tolist()))
        outcomes[k]["skeleton"] = shape
        outcomes[k]["bone_length"] = bone_length(header.skeleton)
        by_hierarchy.setdefault(shape, []).append((k, header, text))
    use_model = any(k in MODEL_KINDS for k in keep)
    needs_roles = use_model or "features" in keep or "contacts" in keep
    groups = []
    for members in by_hierarchy.values():
        skeleton = members[0][1].skeleton
        try:
            roles = JointRoles.find(skeleton) if needs_roles else None
            if use_model:
                model.check_skeleton(skeleton)
        except MocapError as error:  # the hierarchy lacks a role, or does not fit the model
            for k, _, _ in members:
                outcomes[k]["error"] = f"{batch[k].source}: {error}"
            continue
        # Without features or contacts the gait joints and body scale are not used.
        scale = (lambda s: (actor_height(s, roles), hips_rest_height(s, roles))) if roles else (lambda s: (1.0, 1.0))
        clips = [ops.ClipInput.of(text, h, *scale(h.skeleton)) for _, h, text in members]
        gait_joints = roles.gait_joints if roles else [0] * 7
        groups.append(_Group([k for k, _, _ in members], [h for _, h, _ in members], clips,
                             np.ascontiguousarray(skeleton.parents, dtype=np.int64), gait_joints))
    return _Prepared(outcomes, groups, time.perf_counter() - start)


def _kernels(batch: list[_Item], prepared: _Prepared, keep: tuple[str, ...], model, model_float32: bool) -> tuple[list[dict], float, float]:
    """Everything else of each clip (reading the file, its MOTION block, FK, features, contacts)
    as one task of one kernel call per hierarchy, clips in parallel (``clip_pipeline_many``; the
    NumPy twin composes the other kernels' twins), then the model on the whole batch."""
    start = time.perf_counter()
    outcomes = prepared.outcomes
    use_model = any(k in MODEL_KINDS for k in keep)
    requests = ([(0.0, None)] if "features" in keep else []) + ([(None, model.thigh_reference)] if use_model else [])
    kept = []  # (index, local rotations, model features) of each clip for the model
    for group in prepared.groups:
        results = ops.clip_pipeline_many(
            group.clips, group.parents, group.gait_joints, ops.GaitSettings(HEIGHT_THRESHOLD, SPEED_THRESHOLD, MIN_DURATION, FLOOR_PERCENTILE),
            ops.PipelineOutputs(positions="positions" in keep, rotations="rotations" in keep or use_model,
                                features=tuple(ops.FeatureRequest(*r) for r in requests), contacts="contacts" in keep, float32=not use_model),
            max_bytes=inputs.MAX_INPUT_BYTES,
        )
        for k, header, clip, result in zip(group.indices, group.headers, group.clips, results):
            if isinstance(clip.source, str) and not isinstance(result, OSError):  # the kernel read the file whole
                outcomes[k]["bytes"] = batch[k].size
            if isinstance(result, Exception):
                outcomes[k]["error"] = str(_clip_error(batch[k], header, result))
                continue
            positions, rotations, features, contacts = result
            values = {"positions": positions, "rotations": rotations, "contacts": contacts}
            if "features" in keep:
                values["features"] = features[0]
            outcomes[k].update(frames=header.frames, fps=1.0 / header.frame_time, frame_time=header.frame_time,
                               values={kind: v.astype(np.float32) if v.dtype == np.float64 else v for kind, v in values.items() if kind in keep})
            if use_model:
                kept.append((k, rotations, features[-1]))
    if use_model:
        parts = decompose_many([r for _, r, _ in kept], [f for _, _, f in kept], model, model_float32)
        for (k, _, _), clip_parts in zip(kept, parts):
            outcomes[k]["values"].update({kind: v.astype(np.float32) for kind, v in clip_parts.items() if kind in keep})
    return outcomes, prepared.seconds, time.perf_counter() - start


def _clip_error(item: _Item, header, error: Exception) -> BVHError:
    """The BVHError of a clip whose number block (ParseError) or file (OSError) could not be read."""
    if isinstance(error, OSError):
        return read_error(item.source, error)
    return block_error(item.source, header, error)


def _collect(batch: list[_Item], outcomes: list[dict], skeleton, keep, record: dict, rows: int, taken: set) -> tuple[dict, int, dict | None]:
    """The batch's outcomes in order: clips and failures into ``record`` (a clip of another
    skeleton than the dataset's, the first parsed clip's, is a failure; so is a clip whose name
    ``taken``, the names taken so far, already holds), their arrays per kind. Returns the
    arrays, the row count after the batch and the dataset's skeleton."""
    arrays: dict[str, list] = {k: [] for k in keep}
    for item, outcome in zip(batch, outcomes):
        shape, error = outcome.get("skeleton"), outcome.get("error")
        if item.name in taken:
            shape, error = None, (f"{item.source}: a clip named {item.name!r} is already in the dataset "
                                  "(names are paths below the source without .bvh; one dataset holds each name once)")
        taken.add(item.name)
        if shape is not None:
            names, parents = list(shape[0]), list(shape[1])
            if skeleton is None:
                skeleton = record["skeleton"] = {"names": names, "parents": parents, "bone_length": outcome["bone_length"]}
            elif names != skeleton["names"] or parents != skeleton["parents"]:
                error = (f"{item.source}: another skeleton ({len(names)} joints) than the dataset's "
                         f"({len(skeleton['names'])} joints, {', '.join(skeleton['names'][:3])}, ...): one dataset holds one skeleton")
            elif error is None:
                error = _units_error(item, outcome["bone_length"], skeleton)
        if error is not None:
            record["failures"].append({"name": item.name, "source": item.source, "error": error})
            continue
        for kind in keep:
            arrays[kind].append(outcome["values"][kind])
        record["clips"].append({"name": item.name, "source": item.source, "frames": outcome["frames"],
                                "fps": outcome["fps"], "frame_time": outcome["frame_time"], "start": rows})
        rows += outcome["frames"]
    return arrays, rows, skeleton


def bone_length(skeleton) -> float:
    """The summed lengths of a skeleton's bones (offsets, End Sites included), in file units:
    what tells a skeleton in metres from the same one in centimetres, whatever its axes."""
    sites = sum(float(np.linalg.norm(offset)) for _, offset in skeleton.end_sites)
    return float(np.linalg.norm(skeleton.offsets, axis=1).sum()) + sites


# People differ in size by less than this factor; units (cm/inch 2.54, m/cm 100) by more.
SAME_UNITS_RATIO = 2.0


def _units_error(item: _Item, length: float, skeleton: dict) -> str | None:
    """Why a clip of the dataset's skeleton is in other units than its first clip, or None:
    positions in two units in one array would be silently wrong."""
    reference = skeleton.get("bone_length")
    if not reference or not length:
        return None
    ratio = length / reference
    if 1 / SAME_UNITS_RATIO <= ratio <= SAME_UNITS_RATIO:
        return None
    return (f"{item.source}: its bones are {ratio:.3g}x as long as the dataset's (summed {length:.4g} against {reference:.4g}): "
            "other units? One dataset holds one unit: rescale it first (expressive-mocap convert --scale)")


def _cut_data_files(partial: Path, kinds: list[_Kind], rows: int) -> None:
    """Each data file holding its reserved header and exactly ``rows`` rows (a resumed run cuts
    off what an interrupted batch appended after the last journal line)."""
    for kind in kinds:
        path = partial / data_file(kind.name)
        with open(path, "r+b" if path.exists() else "w+b") as handle:
            handle.truncate(_HEADER_BYTES + rows * kind.row_bytes)
            handle.seek(0)
            handle.write(_npy_header(kind.dtype, (0, *kind.row)))  # a placeholder until the end


def _not_done(items, done: Counter) -> Iterator[_Item]:
    """The items an earlier run has not journaled: ``done`` counts the names journaled (a name
    twice when a second clip of that name failed as a duplicate)."""
    left = Counter(done)
    for item in items:
        if left[item.name] > 0:
            left[item.name] -= 1
            continue
        yield item


def _append_rows(path: Path, values: list[np.ndarray], dtype: np.dtype) -> None:
    """Append clips' rows to a data file; a failure (a full disk) names the file, and the run
    resumes from its last journaled batch."""
    try:
        with open(path, "ab") as handle:
            for array in values:
                handle.write(np.ascontiguousarray(array, dtype=dtype).data)  # no copy
    except OSError as error:
        raise MocapError(f"cannot write {path}: {error.strerror or error} (rerun the same command to resume)") from None


def _raise_failed_flush(flushes: list, wait: bool = False) -> None:
    """Raise the error of a background flush that failed (a disk reports a full or failing
    device when data are synced, and only once), dropping those that succeeded."""
    for future in list(flushes):
        if wait or future.done():
            flushes.remove(future)
            future.result()


def _flush(paths: list[Path]) -> None:
    """Have the disk write these files' data now (fdatasync), in the background while the next
    batches are computed: otherwise it all waits for the final sync, which nothing overlaps."""
    for path in paths:
        try:
            handle = os.open(path, os.O_RDONLY)
            try:
                getattr(os, "fdatasync", os.fsync)(handle)  # macOS has no fdatasync
            finally:
                os.close(handle)
        except OSError as error:
            raise MocapError(f"cannot write {path}: {error.strerror or error} (rerun the same command to resume)") from None


def _finish(out: Path, kinds: list[_Kind], clips: list, failures: list, skeleton, rows: int, options: dict) -> None:
    """Headers into the data files, offsets and manifest (with each file's size and mtime) into
    .partial, then everything renamed into ``out``, manifest last."""
    from . import __version__

    partial = out / PARTIAL
    for kind in kinds:
        path = partial / data_file(kind.name)
        try:
            with open(path, "r+b") as handle:
                handle.write(_npy_header(kind.dtype, (rows, *kind.row)))
                handle.flush()
                os.fsync(handle.fileno())
        except OSError as error:
            raise MocapError(f"cannot write {path}: {error.strerror or error} (rerun the same command to resume)") from None
    offsets = np.array([c["start"] for c in clips] + [rows], dtype=np.int64)
    buffer = io.BytesIO()
    np.save(buffer, offsets)
    atomic_write(partial / OFFSETS, buffer.getvalue())
    manifest = {
        "format": FORMAT,
        "version": VERSION,
        "package_version": __version__,
        "created": datetime.datetime.now().isoformat(timespec="seconds"),
        "options": options,
        "skeleton": skeleton,
        "frames": rows,
        "kinds": {k.name: {"file": data_file(k.name), "dtype": k.dtype.name, "shape": [rows, *k.row], "description": k.description} for k in kinds},
        "files": file_record(partial, [OFFSETS] + [data_file(k.name) for k in kinds]),
        "feature_names": list(FEATURE_NAMES) if any(k.name == "features" for k in kinds) else None,
        "clips": clips,
        "failures": failures,
    }
    atomic_write(partial / MANIFEST, json.dumps(manifest, indent=1).encode())
    _move_into_place(out)


def _move_into_place(out: Path) -> dict:
    """Rename the finished files of ``out/.partial`` into ``out`` (manifest last), then drop
    .partial; returns the manifest. Safe to repeat after a crash: files already moved are
    skipped. Only the fixed names of the format move: a manifest cannot name others."""
    partial = out / PARTIAL
    manifest = read_manifest(partial / MANIFEST)
    for name in [data_file(k) for k in manifest["kinds"]] + [OFFSETS]:
        if (partial / name).exists():
            os.replace(partial / name, out / name)
    os.replace(partial / MANIFEST, out / MANIFEST)
    remove_partial(out)
    return manifest


__all__ = ["KINDS", "Dataset", "Summary", "load_dataset", "open_source", "preprocess"]
