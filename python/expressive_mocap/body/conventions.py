"""The conventions a file was captured in, read from its data: up axis, facing direction, unit
and actor height, rest pose kind, frame rate; and the change of axes and unit that brings a
motion to the package's canonical frame (Y up, facing +Z, metres) and back.

- **Up**: the mean direction from the feet to the head over the frames (sampled), snapped to the
  nearest axis; how sure: the cosine between the two.
- **Facing**: the rest pose's forward (left x up, left from the right hip joint to the left;
  up along the spine), turned so that the rest's spine stands along the up axis (Bandai-Namco's
  rest pose lies along X); snapped to the nearest horizontal axis.
- **Actor height**: from the leg bones, which no pose changes: thigh plus shank are 0.491 of
  the stature (Drillis & Contini's segment proportions). The unit (m, cm, mm, inches or CMU's
  1/0.45 inch) is the one in which that height is a human's (1.0-2.4 m); how sure falls off with
  the distance from 1.70 m.
- **Rest pose**: T (upper arms within 25 degrees of horizontal and out to the side), A (25-70
  degrees down), else other; "crouch" when the knees are bent over 25 degrees in the rest.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import numpy as np

from .._utils.kept import Kept
from ..errors import MocapError
from ..motion import Motion, Skeleton, spread_frames
from ..rotations import quat
from .body import Body
from .jointmap import JointMap
from .mapcheck import check_posed_map, four_legged

LEG_SHARE_OF_STATURE = 0.491  # thigh + shank (Drillis & Contini 1966)
TYPICAL_HEIGHT_M = 1.70
# "cmu": the CMU database's own unit, 1/0.45 inch (its ASF files' "length 0.45").
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254, "cmu": 0.0254 / 0.45}
AXES = {"+X": (1, 0, 0), "-X": (-1, 0, 0), "+Y": (0, 1, 0), "-Y": (0, -1, 0), "+Z": (0, 0, 1), "-Z": (0, 0, -1)}
SAMPLED_FRAMES = 240  # frames of a motion its up axis and the map's posed checks are read from


@dataclass(frozen=True)
class Conventions:
    """What :func:`read_conventions` found. ``up`` and ``facing`` are axis names (``"+Y"``);
    ``unit`` is ``"m"``, ``"cm"``, ``"mm"``, ``"in"``, ``"cmu"`` (CMU's 1/0.45 inch) or
    ``"unknown"``; ``metres_per_unit``
    converts lengths (for an unknown unit: the scale that makes the actor 1.70 m tall);
    ``height`` is the actor's height in file units; ``sure`` holds how sure each guess is (0-1)."""

    up: str
    facing: str
    unit: str
    metres_per_unit: float
    height: float
    rest_pose: str
    fps: float
    sure: dict

    def rotation(self) -> np.ndarray:
        """The rotation (quaternion) from the file's axes to the canonical ones (Y up, facing +Z)."""
        return _frame_rotation(self.up, self.facing)

    def with_overrides(self, up: str | None = None, facing: str | None = None, unit: str | None = None) -> Conventions:
        """These conventions with any of up, facing or unit given by the user (sure = 1)."""
        sure = dict(self.sure)
        out = {"up": self.up, "facing": self.facing, "unit": self.unit, "metres_per_unit": self.metres_per_unit}
        for name, value in (("up", up), ("facing", facing)):
            if value is not None:
                value = _axis_name(value, name)
                out[name], sure[name] = value, 1.0
        if unit is not None:
            if unit not in UNITS:
                raise MocapError(f"unit: expected one of {', '.join(UNITS)}, got {unit!r}")
            out["unit"], out["metres_per_unit"], sure["unit"] = unit, UNITS[unit], 1.0
        if np.dot(AXES[str(out["up"])], AXES[str(out["facing"])]) != 0:
            raise MocapError(f"facing {out['facing']} must be horizontal, at right angles to up {out['up']}")
        return Conventions(
            str(out["up"]),
            str(out["facing"]),
            str(out["unit"]),
            float(out["metres_per_unit"]),  # type: ignore[arg-type]
            self.height,
            self.rest_pose,
            self.fps,
            sure,
        )


def _axis_name(value: str, what: str) -> str:
    name = value.upper() if value[:1] in "+-" else "+" + value.upper()
    if name not in AXES:
        raise MocapError(f"{what}: expected an axis such as Y, +Z or -X, got {value!r}")
    return name


@lru_cache(maxsize=64)
def _frame_rotation(up: str, facing: str) -> np.ndarray:
    """The rotation taking axis ``up`` to +Y and ``facing`` to +Z (names such as ``"+Z"``)."""
    u, f = np.array(AXES[up], float), np.array(AXES[facing], float)
    turn = quat.from_matrix(np.stack([np.cross(u, f), u, f]))  # rows: where X, Y, Z come from
    turn.setflags(write=False)
    return turn


def _nearest_axis(v: np.ndarray, exclude: str | None = None) -> tuple[str, float]:
    v = v / max(float(np.linalg.norm(v)), 1e-30)
    best = max(
        (name for name in AXES if exclude is None or name[1] != exclude[1]), key=lambda n: float(np.dot(AXES[n], v))
    )
    return best, float(np.dot(AXES[best], v))


def body_axes(positions: np.ndarray, jmap: JointMap) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per pose ``[..., J, 3]``: unit up (hips to chest), left (right to left hip joint, made
    perpendicular to up) and forward (left x up), each ``[..., 3]``."""
    up = positions[..., jmap["chest"], :] - positions[..., jmap["hips"], :]
    up = up / np.linalg.norm(up, axis=-1, keepdims=True)
    left = positions[..., jmap["left_upper_leg"], :] - positions[..., jmap["right_upper_leg"], :]
    left = left - up * np.sum(left * up, axis=-1, keepdims=True)
    left = left / np.linalg.norm(left, axis=-1, keepdims=True)
    return up, left, np.cross(left, up)


def stature(skeleton: Skeleton, jmap: JointMap) -> float:
    """The actor's height in file units, from the leg bones (see the module's notes)."""
    legs = []
    positions = skeleton.rest_positions()[0]
    for side in ("left", "right"):
        hip, knee, ankle = (positions[jmap[f"{side}_{r}"]] for r in ("upper_leg", "lower_leg", "foot"))
        legs.append(np.linalg.norm(knee - hip) + np.linalg.norm(ankle - knee))
    return float(np.mean(legs)) / LEG_SHARE_OF_STATURE


def rest_pose_kind(skeleton: Skeleton, jmap: JointMap) -> tuple[str, float]:
    """``("T" | "A" | "crouch" | "other", how sure)`` of the skeleton's rest pose."""
    rest = skeleton.rest_positions()[0]
    up, left, _ = body_axes(rest, jmap)
    knees = []
    for side in ("left", "right"):
        hip, knee, ankle = (rest[jmap[f"{side}_{r}"]] for r in ("upper_leg", "lower_leg", "foot"))
        knees.append(_angle(knee - hip, ankle - knee))
    knee = max(knees)
    if knee > 25:
        return "crouch", float(min(1.0, (knee - 25) / 20))
    if "left_upper_arm" not in jmap:
        return "other", 0.5
    drops, outward = [], []
    for side, sign in (("left", 1.0), ("right", -1.0)):
        arm = rest[jmap[f"{side}_forearm"]] - rest[jmap[f"{side}_upper_arm"]]
        arm = arm / np.linalg.norm(arm)
        drops.append(-np.degrees(np.arcsin(np.clip(arm @ up, -1, 1))))
        outward.append(sign * float(arm @ left))
    drop = float(np.mean(drops))
    if min(outward) < 0.3:
        return "other", 0.5
    if abs(drop) <= 25:
        return "T", float(1 - abs(drop) / 50)
    if 25 < drop <= 70:
        return "A", float(1 - abs(drop - 47.5) / 45)
    return "other", 0.5


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    cos = float(a @ b) / max(float(np.linalg.norm(a) * np.linalg.norm(b)), 1e-30)
    return float(np.degrees(np.arccos(np.clip(cos, -1, 1))))


