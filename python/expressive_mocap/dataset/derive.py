"""Model-ready arrays: the options of ``preprocess`` that shape what is stored (rotation form,
position frame, frame rate, mirrored copies) and the pure functions that make a batch's stored
arrays from its clips' world positions and local rotations.

Everything here works on the clips of one skeleton at once, their frames concatenated
(``starts``: each clip's first row), so a batch costs a few NumPy calls, not a few per clip.
Time derivatives are ``np.gradient``'s, clip by clip: central differences, one-sided at a clip's
first and last frame, zero for a one-frame clip; no difference ever spans two clips.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import ops
from ..errors import ArgumentError
from ..motion import Motion
from ..reference.forms import clip_gradient
from ..rotations import quat
from . import representations
from .heading import HeadingFrame, to_heading, turn_by_yaw

POSITION_FRAMES = ("world", "root", "heading", "clip")
DERIVED_KINDS = ("velocities", "accelerations", "root_velocity", "angular_velocities", "heading")
# Rotation forms the clip kernels give as they are, and their matrix columns (0: quaternions).
KERNEL_COLUMNS = {"quaternion": 0, "6d": 2, "matrix": 3}
# A resampled clip takes the source's every n-th frame as it is when the rates are this close to n:1
# (files round the frame time: 0.0333333 s for 30 fps).
RATE_TOLERANCE = 1e-4


@dataclass(frozen=True)
class Options:
    """How the stored arrays are shaped: ``rotations`` (a form of
    :data:`~expressive_mocap.dataset.representations.KINDS`, ``"euler:ORDER"`` for Euler angles),
    ``positions`` (:data:`POSITION_FRAMES`), ``fps`` (resample every clip first; None: as read)
    and ``mirror`` (store each clip's mirror image after it)."""

    rotations: str = "quaternion"
    positions: str = "world"
    fps: float | None = None
    mirror: bool = False

    @classmethod
    def of(cls, rotations: str | None = None, positions: str | None = None, fps=None, mirror: bool = False) -> Options:
        """Checked options; ``"euler"`` alone is ``"euler:ZXY"``. An ArgumentError names a bad one."""
        rotations = rotations or "quaternion"
        form, _, order = rotations.partition(":")
        if form not in representations.KINDS or (order and form != "euler"):
            raise ArgumentError(
                f"--rotations: expected one of {', '.join(representations.KINDS)} (euler:ORDER for an order), "
                f"got {rotations!r}"
            )
        if form == "euler":
            order = (order or "ZXY").upper()
            if sorted(order) != ["X", "Y", "Z"]:
                raise ArgumentError(
                    f"--rotations: an Euler order is X, Y and Z once each, e.g. euler:ZXY, got {order!r}"
                )
            rotations = f"euler:{order}"
        positions = positions or "world"
        if positions not in POSITION_FRAMES:
            raise ArgumentError(f"--positions: expected one of {', '.join(POSITION_FRAMES)}, got {positions!r}")
        if fps is not None:
            if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not (np.isfinite(fps) and fps > 0):
                raise ArgumentError(f"--fps: a positive number of frames per second, got {fps!r}")
            fps = float(fps)
        return cls(rotations, positions, fps, bool(mirror))

    @property
    def form(self) -> tuple[str, str]:
        """The rotation form and its Euler order (``"ZXY"`` unless Euler)."""
        form, _, order = self.rotations.partition(":")
        return form, order or "ZXY"

    @property
    def width(self) -> int:
        """Values a rotation takes in the stored form."""
        return representations.KINDS[self.form[0]]

    @property
    def decoded(self) -> bool:
        """Whether clips are decoded into arrays before the kernels (to resample or mirror them)."""
        return self.fps is not None or self.mirror

    def heading(self, keep) -> bool:
        """Whether the skeleton's heading frame (its up axis at least) is needed for the kinds ``keep``."""
        moving = any(k in keep for k in ("positions", "velocities", "accelerations"))
        return "root_velocity" in keep or "heading" in keep or (moving and self.positions != "world")

    def positions_needed(self, keep) -> bool:
        return any(k in keep for k in ("positions", "velocities", "accelerations", "root_velocity", "heading"))

    def rotations_needed(self, keep) -> bool:
        return "rotations" in keep or "angular_velocities" in keep

    def plain(self, keep) -> bool:
        """Whether the kernels' float32 outputs are stored as they are: positions in the world's
        frame, rotations as quaternions or matrix columns, velocities of the world positions
        (the clip kernels make those forms, :class:`~expressive_mocap.ops.PipelineOutputs`);
        nothing mirrored and no other derived kind (:func:`derive` makes those)."""
        return (
            self.form[0] in KERNEL_COLUMNS
            and self.positions == "world"
            and not self.mirror
            and not any(k in keep for k in DERIVED_KINDS if k != "velocities")
        )

    @property
    def rotation_columns(self) -> int:
        """The clip kernels' rotation form for this form (0: quaternions; see :data:`KERNEL_COLUMNS`)."""
        return KERNEL_COLUMNS.get(self.form[0], 0)

    def record(self) -> dict:
        """The options as the manifest records them."""
        return {"rotations": self.rotations, "positions": self.positions, "fps": self.fps, "mirror": self.mirror}


@dataclass(frozen=True)
class RunOptions:
    """Everything a preprocessing run was asked for that its dataset depends on: the kinds kept
    (``keep``), the body ``model`` (its resolved path, ``"shipped"`` or None) and whether it runs
    in float32, the ``source``'s canonical path, the kernel ``backend``, whether clips go onto the
    ``canonical`` body (with the user's ``joint_map``), how the arrays are shaped
    (``shaping``), and the SMPL-family body model parameter files are read with
    (``smpl_model``). A run resumes, and a finished dataset counts as done, only under the
    same options; the manifest and an interrupted run's record hold them as :meth:`record`."""

    keep: tuple[str, ...]
    model: str | None
    model_float32: bool
    source: str
    backend: str
    canonical: bool = False
    joint_map: dict | None = None
    shaping: Options = Options()
    smpl_model: str | None = None

    @property
    def canonical_map(self) -> dict | None:
        """What the batches' work needs of the canonical options: the joint map (``{}``: none), or
        None when clips stay on their own skeleton."""
        return (self.joint_map or {}) if self.canonical else None

    def record(self) -> dict:
        """The options as the manifest (``options``) and ``run.json`` record them."""
        return {"keep": list(self.keep), "model": self.model, "model_float32": bool(self.model_float32),
                "source": self.source, "backend": self.backend, "canonical": bool(self.canonical),
                "joint_map": self.joint_map or None, **self.shaping.record(),
                # Only when given: the options of a run from before the key still match.
                **({"smpl_model": self.smpl_model} if self.smpl_model else {})}  # fmt: skip


def resampled(motion: Motion, fps: float) -> Motion:
    """``motion`` at ``fps`` frames a second, from its first frame, as many frames as its duration
    holds: each source frame as it is when ``fps`` divides the source's rate (the same rate: the
    clip itself; half: every second frame), else :meth:`Motion.resample` (slerp for rotations,
    linear for translations; a MocapError when that would make more frames than a motion may hold)."""
    ratio = (1.0 / motion.frame_time) / fps  # source frames per output frame
    step = round(ratio)
    if step >= 1 and abs(ratio - step) <= RATE_TOLERANCE * ratio:
        rows = slice(0, motion.n_frames, step)
        return Motion(motion.skeleton, motion.rotations[rows], motion.translations[rows], 1.0 / fps)
    if motion.n_frames < 2:
        return Motion(motion.skeleton, motion.rotations, motion.translations, 1.0 / fps)
    return motion.resample(fps=fps)


def _rotation_change(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation vectors of ``a b^-1``: the turn from ``b`` to ``a`` in the axes they are written in."""
    return quat.log(quat.mul(a, quat.conjugate(b)))


def derive(
    keep,
    options: Options,
    positions: np.ndarray | None,
    rotations: np.ndarray | None,
    starts: np.ndarray,
    frame_time: np.ndarray,
    frame: HeadingFrame | None,
    root: int = 0,
) -> dict[str, np.ndarray]:
    """The stored arrays (float32, kind -> ``[N, ...]``) of the kinds ``keep`` among positions,
    rotations and :data:`DERIVED_KINDS`, for clips of one skeleton whose world ``positions [N, J, 3]``
    and local ``rotations [N, J, 4]`` are concatenated (clips begin at rows ``starts``, each row's
    clip's ``frame_time [N]``). ``frame``: the skeleton's heading frame, when ``options.heading(keep)``;
    ``root``: the root joint. See docs/preprocessing.md for each kind's definition."""
    out: dict[str, np.ndarray] = {}
    if rotations is not None and "rotations" in keep:
        form, order = options.form
        out["rotations"] = representations.encode(rotations, form, order, np.float32)
    if rotations is not None and "angular_velocities" in keep:
        out["angular_velocities"] = clip_gradient(rotations, starts, frame_time, _rotation_change)
    if positions is not None and options.positions_needed(keep):
        out.update(_positions(keep, options, positions, starts, frame_time, frame, root))
    return {kind: np.asarray(values, dtype=np.float32) for kind, values in out.items()}


def _positions(
    keep, options: Options, positions: np.ndarray, starts: np.ndarray, frame_time: np.ndarray, frame, root: int
) -> dict[str, np.ndarray]:
    """The positions kept, their velocities and accelerations and the root velocity."""
    out = {}
    where = options.positions
    if frame is None and options.heading(keep):
        raise ArgumentError(f"--positions {where} and root_velocity need the skeleton's heading frame")
    turned = where in ("heading", "clip") or "root_velocity" in keep or "heading" in keep
    yaw = unwrap_by_clip(frame.yaw(positions), starts) if turned else np.zeros(len(positions))
    origin = frame.origin(positions) if turned else np.zeros((len(positions), 3))
    if where == "world":
        stored = positions
    elif where == "root":
        stored = frame.harmonised(positions - positions[:, root : root + 1])
    elif where == "heading":
        stored = to_heading(positions, frame, yaw, origin)
    else:  # clip: every frame in its clip's first frame's heading frame
        first = np.repeat(starts, np.diff(np.append(starts, len(positions))))
        stored = to_heading(positions, frame, yaw[first], origin[first])
    if "positions" in keep:
        out["positions"] = stored
    if "velocities" in keep or "accelerations" in keep:
        # heading: the world's velocity (harmonised axes) turned into each frame's heading
        moving = frame.harmonised(positions) if where == "heading" else stored
        velocities = ops.clip_gradient(moving, starts, frame_time)
        if "velocities" in keep:
            out["velocities"] = turn_by_yaw(velocities, -yaw) if where == "heading" else velocities
        if "accelerations" in keep:
            accelerations = ops.clip_gradient(velocities, starts, frame_time)
            out["accelerations"] = turn_by_yaw(accelerations, -yaw) if where == "heading" else accelerations
    if "heading" in keep:  # what takes any of the frames back to the world's (harmonised) axes
        out["heading"] = np.stack([origin[:, 0], origin[:, 2], yaw], axis=-1)
    if "root_velocity" in keep:
        hips = ops.clip_gradient(frame.harmonised(positions[:, frame.hips]), starts, frame_time)
        out["root_velocity"] = np.concatenate(
            [turn_by_yaw(hips, -yaw), ops.clip_gradient(yaw, starts, frame_time)[:, None]], axis=-1
        )
    return out


def unwrap_by_clip(angles: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``angles`` (radians, clips end to end from rows ``starts``) unwrapped within each clip, each
    clip's first frame left in [-pi, pi]: as each clip alone gives, bit for bit, whatever comes
    before it. Clip by clip: unwrapping the whole run and taking each clip's whole turns back off
    changed the last bits (a yaw rate of a resumed run differed by 1e-13)."""
    out = np.empty(len(angles))
    bounds = np.append(starts, len(angles))
    for first, end in zip(bounds[:-1], bounds[1:]):
        out[first:end] = np.unwrap(angles[first:end])
    return out


def totals(arrays: list[np.ndarray]) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """``(rows, sums, squares)`` of each of ``arrays`` (``[n_i, ...]`` float32, one row shape): its
    row count and the float64 sums of its rows and of their squares ``[...]``, the increments of the
    running normalisation statistics (:mod:`.stats`), each the same whatever arrays come with it."""
    sums, squares = ops.column_totals(arrays)
    return [(len(a), s1, s2) for a, s1, s2 in zip(arrays, sums, squares)]


__all__ = [
    "DERIVED_KINDS", "POSITION_FRAMES", "Options", "RunOptions", "derive", "resampled", "totals", "unwrap_by_clip",
]  # fmt: skip
