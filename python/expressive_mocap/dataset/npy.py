"""The data files of a run, ``.npy`` files written in pieces: a header of fixed size reserved
at the start (a placeholder until the end, when the row count is known), each batch's rows
appended, synced in the background, cut back to the last journaled batch on resuming."""

from __future__ import annotations

import os
import struct
from concurrent.futures import Future
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..decoupling.features import FEATURE_NAMES
from ..errors import ArgumentError, DatasetError
from .format import data_file

HEADER_BYTES = 128  # room reserved at the start of each data file for its .npy header


def npy_header(dtype: np.dtype, shape: tuple) -> bytes:
    """A version 1.0 .npy header padded to exactly ``HEADER_BYTES`` (64-byte aligned data)."""
    descr = np.lib.format.dtype_to_descr(dtype)
    text = repr({"descr": descr, "fortran_order": False, "shape": tuple(shape)}).encode("latin1")
    room = HEADER_BYTES - 10 - len(text) - 1
    if room < 0:
        raise ArgumentError(f"array shape {shape} too long for the reserved .npy header")
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", HEADER_BYTES - 10) + text + b" " * room + b"\n"


@dataclass
class Kind:
    """How one kind of array is stored: dtype and the shape of one frame's row."""

    name: str
    dtype: np.dtype
    row: tuple[int, ...]
    description: str

    @property
    def row_bytes(self) -> int:
        return int(np.prod(self.row, dtype=np.int64)) * self.dtype.itemsize


def kinds_for(keep: tuple[str, ...], joints: int, width: int = 4) -> list[Kind]:
    """How each kind kept is stored, for a skeleton of ``joints`` joints whose rotations take
    ``width`` values each (the form of ``--rotations``; the manifest's options name it)."""
    f32 = np.dtype(np.float32)
    table = {
        "positions": (f32, (joints, 3), "positions [N, J, 3] (file units; frame: options.positions, axes: up)"),
        "rotations": (f32, (joints, width), f"local rotations [N, J, {width}] (form: options.rotations)"),
        "features": (f32, (len(FEATURE_NAMES),), "dynamic_features [N, 19] (causal defaults), columns FEATURE_NAMES"),
        "contacts": (np.dtype(bool), (2,), "foot_contacts [N, 2] (offline defaults; left, right)"),
        "activity": (f32, (joints,), "decomposition activity per joint [N, J] in [0, 1]"),
        "body": (f32, (joints, 4), "body-mechanics rotations B' [N, J, 4] (x, y, z, w)"),
        "expressive": (f32, (joints, 4), "filtered expressive rotations E* [N, J, 4] (x, y, z, w)"),
        "velocities": (f32, (joints, 3), "velocities of the positions [N, J, 3] (units/s; heading: in each frame's)"),
        "accelerations": (f32, (joints, 3), "accelerations of the positions [N, J, 3] (units/s^2)"),
        "root_velocity": (
            f32,
            (4,),
            "hips' velocity in its heading frame [N, 4]: left, up, forward (units/s), yaw rate (rad/s)",
        ),
        "angular_velocities": (
            f32,
            (joints, 3),
            "local rotation rates [N, J, 3] (rotation vectors, rad/s, parent's axes)",
        ),
        "heading": (f32, (3,), "each frame's heading frame [N, 3]: origin x, z (units), yaw (rad), harmonised axes"),
    }
    return [Kind(k, *table[k]) for k in keep]


def _cannot_write(path: Path, error: OSError) -> DatasetError:
    return DatasetError(f"cannot write {path}: {error.strerror or error} (rerun the same command to resume)")


def cut_data_files(partial: Path, kinds: list[Kind], rows: int) -> None:
    """Each data file holding its reserved header and exactly ``rows`` rows (a resumed run cuts
    off what an interrupted batch appended after the last journal line)."""
    for kind in kinds:
        path = partial / data_file(kind.name)
        with open(path, "r+b" if path.exists() else "w+b") as handle:
            handle.truncate(HEADER_BYTES + rows * kind.row_bytes)
            handle.seek(0)
            handle.write(npy_header(kind.dtype, (0, *kind.row)))  # a placeholder until the end


def append_rows(path: Path, values: list[np.ndarray], dtype: np.dtype) -> None:
    """Append clips' rows to a data file; a failure (a full disk) names the file, and the run
    resumes from its last journaled batch."""
    try:
        with open(path, "ab") as handle:
            for array in values:
                handle.write(np.ascontiguousarray(array, dtype=dtype).data)  # no copy
    except OSError as error:
        raise _cannot_write(path, error) from None


def flush(paths: list[Path]) -> None:
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
            raise _cannot_write(path, error) from None


def raise_failed_flush(flushes: list[Future], wait: bool = False) -> None:
    """Raise the error of a background flush that failed (a disk reports a full or failing
    device when data are synced, and only once), dropping those that succeeded."""
    for future in list(flushes):
        if wait or future.done():
            flushes.remove(future)
            future.result()


def write_final_header(path: Path, kind: Kind, rows: int) -> None:
    """The data file's real header, for its ``rows`` rows, written over the placeholder and synced."""
    try:
        with open(path, "r+b") as handle:
            handle.write(npy_header(kind.dtype, (rows, *kind.row)))
            handle.flush()
            os.fsync(handle.fileno())
    except OSError as error:
        raise _cannot_write(path, error) from None


__all__ = [
    "HEADER_BYTES",
    "Kind",
    "append_rows",
    "cut_data_files",
    "flush",
    "kinds_for",
    "npy_header",
    "raise_failed_flush",
    "write_final_header",
]
