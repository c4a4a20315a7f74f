"""How augmentation changes each kind of a window: rotation about the vertical, speed
perturbation, Gaussian noise and joint dropout (the transforms and their draws:
:mod:`.transforms`; :class:`Augment` is a shorthand for some of them, on every window).

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
from .transforms import Compose, Draws, Noise, RandomRotation, Speed, Transform

VECTOR_KINDS = ("positions", "velocities", "accelerations")  # rotated unless in the heading frame
ROOT_ROTATION_KINDS = ("rotations",)
ROOT_VECTOR_KINDS = ("angular_velocities",)
UNDEFINED_UNDER_ROTATION = ("body", "expressive")
RATE_POWER = {"velocities": 1, "accelerations": 2, "root_velocity": 1, "angular_velocities": 1}
FEATURE_RATES = (0, 1, 2, 3, 4, 5)  # features' hips velocities (per second)
FEATURE_TIMES = (8, 9)  # features' air times (seconds)
QUATERNION_KINDS = ("body", "expressive")  # always (x, y, z, w)
JOINT_KINDS = (  # kinds with a joint axis after the frames': what a joint dropout zeroes
    "positions",
    "rotations",
    "velocities",
    "accelerations",
    "angular_velocities",
    "activity",
    "body",
    "expressive",
)


@dataclass(frozen=True)
class Augment:
    """A shorthand for a :class:`~expressive_mocap.dataset.transforms.Compose` applying to every
    window: ``rotate`` False, True (an angle uniform in [-pi, pi)) or a number (uniform in
    [-rotate, rotate] radians); ``speed`` None or ``(low, high)`` factors, drawn log-uniformly;
    ``noise`` the std of Gaussian noise on every float kind, or ``{kind: std}``."""

    rotate: bool | float = False
    speed: tuple[float, float] | None = None
    noise: float | Mapping[str, float] = field(default=0.0)

    def __post_init__(self):
        self.transforms()  # the transforms check their arguments

    @property
    def active(self) -> bool:
        return bool(self.rotate) or self.speed is not None or bool(self.noise)

    def transforms(self) -> Compose:
        """The transforms this stands for, each with p = 1."""
        chosen: list[Transform] = []
        if self.rotate is not False and self.rotate != 0:
            chosen.append(RandomRotation(math.pi if self.rotate is True else float(self.rotate)))
        if self.speed is not None:
            try:
                chosen.append(Speed(self.speed))
            except ArgumentError:
                raise ArgumentError(f"argument `speed`: (low, high) with 0 < low <= high, got {self.speed}") from None
        if self.noise:
            chosen.append(Noise(self.noise))
        return Compose(chosen)


def as_compose(augment) -> Compose | None:
    """``augment`` (None, an :class:`Augment`, a transform, a list of them or a
    :class:`~expressive_mocap.dataset.transforms.Compose`) as a Compose, or None when it does
    nothing."""
    if augment is None:
        return None
    if isinstance(augment, Augment):
        augment = augment.transforms()
    elif isinstance(augment, Transform):
        augment = Compose([augment])
    elif isinstance(augment, (list, tuple)):
        augment = Compose(augment)
    if not isinstance(augment, Compose):
        raise ArgumentError(
            f"argument `augment`: an Augment, a Compose of transforms or a list of them, got {type(augment).__name__}"
        )
    return augment if augment.active else None


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


def rotate_some(batch: dict, angles: np.ndarray, manifest: Mapping, roots) -> None:
    """:func:`rotate_window_kinds` on the windows whose angle is not 0, the others untouched."""
    turned = angles != 0
    if turned.all():
        rotate_window_kinds(batch, angles, manifest, roots)
    elif turned.any():
        part = {kind: values[turned] for kind, values in batch.items()}
        rotate_window_kinds(part, angles[turned], manifest, roots)
        for kind, values in part.items():
            batch[kind][turned] = values


def add_noise(batch: dict, draws: Draws, noise: Noise) -> None:
    """Gaussian noise on the float kinds of ``batch`` (not contacts), in place, for the windows
    drawn to get it: each window's from its own generator (:meth:`Draws.noise_streams`)."""
    kinds = [k for k in batch if k != "contacts" and noise.of(k)]
    hit = np.flatnonzero(draws.noised)
    if not kinds or not len(hit):
        return
    sizes = [int(np.prod(batch[k].shape[1:])) for k in kinds]
    normal = np.empty((len(hit), sum(sizes)), dtype=np.float32)
    for row, generator in zip(normal, draws.noise_streams(hit)):
        generator.standard_normal(out=row, dtype=np.float32)
    at = 0
    for kind, size in zip(kinds, sizes):
        part = normal[:, at : at + size].reshape((len(hit),) + batch[kind].shape[1:])
        part *= noise.of(kind)
        if len(hit) == len(draws.noised):
            batch[kind] += part
        else:
            batch[kind][hit] += part
        at += size


def drop_joints(batch: dict, dropped: np.ndarray) -> None:
    """Zero, in place, the joints ``dropped`` ``[B, J]`` of every kind with a joint axis."""
    window, joint = np.nonzero(dropped)
    if len(window):
        for kind in JOINT_KINDS:
            if kind in batch:
                batch[kind][window, :, joint] = 0


__all__ = [
    "JOINT_KINDS",
    "Augment",
    "add_noise",
    "as_compose",
    "drop_joints",
    "rotate_some",
    "about_up",
    "interpolate",
    "rotate_root",
    "rotate_vectors",
    "rotate_window_kinds",
    "rotation_form",
    "scale_rates",
]
