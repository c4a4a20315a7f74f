"""Foot contacts: when each foot is on the floor (after Lee et al. 2002), the floor itself, and the
steps and cadence read from the contacts. Used by every method, the CLI and preprocessing.

Thresholds are fractions of the actor's height (:attr:`expressive_mocap.body.Body.actor_height`),
speeds per second; Y is up. The per-frame filter runs in the kernels (Rust, or the NumPy twin).
A motion's floor and contacts are kept on its :class:`~expressive_mocap.body.Take`: asked again
for the same take and settings, they are not computed again.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .. import ops
from ..errors import ArgumentError
from ..motion import Motion
from .roles import JointRoles
from .take import Take

HEIGHT_THRESHOLD = 0.05  # x actor height
SPEED_THRESHOLD = 0.5  # x actor height per second
MIN_DURATION = 0.1  # seconds: shorter contact or flight runs are noise
FLOOR_PERCENTILE = 5.0


class ContactInterval(NamedTuple):
    """Frames ``start`` to ``end`` (both included) in contact, lasting ``seconds`` (frames x frame time)."""

    start: int
    end: int
    seconds: float


def take_of(source: Motion | Take) -> Take:
    """:meth:`Take.of` ``source``, refusing a motion without frames."""
    take = Take.of(source)
    if take.motion.n_frames == 0:
        raise ArgumentError("argument `motion`: the motion has no frames")
    return take


def _positive(name: str, value) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise ArgumentError(f"argument `{name}`: expected a number, got {value!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise ArgumentError(f"argument `{name}`: must be a positive number, got {value}")
    return value


def _frames(seconds: float, motion: Motion) -> int:
    return max(1, int(round(seconds * motion.fps)))


def default_floor(positions: np.ndarray, roles: JointRoles) -> float:
    """The floor height: the 5th percentile of both toes' heights over the clip (``positions [F, J, 3]``)."""
    return float(np.percentile(positions[:, list(roles.toes), 1], FLOOR_PERCENTILE))


def floor_of(source: Motion | Take) -> float:
    """:func:`default_floor` of a motion (kept on its take)."""
    take = take_of(source)
    return take.kept("floor", lambda: default_floor(take.positions, take.body.roles))


def percentiles_by_clip(values: np.ndarray, bounds, q: float) -> np.ndarray:
    """``np.percentile(values[a:b], q)`` of each clip ``a, b`` of ``bounds`` (where clips laid end
    to end begin, then where the last one ends; ``values [F, ...]``, a clip's every value), the
    same numbers (linear interpolation, as NumPy computes it) from one sort instead of a call a
    clip. A clip without frames gives NaN."""
    bounds = np.asarray(bounds, dtype=np.int64)
    per_frame = int(np.prod(values.shape[1:], dtype=np.int64))
    flat = values.reshape(-1)
    counts = np.diff(bounds) * per_frame
    clip = np.repeat(np.arange(len(counts)), counts)
    ordered = flat[np.lexsort((flat, clip))]
    starts = bounds[:-1] * per_frame
    # NumPy's virtual index of the linear method, and its interpolation (numpy.lib.function_base).
    virtual = (counts - 1) * np.true_divide(q, 100)
    previous = np.floor(virtual).astype(np.intp)
    above, below = virtual >= counts - 1, virtual < 0
    low = np.where(above, counts - 1, np.where(below, 0, previous))
    high = np.where(above, counts - 1, np.where(below, 0, previous + 1))
    empty = counts == 0
    a = ordered[np.where(empty, 0, starts + low)] if len(ordered) else np.zeros(len(counts))
    b = ordered[np.where(empty, 0, starts + high)] if len(ordered) else np.zeros(len(counts))
    gamma = virtual - previous
    diff = b - a
    out = a + diff * gamma
    out = np.where(gamma >= 0.5, b - diff * (1 - gamma), out)
    return np.where(empty, np.nan, out)


def _floor(floor, take: Take, causal: bool) -> float:
    if floor is None:
        return 0.0 if causal else floor_of(take)
    value = float(floor)
    if not np.isfinite(value):
        raise ArgumentError(f"argument `floor`: must be a finite height, got {floor}")
    return value


