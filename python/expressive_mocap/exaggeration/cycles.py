"""Cycles: a walk's footstrike-to-footstrike cycles (or a whole clip), their time normalisation
to ``T`` samples and back, and their heading (the travel direction, removed before measuring)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..body.contacts import foot_contacts, footstrikes
from ..body.roles import facing_yaw
from ..body.take import Take
from ..errors import ArgumentError, MocapError
from ..motion import Motion
from ..rotations import quat
from .gestures import gesture_cycles
from .settings import CYCLE_CHOICES, TRAINING, CycleChoice


@dataclass(frozen=True)
class Cycle:
    """Frames ``start`` to ``end`` (both included; ``end`` is the next footstrike of ``foot``,
    0 = left, 1 = right, -1 for a whole clip or a given range)."""

    start: int
    end: int
    foot: int = -1

    @property
    def n_frames(self) -> int:
        return self.end - self.start + 1


def find_cycles(motion: Motion | Take, foot: int | None = TRAINING.foot) -> list[Cycle]:
    """Gait cycles of a walk: footstrike to next footstrike of ``foot`` (0 = left, the default, so
    that every cycle of every clip starts in the same phase; None: the foot whose cycles cover
    more frames). The cycles follow each other without gaps; empty when the foot never strikes twice."""
    strikes = footstrikes(foot_contacts(motion))
    best: list[Cycle] = []
    for side in (0, 1) if foot is None else (int(foot),):
        frames = strikes[strikes[:, 1] == side, 0]
        cycles = [Cycle(int(a), int(b), side) for a, b in zip(frames[:-1], frames[1:]) if b - a >= 2]
        if sum(c.n_frames for c in cycles) > sum(c.n_frames for c in best):
            best = cycles
    return best


def normalise_cycle(motion: Motion, cycle: Cycle, samples: int = TRAINING.samples) -> Motion:
    """The frames of ``cycle`` resampled to ``samples`` frames over the same span (slerp for
    rotations, linear for translations): the time-normalised cycle."""
    if cycle.start < 0 or cycle.end >= motion.n_frames or cycle.end - cycle.start < 1:
        raise ArgumentError(f"cycle frames {cycle.start}-{cycle.end} do not fit a {motion.n_frames}-frame motion")
    return motion[cycle.start : cycle.end + 1].resample(n_frames=samples)


def to_cycle_timing(trajectory: np.ndarray, n_frames: int) -> np.ndarray:
    """Map a normalised trajectory ``[T, ...]`` back to a cycle of ``n_frames`` frames (the
    inverse of the uniform time normalisation: linear interpolation at each frame's phase)."""
    trajectory = np.asarray(trajectory, dtype=np.float64)
    return quat.resample(trajectory, quat.spanning_positions(len(trajectory), n_frames), rotations=False)


def check_cycle_choice(cycle: CycleChoice) -> None:
    """Refuse a ``cycle`` that is neither a name of :data:`CYCLE_CHOICES`, an index nor a range."""
    if not isinstance(cycle, tuple) and cycle not in CYCLE_CHOICES and not isinstance(cycle, (int, np.integer)):
        raise ArgumentError(
            f"cycle must be one of {', '.join(CYCLE_CHOICES)}, an index or a (start, end) range, got {cycle!r}"
        )


def choose_cycles(motion: Motion | Take, cycle: CycleChoice, foot: int = TRAINING.foot) -> list[Cycle]:
    """The cycles of a training clip for ``cycle`` = "all" (every one), "middle" (the one nearest the
    clip's middle: steady walking), "first", "whole" (the clip), "gesture" (a gesture's strokes or
    span: :func:`~expressive_mocap.exaggeration.gestures.gesture_cycles`), an index, or a
    ``(start, end)`` frame range; walking cycles run from one footstrike of ``foot`` to the next."""
    take = Take.of(motion)
    motion = take.motion
    if isinstance(cycle, tuple):
        start, end = (int(v) for v in cycle)
        return [Cycle(start, end)]
    if cycle == "whole":
        return [Cycle(0, motion.n_frames - 1)]
    if cycle == "gesture":
        return [Cycle(first, last) for first, last in gesture_cycles(take)]
    check_cycle_choice(cycle)
    cycles = find_cycles(take, foot=foot)
    if not cycles:
        raise MocapError(
            f"no gait cycle found in its {motion.n_frames} frames (no foot strikes twice): for an action other than "
            "walking take the whole clip (--cycle whole; in Python cycle='whole') or a (start, end) frame range"
        )
    if cycle == "first":
        return cycles[:1]
    if cycle == "all":
        return cycles
    if cycle == "middle":
        middle = motion.n_frames / 2
        return [min(cycles, key=lambda c: abs((c.start + c.end) / 2 - middle))]
    assert isinstance(cycle, (int, np.integer))  # check_cycle_choice let nothing else through
    if not -len(cycles) <= cycle < len(cycles):
        raise MocapError(f"cycle {cycle}: the clip has {len(cycles)} cycles")
    return [cycles[cycle]]


def cycles_for(motion: Motion | Take, cycle: CycleChoice, foot: int = TRAINING.foot) -> list[Cycle]:
    """The cycles an edit or an intensity estimate reads in ``motion`` for a model trained with
    the cycle choice ``cycle``: a gesture's for "gesture", the whole clip for "whole", else the gait
    cycles of ``foot`` (the whole clip when that foot never strikes twice)."""
    take = Take.of(motion)
    if cycle in ("whole", "gesture"):
        return choose_cycles(take, cycle)
    return find_cycles(take, foot=foot) or [Cycle(0, take.motion.n_frames - 1)]


# --------------------------------------------------------------------------- heading


def _yaw(vector: np.ndarray) -> float:
    """Degrees about Y that turn +Z towards the horizontal ``vector``."""
    return float(np.degrees(np.arctan2(vector[0], vector[2])))


def cycle_heading(take: Take, cycle: Cycle) -> float:
    """The yaw (degrees) of a cycle's travel direction: the hips' horizontal displacement from its
    first to its last frame; where the hips barely travel (< 5% of the actor's height), the
    facing direction (perpendicular to the line from the right to the left upper leg)."""
    positions, roles = take.positions, take.body.roles
    hips = positions[[cycle.start, cycle.end], roles.hips]
    travel = hips[1] - hips[0]
    travel[1] = 0.0
    if np.linalg.norm(travel) >= 0.05 * take.body.actor_height:
        return _yaw(travel)
    return facing_yaw(positions[cycle.start : cycle.end + 1], roles)


def frame_yaw(take: Take, cycles: Sequence[Cycle]) -> np.ndarray:
    """Heading (degrees) of every frame: its cycle's; before the first / after the last, the nearest."""
    frames = take.motion.n_frames
    yaw = np.zeros(frames)
    if not cycles:
        return yaw + cycle_heading(take, Cycle(0, frames - 1))
    headings = [cycle_heading(take, c) for c in cycles]
    yaw[: cycles[0].start] = headings[0]
    for c, h in zip(cycles, headings):
        yaw[c.start : c.end + 1] = h
    yaw[cycles[-1].end :] = headings[-1]
    return yaw


def without_heading(rotations: np.ndarray, hips: int, yaw: np.ndarray | float) -> np.ndarray:
    """Rotations with the hips pre-multiplied by the inverse of ``yaw`` (degrees, per frame or one)."""
    out = rotations.copy()
    out[:, hips] = quat.mul(quat.about("Y", -np.broadcast_to(yaw, len(rotations))), rotations[:, hips])
    return out


@dataclass
class SampledCycles:
    """Time-normalised cycles of one clip: heading-free rotations ``[C, T, J, 4]`` and hips
    heights / actor height ``[C, T]``."""

    rotations: np.ndarray
    heights: np.ndarray


def sample_cycles(take: Take, cycles: Sequence[Cycle], samples: int) -> SampledCycles:
    """Each of ``cycles`` time-normalised to ``samples`` frames with its own heading removed."""
    motion, roles, height = take.motion, take.body.roles, take.body.actor_height
    rots, heights = [], []
    for cycle in cycles:
        yaw = cycle_heading(take, cycle)
        part = normalise_cycle(motion, cycle, samples)
        rots.append(without_heading(part.rotations, roles.hips, yaw))
        heights.append(part.positions()[:, roles.hips, 1] / height)
    return SampledCycles(np.stack(rots), np.stack(heights))


__all__ = [
    "Cycle",
    "SampledCycles",
    "check_cycle_choice",
    "choose_cycles",
    "cycle_heading",
    "cycles_for",
    "find_cycles",
    "frame_yaw",
    "normalise_cycle",
    "sample_cycles",
    "to_cycle_timing",
    "without_heading",
]
