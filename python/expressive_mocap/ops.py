"""The only code that calls the kernels: one wrapper per kernel family, which checks and
coerces its arguments (an :class:`~expressive_mocap.errors.ArgumentError` naming the bad one),
builds the kernel's argument objects (:class:`ChannelLayout`, :class:`MotionBlock`,
:class:`ClipInput`, :class:`GaitSettings`, :class:`PipelineOutputs`) and calls the backend in
use: the Rust kernel or its NumPy twin (see :mod:`expressive_mocap.backend`), which take the
same arguments and raise the same exceptions. Leading batch dimensions are folded into frames.

Arrays written by another thread during a call: the Rust kernels run without the GIL, so
other Python threads run meanwhile. Index arrays (``parents``, channel columns, gait joints)
and bool flags are copied before the GIL is released, so a write to them during a call has no
effect on it: it is computed from the values at the call, or refused with an ArgumentError. Float
arrays are read in place (copying them would cost as much as some kernels): a write to one
during a call gives results computed from a mix of its old and new values, and nothing worse
(no crash, no error). Don't write to a kernel's inputs while it runs if you need its result.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any, NamedTuple

import numpy as np

from . import motion  # its Euler order names (a module import: motion imports this module)
from .backend import kernels
from .errors import ArgumentError

ACTIVATIONS = ("tanh", "linear")  # of a dense layer (mlp_forward); the kernels implement these


def _array(name: str, value, dtype, kinds: str = "biuf") -> np.ndarray:
    """``value`` as a C-contiguous array of ``dtype``; an ArgumentError naming the argument when its
    dtype kind is not one of ``kinds`` (numbers; integers only where indices are expected)."""
    array = np.asarray(value)
    if array.dtype.kind not in kinds:
        wanted = "integers" if kinds == "iu" else "numbers"
        raise ArgumentError(f"argument `{name}`: expected an array of {wanted}, got dtype {array.dtype}")
    return np.ascontiguousarray(array, dtype=dtype)


def _f64(name: str, array, last: int) -> np.ndarray:
    array = _array(name, array, np.float64)
    if array.ndim < 2 or array.shape[-1] != last:
        raise ArgumentError(f"argument `{name}`: expected shape [..., J, {last}], got {list(array.shape)}")
    return array


def _orders(orders, joints: int) -> np.ndarray:
    """Orders as a ``[J, 3]`` uint8 array from one order ("ZXY") or one per joint."""
    if isinstance(orders, str):
        orders = [orders] * joints
    axes = np.array([motion.axes_of(o) if isinstance(o, str) else o for o in orders], dtype=np.uint8)
    if axes.shape != (joints, 3):
        raise ArgumentError(f"argument `orders`: expected one order or {joints} orders, got {axes.shape[0]}")
    return axes


def euler_to_quat(angles, orders) -> np.ndarray:
    """Euler angles ``[..., J, 3]`` in degrees -> unit quaternions ``[..., J, 4]`` (x, y, z, w).

    ``orders``: one order such as ``"ZXY"`` (the BVH channel order, intrinsic, first channel
    outermost, like SciPy's upper-case orders) or a sequence of ``J`` orders.
    """
    angles = _f64("angles", angles, 3)
    batch = angles.shape[:-2]
    flat = angles.reshape(-1, *angles.shape[-2:])
    return kernels().euler_to_quat(flat, _orders(orders, angles.shape[-2])).reshape(*batch, angles.shape[-2], 4)


def quat_to_euler(quats, orders) -> np.ndarray:
    """Unit quaternions ``[..., J, 4]`` (x, y, z, w) -> Euler angles ``[..., J, 3]`` in degrees.

    The middle angle lies in [-90, 90]; at gimbal lock the third angle is 0.
    """
    quats = _f64("quats", quats, 4)
    batch = quats.shape[:-2]
    flat = quats.reshape(-1, *quats.shape[-2:])
    return kernels().quat_to_euler(flat, _orders(orders, quats.shape[-2])).reshape(*batch, quats.shape[-2], 3)


def forward_kinematics(rotations, translations, parents) -> tuple[np.ndarray, np.ndarray]:
    """World rotations ``[F, J, 4]`` and positions ``[F, J, 3]`` from local ones.

    ``rotations [F, J, 4]`` (x, y, z, w) and ``translations [F, J, 3]`` are relative to each
    joint's parent; ``parents [J]`` lists each joint after its parent, roots as -1.
    """
    rotations = _f64("rotations", rotations, 4)
    translations = _f64("translations", translations, 3)
    parents = _array("parents", parents, np.int64, "iu")
    if parents.ndim != 1:
        raise ArgumentError(f"argument `parents`: expected shape [J], got {list(parents.shape)}")
    return kernels().forward_kinematics(rotations, translations, parents)


def forward_kinematics_many(motions) -> list[tuple[np.ndarray, np.ndarray]]:
    """World rotations and positions of many motions at once (in parallel across motions with
    the Rust kernels: the way to run FK over an archive of short clips)."""
    clips = [(m.rotations, m.translations, np.ascontiguousarray(m.skeleton.parents, dtype=np.int64)) for m in motions]
    return kernels().forward_kinematics_many(clips)


def decode_channels(values, rotation_columns, orders, position_columns, offsets) -> tuple[np.ndarray, np.ndarray]:
    """BVH channel values ``[F, C]`` -> local rotations ``[F, J, 4]`` and translations ``[F, J, 3]``.

    The layout arrays are those of :meth:`Skeleton.layout`; ``offsets [J, 3]`` are the rest offsets.
    """
    values = _array("values", values, np.float64)
    if values.ndim != 2:
        raise ArgumentError(f"argument `values`: expected shape [F, C], got {list(values.shape)}")
    rotation_columns = _array("rotation_columns", rotation_columns, np.int64, "iu")
    orders = _array("orders", orders, np.uint8, "iu")
    position_columns = _array("position_columns", position_columns, np.int64, "iu")
    offsets = _array("offsets", offsets, np.float64)
    joints = len(orders)
    for name, array in (
        ("rotation_columns", rotation_columns),
        ("orders", orders),
        ("position_columns", position_columns),
        ("offsets", offsets),
    ):
        if array.shape != (joints, 3):
            raise ArgumentError(
                f"argument `{name}`: expected shape [{joints}, 3] (one row per joint), got {list(array.shape)}"
            )
    return kernels().decode_channels(values, rotation_columns, orders, position_columns, offsets)


def decouple_rotations(original, body, gain: float, exponent: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split local rotations ``original [F, J, 4]`` given body-mechanics rotations ``body``:
    ``E = O B^-1``; activity ``A = clip((tanh(angle(E)) * gain)^exponent, 0, 1)`` ``[F, J]``;
    filtered expressive component ``E* = E^A``; recovered body mechanics ``B' = E*^-1 O``.
    Returns ``(E*, B', A)``; ``E* * B' = O`` exactly. ``gain`` and ``exponent`` have no default
    here: the package's are ``decouple.GAIN`` and ``decouple.EXPONENT``, passed by its callers."""
    original, body = _f64("original", original, 4), _f64("body", body, 4)
    batch = original.shape[:-1]
    e, b, a = kernels().decouple_rotations(_frames(original), _frames(body), float(gain), float(exponent))
    return e.reshape(original.shape), b.reshape(original.shape), a.reshape(batch)


def compose_rotations(expressive, body, scale: float = 1.0) -> np.ndarray:
    """``expressive^scale * body`` for rotations ``[F, J, 4]`` (modulation of expressiveness)."""
    expressive, body = _f64("expressive", expressive, 4), _f64("body", body, 4)
    return kernels().compose_rotations(_frames(expressive), _frames(body), float(scale)).reshape(body.shape)


def _frames(array: np.ndarray) -> np.ndarray:
    """``[..., J, k]`` as ``[F, J, k]``, all leading dimensions folded into frames."""
    return array.reshape(-1, *array.shape[-2:])


def _float(name: str, array) -> np.ndarray:
    """``array`` as a C-contiguous float32 or float64 array (float32 kept, other numbers float64)."""
    array = np.asarray(array)
    return _array(name, array, np.float32 if array.dtype == np.float32 else np.float64)


def mlp_forward(x, weights, biases, activations) -> np.ndarray:
    """Batched forward pass of a dense network: ``h = act_i(h @ weights[i] + biases[i])``.

    ``x [..., in]`` float32 or float64 (kept; other dtypes become float64), leading dimensions
    folded into rows; ``weights[i] [in_i, out_i]``, ``biases[i] [out_i]`` (cast to the dtype of
    ``x``), ``activations[i]`` ``"tanh"`` or ``"linear"``. Returns ``[..., out]``.
    """
    x = _float("x", x)
    if x.ndim < 1:
        raise ArgumentError(f"argument `x`: expected shape [..., in], got {list(x.shape)}")
    weights, biases, activations = list(weights), list(biases), [str(a) for a in activations]
    for i, activation in enumerate(activations):
        if activation not in ACTIVATIONS:
            raise ArgumentError(
                f"argument `activations`: layer {i}: unknown activation {activation!r} (expected one of {ACTIVATIONS})"
            )
    for name, items in (("biases", biases), ("activations", activations)):
        if len(items) != len(weights):
            raise ArgumentError(
                f"argument `{name}`: expected one for each of the {len(weights)} layers, got {len(items)}"
            )
    for i, (w, b) in enumerate(zip(weights, biases)):
        if np.ndim(w) != 2:
            raise ArgumentError(f"argument `weights`: layer {i} must be 2-D [in, out], got shape {list(np.shape(w))}")
        if np.ndim(b) != 1:
            raise ArgumentError(f"argument `biases`: layer {i} must be 1-D [out], got shape {list(np.shape(b))}")
    weights = [_array("weights", w, x.dtype) for w in weights]
    biases = [_array("biases", b, x.dtype) for b in biases]
    batch = x.shape[:-1]
    flat = x.reshape(-1, x.shape[-1])
    out = kernels().mlp_forward(flat, weights, biases, activations)
    return out.reshape(*batch, out.shape[-1])


# -- MOTION blocks -----------------------------------------------------------------------------


@dataclass(frozen=True)
class ChannelLayout:
    """Where each joint's numbers sit in a frame of ``channels`` values (see
    :meth:`Skeleton.layout`): ``rotation_columns``, ``orders``, ``position_columns`` and rest
    ``offsets``, each ``[J, 3]``. Built by :func:`channel_layout`."""

    channels: int
    rotation_columns: np.ndarray
    orders: np.ndarray
    position_columns: np.ndarray
    offsets: np.ndarray


@lru_cache(maxsize=64)
def channel_layout(skeleton) -> ChannelLayout:
    """The :class:`ChannelLayout` of a :class:`~expressive_mocap.motion.Skeleton`. Cached:
    skeletons are immutable (hashed by identity), and the clips of an archive with one
    hierarchy share one (the kernels copy the layout's index arrays: nothing writes to them)."""
    rotation_columns, orders, position_columns = skeleton.layout()
    return ChannelLayout(skeleton.n_channels, rotation_columns, orders, position_columns, skeleton.offsets)


@dataclass(frozen=True)
class MotionBlock:
    """A MOTION number block to read: ``data[start:]`` holds ``frames`` lines laid out as ``layout``."""

    data: bytes
    start: int
    frames: int
    layout: ChannelLayout


def read_motion_blocks(blocks: Sequence[tuple[bytes, Any]]) -> list:
    """Parse and decode many MOTION blocks (in parallel across blocks with the Rust kernels):
    per ``(data, header)`` (a :class:`~expressive_mocap.bvh.Header`: where its block starts,
    how many frames, its skeleton) a ``(rotations [F, J, 4], translations [F, J, 3])`` pair, or
    the :class:`~expressive_mocap.errors.ParseError` of a malformed block in its place."""
    return kernels().read_motion_blocks(
        [MotionBlock(data, h.block_start, h.frames, channel_layout(h.skeleton)) for data, h in blocks]
    )


def format_motion_block(values, decimals: int | None = None) -> bytes:
    """Text of the MOTION number block of channel values ``[F, C]`` (finite numbers);
    ``decimals=None`` is the shortest text that reads back exactly."""
    values = _array("values", values, np.float64)
    if values.ndim != 2:
        raise ArgumentError(f"argument `values`: expected shape [F, C], got {list(values.shape)}")
    return kernels().format_motion_block(values, decimals)


# -- foot contacts and gait features ---------------------------------------------------------


def foot_contacts(
    feet,
    frame_time: float,
    floor: float,
    height_threshold: float,
    speed_threshold: float,
    min_frames: int,
    causal: bool,
) -> np.ndarray:
    """Contact flags ``bool [F, S]`` from world positions ``feet [F, S, P, 3]`` (P points a
    foot: ankle, toe); thresholds in the positions' units (speed per second); runs shorter than
    ``min_frames`` are filtered (offline, or a causal hold when ``causal``)."""
    feet = _array("feet", feet, np.float64)
    return kernels().foot_contacts(
        feet,
        float(frame_time),
        float(floor),
        float(height_threshold),
        float(speed_threshold),
        int(min_frames),
        bool(causal),
    )


def air_time(contacts, frame_time: float) -> np.ndarray:
    """Seconds since each foot last left contact ``[F, S]`` from ``contacts bool [F, S]``."""
    return kernels().air_time(np.ascontiguousarray(contacts, dtype=bool), float(frame_time))


def matrix_columns(quats, columns: int) -> np.ndarray:
    """Unit quaternions ``[..., 4]`` as float32 rotation matrices: ``[..., 9]`` row after row
    (``columns`` 3) or ``[..., 6]`` their first two columns, column after column (2: the 6D form)."""
    quats = _array("quats", quats, np.float64)
    if quats.shape[-1:] != (4,):
        raise ArgumentError(f"argument `quats`: expected shape [..., 4], got {list(quats.shape)}")
    flat = kernels().matrix_columns(quats.reshape(-1, 4), int(columns))
    return flat.reshape(quats.shape[:-1] + flat.shape[1:])


def clip_gradient(values, starts, frame_time) -> np.ndarray:
    """Per clip time derivative of rows ``values [N, ...]`` (clips begin at rows ``starts``, rising
    from 0; ``frame_time [N]`` each row's clip's seconds a frame), as ``np.gradient`` clip by clip:
    central differences, one-sided at a clip's ends, zero for a one-row clip."""
    values = _array("values", values, np.float64)
    if values.ndim == 0:
        raise ArgumentError("argument `values`: expected rows [N, ...], got a scalar")
    flat = values.reshape(len(values), int(np.prod(values.shape[1:])))  # not -1: no rows is fine
    starts = _array("starts", starts, np.int64, "iu")
    frame_time = _array("frame_time", frame_time, np.float64)
    return kernels().clip_gradient(flat, starts, frame_time).reshape(values.shape)


def column_totals(arrays: Sequence[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The float64 sums of the rows of ``arrays`` (each ``[n_i, ...]``, one row shape) and of their
    squares, each shaped like one row: the increments of running normalisation statistics."""
    if not arrays:
        raise ArgumentError("argument `arrays`: expected at least one array")
    shape = arrays[0].shape[1:]
    if any(np.asarray(a).dtype != np.float32 or a.shape[1:] != shape for a in arrays):
        raise ArgumentError(f"argument `arrays`: expected float32 arrays of rows shaped {list(shape)}")
    width = int(np.prod(shape, dtype=np.int64))
    flat = [np.ascontiguousarray(a).reshape(len(a), width) for a in arrays]
    sums, squares = kernels().column_totals(flat, width)
    return sums.reshape(shape), squares.reshape(shape)


def dynamic_features(
    points,
    thighs,
    contacts,
    reference,
    frame_time: float,
    height: float,
    hips_rest_height: float,
    floor: float,
    window: int,
) -> np.ndarray:
    """The 19 dynamic features ``[F, 19]`` from ``points [F, 3, 3]`` (hips, left and right upper
    leg, world), ``thighs [F, 2, 4]`` (local), ``contacts bool [F, 2]`` and the thighs'
    hemisphere ``reference [2, 4]``."""
    return kernels().dynamic_features(
        _array("points", points, np.float64),
        _array("thighs", thighs, np.float64),
        np.ascontiguousarray(contacts, dtype=bool),
        _array("reference", reference, np.float64),
        float(frame_time),
        float(height),
        float(hips_rest_height),
        float(floor),
        int(window),
    )


class GaitSettings(NamedTuple):
    """The thresholds of contact detection shared by the gait kernels (heights in actor heights,
    speed in actor heights per second, duration in seconds, floor as a toe-height percentile)."""

    height_threshold: float
    speed_threshold: float
    min_duration: float
    floor_percentile: float


def clip_gait_many(
    clips,
    roles,
    gait: GaitSettings,
    *,
    features: bool,
    contacts: bool,
    feature_floor: float | None = None,
    thigh_reference=None,
) -> list[tuple[np.ndarray | None, np.ndarray | None]]:
    """Gait arrays of many clips (in parallel with the Rust kernels): per clip ``(positions
    [F, J, 3] world, rotations [F, J, 4] local, frame_time, height, hips_rest_height)``, ``roles``
    the 7 gait joints; per clip ``(features [F, 19] or None, contacts bool [F, 2] or None)``."""
    return kernels().clip_gait_many(
        clips, [int(r) for r in roles], *gait, bool(features), bool(contacts), feature_floor, thigh_reference
    )


# -- the whole per-clip work of preprocessing -----------------------------------------------------


@dataclass(frozen=True)
class ClipInput:
    """One clip for :func:`clip_pipeline_many`: ``source`` its bytes or its path (read by the
    kernel), ``start`` where its MOTION block begins, its ``frames``, ``layout`` and
    ``frame_time``, and its body scale (``height``, ``hips_rest_height``)."""

    source: bytes | str
    start: int
    frames: int
    layout: ChannelLayout
    frame_time: float
    height: float
    hips_rest_height: float

    @classmethod
    def of(cls, source: bytes | str | os.PathLike, header, height: float, hips_rest_height: float) -> ClipInput:
        """The clip of a :class:`~expressive_mocap.bvh.Header` whose text is ``source``."""
        text = source if isinstance(source, bytes) else os.fspath(source)
        return cls(
            text,
            header.block_start,
            header.frames,
            channel_layout(header.skeleton),
            header.frame_time,
            height,
            hips_rest_height,
        )


@dataclass(frozen=True)
class FeatureRequest:
    """One causal feature array [F, 19] to compute: on ``floor`` (None: the toe-height
    percentile) with ``thigh_reference [2, 4]`` (None: the first frame's thighs)."""

    floor: float | None
    thigh_reference: np.ndarray | None = None


@dataclass(frozen=True)
class PipelineOutputs:
    """What :func:`clip_pipeline_many` keeps of each clip; float arrays in float32 if ``float32``.
    ``rotation_columns``: the rotations as quaternions (0) or as their matrices' first two
    columns (2, the 6D form) or whole matrices (3), as :func:`matrix_columns` gives them;
    ``velocities``: the world positions' time derivative, as :func:`clip_gradient` gives it."""

    positions: bool = False
    rotations: bool = False
    features: tuple[FeatureRequest, ...] = ()
    contacts: bool = False
    float32: bool = False
    rotation_columns: int = 0
    velocities: bool = False


def clip_pipeline_many(
    clips: Sequence[ClipInput],
    parents,
    roles,
    gait: GaitSettings,
    outputs: PipelineOutputs,
    max_bytes: int | None = None,
) -> list:
    """The whole per-clip work of many clips of one skeleton (``parents [J]``, ``roles`` its 7
    gait joints), clips in parallel with the Rust kernels: reading the file (a path, at most
    ``max_bytes``, default ``files.MAX_INPUT_BYTES``), MOTION block, FK, features, contacts.
    Per clip ``(positions or None, rotations or None, [features per request], contacts or
    None, velocities or None)``, or the ``ParseError`` / ``OSError`` of a clip whose block /
    file cannot be read."""
    parents = _array("parents", parents, np.int64, "iu")
    if outputs.rotation_columns not in (0, 2, 3):
        raise ArgumentError(
            "argument `rotation_columns`: expected 0 (quaternions), 2 (6d) or 3 (the whole matrix), "
            f"got {outputs.rotation_columns!r}"
        )
    features = tuple(
        FeatureRequest(
            f.floor, None if f.thigh_reference is None else _array("thigh_reference", f.thigh_reference, np.float64)
        )
        for f in outputs.features
    )
    outputs = replace(outputs, features=features)
    return kernels().clip_pipeline_many(
        list(clips), parents, [int(r) for r in roles], gait=GaitSettings(*gait), outputs=outputs, max_bytes=max_bytes
    )


def repeated_headers(paths: Sequence[str | os.PathLike], template: bytes, joints: int, count: int) -> list:
    """The headers of files that repeat one already read, ``template`` its bytes through its
    MOTION line (``joints`` joints), each file read from its first ``count`` bytes, in parallel
    with the Rust kernels and without the GIL: per path ``(frames, frame_time, block_start)``,
    or ``(first bytes, size)`` of a file that is anything else (for the full reader), or the
    ``OSError`` of a file that cannot be read or is refused."""
    return kernels().repeated_headers([os.fspath(p) for p in paths], bytes(template), int(joints), int(count))


# -- inverse kinematics ----------------------------------------------------------------------------


def two_bone_ik(root, upper, lower, upper_bone, lower_bone, target) -> tuple[np.ndarray, np.ndarray]:
    """New world rotations ``(upper, lower)`` ``[F, 4]`` of two-bone chains reaching for
    ``target [F, 3]`` (see :func:`expressive_mocap.ik.two_bone_ik`); ``upper_bone`` and
    ``lower_bone`` ``[3]`` (every frame's) or ``[F, 3]``."""
    root = _array("root", root, np.float64)
    frames = len(root) if root.ndim else 0

    def rows(name: str, value, width: int) -> np.ndarray:
        value = _array(name, value, np.float64)
        if value.ndim == 1 and value.shape == (width,) and name.endswith("bone"):
            value = np.ascontiguousarray(np.broadcast_to(value, (frames, width)))
        if value.shape != (frames, width):
            raise ArgumentError(f"argument `{name}`: expected shape [{frames}, {width}], got {list(value.shape)}")
        return value

    return kernels().two_bone_ik(
        rows("root", root, 3),
        rows("upper", upper, 4),
        rows("lower", lower, 4),
        rows("upper_bone", upper_bone, 3),
        rows("lower_bone", lower_bone, 3),
        rows("target", target, 3),
    )


def plant_feet(rotations, translations, parents, legs, contacts, guide, starts, blend: int) -> np.ndarray:
    """The local rotations ``[F, J, 4]`` of a motion with its feet planted (see
    :func:`expressive_mocap.skeletons.planting.plant_feet`): ``legs [2, 3]`` (hip, knee, foot;
    -1s: a leg left as it is), ``contacts bool [F, 2]``, ``guide [F, 2, 3]``, ``starts`` where
    clips laid end to end begin and the last one ends, ``blend`` frames of easing."""
    return kernels().plant_feet(
        _f64("rotations", rotations, 4),
        _f64("translations", translations, 3),
        _array("parents", parents, np.int64, "iu"),
        _array("legs", legs, np.int64, "iu"),
        np.ascontiguousarray(contacts, dtype=bool),
        _f64("guide", guide, 3),
        _array("starts", starts, np.int64, "iu"),
        int(blend),
    )


# -- retargeting ---------------------------------------------------------------------------------


class TransferPlan(NamedTuple):
    """What :func:`retarget_transfer` does in every frame, made once per pair of skeletons (see
    :mod:`expressive_mocap.skeletons.retargeting`): per role its ``source`` and ``target`` joint
    and alignment ``aligns [R, 4]``; the roles ``swung`` onto the source's bone from joint
    ``starts`` to joint ``ends`` (at rest ``rest_lines [S, 3]``, canonical axes); the target's
    spine joints ``shared`` taking the share ``shares`` of the turn from ``tops`` to
    ``bottoms``; the target joints ``held`` with ``copied``, their nearest computed ancestor
    (-1: none); both as changes from ``reference [Jt, 4]``, the target's world rotations in its
    reference pose (canonical axes; the rest pose: all the identity); the target's ``parents``;
    both skeletons' turns onto the canonical axes."""

    source: np.ndarray
    target: np.ndarray
    aligns: np.ndarray
    swung: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    rest_lines: np.ndarray
    shared: np.ndarray
    tops: np.ndarray
    bottoms: np.ndarray
    shares: np.ndarray
    held: np.ndarray
    copied: np.ndarray
    reference: np.ndarray
    parents: np.ndarray
    turn_source: tuple[float, float, float, float]
    turn_target: tuple[float, float, float, float]

    @classmethod
    def of(cls, *parts) -> TransferPlan:
        """A plan of the parts in the fields' order, each coerced: index arrays int64,
        ``aligns``, ``reference`` and ``rest_lines`` float ``[N, 4]`` and ``[N, 3]``, turns four floats."""
        fields = dict(zip(cls._fields, parts))
        for name in ("aligns", "rest_lines", "shares", "reference"):
            fields[name] = _array(name, fields[name], np.float64)
        fields["aligns"] = fields["aligns"].reshape(-1, 4)
        fields["reference"] = fields["reference"].reshape(-1, 4)
        fields["rest_lines"] = fields["rest_lines"].reshape(-1, 3)
        for name in ("source", "target", "swung", "starts", "ends", "shared", "tops", "bottoms", "held", "copied"):
            value = np.asarray(fields[name])
            value = value.astype(np.int64) if value.size == 0 else value  # [] reads as floats
            fields[name] = _array(name, value, np.int64, "iu").reshape(-1)
        fields["parents"] = _array("parents", fields["parents"], np.int64, "iu")
        for name in ("turn_source", "turn_target"):
            fields[name] = tuple(float(v) for v in np.asarray(fields[name], dtype=np.float64).reshape(4))
        return cls(**fields)


def retarget_transfer(world, positions, plan: TransferPlan) -> np.ndarray:
    """The target skeleton's local rotations ``[F, Jt, 4]`` from the source's world rotations
    ``world [F, Js, 4]`` and positions ``positions [F, Js, 3]``, along ``plan``."""
    return kernels().retarget_transfer(_f64("world", world, 4), _f64("positions", positions, 3), plan)


@dataclass(frozen=True)
class ClipArrays:
    """One clip already decoded, for :func:`arrays_pipeline_many`: local ``rotations [F, J, 4]``
    and ``translations [F, J, 3]``, its ``frame_time`` and body scale (as :class:`ClipInput`)."""

    rotations: np.ndarray
    translations: np.ndarray
    frame_time: float
    height: float
    hips_rest_height: float

    @property
    def frames(self) -> int:
        return len(self.rotations)


def stored_rotations(quats: np.ndarray, columns: int) -> np.ndarray:
    """Local rotations ``[F, J, 4]`` in the form :class:`PipelineOutputs` asks for: as they are
    (``columns`` 0) or their matrices' first ``columns`` columns, in float64 (as the pipeline's)."""
    from .reference.forms import matrix_entries  # the twin's formula: the same as the kernel's

    return quats if columns == 0 else matrix_entries(quats, columns)


def arrays_pipeline_many(
    clips: Sequence[ClipArrays], parents, roles, gait: GaitSettings, outputs: PipelineOutputs
) -> list[tuple]:
    """What :func:`clip_pipeline_many` gives of clips whose frames are arrays already (a
    retargeted clip): FK, features and contacts, the same kernels clips in parallel, per clip
    ``(positions or None, rotations or None, [features per request], contacts or None,
    velocities or None)``."""
    parents = _array("parents", parents, np.int64, "iu")
    local = [(_f64("rotations", c.rotations, 4), _f64("translations", c.translations, 3), parents) for c in clips]
    kinematics = kernels().forward_kinematics_many(local)
    gait_clips = [
        (p, r, c.frame_time, c.height, c.hips_rest_height) for c, (r, _, _), (_, p) in zip(clips, local, kinematics)
    ]
    roles = [int(r) for r in roles]
    contacts: list = [None] * len(clips)
    features: list[list] = [[] for _ in clips]
    for number, request in enumerate(outputs.features):  # the contacts come with the first request
        with_contacts = outputs.contacts and number == 0
        reference = None if request.thigh_reference is None else _f64("thigh_reference", request.thigh_reference, 4)
        found = kernels().clip_gait_many(
            gait_clips, roles, *gait, True, with_contacts, request.floor, reference
        )  # fmt: skip
        for k, (f, c) in enumerate(found):
            features[k].append(f)
            contacts[k] = c if with_contacts else contacts[k]
    if outputs.contacts and not outputs.features:
        contacts = [c for _, c in kernels().clip_gait_many(gait_clips, roles, *gait, False, True)]
    dtype = np.float32 if outputs.float32 else np.float64
    return [
        (
            p.astype(dtype, copy=False) if outputs.positions else None,
            stored_rotations(r, outputs.rotation_columns).astype(dtype, copy=False) if outputs.rotations else None,
            [f.astype(dtype, copy=False) for f in found],
            contact,
            clip_gradient(p, [0], np.full(len(p), c.frame_time)).astype(dtype, copy=False)
            if outputs.velocities
            else None,
        )
        for c, (r, _, _), (_, p), found, contact in zip(clips, local, kinematics, features, contacts)
    ]


__all__ = [
    "ACTIVATIONS",
    "ChannelLayout",
    "ClipArrays",
    "ClipInput",
    "FeatureRequest",
    "GaitSettings",
    "MotionBlock",
    "PipelineOutputs",
    "TransferPlan",
    "air_time",
    "arrays_pipeline_many",
    "channel_layout",
    "clip_gait_many",
    "clip_gradient",
    "clip_pipeline_many",
    "column_totals",
    "compose_rotations",
    "decode_channels",
    "decouple_rotations",
    "dynamic_features",
    "euler_to_quat",
    "foot_contacts",
    "format_motion_block",
    "forward_kinematics",
    "forward_kinematics_many",
    "matrix_columns",
    "mlp_forward",
    "plant_feet",
    "quat_to_euler",
    "read_motion_blocks",
    "repeated_headers",
    "retarget_transfer",
    "two_bone_ik",
]
