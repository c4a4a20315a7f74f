"""A gesture's own cycles: the periods of a repeated arm gesture (a wave), else the span the
hands move in (a raise of the arm and its lowering).

A gesture clip holds idle frames, the arm raised, the gesture and the arm lowered, in lengths
that differ from take to take; time-normalised as one whole clip, a wave's strokes fall at a
different phase in every take and average away. Here the moving hand's path about the chest is
read: the frames where it is away from where it starts and ends (the span), and within them the
slow raise removed, what repeats (the period, from the path's autocorrelation) and one cycle per
stroke, peak to peak along the stroke's main direction.
"""

from __future__ import annotations

import numpy as np

from ..body.take import Take

MOVING = 0.3  # the span: frames where the hand is this share of its farthest from rest, or more
SLOW_SECONDS = 0.5  # motion slower than this (the raise, a drift) is not a stroke
PERIOD_SECONDS = (0.2, 2.5)  # a stroke's period lies in this range
REPEATS = 0.3  # the autocorrelation a period must reach to count as repeating
PERIOD_SPREAD = (0.6, 1.5)  # a stroke's length against the period, for it to be one stroke


def moving_hand(take: Take) -> tuple[np.ndarray, np.ndarray]:
    """The path ``[F, 3]`` about the chest of the hand that travels farther about it (the waving
    or raised one, not the one hanging or swinging with a walk), and its distance ``[F]`` from
    where it rests at the clip's ends."""
    positions, jmap = take.positions, take.body.joint_map
    paths = [positions[:, jmap[f"{side}_hand"]] - positions[:, jmap["chest"]] for side in ("left", "right")]
    path = max(paths, key=lambda p: float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()))
    ends = min(3, len(path))
    rest = np.concatenate([path[:ends], path[-ends:]]).mean(axis=0)
    return path, np.linalg.norm(path - rest, axis=1)


def gesture_span(away: np.ndarray) -> tuple[int, int]:
    """First and last frame where the hand is at least :data:`MOVING` of its farthest from rest."""
    on = np.flatnonzero(away >= MOVING * away.max()) if away.max() > 0 else np.arange(len(away))
    return int(on[0]), int(on[-1])


def stroke_period(strokes: np.ndarray, fps: float) -> tuple[int | None, float]:
    """The period in frames of ``strokes`` ``[F, 3]`` (the hand's fast motion) and how well it
    repeats: the first lag in :data:`PERIOD_SECONDS` where its autocorrelation peaks at
    :data:`REPEATS` or more, and the highest such peak (None and 0 when nothing repeats)."""
    n = len(strokes)
    power = float(np.mean(np.sum(strokes * strokes, axis=1)))
    shortest, longest = int(PERIOD_SECONDS[0] * fps), min(n // 2, int(PERIOD_SECONDS[1] * fps))
    if power <= 0 or longest <= shortest:
        return None, 0.0
    lags = np.arange(longest + 1)
    # Each lag's mean product over the frames it overlaps (unbiased: long lags are not shrunk).
    correlation = np.array([np.sum(strokes[: n - k] * strokes[k:]) / (n - k) for k in lags]) / power
    from scipy.signal import find_peaks  # here: scipy.signal takes a second to import

    peaks, _ = find_peaks(correlation)
    peaks = peaks[(peaks >= shortest) & (correlation[peaks] >= REPEATS)]
    return (int(peaks[0]), float(correlation[peaks].max())) if len(peaks) else (None, 0.0)


def _strokes(take: Take) -> tuple[int, int, np.ndarray]:
    """The moving hand's span (first and last frame) and the fast part ``[S, 3]`` of its path
    about the chest over the span (the slow raise removed; none in a span of under 4 frames)."""
    path, away = moving_hand(take)
    start, end = gesture_span(away)
    part = path[start : end + 1] - path[start : end + 1].mean(axis=0)
    if len(part) < 4:
        return start, end, np.zeros_like(part)
    from scipy.ndimage import gaussian_filter1d  # here: SciPy takes a tenth of a second to import

    return start, end, part - gaussian_filter1d(part, SLOW_SECONDS * take.motion.fps, axis=0, mode="nearest")


def repetition(motion: Take) -> float:
    """How well the moving hand's strokes repeat (:func:`stroke_period`'s peak): near 1 for a
    wave, 0 for a single raise."""
    take = Take.of(motion)
    return stroke_period(_strokes(take)[2], take.motion.fps)[1]


def _signed(direction: np.ndarray, take: Take, start: int, end: int) -> np.ndarray:
    """``direction`` (a unit stroke direction, of either sign) pointing to the body's left, or up
    for a stroke more up-down than sideways: so every take's strokes start at the same end."""
    positions, jmap = take.positions[start : end + 1], take.body.joint_map
    left = np.mean(positions[:, jmap["left_upper_arm"]] - positions[:, jmap["right_upper_arm"]], axis=0)
    up = np.mean(positions[:, jmap["head"]] - positions[:, jmap["hips"]], axis=0)
    left, up = (v / max(float(np.linalg.norm(v)), 1e-12) for v in (left, up))
    axis = left if abs(direction @ left) >= abs(direction @ up) else up
    return direction if direction @ axis >= 0 else -direction


def gesture_cycles(motion: Take) -> list[tuple[int, int]]:
    """The cycles of a gesture, as (first, last) frames: one per stroke of a repeated gesture (peak to peak along the
    hand's main stroke direction, the longest run of strokes about one period long, at least
    two; each stroke starts at the end of its path nearest the body's left, or its top), else one
    cycle over the span the hand moves in."""
    take = Take.of(motion)
    start, end, strokes = _strokes(take)
    span = [(start, end)] if end > start else [(0, take.motion.n_frames - 1)]
    period = stroke_period(strokes, take.motion.fps)[0]
    if period is None:
        return span
    direction = _signed(np.linalg.svd(strokes, full_matrices=False)[2][0], take, start, end)
    from scipy.ndimage import gaussian_filter1d
    from scipy.signal import find_peaks

    along = gaussian_filter1d(strokes @ direction, 1.0)
    peaks, _ = find_peaks(along, distance=max(2, int(PERIOD_SPREAD[0] * period)))
    runs: list[list[tuple[int, int]]] = [[]]
    for a, b in zip(peaks[:-1], peaks[1:]):
        if PERIOD_SPREAD[0] * period <= b - a <= PERIOD_SPREAD[1] * period:
            runs[-1].append((int(a) + start, int(b) + start))
        elif runs[-1]:
            runs.append([])
    longest = max(runs, key=len)
    return longest if len(longest) >= 2 else span


__all__ = ["gesture_cycles", "gesture_span", "moving_hand", "repetition", "stroke_period"]