def guess_unit(height: float) -> tuple[str, float, float]:
    """``(unit, metres per unit, how sure)`` for an actor ``height`` file units tall."""
    best = ("unknown", TYPICAL_HEIGHT_M / height if height > 0 else 1.0, 0.0)
    for unit, metres in UNITS.items():
        tall = height * metres
        if 1.0 <= tall <= 2.4:
            sure = float(np.exp(-((np.log(tall / TYPICAL_HEIGHT_M) / 0.25) ** 2)))
            if sure > best[2]:
                best = (unit, metres, sure)
    return best


def up_and_facing(skeleton: Skeleton, jmap: JointMap, positions: np.ndarray) -> tuple[tuple, tuple]:
    """``((up, how sure), (facing, how sure))`` of a skeleton whose posed world positions
    ``[F, J, 3]`` (a sample of frames) are given (see the module's notes)."""
    up = up_of(jmap, positions)
    return up, facing_of(skeleton, jmap, up[0])


def up_of(jmap: JointMap, positions: np.ndarray) -> tuple[str, float]:
    """``(up, how sure)``: the axis nearest the mean line from the feet to the head in the posed
    world positions ``[F, J, 3]``: the one thing of a motion's axes its frames must tell."""
    if not len(positions):  # no frames: no telling (+X, sure 0, as ups_of reads such a clip)
        return _nearest_axis(np.zeros(3))
    feet = 0.5 * (positions[:, jmap["left_foot"]] + positions[:, jmap["right_foot"]])
    return _nearest_axis(np.mean(positions[:, jmap["head"]] - feet, axis=0))


