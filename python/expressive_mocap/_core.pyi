"""Type stubs of the Rust extension. Every function has a NumPy twin of the same name and
signature in ``expressive_mocap.reference``; call them through ``expressive_mocap.ops``. Bad
arguments raise ``expressive_mocap.errors.ArgumentError`` (TypeError for a wrong dtype or a
non-contiguous array), a malformed MOTION block ``expressive_mocap.errors.ParseError``.

Every function releases the GIL. Index and bool arrays are copied first (a write to them by
another thread during a call has no effect on it); float arrays are read in place, so a write to
one during a call gives results from a mix of old and new values (see ``expressive_mocap.ops``)."""

import os
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from expressive_mocap.errors import ParseError
from expressive_mocap.ops import ClipInput, GaitSettings, MotionBlock, PipelineOutputs, TransferPlan

_F64 = npt.NDArray[np.float64]
_Float = npt.NDArray[np.float32] | npt.NDArray[np.float64]

__all__ = [
    "air_time",
    "check_motion_block",
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
    "num_threads",
    "parse_motion_block",
    "plant_feet",
    "quat_to_euler",
    "read_motion_blocks",
    "repeated_headers",
    "retarget_transfer",
    "split_rotations",
    "split_rotations_many",
    "two_bone_ik",
]

num_threads: int

def parse_motion_block(data: bytes, start: int, frames: int, channels: int) -> _F64:
    """Parse ``frames`` lines of ``channels`` finite numbers from ``data[start:]`` -> ``[frames, channels]``."""

def check_motion_block(data: bytes, start: int, frames: int, channels: int) -> None:
    """Raise the ``ParseError`` that ``parse_motion_block`` would raise for this block, or return None."""

def decode_channels(
    values: _F64,
    rotation_columns: npt.NDArray[np.int64],
    orders: npt.NDArray[np.uint8],
    position_columns: npt.NDArray[np.int64],
    offsets: _F64,
) -> tuple[_F64, _F64]:
    """Channel values ``[F, C]`` -> local rotations ``[F, J, 4]`` and translations ``[F, J, 3]``."""

def read_motion_blocks(blocks: Sequence[MotionBlock]) -> list[tuple[_F64, _F64] | ParseError]:
    """Parse and decode many blocks in parallel: per block (read by attribute: ``data``, ``start``, ``frames``,
    ``layout``) a ``(rotations, translations)`` pair or a ``ParseError``."""

def euler_to_quat(angles: _F64, orders: npt.NDArray[np.uint8]) -> _F64:
    """Euler angles ``[F, J, 3]`` (degrees) and orders ``[J, 3]`` (axis indices) -> quaternions ``[F, J, 4]``."""

def quat_to_euler(quats: _F64, orders: npt.NDArray[np.uint8]) -> _F64:
    """Quaternions ``[F, J, 4]`` (x, y, z, w) -> Euler angles ``[F, J, 3]`` in degrees."""

def forward_kinematics(rotations: _F64, translations: _F64, parents: npt.NDArray[np.int64]) -> tuple[_F64, _F64]:
    """World rotations ``[F, J, 4]`` and positions ``[F, J, 3]`` from local ones and ``parents [J]``."""

def forward_kinematics_many(clips: list[tuple[_F64, _F64, npt.NDArray[np.int64]]]) -> list[tuple[_F64, _F64]]:
    """Forward kinematics of many ``(rotations, translations, parents)`` clips, in parallel across clips."""

def format_motion_block(values: _F64, decimals: int | None = None) -> bytes:
    """Text of the MOTION block for ``values [F, C]``; ``decimals=None`` is the shortest exact text."""

def foot_contacts(
    feet: _F64,
    frame_time: float,
    floor: float,
    height_threshold: float,
    speed_threshold: float,
    min_frames: int,
    causal: bool,
) -> npt.NDArray[np.bool_]:
    """Contacts ``bool [F, S]`` from world positions ``feet [F, S, P, 3]`` (P points a foot: ankle, toe);
    thresholds in file units (speed per second); runs shorter than ``min_frames`` filtered (offline or causal hold)."""

def air_time(contacts: npt.NDArray[np.bool_], frame_time: float) -> _F64:
    """Seconds since each foot last left contact ``[F, S]`` from ``contacts bool [F, S]``."""

def dynamic_features(
    points: _F64,
    thighs: _F64,
    contacts: npt.NDArray[np.bool_],
    reference: _F64,
    frame_time: float,
    height: float,
    hips_rest_height: float,
    floor: float,
    window: int,
) -> _F64:
    """The 19 features ``[F, 19]`` from ``points [F, 3, 3]`` (hips, left and right upper leg,
    world), ``thighs [F, 2, 4]`` (local), ``contacts bool [F, 2]`` and the thighs' hemisphere
    ``reference [2, 4]``."""

def mlp_forward(x: _Float, weights: list[_Float], biases: list[_Float], activations: list[str]) -> _Float:
    """Dense network on ``x [N, in]`` (float32 or float64, kept): per layer ``act(h @ W [in, out] + b [out])``,
    ``act`` "tanh" or "linear"; weights and biases in the dtype of ``x``. Rows in parallel, GIL released."""

