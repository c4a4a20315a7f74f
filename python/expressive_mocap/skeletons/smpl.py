"""SMPL-family parameter files (AMASS's ``.npz``) read as a :class:`~expressive_mocap.motion.Motion`
on the body model's kinematic tree, with the body model's own joint places for the given shape.

A parameter file holds ``poses [F, 3J]`` (axis-angle per joint, radians: SMPL's 24 joints, 72
numbers; SMPL-H's 52, 156; SMPL-X's 55, 165), ``trans [F, 3]`` (metres), ``betas [B]`` (the
shape), ``gender`` and ``mocap_framerate`` (``mocap_frame_rate`` in AMASS's SMPL-X files). The body
model is the user's own licensed file (never shipped or downloaded by the package): an ``.npz``
with ``v_template [V, 3]``, ``shapedirs [V, 3, B']``, ``J_regressor [J, V]`` and ``kintree_table
[2, J]`` (its other arrays, the skinning weights, pose blend shapes and faces, are not needed for
the joints and not read). Both are loaded without pickles (``allow_pickle=False``), their sizes
bounded before loading.
"""

from __future__ import annotations

import io
import os
import zipfile
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from .._utils.files import read_input
from .._utils.model_files import MAX_MODEL_BYTES, MODEL_ZIP_SLACK
from ..errors import ArgumentError, ModelError
from ..motion import Motion, Skeleton
from ..rotations import quat
from .layouts import _SMPL

_BODY = tuple(name for name, _ in _SMPL[:22])
_FINGERS = tuple(f"{finger}{k}" for finger in ("index", "middle", "pinky", "ring", "thumb") for k in (1, 2, 3))
_HANDS = tuple(f"{side}_{finger}" for side in ("left", "right") for finger in _FINGERS)
# Joint names by joint count: SMPL, SMPL-H (the hands after the body, left first) and SMPL-X.
JOINT_NAMES: dict[int, tuple[str, ...]] = {
    24: tuple(name for name, _ in _SMPL),
    52: _BODY + _HANDS,
    55: _BODY + ("jaw", "left_eye_smplhf", "right_eye_smplhf") + _HANDS,
}
_ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
_CHANNELS = ("Zrotation", "Yrotation", "Xrotation")
# AMASS is Z up; the package is Y up: turning the world by -90 degrees about X takes +Z to +Y.
Z_UP_TO_Y_UP = quat.about("X", -90.0)
_MODEL_KEYS = ("v_template", "shapedirs", "J_regressor", "kintree_table")


class SmplBody(NamedTuple):
    """A body model's arrays that the joints need, loaded once (:func:`load_body_model`) for
    many parameter files, and the name its errors give."""

    arrays: dict[str, np.ndarray]
    name: str


def load_body_model(source: str | os.PathLike | Mapping[str, np.ndarray]) -> SmplBody:
    """The arrays of an SMPL-family body model file (or a mapping of them) that :func:`read_smpl`
    needs, for reading many parameter files with one model (a model file is tens of megabytes)."""
    return SmplBody(*_load(source, "SMPL body model (.npz)", _MODEL_KEYS, ModelError))


