"""Joint layouts of position arrays (what motion-generation models and pose estimators write) and
reading such arrays from ``.npy`` / ``.npz`` files.

A :class:`Layout` names a position array's joints in order, their parents and, where the names
alone would not tell, which joint plays which body role (a joint map, as ``--map`` files give it):

- ``humanml3d``: the 22 SMPL body joints in SMPL's order (HumanML3D, text-to-motion models);
- ``smpl24``: those and the two hand joints (SMPL's 24);
- ``h36m17``: the 17 joints of Human3.6M's common convention (pose estimators);
- a JSON file ``{"joints": [...], "parents": [...], "map": {role: joint}, "fps": F}`` (``map``
  and ``fps`` optional: roles the names and topology do not find, in the ``--map`` format);
- the ``joints`` and ``parents`` arrays of an ``.npz`` written by ``expressive-mocap positions``.
"""

from __future__ import annotations

import io
import json
import pickle
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._utils.files import read_input
from ..body.jointmap import JointMap
from ..errors import MocapError
from ..rotations import quat

_SMPL = (
    ("pelvis", -1),
    ("left_hip", 0),
    ("right_hip", 0),
    ("spine1", 0),
    ("left_knee", 1),
    ("right_knee", 2),
    ("spine2", 3),
    ("left_ankle", 4),
    ("right_ankle", 5),
    ("spine3", 6),
    ("left_foot", 7),
    ("right_foot", 8),
    ("neck", 9),
    ("left_collar", 9),
    ("right_collar", 9),
    ("head", 12),
    ("left_shoulder", 13),
    ("right_shoulder", 14),
    ("left_elbow", 16),
    ("right_elbow", 17),
    ("left_wrist", 18),
    ("right_wrist", 19),
    ("left_hand", 20),
    ("right_hand", 21),
)
_SMPL_MAP: dict[str, object] = {"hips": "pelvis", "spine": ["spine1", "spine2", "spine3"], "chest": "spine3"}
_SMPL_MAP.update({"neck": "neck", "head": "head"})
for _side in ("left", "right"):
    _SMPL_MAP.update(
        {
            f"{_side}_clavicle": f"{_side}_collar",
            f"{_side}_upper_arm": f"{_side}_shoulder",
            f"{_side}_forearm": f"{_side}_elbow",
            f"{_side}_hand": f"{_side}_wrist",
            f"{_side}_upper_leg": f"{_side}_hip",
            f"{_side}_lower_leg": f"{_side}_knee",
            f"{_side}_foot": f"{_side}_ankle",
            f"{_side}_toes": f"{_side}_foot",
        }
    )

_H36M = (
    ("hip", -1),
    ("right_hip", 0),
    ("right_knee", 1),
    ("right_foot", 2),
    ("left_hip", 0),
    ("left_knee", 4),
    ("left_foot", 5),
    ("spine", 0),
    ("thorax", 7),
    ("neck_nose", 8),
    ("head", 9),
    ("left_shoulder", 8),
    ("left_elbow", 11),
    ("left_wrist", 12),
    ("right_shoulder", 8),
    ("right_elbow", 14),
    ("right_wrist", 15),
)
_H36M_MAP: dict[str, object] = {"hips": "hip", "spine": ["spine", "thorax"], "chest": "thorax"}
_H36M_MAP.update({"neck": "neck_nose", "head": "head"})
for _side in ("left", "right"):
    _H36M_MAP.update(
        {
            f"{_side}_upper_arm": f"{_side}_shoulder",
            f"{_side}_forearm": f"{_side}_elbow",
            f"{_side}_hand": f"{_side}_wrist",
            f"{_side}_upper_leg": f"{_side}_hip",
            f"{_side}_lower_leg": f"{_side}_knee",
            f"{_side}_foot": f"{_side}_foot",
        }
    )


class Layout(NamedTuple):
    """A position array's joints: ``names`` in the array's order, ``parents`` (-1 for the root,
    each parent before its child), ``joint_map`` (role -> joint name, ``spine`` -> names; None:
    found from the names and topology) and the frame rate its source writes (None: unknown)."""

    name: str
    names: tuple[str, ...]
    parents: tuple[int, ...]
    joint_map: dict | None
    fps: float | None = None