def ups_of(jmap: JointMap, samples: list[np.ndarray]) -> list[str]:
    """:func:`up_of`'s axis for each of many clips' posed positions ``[F_i, J, 3]``, in a few
    NumPy calls whatever their number (a clip of no frames reads +X, as :func:`up_of` does)."""
    if not samples:
        return []
    joints = [jmap["head"], jmap["left_foot"], jmap["right_foot"]]
    counts = np.array([len(s) for s in samples])
    points = np.concatenate([s[:, joints] for s in samples])  # [sum F_i, 3, 3]
    lines = points[:, 0] - 0.5 * (points[:, 1] + points[:, 2])
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    sums = np.zeros((len(samples), 3))
    some = counts > 0
    sums[some] = np.add.reduceat(lines, starts[some])  # reduceat would give an empty clip the next row
    means = sums / np.maximum(counts, 1)[:, None]
    names = list(AXES)
    return [names[k] for k in np.argmax(means @ np.array([AXES[n] for n in names], float).T, axis=1)]


def facing_of(skeleton: Skeleton, jmap: JointMap, up: str) -> tuple[str, float]:
    """``(facing, how sure)`` of ``skeleton`` whose up axis is ``up``: its rest pose's forward
    (:func:`body_axes`), turned upright, nearest axis across ``up``. The same for every motion of
    a skeleton: kept for the skeletons met last."""

    def facing() -> tuple[str, float]:
        rest_up, _, rest_forward = body_axes(skeleton.rest_positions()[0], jmap)
        forward = quat.rotate(quat.between(rest_up, np.array(AXES[up], float)), rest_forward)
        return _nearest_axis(forward - np.dot(forward, AXES[up]) * np.array(AXES[up]), exclude=up)

    return _FACINGS.get((skeleton.content_key, tuple(jmap.joints.items()), up), facing)


_FACINGS: Kept[tuple[str, float]] = Kept(64)


def frame_rotation(up: str, facing: str) -> np.ndarray:
    """The rotation (quaternion) taking axis ``up`` to +Y and ``facing`` to +Z (names such as ``"+Z"``)."""
    return _frame_rotation(up, facing)


