"""Noise in joint positions, found and taken out before a fit (:mod:`.fit`).

Positions count as noisy where the steadiest joint jitters between frames (:func:`noise`); they
are then smoothed over time, and the feet more through their contacts (:func:`steady_feet`),
where a stance foot moves slowly and what is left of noise is noise.
"""

from __future__ import annotations

import numpy as np

from ..body.jointmap import JointMap

# Positions count as noisy where :func:`noise` passes this share of the actor's height (0.4 cm
# of 141: clean captures and their runs measure 0.01-0.25 cm, 1 cm of added noise 0.7-1.0), and
# are then smoothed over a Gaussian of DENOISE frames at 30 fps.
NOISY = 0.003
DENOISE = 2.0
STANCE = 6.0  # the Gaussian (frames at 30 fps) a noisy foot is smoothed over through a contact
EASE = 2.0  # ... eased in and out over a Gaussian of these frames
SWING = 1.5  # ... and over this one outside them


def steady_feet(points: np.ndarray, contacts: np.ndarray, jmap: JointMap, fps: float) -> np.ndarray:
    """``points`` with each foot's ankle and toes smoothed over a Gaussian of :data:`STANCE`
    frames through each run of its ``contacts [F, 2]``: a stance foot moves slowly (rolling from
    heel to toe), so what is left of noise there is noise, and retargeting plants the target's
    foot where the source's goes."""
    from scipy.ndimage import gaussian_filter1d

    out = points.copy()
    for s, side in enumerate(("left", "right")):
        joints = [jmap[f"{side}_{p}"] for p in ("foot", "toes") if f"{side}_{p}" in jmap]
        on = contacts[:, s].astype(float)
        # Eased in and out (no step where a contact starts or ends), nothing outside them.
        weight = np.minimum(on, gaussian_filter1d(on, EASE * fps / 30.0, mode="nearest"))[:, None, None]
        # Swinging, the foot's short bone still turns with what noise is left: smoothed a little more.
        out[:, joints] = gaussian_filter1d(points[:, joints], SWING * fps / 30.0, axis=0, mode="nearest")
        edges = np.flatnonzero(np.diff(np.concatenate([[0], on.astype(int), [0]])))
        for a, b in zip(edges[::2], edges[1::2]):
            steady = gaussian_filter1d(points[a:b, joints], STANCE * fps / 30.0, axis=0, mode="nearest")
            out[a:b, joints] = weight[a:b] * steady + (1.0 - weight[a:b]) * out[a:b, joints]
    return out


def noise(points: np.ndarray, fps: float) -> float:
    """How much frame-to-frame noise positions ``[F, J, 3]`` carry (their units): the steadiest
    joint's median second difference, as the standard deviation of white noise giving it (motion
    adds to it; at 30 fps a run's steadiest joint reads 0.25 cm)."""
    if len(points) < 3:
        return 0.0
    second = np.abs(points[2:] - 2.0 * points[1:-1] + points[:-2])
    return float(np.median(second, axis=(0, 2)).min() / (0.6745 * np.sqrt(6.0)))


__all__ = ["DENOISE", "EASE", "NOISY", "STANCE", "SWING", "noise", "steady_feet"]
