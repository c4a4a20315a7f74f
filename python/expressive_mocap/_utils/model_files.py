"""Model files read as data: ``.npz`` of plain arrays plus one JSON object, never pickles, their
sizes bounded before loading and their arrays checked."""

from __future__ import annotations

import io
import json
import os
import zipfile

import numpy as np

from ..errors import MocapError
from .files import read_input

# The arrays of a model file may not take more than this, checked from their .npy headers before
# loading (a zip bomb of zeros compresses 1000 to 1, and a header alone can claim terabytes).
MAX_MODEL_BYTES = 256 << 20
MODEL_ZIP_SLACK = 1 << 20  # a model file is its arrays plus the zip's own headers


def read_model_file(source: str | os.PathLike | bytes, what: str) -> tuple[dict[str, np.ndarray], dict, str]:
    """The arrays, the JSON metadata (the array ``meta``, a JSON object) and a name for errors of
    an ``.npz`` model file, read with ``allow_pickle=False`` after checking from the ``.npy`` headers
    that its arrays hold no objects and take at most :data:`MAX_MODEL_BYTES`. Any damage is a
    :class:`MocapError` naming the file and ``what`` it should be; checking the arrays against the
    model's schema is the caller's part."""
    name = "<bytes>" if isinstance(source, (bytes, bytearray)) else str(source)
    try:
        data = (
            bytes(source)
            if isinstance(source, (bytes, bytearray))
            else read_input(source, MAX_MODEL_BYTES + MODEL_ZIP_SLACK)
        )
    except OSError as error:
        raise MocapError(f"{name}: cannot read the model file: {error.strerror or error}") from None
    try:
        _check_array_sizes(data)
        with np.load(io.BytesIO(data), allow_pickle=False) as archive:
            arrays = {k: archive[k] for k in archive.files}
        meta = json.loads(str(arrays.pop("meta")))
        if not isinstance(meta, dict):
            raise ValueError(f"the metadata is a JSON {type(meta).__name__}, not an object")
    except (zipfile.BadZipFile, EOFError, OSError, KeyError, ValueError, TypeError, RuntimeError, MemoryError) as error:
        # Damaged zips and arrays raise any of these; a pickled array raises ValueError; metadata
        # nested past Python's stack RecursionError (a RuntimeError).
        raise MocapError(f"{name}: not a readable {what} ({type(error).__name__}: {error})") from None
    return arrays, meta, name


def _check_array_sizes(data: bytes) -> None:
    """Read only the ``.npy`` headers of an ``.npz`` archive: refuse object arrays (pickles) and
    arrays that would take more than :data:`MAX_MODEL_BYTES` together, before loading any."""
    total = 0
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        for info in archive.infolist():
            with archive.open(info) as member:
                version = np.lib.format.read_magic(member)
                if version not in ((1, 0), (2, 0)):
                    raise ValueError(f"{info.filename}: .npy format version {version} is not read")
                read_header = (
                    np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
                )
                shape, _, dtype = read_header(member)
            if dtype.hasobject:
                raise ValueError(f"{info.filename} holds Python objects (pickles are never loaded)")
            total += int(np.prod(shape, dtype=object)) * dtype.itemsize
            if total > MAX_MODEL_BYTES:
                raise ValueError(f"its arrays would take more than {MAX_MODEL_BYTES} bytes")


def finite_array(arrays: dict, key: str, name: str, shape: tuple | None = None, kinds: str = "fiu") -> np.ndarray:
    """``arrays[key]``, checked: present, of a numeric dtype kind in ``kinds``, all finite, and of
    ``shape`` when given; a :class:`MocapError` naming the file and the key otherwise."""
    if key not in arrays:
        raise MocapError(f"{name}: model file lacks {key!r}")
    value = arrays[key]
    if (
        value.dtype.kind not in kinds
        or (shape is not None and value.shape != tuple(shape))
        or not np.isfinite(value.astype(np.float64)).all()
    ):
        expected = f"shape {list(shape)}" if shape is not None else "any shape"
        raise MocapError(
            f"{name}: {key!r} has shape {list(value.shape)} / dtype {value.dtype}, expected finite "
            f"numbers of {expected}"
        )
    return value


def check_keys(arrays: dict, allowed, name: str) -> None:
    """A model file holds the arrays of its format and nothing else."""
    unknown = sorted(set(arrays) - set(allowed))
    if unknown:
        raise MocapError(f"{name}: unexpected arrays in the model file: {', '.join(map(repr, unknown[:5]))}")


__all__ = ["MAX_MODEL_BYTES", "MODEL_ZIP_SLACK", "check_keys", "finite_array", "read_model_file"]