def clip_gait_many(
    clips: list[tuple[_F64, _F64, float, float, float]],
    roles: list[int],
    height_threshold: float,
    speed_threshold: float,
    min_duration: float,
    floor_percentile: float,
    features: bool,
    contacts: bool,
    feature_floor: float | None = None,
    thigh_reference: _F64 | None = None,
) -> list[tuple[_F64 | None, npt.NDArray[np.bool_] | None]]:
    """Gait arrays of many ``(positions, rotations, frame_time, height, hips_rest_height)`` clips, in parallel:
    per clip ``(features [F, 19] or None, contacts bool [F, 2] or None)``."""

def clip_pipeline_many(
    clips: Sequence[ClipInput],
    parents: npt.NDArray[np.int64],
    roles: list[int],
    gait: GaitSettings,
    outputs: PipelineOutputs,
    max_bytes: int | None = None,
) -> list[
    tuple[_Float | None, _Float | None, list[_Float], npt.NDArray[np.bool_] | None, _Float | None]
    | ParseError
    | OSError
]:
    """The whole per-clip work of many clips of one skeleton (file, MOTION block, FK, features, contacts, and the stored
    forms of rotations and velocities), in parallel; arguments read by attribute (see ``expressive_mocap.ops``). A
    ``ParseError`` or ``OSError`` in the place of a clip whose block or file cannot be read."""

def decouple_rotations(original: _F64, body: _F64, gain: float, exponent: float) -> tuple[_F64, _F64, _F64]:
    """``(E*, B', A)`` of rotations ``original`` and ``body`` ``[F, J, 4]``: filtered expressive rotations, recovered
    body mechanics and the activity ``[F, J]``."""

def split_rotations(
    original: _F64,
    body: _F64,
    gain: float,
    exponent: float,
    scale: _F64,
    body_sigma: float,
    activity_sigma: float,
    trunk_joints: Sequence[int] = ...,
    trunk_bones: Sequence[tuple[float, float, float]] = ...,
    trunk_scale: float = ...,
    arm_parents: Sequence[int] = ...,
    arm_joints: Sequence[int] = ...,
) -> tuple[_F64, _F64, _F64]:
    """One clip's ``(E*, B', A)`` with the body mechanics and the activity smoothed over frames,
    the trunk joints read at least as active as their chain's lean, the ``arm_joints`` (with the
    skeleton's ``arm_parents``) filtered in world axes."""

def split_rotations_many(
    originals: Sequence[_F64],
    bodies: Sequence[_F64],
    gain: float,
    exponent: float,
    scale: _F64,
    body_sigmas: Sequence[float],
    activity_sigmas: Sequence[float],
    trunk_joints: Sequence[int] = ...,
    trunk_bones: Sequence[tuple[float, float, float]] = ...,
    trunk_scale: float = ...,
    arm_parents: Sequence[int] = ...,
    arm_joints: Sequence[int] = ...,
) -> list[tuple[_F64, _F64, _F64]]:
    """``split_rotations`` of many clips in one call, clips in parallel, each with its own
    smoothing widths."""

def compose_rotations(expressive: _F64, body: _F64, scale: float = 1.0) -> _F64:
    """``expressive^scale * body`` for rotations ``[F, J, 4]``."""

def retarget_transfer(world: _F64, positions: _F64, plan: TransferPlan) -> _F64:
    """The target skeleton's local rotations ``[F, Jt, 4]`` from the source's world rotations
    ``[F, Js, 4]`` and positions ``[F, Js, 3]``, along ``plan``."""

def two_bone_ik(
    root: _F64, upper: _F64, lower: _F64, upper_bone: _F64, lower_bone: _F64, target: _F64
) -> tuple[_F64, _F64]:
    """New world rotations ``(upper, lower)`` ``[F, 4]`` of two-bone chains reaching for ``target``."""

def plant_feet(
    rotations: _F64,
    translations: _F64,
    parents: npt.NDArray[np.int64],
    legs: npt.NDArray[np.int64],
    contacts: npt.NDArray[np.bool_],
    guide: _F64,
    starts: npt.NDArray[np.int64],
    blend: int,
) -> _F64:
    """Local rotations ``[F, J, 4]`` with the feet planted (legs ``[2, 3]``, contacts ``[F, 2]``,
    guide ``[F, 2, 3]``, clip ``starts``, ``blend`` frames of easing)."""

def matrix_columns(quats: _F64, columns: int) -> npt.NDArray[np.float32]:
    """Unit quaternions ``[N, 4]`` -> float32 rotation matrices ``[N, 9]`` row after row (``columns`` 3)
    or their first two columns ``[N, 6]`` (2)."""

def clip_gradient(values: _F64, starts: npt.NDArray[np.int64], frame_time: _F64) -> _F64:
    """Per-clip time derivative of rows ``values [N, C]``; clips begin at ``starts``, ``frame_time [N]``."""

def column_totals(arrays: list[npt.NDArray[np.float32]], width: int) -> tuple[_F64, _F64]:
    """Float64 sums of the rows of each of ``arrays`` (each ``[n, width]``, summed row after row) and of
    their squares: ``([A, width], [A, width])``."""

def repeated_headers(
    paths: Sequence[str | os.PathLike[str]], template: bytes, joints: int, count: int, max_bytes: int | None = None
) -> list[tuple[int, float, int] | tuple[bytes, int] | OSError]:
    """Per file, read in parallel from its first ``count`` bytes: ``(frames, frame_time, block_start)`` when it
    repeats the header ``template``, else ``(first bytes, size)``, or an ``OSError``."""
