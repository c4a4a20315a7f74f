"""Type stubs of the Rust extension. Every function has a NumPy twin of the same name and
signature in ``expressive_mocap.reference``; call them through ``expressive_mocap.kernels``.

Every function releases the GIL. Index and bool arrays are copied first (a write to them by
another thread during a call has no effect on it); float arrays are read in place, so a write to
one during a call gives results from a mix of old and new values (see ``expressive_mocap.kernels``)."""

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
Float = npt.NDArray[np.float32] | npt.NDArray[np.float64]

num_threads: int

class ParseError(ValueError):
    """A malformed MOTION block; ``args`` are ``(message, 0-based line within the block)``."""

def parse_motion_block(data: bytes, start: int, frames: int, channels: int) -> F64:
    """Parse ``frames`` lines of ``channels`` finite numbers from ``data[start:]`` -> ``[frames, channels]``."""

def decode_channels(values: F64, rotation_columns: npt.NDArray[np.int64], orders: npt.NDArray[np.uint8], position_columns: npt.NDArray[np.int64], offsets: F64) -> tuple[F64, F64]:
    """Channel values ``[F, C]`` -> local rotations ``[F, J, 4]`` and translations ``[F, J, 3]``."""

def read_motion_blocks(blocks: list[tuple]) -> list[tuple[F64, F64] | ParseError]:
    """Parse and decode many blocks in parallel: per ``(data, start, frames, channels, rotation_columns,
    orders, position_columns, offsets)`` a ``(rotations, translations)`` pair or a ``ParseError``."""

def euler_to_quat(angles: F64, orders: npt.NDArray[np.uint8]) -> F64:
    """Euler angles ``[F, J, 3]`` (degrees) and orders ``[J, 3]`` (axis indices) -> quaternions ``[F, J, 4]``."""

def quat_to_euler(quats: F64, orders: npt.NDArray[np.uint8]) -> F64:
    """Quaternions ``[F, J, 4]`` (x, y, z, w) -> Euler angles ``[F, J, 3]`` in degrees."""

def forward_kinematics(rotations: F64, translations: F64, parents: npt.NDArray[np.int64]) -> tuple[F64, F64]:
    """World rotations ``[F, J, 4]`` and positions ``[F, J, 3]`` from local ones and ``parents [J]``."""

def forward_kinematics_many(clips: list[tuple[F64, F64, npt.NDArray[np.int64]]]) -> list[tuple[F64, F64]]:
    """Forward kinematics of many ``(rotations, translations, parents)`` clips, in parallel across clips."""

def format_motion_block(values: F64, decimals: int | None = None) -> bytes:
    """Text of the MOTION block for ``values [F, C]``; ``decimals=None`` is the shortest exact text."""

def foot_contacts(feet: F64, frame_time: float, floor: float, height_threshold: float, speed_threshold: float, min_frames: int, causal: bool) -> npt.NDArray[np.bool_]:
    """Contacts ``bool [F, S]`` from world positions ``feet [F, S, P, 3]`` (P points a foot: ankle, toe);
    thresholds in file units (speed per second); runs shorter than ``min_frames`` filtered (offline or causal hold)."""

def air_time(contacts: npt.NDArray[np.bool_], frame_time: float) -> F64:
    """Seconds since each foot last left contact ``[F, S]`` from ``contacts bool [F, S]``."""

def dynamic_features(
    points: F64, thighs: F64, contacts: npt.NDArray[np.bool_], reference: F64, frame_time: float, height: float, hips_rest_height: float, floor: float, window: int
) -> F64:
    """The 19 features ``[F, 19]`` from ``points [F, 3, 3]`` (hips, left and right upper leg, world), ``thighs [F, 2, 4]``
    (local), ``contacts bool [F, 2]`` and the thighs' hemisphere ``reference [2, 4]``."""


def mlp_forward(x: Float, weights: list[Float], biases: list[Float], activations: list[str]) -> Float:
    """Dense network on ``x [N, in]`` (float32 or float64, kept): per layer ``act(h @ W [in, out] + b [out])``,
    ``act`` "tanh" or "linear"; weights and biases in the dtype of ``x``. Rows in parallel, GIL released."""
