"""The dataset format on disk: its fixed file names, the kinds of arrays, and the checks of a
manifest and of the files it vouches for.

A dataset folder holds, by fixed names only, ``manifest.json``, ``offsets.npy`` and one
``{kind}.npy`` per kind kept (see :data:`KINDS`), plus ``.lock`` (the run's advisory lock) and,
while a run is unfinished, ``.partial/`` (its journal and growing data files). Nothing here ever
opens or deletes a path a manifest names: names come from this module, so a tampered manifest
cannot point a reader or ``--overwrite`` outside the folder.

The manifest records each file's size and modification time as written. :func:`verify` checks
them, the ``.npy`` headers (dtype, shape, row count) and the clips' offsets against the
manifest, so a dataset that another process rewrote, a half-copied one, or one whose files do
not belong together is refused with a one-line error instead of being read as data.
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, DatasetError

FORMAT = "expressive-mocap dataset"
VERSION = 2  # 2: the manifest records each file's size and mtime; clips keyed by name
KINDS = (
    "positions",
    "rotations",
    "features",
    "contacts",
    "activity",
    "body",
    "expressive",
    "velocities",
    "accelerations",
    "root_velocity",
    "angular_velocities",
    "heading",
)
MODEL_KINDS = ("activity", "body", "expressive")
# Values of a rotation in each form of --rotations (representations.KINDS; not imported: reading stays light).
ROTATION_WIDTHS = {
    "quaternion": 4,
    "6d": 6,
    "matrix": 9,
    "axis-angle": 3,
    "euler": 3,
}  # the kinds that need a body-mechanics model
DEFAULT_KEEP = ("positions", "features", "contacts")  # + activity with a model
MANIFEST = "manifest.json"
OFFSETS = "offsets.npy"
PARTIAL = ".partial"
LOCK = ".lock"
MIRRORED = "@mirrored"  # what a mirror image's clip name adds to its clip's (--mirror)
JOURNAL = "journal.jsonl"  # in .partial: one line per batch written
RUN = "run.json"  # in .partial: the options of the interrupted run
MAX_MANIFEST_BYTES = 256 << 20  # ~1 M clips with their failures


def data_file(kind: str) -> str:
    """The one file name of a kind's array."""
    if kind not in KINDS:
        raise ArgumentError(f"unknown kind {kind!r}; choose from {', '.join(KINDS)}")
    return f"{kind}.npy"


OWN_FILES = frozenset([MANIFEST, OFFSETS, *map(data_file, KINDS)])  # what a finished dataset may hold
PARTIAL_FILES = OWN_FILES | {JOURNAL, RUN}  # what .partial may hold (and atomic writes' temporaries)


def read_manifest(path: Path) -> dict:
    """The manifest at ``path``, checked as far as it speaks of itself: our format and version,
    fixed file names, kinds and shapes consistent with the frame count, clips with unique names
    and contiguous rows. A :class:`DatasetError` naming the file otherwise."""
    try:
        info = os.stat(path)
        if not stat.S_ISREG(info.st_mode) or info.st_size > MAX_MANIFEST_BYTES:
            raise ValueError("not a regular file of at most 256 MiB")
        manifest = json.loads(path.read_bytes())
    except (OSError, ValueError, RecursionError) as error:  # RecursionError: JSON nested past the stack
        raise DatasetError(f"{path}: not a readable dataset manifest ({error})") from None
    problem = _manifest_problem(manifest)
    if problem:
        raise DatasetError(f"{path}: {problem}")
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
        if (
            not isinstance(shape, list)
            or not shape
            or shape[0] != rows
            or not all(isinstance(n, int) and n >= 0 for n in shape)
        ):
            return f"{kind}: shape {shape} does not hold the {rows} frames of the dataset"
    return _options_problem(manifest, kinds) or _clips_problem(clips, rows)


def _options_problem(manifest: dict, kinds: dict) -> str | None:
    """Why the manifest's rotation form, up axis or statistics do not fit its kinds, or None."""
    options = manifest.get("options") or {}
    form = str(options.get("rotations") or "quaternion").partition(":")[0]
    if form not in ROTATION_WIDTHS:
        return f"rotations in an unknown form {form!r}"
    if "rotations" in kinds and kinds["rotations"]["shape"][-1:] != [ROTATION_WIDTHS[form]]:
        return f"rotations of shape {kinds['rotations']['shape']} are not in the form {form!r} it names"
    fps = manifest.get("fps")
    if fps is not None and (isinstance(fps, bool) or not isinstance(fps, (int, float)) or not fps > 0):
        return f"a frame rate (fps) that is not a positive number: {str(fps)[:80]}"
    for key in ("up", "rotations_up"):
        up = manifest.get(key)
        if up is not None and (not isinstance(up, list) or len(up) != 3):
            return f"an up axis ({key}) that is not 3 numbers: {str(up)[:80]}"
    stats = manifest.get("stats") or {}
    if not isinstance(stats, dict):
        return "statistics that are not a mapping of kinds"
    for kind, entry in stats.items():
        row = kinds.get(kind, {}).get("shape", [None])[1:]
        if (
            kind not in kinds
            or not isinstance(entry, dict)
            or list(np.shape(entry.get("mean", 0.0))) != row
            or list(np.shape(entry.get("std", 0.0))) != row
        ):
            return f"statistics of {kind!r} that do not fit its kinds' rows"
    return None