def foot_contacts(
    motion: Motion | Take,
    *,
    floor: float | None = None,
    causal: bool = False,
    height_threshold: float = HEIGHT_THRESHOLD,
    speed_threshold: float = SPEED_THRESHOLD,
    min_duration: float = MIN_DURATION,
) -> np.ndarray:
    """Contacts ``bool [F, 2]`` (left, right foot) after Lee et al. 2002.

    A foot (its ankle and toe: either counts) touches when its height above ``floor`` is below
    ``height_threshold`` x actor height and its speed below ``speed_threshold`` x actor height
    per second. Offline (default) contact and flight runs shorter than ``min_duration`` seconds
    are absorbed by their neighbours; ``causal=True`` uses a hold of ``min_duration`` instead
    (a change counts once it has lasted that long; frame ``t`` uses frames ``<= t``).
    ``floor`` defaults to the 5th percentile of toe heights (0 when causal). ``motion``: a
    motion, or a :class:`~expressive_mocap.body.Take` of one (whose Body gives the joints and
    the actor's height: a Body read with a user's joint map picks other feet).
    """
    take = take_of(motion)
    floor = _floor(floor, take, causal)
    settings = (
        floor,
        bool(causal),
        _positive("height_threshold", height_threshold),
        _positive("speed_threshold", speed_threshold),
        _positive("min_duration", min_duration),
    )
    return take.kept(("contacts", settings), lambda: _contacts(take, *settings)).copy()


def _contacts(
    take: Take, floor: float, causal: bool, height_threshold: float, speed_threshold: float, min_duration: float
) -> np.ndarray:
    roles, height, motion = take.body.roles, take.body.actor_height, take.motion
    feet = take.positions[:, [[roles.feet[0], roles.toes[0]], [roles.feet[1], roles.toes[1]]]]
    return ops.foot_contacts(
        np.ascontiguousarray(feet),
        motion.frame_time,
        floor,
        height_threshold * height,
        speed_threshold * height,
        _frames(min_duration, motion),
        causal,
    )


def air_time(contacts, frame_time: float) -> np.ndarray:
    """Seconds since each foot last left contact ``[F, S]`` from ``contacts bool [F, S]`` (0 in
    contact; a clip that starts in flight counts from one frame before its start)."""
    contacts = np.asarray(contacts)
    if contacts.ndim != 2 or contacts.dtype.kind not in "biu":
        raise ArgumentError(
            f"argument `contacts`: expected flags [F, S] (bool or 0/1), got {contacts.dtype} of shape "
            f"{list(contacts.shape)}"
        )
    return ops.air_time(np.ascontiguousarray(contacts, dtype=bool), _positive("frame_time", frame_time))


def contact_intervals(contacts, frame_time: float) -> list:
    """Contact intervals of one foot ``contacts [F]`` as a list of :class:`ContactInterval`, or
    of each foot of ``contacts [F, S]`` as a list per foot."""
    contacts = np.asarray(contacts, dtype=bool)
    frame_time = _positive("frame_time", frame_time)
    if contacts.ndim == 2:
        return [contact_intervals(contacts[:, s], frame_time) for s in range(contacts.shape[1])]
    if contacts.ndim != 1:
        raise ArgumentError(f"argument `contacts`: expected shape [F] or [F, S], got {list(contacts.shape)}")
    edges = np.diff(np.r_[0, contacts.astype(np.int8), 0])
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [ContactInterval(int(a), int(b), float((b - a + 1) * frame_time)) for a, b in zip(starts, ends)]


def footstrikes(contacts) -> np.ndarray:
    """Footstrikes ``int [N, 2]`` (frame, foot), in time order: the frames where a contact
    begins, the first frame excluded (a contact there started before the clip)."""
    contacts = np.asarray(contacts, dtype=bool)
    if contacts.ndim != 2:
        raise ArgumentError(f"argument `contacts`: expected shape [F, S], got {list(contacts.shape)}")
    frames, feet = np.nonzero(contacts[1:] & ~contacts[:-1])
    order = np.lexsort((feet, frames))
    return np.stack([frames[order] + 1, feet[order]], axis=1)


def cadence(contacts, frame_time: float) -> float:
    """Steps per second: footstrikes (both feet) per second between the first and the last
    one; NaN with fewer than two footstrikes."""
    strikes = footstrikes(contacts)[:, 0]
    frame_time = _positive("frame_time", frame_time)
    if len(strikes) < 2 or strikes[-1] == strikes[0]:
        return float("nan")
    return (len(strikes) - 1) / ((strikes[-1] - strikes[0]) * frame_time)


__all__ = [
    "FLOOR_PERCENTILE",
    "HEIGHT_THRESHOLD",
    "MIN_DURATION",
    "SPEED_THRESHOLD",
    "ContactInterval",
    "air_time",
    "cadence",
    "contact_intervals",
    "default_floor",
    "floor_of",
    "foot_contacts",
    "footstrikes",
    "percentiles_by_clip",
]
