"""Noise in joint positions, found and taken out before a fit (:mod:`.fit`).

Positions count as noisy where the steadiest joint jitters between frames (:func:`noise`); they
are then smoothed over time, and the feet through their contacts (:func:`steady_feet`), where a
stance foot moves slowly and what is left of noise is noise.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..body.jointmap import JointMap

if TYPE_CHECKING:
    from ..motion import Motion
    from .layouts import Layout

# Positions count as noisy where :func:`noise` passes this share of the actor's height (0.4 cm
# of 141: clean captures and their runs measure 0.01-0.25 cm, 1 cm of added noise 0.7-1.0), and
# are then smoothed over a Gaussian of DENOISE frames at 30 fps.
NOISY = 0.003
DENOISE = 2.0
# The feet's penalties (weights at 30 fps, against the squared distance from the positions): on their acceleration
# everywhere, about the smoothing of a 2.5-frame Gaussian but leaving a steady velocity alone; on
# their velocity through a contact, holding a stance foot still. Chosen on a dataset-2 walk with
# 1 cm of noise (ACCELERATION 10-150 and STILL 36-400 tried): the stance ankle moves 5.6 (humanml3d)
# and 3.4 cm/s (h36m17) in mid-stance against the clean fit's 2.9, where the Gaussians the feet
# had (one over each contact, after the whole body's) left 10.9 and 6.5.
ACCELERATION = 40.0
STILL = 36.0


def steady_feet(points: np.ndarray, raw: np.ndarray, contacts: np.ndarray, jmap: JointMap, fps: float) -> np.ndarray:
    """``points`` with each foot's ankle and toes taken from the unsmoothed ``raw`` positions and
    smoothed through their ``contacts [F, 2]``: the positions nearest to them whose acceleration
    (everywhere) and, through a contact, velocity are penalised (:data:`ACCELERATION`,
    :data:`STILL`; a least-squares problem, one banded solve). A Gaussian drags a swinging foot's
    speed into the stance it lands in and leaves from (the foot slid 11 cm/s in mid-stance); a
    penalty on acceleration leaves a steady velocity as it is, and the stance is held on its own."""
    from scipy.linalg import solve_banded  # here: SciPy takes a tenth of a second to import

    out = points.copy()
    frames = len(points)
    if frames < 3:
        return out
    rate = fps / 30.0  # the penalties are for 30 fps: a difference over k frames scales by k
    for s, side in enumerate(("left", "right")):
        joints = [jmap[f"{side}_{p}"] for p in ("foot", "toes") if f"{side}_{p}" in jmap]
        still = np.where(contacts[1:, s] & contacts[:-1, s], STILL * rate**2, 0.0)
        banded = _penalised(frames, still, np.full(frames - 2, ACCELERATION * rate**4))
        out[:, joints] = solve_banded((2, 2), banded, raw[:, joints].reshape(frames, -1)).reshape(raw[:, joints].shape)
    return out


def _penalised(frames: int, velocity: np.ndarray, acceleration: np.ndarray) -> np.ndarray:
    """The banded form ``[5, F]`` of ``I + D1' diag(velocity) D1 + D2' diag(acceleration) D2``
    (D1, D2: first and second differences over ``frames``), as :func:`scipy.linalg.solve_banded`
    takes it: ``A[i, j]`` at ``[2 + i - j, j]``."""
    banded = np.zeros((5, frames))
    banded[2] = 1.0
    for weights, stencil in ((velocity, (-1.0, 1.0)), (acceleration, (1.0, -2.0, 1.0))):
        n = len(weights)  # difference r touches frames r .. r + len(stencil) - 1: A[r + a, r + b]
        for a, ca in enumerate(stencil):
            for b, cb in enumerate(stencil):
                banded[2 + a - b, b : b + n] += weights * ca * cb
    return banded


def noise(points: np.ndarray, fps: float) -> float:
    """How much frame-to-frame noise positions ``[F, J, 3]`` carry (their units): the steadiest
    joint's median second difference, as the standard deviation of white noise giving it (motion
    adds to it; at 30 fps a run's steadiest joint reads 0.25 cm)."""
    if len(points) < 3:
        return 0.0
    second = np.abs(points[2:] - 2.0 * points[1:-1] + points[:-2])
    return float(np.median(second, axis=(0, 2)).min() / (0.6745 * np.sqrt(6.0)))


def noisy(points: np.ndarray, jmap: JointMap, fps: float) -> bool:
    """Whether positions ``[F, J, 3]`` (Y up) are noisy: :func:`noise` over :data:`NOISY` of the
    actor's height, roughly (the median of the hips' height above the feet plus the line from the
    hips to the head)."""
    feet = np.minimum(points[:, jmap["left_foot"], 1], points[:, jmap["right_foot"], 1])
    spine = np.linalg.norm(points[:, jmap["head"]] - points[:, jmap["hips"]], axis=-1)
    return noise(points, fps) > NOISY * float(np.median(points[:, jmap["hips"], 1] - feet + spine))


def steadied_fit(
    points: np.ndarray, raw: np.ndarray, layout: Layout, user_map: dict, fps: float, smooth: float
) -> tuple[Motion, np.ndarray]:
    """:func:`fit_layout` of smoothed noisy ``points`` whose feet are first steadied through their
    contacts from the ``raw`` positions (:func:`.denoise.steady_feet`), the ankles then put there by
    leg IK (their forward kinematics gathers the noise of every joint above them); and the
    steadied positions. The contacts are read from the positions with the fitted skeleton's roles
    and size: no fit is needed for them (its rest stands in for every frame)."""
    from ..motion import Motion
    from .layout_fit import fit_layout, fit_skeleton
    from .planting import plant_feet, source_contacts
    from .rig import Rig, rest_motion

    rest = rest_motion(fit_skeleton(points, layout)[0])
    rig = Rig.of(rest, user_map)
    frames = len(points)
    still = Motion(
        rest.skeleton, np.repeat(rest.rotations, frames, 0), np.repeat(rest.translations, frames, 0), 1 / fps
    )
    contacts = source_contacts([still], rig, points)
    steadied = steady_feet(points, raw, contacts, rig.jmap, fps)
    ankles = steadied[:, [rig.jmap["left_foot"], rig.jmap["right_foot"]]]
    return plant_feet(fit_layout(steadied, layout, fps, smooth=smooth), rig.jmap, contacts, ankles), steadied


__all__ = ["ACCELERATION", "DENOISE", "NOISY", "STILL", "noise", "noisy", "steadied_fit", "steady_feet"]
