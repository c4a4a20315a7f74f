"""Twin of ``rust/footsteps.rs``: foot contacts (Lee et al. 2002) with a temporal-continuity
filter, and air time. Heights are along Y (up); speeds are backward differences per second."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError


def _check_min_frames(min_frames: int) -> int:
    if int(min_frames) < 1:
        raise ArgumentError(f"argument `min_frames`: must be at least 1, got {min_frames}")
    return int(min_frames)


def foot_contacts(
    feet: np.ndarray,
    frame_time: float,
    floor: float,
    height_threshold: float,
    speed_threshold: float,
    min_frames: int,
    causal: bool,
) -> np.ndarray:
    """Contact flags ``bool [F, S]`` of ``S`` feet from world positions ``feet [F, S, P, 3]``
    of ``P`` points per foot (ankle, toe).

    A point touches when its height above ``floor`` is below ``height_threshold`` and its speed
    (``|x_t - x_{t-1}| / frame_time``; frame 0 takes frame 1's speed offline, 0 when causal) is
    below ``speed_threshold``; a foot touches when any of its points does. Then
    :func:`absorb_short_runs` (offline) or :func:`hold_filter` (causal) with ``min_frames``.
    """
    feet = np.asarray(feet, dtype=np.float64)
    if feet.ndim != 4 or feet.shape[3] != 3 or feet.shape[1] == 0 or feet.shape[2] == 0:
        raise ArgumentError(f"argument `feet`: expected shape [F, S, P, 3], got {list(feet.shape)}")
    if not (np.isfinite(frame_time) and frame_time > 0):
        raise ArgumentError(f"argument `frame_time`: must be a positive number of seconds, got {frame_time}")
    min_frames = _check_min_frames(min_frames)
    if len(feet) == 0:
        return np.zeros((0, feet.shape[1]), dtype=bool)
    speed = np.zeros(feet.shape[:3])
    speed[1:] = np.linalg.norm(feet[1:] - feet[:-1], axis=-1) / frame_time
    if len(feet) > 1 and not causal:
        speed[0] = speed[1]
    touching = (feet[..., 1] - floor < height_threshold) & (speed < speed_threshold)
    raw = touching.any(axis=2)
    filtered = hold_filter if causal else absorb_short_runs
    return np.stack([filtered(raw[:, s], min_frames) for s in range(raw.shape[1])], axis=1).reshape(raw.shape)


def _runs(signal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and lengths of the runs of equal values in a 1-D signal."""
    starts = np.flatnonzero(np.r_[True, signal[1:] != signal[:-1]])
    return starts, np.diff(np.r_[starts, len(signal)])


def absorb_short_runs(signal: np.ndarray, min_frames: int) -> np.ndarray:
    """Offline filter of one foot's flags ``[F]``: a run (of contact or of flight) shorter than
    ``min_frames`` that has a neighbour on both sides takes their value, shortest run first
    (earliest among equals); runs touching either end of the clip are kept."""
    signal = np.array(signal, dtype=bool)
    starts, lengths = _runs(signal)
    values = list(signal[starts])
    start_list, length_list = list(starts), list(lengths)
    while len(length_list) >= 3:
        interior = np.array(length_list[1:-1])
        i = int(np.argmin(interior)) + 1
        if length_list[i] >= min_frames:
            break
        # Flipping run i merges it with both neighbours into one run.
        length_list[i - 1 : i + 2] = [length_list[i - 1] + length_list[i] + length_list[i + 1]]
        del values[i : i + 2], start_list[i : i + 2]
    return np.repeat(np.array(values, dtype=bool), length_list) if length_list else signal


def hold_filter(signal: np.ndarray, min_frames: int) -> np.ndarray:
    """Causal filter of one foot's flags ``[F]`` (hysteresis in time): the state starts as the
    first flag and changes once the flags have disagreed with it for ``min_frames`` frames in a
    row, from that frame on. Frame ``t`` uses flags ``<= t`` only."""
    out = np.empty(len(signal), dtype=bool)
    state, streak = (bool(signal[0]) if len(signal) else False), 0
    for t, flag in enumerate(np.asarray(signal, dtype=bool).tolist()):
        streak = streak + 1 if flag != state else 0
        if streak >= min_frames:
            state, streak = flag, 0
        out[t] = state
    return out


def air_time(contacts: np.ndarray, frame_time: float) -> np.ndarray:
    """Seconds since each foot last left contact, ``[F, S]`` from ``contacts bool [F, S]``: 0 in
    contact, ``k * frame_time`` at the ``k``-th frame of a flight (a clip that starts in flight
    counts from one frame before its start)."""
    contacts = np.asarray(contacts, dtype=bool)
    if contacts.ndim != 2:
        raise ArgumentError(f"argument `contacts`: expected shape [F, S], got {list(contacts.shape)}")
    if not (np.isfinite(frame_time) and frame_time > 0):
        raise ArgumentError(f"argument `frame_time`: must be a positive number of seconds, got {frame_time}")
    frames = np.arange(1, len(contacts) + 1)[:, None]
    # Frame number (1-based) of the last contact at or before each frame, 0 if none yet.
    last = np.maximum.accumulate(np.where(contacts, frames, 0), axis=0)
    return (frames - last) * frame_time


__all__ = [
    "absorb_short_runs",
    "air_time",
    "foot_contacts",
    "hold_filter",
]
