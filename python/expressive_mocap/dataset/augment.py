"""On-the-fly augmentation of windows read from a dataset: rotation about the vertical, speed
perturbation and Gaussian noise (:class:`Augment`), each drawn per window from a seeded generator.

How each kind behaves (``manifest["options"]``: ``positions`` the frame of positions,
``rotations`` the form of rotations; a dataset without them has world positions and quaternions):

============================  ==========================================  ==========================
kind                          rotation by theta about ``manifest["up"]``  speed factor s
============================  ==========================================  ==========================
positions                     rotated (world, root, clip); heading: same  interpolated
velocities                    rotated (world, root, clip); heading: same  interpolated, x s
accelerations                 rotated (world, root, clip); heading: same  interpolated, x s^2
rotations                     root joint(s): theta composed before them   slerp (decode, encode)
                              (decode, rotate, encode in their form)
root_velocity                 same (heading frame)                        interpolated, x s
angular_velocities            root joint(s): rotated (parent = world)     interpolated, x s
heading                       origin turned, yaw + theta                  interpolated
features                      same (heading frame)                        velocities x s, air time / s
contacts                      same                                        nearest frame
activity                      same                                        interpolated
body, expressive              not defined: an error                       slerp
============================  ==========================================  ==========================

Rotations and angular velocities turn about ``manifest["rotations_up"]``, the up axis of the
file's world they are in (``manifest["up"]`` is the positions', Y in the harmonised frames).

Speed factor s > 1 plays the motion faster: the window's ``T`` frames are read ``s`` source
frames apart (``s * (T - 1)`` frames of the clip); past the clip's end its last frame repeats.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat
from . import representations
from .frames import turn_headings
from .representations import decode, encode

VECTOR_KINDS = ("positions", "velocities", "accelerations")  # rotated unless in the heading frame
ROOT_ROTATION_KINDS = ("rotations",)
ROOT_VECTOR_KINDS = ("angular_velocities",)
UNDEFINED_UNDER_ROTATION = ("body", "expressive")
RATE_POWER = {"velocities": 1, "accelerations": 2, "root_velocity": 1, "angular_velocities": 1}
FEATURE_RATES = (0, 1, 2, 3, 4, 5)  # features' hips velocities (per second)
FEATURE_TIMES = (8, 9)  # features' air times (seconds)
QUATERNION_KINDS = ("body", "expressive")  # always (x, y, z, w)


@dataclass(frozen=True)
class Augment:
    """What to draw per window. ``rotate``: False, True (an angle uniform in [-pi, pi)) or a
    number (uniform in [-rotate, rotate] radians); ``speed``: None or ``(low, high)`` factors,
    drawn log-uniformly (``(0.8, 1.25)``: as often slower as faster); ``noise``: the std of
    Gaussian noise added to every float kind (after normalisation, when the reader normalises:
    then in units of each channel's std), or ``{kind: std}``."""

    rotate: bool | float = False
    speed: tuple[float, float] | None = None
    noise: float | Mapping[str, float] = field(default=0.0)

    def __post_init__(self):
        if self.speed is not None and not (0 < self.speed[0] <= self.speed[1]):
            raise ArgumentError(f"argument `speed`: (low, high) with 0 < low <= high, got {self.speed}")

    @property
    def active(self) -> bool:
        return bool(self.rotate) or self.speed is not None or bool(self.noise)

    def angles(self, rng: np.random.Generator, n: int) -> np.ndarray:
        if self.rotate is False or self.rotate == 0:
            return np.zeros(n)
        limit = math.pi if self.rotate is True else float(self.rotate)
        return rng.uniform(-limit, limit, n)

    def speeds(self, rng: np.random.Generator, n: int) -> np.ndarray:
        if self.speed is None:
            return np.ones(n)
        low, high = np.log(self.speed[0]), np.log(self.speed[1])
        return np.exp(rng.uniform(low, high, n)) if high > low else np.full(n, self.speed[0])

    def noise_of(self, kind: str) -> float:
        return float(self.noise.get(kind, 0.0)) if isinstance(self.noise, Mapping) else float(self.noise)


def rotation_form(manifest: Mapping) -> tuple[str, str]:
    """``(form, euler order)`` of the ``rotations`` kind from ``manifest["options"]["rotations"]``."""
    spelled = (manifest.get("options") or {}).get("rotations") or "quaternion"
    form, _, order = str(spelled).partition(":")
    return form, order or "ZXY"


def about_up(up, angles) -> np.ndarray:
    """Quaternions ``[B, 4]`` of rotations by ``angles`` (radians) about the axis ``up``."""
    axis = np.asarray(up, dtype=np.float64)
    axis = axis / np.linalg.norm(axis)
    half = np.asarray(angles, dtype=np.float64)[:, None] / 2
    return np.concatenate([np.sin(half) * axis, np.cos(half)], axis=-1)


def rotate_vectors(values: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Vectors ``[B, ..., 3]`` each rotated by its window's quaternion ``q [B, 4]``."""
    matrix = quat.to_matrix(q).astype(values.dtype)  # [B, 3, 3]
    flat = values.reshape(len(values), -1, 3)
    return np.matmul(flat, np.swapaxes(matrix, 1, 2)).reshape(values.shape)


def rotate_root(values: np.ndarray, q: np.ndarray, roots, form: str, order: str = "ZXY") -> np.ndarray:
    """Rotations ``[B, T, J, n]`` in ``form`` with the root joints' composed after ``q [B, 4]``
    (the world turned about the vertical): decoded, rotated, encoded; quaternions kept on their
    own hemisphere, so rotating by theta then -theta gives the input back."""
    out = values.copy()
    root = np.asarray(values[:, :, roots], dtype=np.float64)
    qs = q[:, None, None, :]
    if form == "quaternion":
        turned = quat.mul(qs, root)
    else:
        turned = encode(quat.mul(qs, decode(root, form, order)), form, order)
    out[:, :, roots] = turned
    return out


def rotate_window_kinds(batch: dict, angles: np.ndarray, manifest: Mapping, roots) -> None:
    """Rotate in place the kinds of ``batch`` (``{kind: [B, T, ...]}``) that turn with the world
    by ``angles [B]`` about ``manifest["up"]`` (the table in this module's notes)."""
    bad = [k for k in UNDEFINED_UNDER_ROTATION if k in batch]
    if bad:
        raise ArgumentError(f"rotation augmentation is not defined for {', '.join(bad)}: leave them out")
    options = manifest.get("options") or {}
    up = manifest.get("up") or [0.0, 1.0, 0.0]
    q = about_up(up, angles)
    if options.get("positions", "world") != "heading":
        for kind in VECTOR_KINDS:
            if kind in batch:
                batch[kind] = rotate_vectors(batch[kind], q)
    if "heading" in batch:  # harmonised axes: a turn about the file's up is one about +Y
        batch["heading"] = turn_headings(batch["heading"].astype(np.float64), angles).astype(batch["heading"].dtype)
    # Rotations stay in the file's world, whose up the positions' may not be (harmonised frames).
    q = about_up(manifest.get("rotations_up") or up, angles)
    for kind in ROOT_VECTOR_KINDS:
        if kind in batch:
            values = batch[kind].copy()
            values[:, :, roots] = rotate_vectors(values[:, :, roots], q)
            batch[kind] = values
    if "rotations" in batch:
        form, order = rotation_form(manifest)
        batch["rotations"] = rotate_root(batch["rotations"], q, roots, form, order).astype(batch["rotations"].dtype)


def interpolate(kind: str, a: np.ndarray, b: np.ndarray, frac: np.ndarray, manifest: Mapping) -> np.ndarray:
    """Frames between ``a`` and ``b`` (``[B, T, ...]``, the frames before and after each sample)
    at ``frac [B, T]`` in [0, 1): ``a`` where ``frac`` is 0 (to rounding, for rotations)."""
    at = frac.reshape(frac.shape + (1,) * (a.ndim - 2))
    if a.dtype == bool or kind == "contacts":
        return np.where(at < 0.5, a, b)
    if kind == "rotations" or kind in QUATERNION_KINDS:
        form, order = rotation_form(manifest) if kind == "rotations" else ("quaternion", "ZXY")
        return representations.interpolate(a, b, at, form, order)
    mixed = b - a
    mixed *= at.astype(a.dtype)
    mixed += a
    return mixed


def scale_rates(kind: str, values: np.ndarray, speeds: np.ndarray) -> np.ndarray:
    """Rates of ``kind`` ``[B, T, ...]`` of motion played ``speeds [B]`` times faster."""
    s = speeds.reshape((-1,) + (1,) * (values.ndim - 1)).astype(values.dtype)
    if kind in RATE_POWER:
        return values * s ** RATE_POWER[kind]
    if kind == "features":
        out = values.copy()
        out[..., list(FEATURE_RATES)] *= s
        out[..., list(FEATURE_TIMES)] /= s
        return out
    return values


__all__ = [
    "Augment",
    "about_up",
    "interpolate",
    "rotate_root",
    "rotate_vectors",
    "rotate_window_kinds",
    "rotation_form",
    "scale_rates",
]