def _clips_problem(clips: list, rows: int) -> str | None:
    """Why the manifest's clip records are not unique names of contiguous rows filling ``rows``."""
    start, names = 0, set()
    for clip in clips:
        if (
            not isinstance(clip, dict)
            or not isinstance(clip.get("name"), str)
            or not isinstance(clip.get("frames"), int)
        ):
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
    :class:`DatasetError` naming the file otherwise."""
    recorded = manifest.get("files", {}) if manifest["version"] >= 2 else None
    names = [OFFSETS] + [data_file(k) for k in manifest["kinds"]]
    if recorded is not None and sorted(recorded) != sorted(names):
        raise DatasetError(f"{folder / MANIFEST}: records files {sorted(recorded)}, expected {sorted(names)}")
    for name in names:
        _check_file(folder / name, None if recorded is None else recorded[name], check_times)
    for kind, entry in manifest["kinds"].items():
        _check_npy(folder / data_file(kind), np.dtype(entry["dtype"]), tuple(entry["shape"]))
    clips = manifest["clips"]
    _check_npy(folder / OFFSETS, np.dtype(np.int64), (len(clips) + 1,))
    offsets = np.load(folder / OFFSETS)
    expected_offsets = np.array([c["start"] for c in clips] + [manifest["frames"]], dtype=np.int64)
    if not np.array_equal(offsets, expected_offsets):
        raise DatasetError(f"{folder / OFFSETS}: the clips' rows differ from the manifest's")


def _check_file(path: Path, expected: dict | None, check_times: bool) -> None:
    """``path`` is a regular file of the size (and mtime) the manifest records, when it records them."""
    try:
        info = os.lstat(path)
    except OSError as error:
        raise DatasetError(f"{path}: part of the dataset, cannot be read: {error.strerror or error}") from None
    if not stat.S_ISREG(info.st_mode):
        raise DatasetError(f"{path}: part of the dataset, is not a regular file")
    if expected is None:
        return
    if info.st_size != expected["bytes"]:
        raise DatasetError(
            f"{path}: {info.st_size:,} bytes, the manifest says {expected['bytes']:,}: "
            "the file was changed after the dataset was written"
        )
    if check_times and info.st_mtime_ns != expected["mtime_ns"]:
        raise DatasetError(
            f"{path}: modified after the dataset was written (a copy that did not keep modification "
            "times? load with check_times=False)"
        )


def _check_npy(path: Path, dtype: np.dtype, shape: tuple) -> None:
    """The ``.npy`` file at ``path`` holds a C-ordered ``dtype`` array of ``shape`` that fills it."""
    try:
        with open(path, "rb") as handle:
            version = np.lib.format.read_magic(handle)
            if version not in ((1, 0), (2, 0)):
                raise ValueError(f".npy format version {version}")
            if version == (1, 0):
                found_shape, fortran, found_dtype = np.lib.format.read_array_header_1_0(handle)
            else:
                found_shape, fortran, found_dtype = np.lib.format.read_array_header_2_0(handle)
            header_end = handle.tell()
        size = os.stat(path).st_size
    except (OSError, ValueError) as error:
        raise DatasetError(f"{path}: not a readable .npy file ({error})") from None
    if found_dtype != dtype or tuple(found_shape) != shape or fortran:
        raise DatasetError(f"{path}: holds {found_dtype} {list(found_shape)}, the manifest says {dtype} {list(shape)}")
    expected = header_end + int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
    if size != expected:
        raise DatasetError(f"{path}: {size:,} bytes where a {dtype} array of shape {list(shape)} takes {expected:,}")


__all__ = [
    "DEFAULT_KEEP",
    "FORMAT",
    "JOURNAL",
    "KINDS",
    "LOCK",
    "MANIFEST",
    "MAX_MANIFEST_BYTES",
    "MIRRORED",
    "MODEL_KINDS",
    "OFFSETS",
    "OWN_FILES",
    "ROTATION_WIDTHS",
    "PARTIAL",
    "PARTIAL_FILES",
    "RUN",
    "VERSION",
    "data_file",
    "file_record",
    "read_manifest",
    "verify",
]