def read_smpl(
    params: str | os.PathLike | bytes | Mapping[str, np.ndarray],
    body_model: str | os.PathLike | Mapping[str, np.ndarray] | SmplBody,
    fps: float | None = None,
    name: str | None = None,
) -> Motion:
    """The motion of an SMPL-family parameter file (AMASS ``.npz``) on ``body_model``'s skeleton.

    The rest joints are ``J = J_regressor @ (v_template + shapedirs[..., :B] @ betas[:B])`` (``B``
    the betas both files have); joint ``j``'s offset is ``J[j] - J[parent]``, the root's ``J[0]``;
    the local rotations are the axis-angle ``poses``; the root is placed at ``trans + J[0]`` as the
    model's forward pass places the pelvis. Names: SMPL's (``pelvis``, ``left_hip``, ...), SMPL-H's
    hand joints (``left_index1`` ... ``right_thumb3``), SMPL-X's ``jaw`` and eyes, by joint count
    (``joint<j>`` for another count); parents from ``kintree_table``. The joints are listed depth
    first, as a BVH file nests them (SMPL lists them breadth first): find them by name.

    **Y up**: AMASS's world is Z up; the motion is given in the package's Y-up convention, the
    root's rotation and translation turned by -90 degrees about X (so ``(x, y, z)`` becomes
    ``(x, z, -y)`` for every joint position; the model's rest pose is Y up already). Lengths in
    metres. ``frame_time`` is ``1 / mocap_framerate``, or ``1 / fps`` where the file has no rate
    (``fps`` is only used then). ``params``/``body_model``: ``.npz`` paths, or mappings of arrays;
    ``params`` also the bytes of an ``.npz`` (an archive's member), ``name`` then naming it in
    errors; ``body_model`` also a :class:`SmplBody` loaded once for many files.

    Raises :class:`ArgumentError` for a bad parameter file and :class:`ModelError` for a bad
    body model (or one whose joint count does not match the poses), naming the file.
    """
    arrays, name = _load(params, "SMPL parameter file (AMASS .npz)", ("poses", "trans", "betas"), ArgumentError, name)
    model, model_name = body_model if isinstance(body_model, SmplBody) else load_body_model(body_model)
    poses = _numbers(arrays, "poses", name, 2, ArgumentError)
    frames = len(poses)
    if frames == 0 or poses.shape[1] % 3:
        raise ArgumentError(f"{name}: 'poses' has shape {list(poses.shape)}, expected [F >= 1, 3 x joints]")
    trans = _numbers(arrays, "trans", name, 2, ArgumentError)
    if trans.shape != (frames, 3):
        raise ArgumentError(f"{name}: 'trans' has shape {list(trans.shape)}, expected [{frames}, 3] (one per pose)")
    betas = _numbers(arrays, "betas", name, None, ArgumentError)
    if betas.ndim > 2 or (betas.ndim == 2 and len(betas) != 1):
        raise ArgumentError(f"{name}: 'betas' has shape {list(betas.shape)}, expected [B] (one shape)")
    betas = betas.reshape(-1)
    frame_time = _frame_time(arrays, name, fps)

    template = _numbers(model, "v_template", model_name, 2, ModelError)
    vertices = len(template)
    if template.shape[1] != 3 or vertices == 0:
        raise ModelError(f"{model_name}: 'v_template' has shape {list(template.shape)}, expected [V, 3]")
    shapedirs = _numbers(model, "shapedirs", model_name, 3, ModelError)
    if shapedirs.shape[:2] != (vertices, 3):
        raise ModelError(f"{model_name}: 'shapedirs' has shape {list(shapedirs.shape)}, expected [{vertices}, 3, B]")
    regressor = _numbers(model, "J_regressor", model_name, 2, ModelError)
    joints = poses.shape[1] // 3
    if regressor.shape[1] != vertices:
        raise ModelError(f"{model_name}: 'J_regressor' has shape {list(regressor.shape)}, expected [J, {vertices}]")
    if len(regressor) != joints:
        raise ModelError(
            f"{model_name}: the body model has {len(regressor)} joints, but {name}'s poses have {joints} "
            f"({poses.shape[1]} numbers a frame); use the body model the parameters were fitted with"
        )
    parents = _parents(model, model_name, joints)

    shape = min(len(betas), shapedirs.shape[2])
    rest = regressor @ (template + shapedirs[..., :shape] @ betas[:shape])  # [J, 3]
    smpl_names = JOINT_NAMES.get(joints, tuple(f"joint{j}" for j in range(joints)))
    # SMPL lists its joints breadth first; a BVH file nests them, depth first.
    order = _depth_first(parents)
    position = np.empty(joints, dtype=np.int64)
    position[order] = np.arange(joints)
    names = tuple(smpl_names[j] for j in order)
    rest, poses = rest[order], poses.reshape(frames, joints, 3)[:, order]
    parents = np.where(parents[order] < 0, -1, position[np.maximum(parents[order], 0)])
    offsets = rest - rest[np.maximum(parents, 0)]
    offsets[0] = rest[0]
    skeleton = Skeleton(
        names=names,
        parents=parents,
        offsets=offsets,
        channels=(_ROOT_CHANNELS,) + (_CHANNELS,) * (joints - 1),
        end_sites=_end_sites(parents, offsets),
    )
    rotations = quat.exp(poses)
    rotations[:, 0] = quat.normalize(quat.mul(Z_UP_TO_Y_UP, rotations[:, 0]))
    translations = np.repeat(offsets[None], frames, axis=0)
    translations[:, 0] = quat.rotate(Z_UP_TO_Y_UP, trans + rest[0])
    return Motion(skeleton, rotations, translations, frame_time)


def _depth_first(parents: np.ndarray) -> list[int]:
    """Joint order with every joint after its parent, depth first, children in their order."""
    children: dict[int, list[int]] = {}
    for j, p in enumerate(parents.tolist()):
        children.setdefault(p, []).append(j)
    order, stack = [], [0]
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(children.get(j, [])))
    return order


def _end_sites(parents: np.ndarray, offsets: np.ndarray) -> tuple:
    """An End Site on every joint without children, half its own bone on along that bone (BVH
    readers expect one there; SMPL's joints have no tips)."""
    leaves = sorted(set(range(1, len(parents))) - set(parents.tolist()))
    return tuple((j, tuple((0.5 * offsets[j]).tolist())) for j in leaves)