def _builtin(name: str, joints, joint_map: dict, fps: float) -> Layout:
    names = tuple(n for n, _ in joints)
    return Layout(name, names, tuple(p for _, p in joints), joint_map, fps)


LAYOUTS = {
    "humanml3d": _builtin("humanml3d", _SMPL[:22], dict(_SMPL_MAP), 20.0),  # HumanML3D's 20 fps
    "smpl24": _builtin("smpl24", _SMPL, dict(_SMPL_MAP), 30.0),
    "h36m17": _builtin("h36m17", _H36M, dict(_H36M_MAP), 50.0),  # Human3.6M's 50 Hz
}


def layout_of(name: str) -> Layout:
    """A layout by name (:data:`LAYOUTS`) or from a JSON file (see the module's notes)."""
    if name in LAYOUTS:
        return LAYOUTS[name]
    path = Path(name)
    if path.suffix.lower() != ".json" and not path.exists():
        raise MocapError(f"layout {name!r}: expected {', '.join(LAYOUTS)} or a JSON layout file")
    try:
        data = json.loads(read_input(path).decode("utf-8", errors="replace"))
    except (OSError, ValueError, RecursionError) as error:
        raise MocapError(f"{path}: not a readable JSON layout ({error})") from None
    if not isinstance(data, dict) or "joints" not in data or "parents" not in data:
        raise MocapError(f'{path}: a layout is a JSON object with "joints" (names) and "parents" (indices)')
    joints, parents = data["joints"], data["parents"]
    if not (isinstance(joints, list) and all(isinstance(j, str) for j in joints)):
        raise MocapError(f'{path}: "joints" must be a list of joint names')
    if not (isinstance(parents, list) and len(parents) == len(joints) and all(type(p) is int for p in parents)):
        raise MocapError(f'{path}: "parents" must be a list of {len(joints)} integers (-1 for the root)')
    joint_map = data.get("map")
    if joint_map is not None:
        joint_map = _checked_map(path, joint_map)
    fps = data.get("fps")
    if fps is not None and not (isinstance(fps, (int, float)) and fps > 0):
        raise MocapError(f'{path}: "fps" must be a positive number')
    checked(Layout(path.name, tuple(joints), tuple(parents), joint_map, fps), path)
    return Layout(path.name, tuple(joints), tuple(parents), joint_map, None if fps is None else float(fps))


def _checked_map(path: Path, joint_map: object) -> dict:
    """A layout file's ``map`` checked as a ``--map`` file's table is."""
    from ..body.jointmap import map_table

    return map_table(joint_map, f"{path} (map)")


def checked(layout: Layout, where) -> Layout:
    """``layout`` if its parents make a tree whose parents come first, else a MocapError."""
    parents = layout.parents
    if not parents or parents[0] != -1 or any(not 0 <= p < j for j, p in enumerate(parents) if j):
        raise MocapError(
            f"{where}: the layout's first joint is its root (parent -1) and every parent comes before its child"
        )
    if len(set(layout.names)) != len(layout.names):
        raise MocapError(f"{where}: the layout names a joint twice")
    return layout


# Keys of an .npz tried in turn for the positions; else its only array.
NPZ_KEYS = ("positions", "joints", "motion", "poses", "data", "arr_0")


def read_positions(
    path, layout: Layout | None = None, sample: int = 0
) -> tuple[np.ndarray, Layout | None, float | None]:
    """The positions ``[F, J, 3]`` (float64) in the file ``path`` (``.npy`` or ``.npz``; see
    :func:`as_frames` for the shapes), the layout an ``.npz`` of ``expressive-mocap positions``
    carries (its ``joints`` and ``parents``; None otherwise) and its frame rate (from its
    ``frame_time`` or ``fps``; None otherwise). ``layout``: the one the array must fit."""
    array, arrays = _stored(path)
    carried: Layout | None = None
    fps = None
    names, parents = arrays.get("joints"), arrays.get("parents")
    if names is not None and parents is not None and names.dtype.kind == "U" and names.ndim == 1:
        carried = checked(Layout(Path(path).name, tuple(map(str, names)), tuple(map(int, parents)), None), path)
    if "frame_time" in arrays and arrays["frame_time"].size == 1 and float(arrays["frame_time"]) > 0:
        fps = 1.0 / float(arrays["frame_time"])
    elif "fps" in arrays and arrays["fps"].size == 1 and float(arrays["fps"]) > 0:
        fps = float(arrays["fps"])
    array = _trimmed(array, arrays.get("lengths"), sample)
    joints = len((layout or carried).names) if (layout or carried) is not None else None  # type: ignore[union-attr]
    return as_frames(np.asarray(array), joints, path, sample), carried, fps