def read_conventions(motion: Motion, jmap: JointMap) -> Conventions:
    """The conventions of ``motion`` (see the module's notes)."""
    skeleton = motion.skeleton
    positions = motion[spread_frames(motion.n_frames, SAMPLED_FRAMES)].positions()
    check_posed_map(jmap, positions)
    (up, up_sure), (facing, facing_sure) = up_and_facing(skeleton, jmap, positions)
    if four_legged(jmap, positions, np.array(AXES[up], dtype=np.float64)):
        warnings.warn(
            "this skeleton moves on four legs (its trunk level, its hands as low as its feet, in most frames): "
            "it was mapped as a human's, front legs as arms; give a joint map file if that is wrong",
            stacklevel=2,
        )
    height, (unit, metres, unit_sure), (kind, kind_sure) = _of_skeleton(skeleton, jmap)
    sure = {
        "up": round(up_sure, 3),
        "facing": round(facing_sure, 3),
        "unit": round(unit_sure, 3),
        "rest_pose": round(kind_sure, 3),
    }
    return Conventions(up, facing, unit, metres, height, kind, motion.fps, sure)


def _of_skeleton(skeleton: Skeleton, jmap: JointMap) -> tuple:
    """The conventions a skeleton alone tells: its actor's height, unit and rest pose, kept for the
    skeletons met last (an archive's clips share a few)."""

    def tells() -> tuple:
        height = stature(skeleton, jmap)
        return height, guess_unit(height), rest_pose_kind(skeleton, jmap)

    return _SKELETONS.get((skeleton.content_key, tuple(jmap.joints.items())), tells)


_SKELETONS: Kept[tuple] = Kept(64)


def to_canonical(motion: Motion, conventions: Conventions) -> Motion:
    """``motion`` in the canonical frame: Y up, facing +Z, metres (every local rotation turned
    with the axes, offsets and translations turned and scaled)."""
    return _changed(motion, conventions.rotation(), conventions.metres_per_unit)


def from_canonical(motion: Motion, conventions: Conventions) -> Motion:
    """The inverse of :func:`to_canonical`: back to the file's own axes and unit."""
    return _changed(motion, quat.conjugate(conventions.rotation()), 1.0 / conventions.metres_per_unit)


def upright(motion: Motion) -> Motion:
    """``motion`` turned so that its up axis (read from its data) is +Y, lengths as they are:
    what pictures and Y-up code need. Returned as it is when already Y-up or not mappable."""
    return upright_and_back(motion)[0]


def upright_and_back(motion: Motion) -> tuple[Motion, Callable[[Motion], Motion]]:
    """:func:`upright` of ``motion``, and the turn that puts a motion of the same skeleton back
    into ``motion``'s own axes (the identity when nothing was turned)."""
    try:
        up = read_conventions(motion, Body.of(motion.skeleton).joint_map).up
    except MocapError:
        up = "+Y"
    if up == "+Y":
        return motion, lambda edited: edited
    turn = quat.between(np.array(AXES[up], float), np.array([0.0, 1.0, 0.0]))
    skeleton = motion.skeleton

    def back(edited: Motion) -> Motion:
        turned = _changed(edited, quat.conjugate(turn), 1.0)
        return Motion(skeleton, turned.rotations, turned.translations, turned.frame_time)

    return _changed(motion, turn, 1.0), back


def _changed(motion: Motion, turn: np.ndarray, scale: float) -> Motion:
    skeleton = motion.skeleton
    offsets = quat.rotate(turn, skeleton.offsets) * scale
    sites = quat.rotate(turn, np.array([o for _, o in skeleton.end_sites]).reshape(-1, 3)) * scale
    turned = skeleton.with_offsets(offsets, sites)
    rotations = quat.mul(quat.mul(turn, motion.rotations), quat.conjugate(turn))
    translations = quat.rotate(turn, motion.translations) * scale
    return Motion(turned, rotations, translations, motion.frame_time)


__all__ = [
    "AXES",
    "SAMPLED_FRAMES",
    "UNITS",
    "Conventions",
    "body_axes",
    "facing_of",
    "frame_rotation",
    "from_canonical",
    "guess_unit",
    "read_conventions",
    "rest_pose_kind",
    "stature",
    "to_canonical",
    "up_and_facing",
    "up_of",
    "ups_of",
    "upright",
    "upright_and_back",
]