def _load(
    source, what: str, keys: tuple[str, ...], error: type[Exception], name: str | None = None
) -> tuple[dict[str, np.ndarray], str]:
    """The arrays of an ``.npz`` (its path or bytes, or a mapping, named ``<what>``) and a name for
    errors (``name``, else the path). Only the arrays a reader needs are loaded, pickles never
    (``allow_pickle=False``), their sizes checked from the ``.npy`` headers first: an object array
    elsewhere in the file is not read."""
    if isinstance(source, Mapping):
        return {k: np.asarray(v) for k, v in source.items()}, name or f"<{what}>"
    if isinstance(source, bytes):
        data, name = source, name or f"<{what}>"
    else:
        name = name or str(source)
        try:
            data = read_input(source, MAX_MODEL_BYTES + MODEL_ZIP_SLACK)
        except OSError as problem:
            raise error(f"{name}: cannot read the {what}: {problem.strerror or problem}") from None
    wanted = keys + ("mocap_framerate", "mocap_frame_rate")
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            members = {info.filename.removesuffix(".npy"): info for info in archive.infolist()}
            total = 0
            for key in wanted:
                if key in members:
                    with archive.open(members[key]) as member:
                        version = np.lib.format.read_magic(member)
                        read_header = getattr(np.lib.format, f"read_array_header_{version[0]}_{version[1]}")
                        header_shape, _, dtype = read_header(member)
                    total += int(np.prod(header_shape, dtype=object)) * dtype.itemsize
            if total > MAX_MODEL_BYTES:
                raise ValueError(f"its arrays would take more than {MAX_MODEL_BYTES} bytes")
        with np.load(io.BytesIO(data), allow_pickle=False) as archive:
            return {k: archive[k] for k in wanted if k in archive.files}, name
    except (zipfile.BadZipFile, EOFError, OSError, AttributeError, ValueError, TypeError, MemoryError) as problem:
        # A pickled array raises ValueError; an unknown .npy version AttributeError.
        raise error(f"{name}: not a readable {what} ({type(problem).__name__}: {problem})") from None


def _numbers(arrays: dict, key: str, name: str, ndim: int | None, error: type[Exception]) -> np.ndarray:
    """``arrays[key]`` as finite float64 of ``ndim`` dimensions, or ``error`` naming the file."""
    if key not in arrays:
        found = ", ".join(map(repr, sorted(arrays))) or "none of those read"
        raise error(f"{name}: no {key!r} array, which this file needs (found: {found})")
    value = arrays[key]
    if value.dtype.kind not in "fiu" or (ndim is not None and value.ndim != ndim):
        dims = f"{ndim}-dimensional " if ndim is not None else ""
        raise error(f"{name}: {key!r} has shape {list(value.shape)} / dtype {value.dtype}, expected {dims}numbers")
    value = value.astype(np.float64)
    if not np.isfinite(value).all():
        raise error(f"{name}: {key!r} holds non-finite values (NaN or infinity)")
    return value


def _frame_time(arrays: dict, name: str, fps: float | None) -> float:
    key = next((k for k in ("mocap_framerate", "mocap_frame_rate") if k in arrays), None)
    if key is None:
        if fps is None:
            raise ArgumentError(f"{name}: no 'mocap_framerate' in the file: give the frame rate (--fps)")
        rate = float(fps)
    else:
        value = arrays[key]
        if value.dtype.kind not in "fiu" or value.size != 1:
            got = f"shape {list(value.shape)} / dtype {value.dtype}"
            raise ArgumentError(f"{name}: {key!r} has {got}, expected a number")
        rate = float(value.reshape(-1)[0])
    if not (np.isfinite(rate) and rate > 0):
        raise ArgumentError(f"{name}: the frame rate {rate:g} is not a positive number")
    return 1.0 / rate


def _parents(model: dict, name: str, joints: int) -> np.ndarray:
    """Row 0 of ``kintree_table``, the root's (a huge number or -1) made -1; each joint after its parent."""
    if "kintree_table" not in model:
        raise ModelError(f"{name}: no 'kintree_table' array (expected [2, {joints}]: parents, joints)")
    table = model["kintree_table"]
    if table.dtype.kind not in "iu" or table.shape != (2, joints):
        raise ModelError(
            f"{name}: 'kintree_table' has shape {list(table.shape)} / dtype {table.dtype}, "
            f"expected integers [2, {joints}]"
        )
    parents = table[0].astype(np.int64)  # the root's 2^32 - 1 (or -1) is set to -1 below
    parents[0] = -1
    later = parents[1:]
    if not ((later >= 0) & (later < np.arange(1, joints))).all():
        raise ModelError(f"{name}: 'kintree_table' does not list each joint after its parent, the root first")
    return parents


__all__ = ["JOINT_NAMES", "Z_UP_TO_Y_UP", "read_smpl"]