def sample_count(path) -> int:
    """How many samples the positions file ``path`` holds: ``N`` of a batch (``[N, J, 3, F]`` or
    ``[N, F, J, 3]``), else 1."""
    array = _stored(path)[0]
    return int(array.shape[0]) if array.ndim == 4 else 1


def _stored(path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The positions array the file ``path`` stores (an ``.npy``'s, or an ``.npz``'s or pickled
    dict's under :data:`NPZ_KEYS`, else its only numeric array) and the arrays beside it."""
    data = read_input(path)
    try:
        loaded = np.load(io.BytesIO(data), allow_pickle=False)
    except ValueError as error:
        # NumPy takes any bytes that are not an array for a pickle: only a .npy is unpickled
        if "allow_pickle" not in str(error) or not data.startswith(b"\x93NUMPY"):
            raise MocapError(f"{path}: not a NumPy .npy or .npz file ({error})") from None
        loaded = _pickled_npy(data, path)
    except (OSError, EOFError) as error:
        raise MocapError(f"{path}: not a NumPy .npy or .npz file ({error})") from None
    if not isinstance(loaded, (np.lib.npyio.NpzFile, dict)):
        return loaded, {}
    if isinstance(loaded, dict):
        arrays = {str(k): np.asarray(v) for k, v in loaded.items() if isinstance(v, np.ndarray)}
    else:
        with loaded:
            arrays = {k: loaded[k] for k in loaded.files}
    numeric = {k: a for k, a in arrays.items() if a.dtype.kind in "fiu" and a.ndim >= 2}
    key = next((k for k in NPZ_KEYS if k in numeric), None)
    if key is None and len(numeric) == 1:
        key = next(iter(numeric))
    if key is None:
        raise MocapError(
            f"{path}: no positions array (tried the keys {', '.join(NPZ_KEYS)}, then the only array); "
            f"it holds {', '.join(f'{k} {list(a.shape)}' for k, a in arrays.items()) or 'nothing'}"
        )
    return numeric[key], arrays


# What a .npy of Python objects may hold to be read: NumPy arrays, their dtypes and scalars
# (plain numbers, strings, lists and dicts need no class). Unpickling anything else can run code.
_PICKLED_CLASSES = {
    (module, name)
    for module in ("numpy.core.multiarray", "numpy._core.multiarray")
    for name in ("_reconstruct", "scalar")
} | {("numpy", "ndarray"), ("numpy", "dtype")}


class _ArraysOnly(pickle.Unpickler):
    def find_class(self, module: str, name: str):
        if (module, name) not in _PICKLED_CLASSES:
            raise pickle.UnpicklingError(
                f"it holds a {module}.{name}, which is not read (only arrays, numbers and text)"
            )
        if module.startswith("numpy.core.") and np.lib.NumpyVersion(np.__version__) >= "2.0.0":
            module = "numpy._core." + module.removeprefix("numpy.core.")  # NumPy 1's pickles, read by NumPy 2
        return super().find_class(module, name)


def _pickled_npy(data: bytes, path) -> dict:
    """The dict a ``.npy`` of Python objects holds, as motion-diffusion-model writes its
    ``results.npy`` (``motion`` [N, J, 3, F], ``text``, ``lengths``...): unpickled with NumPy
    arrays, numbers, text and plain containers only (:data:`_PICKLED_CLASSES`), so that reading a
    file cannot run code from it."""
    stream = io.BytesIO(data)
    try:
        version = np.lib.format.read_magic(stream)
        shape, _, dtype = (
            np.lib.format.read_array_header_1_0(stream)
            if version == (1, 0)
            else np.lib.format.read_array_header_2_0(stream)
        )
        held = _ArraysOnly(stream).load() if dtype.hasobject and shape == () else None
    except (ValueError, pickle.UnpicklingError, EOFError, AttributeError, TypeError) as error:
        raise MocapError(f"{path}: a .npy of Python objects that cannot be read safely: {error}") from None
    if isinstance(held, np.ndarray) and held.shape == ():
        held = held.item()
    if not isinstance(held, dict):
        raise MocapError(
            f"{path}: a .npy of Python objects, expected one dict of arrays (as motion-diffusion-model writes)"
        )
    return held


def _trimmed(array: np.ndarray, lengths: np.ndarray | None, sample: int) -> np.ndarray:
    """A batch ``[N, J, 3, F]`` cut to its samples' own frame counts where the file gives them
    (``lengths`` [N]: the samples are padded to the longest), else as it is."""
    if lengths is None or array.ndim != 4 or lengths.shape != (array.shape[0],) or lengths.dtype.kind not in "iu":
        return array
    if not -len(lengths) <= sample < len(lengths):
        return array  # out of range: as_frames says so
    length = int(lengths[sample])
    return array[..., :length] if 2 <= length <= array.shape[-1] else array


def as_frames(array: np.ndarray, joints: int | None, where, sample: int = 0) -> np.ndarray:
    """``array`` as ``[F, J, 3]`` float64: from ``[F, J, 3]``, ``[N, J, 3, F]`` or ``[N, F, J, 3]``
    (sample ``sample`` of ``N``: text-to-motion models' batches, motion-diffusion-model's and
    T2M-GPT's) or ``[F, J*3]``; ``joints``: the layout's ``J``."""
    j = joints or "J"
    expected = f"[F, {j}, 3], [N, {j}, 3, F], [N, F, {j}, 3] or [F, {joints * 3 if joints else 'J*3'}]"
    shape = list(array.shape)
    if array.dtype.kind not in "fiu":
        raise MocapError(f"{where}: expected numbers, found an array of {array.dtype}")
    if array.ndim == 4 and (shape[2] == 3 or shape[3] == 3):
        if not -shape[0] <= sample < shape[0]:
            raise MocapError(f"{where}: --sample {sample} is out of range: the array {shape} holds {shape[0]} samples")
        array = np.moveaxis(array[sample], -1, 0) if shape[2] == 3 else array[sample]
    elif array.ndim == 2 and shape[1] % 3 == 0 and (joints is None or shape[1] == 3 * joints):
        array = array.reshape(shape[0], -1, 3)
    elif array.ndim != 3 or shape[2] != 3:
        raise MocapError(f"{where}: found an array of shape {shape}, expected {expected}")
    if joints is not None and array.shape[1] != joints:
        raise MocapError(f"{where}: found an array of shape {shape} ({array.shape[1]} joints), expected {expected}")
    if len(array) < 2:
        raise MocapError(f"{where}: found an array of shape {shape}: {len(array)} frame, at least 2 are needed")
    out = np.asarray(array, dtype=np.float64)
    if not np.isfinite(out).all():
        frame, joint = np.argwhere(~np.isfinite(out))[0, :2]
        raise MocapError(f"{where}: the position of joint {joint} at frame {frame} is not finite")
    return out


def upright(positions: np.ndarray, jmap: JointMap, up: str | None = None) -> tuple[np.ndarray, str]:
    """``positions [F, J, 3]`` turned so that up (``"y"``, ``"z"``, optionally signed; None: the
    axis nearest the mean line from the hips to the head) is +Y, and that axis's name."""
    if up is None:
        line = np.mean(positions[:, jmap["head"]] - positions[:, jmap["hips"]], axis=0)
        axis = int(np.argmax(np.abs(line)))
        sign = "-" if line[axis] < 0 else "+"
    else:
        given = up.strip().lower()
        sign, name = (given[0], given[1:]) if given[:1] in "+-" else ("+", given)
        if name not in ("x", "y", "z"):
            raise MocapError(f"up: expected y or z (optionally signed), got {up!r}")
        axis = "xyz".index(name)
    vector = np.zeros(3)
    vector[axis] = -1.0 if sign == "-" else 1.0
    name = f"{sign}{'XYZ'[axis]}"
    if name == "+Y":
        return positions, name
    return quat.rotate(quat.between(vector, np.array([0.0, 1.0, 0.0])), positions), name


__all__ = ["LAYOUTS", "NPZ_KEYS", "Layout", "as_frames", "layout_of", "read_positions", "sample_count", "upright"]
