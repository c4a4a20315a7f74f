"""Decoupling expressiveness from body mechanics (Boehs, Vieira & Pereira, "Decoupling
Expressiveness and Body-Mechanics in Human Motion") and its applications: modulation, source
mixing, asynchronous blending.

A body-mechanics model is anything with ``predict(motion) -> rotations [F, J, 4]``: the local
rotations a neutral performer would have at each frame given the motion's dynamics (root and
hips copied from the motion). The shipped one is :class:`expressive_mocap.model.BodyModel`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from . import quat
from .errors import MocapError
from .features import mean_rotation
from .ops import compose_rotations, decouple_rotations, forward_kinematics
from .motion import Motion
from .roles import JointRoles, facing_yaw, path_joint

GAIN = 2.0  # g of the activity index A = clip((tanh(a) g)^b, 0, 1)
EXPONENT = 4.0  # b
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


class BodyMechanicsModel(Protocol):
    def predict(self, motion: Motion) -> np.ndarray:
        """Body-mechanics local rotations ``[F, J, 4]`` for ``motion``."""


@dataclass(frozen=True)
class Decomposition:
    """``original`` split into filtered expressive rotations ``expressive`` (E*, ``[F, J, 4]``,
    identity where nothing expressive happens) and body-mechanics rotations ``body`` (B'), with
    the per-joint ``activity`` ``[F, J]`` in [0, 1]; ``E* * B' = O`` exactly."""

    original: Motion
    expressive: np.ndarray
    body: np.ndarray
    activity: np.ndarray

    def body_motion(self) -> Motion:
        """The body-mechanics component as a motion (translations and root trajectory of the original)."""
        return self._with_rotations(self.body)

    def expressive_motion(self) -> Motion:
        """The expressive component made visible: E* laid on the clip's mean body-mechanics
        pose (a neutral stance), root and hips following the original."""
        mean_body = mean_rotation(self.body)
        return self._with_rotations(quat.mul(self.expressive, mean_body[None]))

    def recompose(self, scale: float = 1.0) -> Motion:
        """``E*^scale * B'``: 1 gives back the original, 0 the body mechanics, 1.5 150% expressiveness."""
        return self._with_rotations(compose_rotations(self.expressive, self.body, scale))

    def _with_rotations(self, rotations: np.ndarray) -> Motion:
        o = self.original
        return Motion(o.skeleton, rotations, o.translations, o.frame_time)


def decompose(motion: Motion, model: BodyMechanicsModel, gain: float = GAIN, exponent: float = EXPONENT) -> Decomposition:
    """Split ``motion`` into expressive and body-mechanics components with ``model``."""
    predicted = np.asarray(model.predict(motion), dtype=np.float64)
    if predicted.shape != motion.rotations.shape:
        raise MocapError(f"the model predicted rotations {list(predicted.shape)} for a motion of {list(motion.rotations.shape)}")
    expressive, body, activity = decouple_rotations(motion.rotations, predicted, gain, exponent)
    return Decomposition(motion, expressive, body, activity)


def modulate(motion: Motion, scale: float, model: BodyMechanicsModel, gain: float = GAIN, exponent: float = EXPONENT) -> Motion:
    """The motion with its expressiveness scaled: ``O_s = E*^s B'`` (1 = unchanged, 0 = body mechanics only)."""
    return decompose(motion, model, gain, exponent).recompose(scale)


def _check_same_skeleton(a: Motion, b: Motion, what: str) -> None:
    if a.skeleton.names != b.skeleton.names:
        raise MocapError(f"{what}: the two motions have different skeletons ({a.skeleton.n_joints} and {b.skeleton.n_joints} joints, or other names)")


def _aligned(rotations: np.ndarray, frames: int, align: str, offset: int) -> np.ndarray:
    """``rotations [F, J, 4]`` on a timeline of ``frames`` frames: frame by frame from ``offset``
    (holding the last frame), or resampled (slerp) to that length."""
    if align == "index":
        index = np.clip(np.arange(frames) + offset, 0, len(rotations) - 1)
        return rotations[index]
    if align == "resample":
        if len(rotations) < 2 or frames < 2:
            return rotations[np.zeros(frames, dtype=int)]
        position = np.linspace(0, len(rotations) - 1, frames)
        i0 = np.minimum(position.astype(int), len(rotations) - 2)
        return quat.slerp(rotations[i0], rotations[i0 + 1], (position - i0)[:, None])
    raise MocapError(f"align must be 'index' or 'resample', got {align!r}")


def mix(body_source: Motion, expressive_source: Motion, model: BodyMechanicsModel, align: str = "index", offset: int = 0,
        gain: float = GAIN, exponent: float = EXPONENT) -> Motion:
    """The body mechanics (and root trajectory) of ``body_source`` with the expressive component
    of ``expressive_source``: ``E*_Y B'_X``. The expressive source is aligned to the body source
    frame by frame from ``offset`` (``align="index"``) or resampled to its length (``"resample"``)."""
    _check_same_skeleton(body_source, expressive_source, "mix")
    body = decompose(body_source, model, gain, exponent)
    expressive = decompose(expressive_source, model, gain, exponent).expressive
    rotations = compose_rotations(_aligned(expressive, body_source.n_frames, align, offset), body.body)
    return Motion(body_source.skeleton, rotations, body_source.translations, body_source.frame_time)


def _weights(frames: int, window: tuple[int, int]) -> np.ndarray:
    """Smoothstep from 0 before ``window[0]`` to 1 from ``window[1]`` on; an empty window is a step."""
    start, end = window
    if end < start:
        raise MocapError(f"a window must not end before it starts, got {start}:{end}")
    t = np.arange(frames, dtype=np.float64)
    if end == start:
        return (t >= start).astype(np.float64)
    x = np.clip((t - start) / (end - start), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _on_timeline(motion: Motion, start: int, frames: int) -> np.ndarray:
    """Frame indices of ``motion`` placed from output frame ``start`` (held at both ends)."""
    return np.clip(np.arange(frames) - start, 0, motion.n_frames - 1)


FACING_SECONDS = 1.0  # the facing at the anchor is averaged over about a gait cycle (the pelvis swings)


def _facing_at(positions: np.ndarray, roles: JointRoles, frame: int, fps: float) -> float:
    half = max(1, int(round(FACING_SECONDS * fps / 2)))
    return facing_yaw(positions[max(0, frame - half) : frame + half + 1], roles)


def _turned(motion: Motion, carrier: int, degrees: float, pivot: np.ndarray, to: np.ndarray) -> Motion:
    """``motion`` turned ``degrees`` about the vertical through its carrier's world position
    ``pivot`` and moved on the floor plane so that the pivot lands on ``to``: the carrier's world
    rotation pre-multiplied by the turn, its world path rotated with it (heights kept)."""
    world_rotations, positions = motion.fk()
    turn = quat.about("Y", degrees)
    parent = motion.skeleton.parents[carrier]
    if parent >= 0:
        parent_rotation, parent_position = world_rotations[:, parent], positions[:, parent]
    else:
        parent_rotation, parent_position = np.broadcast_to(IDENTITY, (motion.n_frames, 4)), np.zeros((motion.n_frames, 3))
    path = positions[:, carrier] - pivot * [1.0, 0.0, 1.0]
    path = quat.rotate(np.broadcast_to(turn, (motion.n_frames, 4)), path) + to * [1.0, 0.0, 1.0]
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    inverse = quat.conjugate(parent_rotation)
    rotations[:, carrier] = quat.mul(inverse, quat.mul(turn[None], world_rotations[:, carrier]))
    translations[:, carrier] = quat.rotate(inverse, path - parent_position)
    return Motion(motion.skeleton, rotations, translations, motion.frame_time)


def _second_start(body_window: tuple[int, int], expressive_window: tuple[int, int] | None) -> int:
    """The output frame where a blend's second motion starts: the earlier window's start."""
    return min(body_window[0], expressive_window[0]) if expressive_window is not None else body_window[0]


@dataclass(frozen=True)
class BlendAlignment:
    """How :func:`blend` places the second motion: ``joint`` carries the path (index), ``anchor``
    the output frame (the body window's start); the second motion is turned ``turn`` degrees about
    the vertical through its ``joint``'s position ``pivot [3]`` at the anchor, then moved by
    ``shift [3]`` on the floor plane (file units)."""

    joint: int
    anchor: int
    turn: float
    pivot: np.ndarray
    shift: np.ndarray


def blend_alignment(first: Motion, second: Motion, body_window: tuple[int, int], expressive_window: tuple[int, int] | None = None,
                    roles: JointRoles | None = None, first_positions: np.ndarray | None = None) -> BlendAlignment:
    """The placement of ``second`` that :func:`blend` uses with these windows."""
    roles = roles or JointRoles.find(first.skeleton)
    start = _second_start(body_window, expressive_window)
    frames = start + second.n_frames
    anchor = min(body_window[0], frames - 1)
    i, j = _on_timeline(first, 0, frames)[anchor], _on_timeline(second, start, frames)[anchor]
    joint = min(path_joint(m.translations, m.skeleton, roles) for m in (first, second))  # the higher on the chain
    a = first.positions() if first_positions is None else first_positions
    b = second.positions()
    turn = _facing_at(a, roles, i, first.fps) - _facing_at(b, roles, j, second.fps)
    turn = (turn + 180.0) % 360.0 - 180.0
    return BlendAlignment(joint, int(anchor), float(turn), b[j, joint].copy(), (a[i, joint] - b[j, joint]) * [1.0, 0.0, 1.0])


def blend(first: Motion, second: Motion, model: BodyMechanicsModel | None, body_window: tuple[int, int],
          expressive_window: tuple[int, int] | None = None, gain: float = GAIN, exponent: float = EXPONENT,
          roles: JointRoles | None = None) -> Motion:
    """Blend from ``first`` to ``second``, body mechanics over ``body_window`` and the expressive
    component over ``expressive_window`` (output frames ``(start, end)``; slerp with smoothstep
    weights). ``second`` starts at the earlier window's start. At the start of the body window
    (the anchor) it is turned about the vertical to face where ``first`` faces (the facing from the
    upper legs, averaged over a second around the anchor) and moved on the floor plane to where
    ``first``'s path is; both applied to the joint that carries the path (:func:`path_joint`: the
    hips on Bandai-Namco files, whose root never moves). In the body window the path follows the
    blend of both motions' steps, so it never moves faster than either (:func:`blend_alignment`
    tells the turn and the move). Without a model (or without an expressive window) this is the
    naive blend: whole poses over ``body_window``."""
    _check_same_skeleton(first, second, "blend")
    roles = roles or JointRoles.find(first.skeleton)
    start = _second_start(body_window, expressive_window)
    frames = start + second.n_frames
    i, j = _on_timeline(first, 0, frames), _on_timeline(second, start, frames)
    body_weights = _weights(frames, body_window)

    first_positions = first.positions()
    alignment = blend_alignment(first, second, body_window, expressive_window, roles, first_positions)
    carrier = alignment.joint
    second = _turned(second, carrier, alignment.turn, alignment.pivot, alignment.pivot + alignment.shift)

    if model is None or expressive_window is None:
        rotations = quat.slerp(first.rotations[i], second.rotations[j], body_weights[:, None])
    else:
        a, b = decompose(first, model, gain, exponent), decompose(second, model, gain, exponent)
        body = quat.slerp(a.body[i], b.body[j], body_weights[:, None])
        expressive = quat.slerp(a.expressive[i], b.expressive[j], _weights(frames, expressive_window)[:, None])
        rotations = compose_rotations(expressive, body)

    w = body_weights[:, None, None]
    translations = (1 - w) * first.translations[i] + w * second.translations[j]
    # The carrier's world path: the first's, plus the blend's share of the difference between the
    # two motions' steps on the floor plane (so the path never jumps: each step is a mix of the
    # inputs' steps); heights blended directly. Then back into the blended parent's frame.
    path_a, path_b = first_positions[i, carrier], second.positions()[j, carrier]
    # A step into frame t takes the weight of frame t - 1: at a cut the anchor frame is still the first's.
    steps = np.diff(path_b - path_a, axis=0, prepend=(path_b - path_a)[:1]) * np.r_[0.0, body_weights[:-1]][:, None]
    path = path_a + np.cumsum(steps * [1.0, 0.0, 1.0], axis=0)
    path[:, 1] = (1 - body_weights) * path_a[:, 1] + body_weights * path_b[:, 1]
    parent = first.skeleton.parents[carrier]
    if parent >= 0:
        world_rotations, positions = forward_kinematics(rotations, translations, first.skeleton.parents)
        path = quat.rotate(quat.conjugate(world_rotations[:, parent]), path - positions[:, parent])
    translations[:, carrier] = path
    return Motion(first.skeleton, rotations, translations, first.frame_time)


class StreamingDecoupler:
    """Decouples a motion one frame at a time, as it arrives (e.g. from a live capture).

    The features are causal, so frame ``t`` needs only the frames before it: the decoupler keeps
    the last ``history`` seconds (enough for the velocity mean, the contact filter and the air
    time of any step) and returns, for each new frame, its body-mechanics rotations, filtered
    expressive rotations and activity per joint. The floor is given (default 0), not estimated.
    """

    def __init__(self, model, skeleton, frame_time: float, floor: float = 0.0, history: float = 2.0,
                 gain: float = GAIN, exponent: float = EXPONENT):
        self.model, self.skeleton, self.frame_time = model, skeleton, float(frame_time)
        self.floor, self.gain, self.exponent = float(floor), gain, exponent
        self.capacity = max(2, int(round(history / self.frame_time)))
        self._rotations: list[np.ndarray] = []
        self._translations: list[np.ndarray] = []

    def push(self, rotations, translations) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One frame in (local ``rotations [J, 4]``, ``translations [J, 3]``); its body mechanics
        ``[J, 4]``, expressive component ``[J, 4]`` and activity ``[J]`` out."""
        self._rotations.append(np.asarray(rotations, dtype=np.float64))
        self._translations.append(np.asarray(translations, dtype=np.float64))
        del self._rotations[: -self.capacity], self._translations[: -self.capacity]
        window = Motion(self.skeleton, np.stack(self._rotations), np.stack(self._translations), self.frame_time)
        features = self.model.features(window, floor=self.floor)[-1:]
        body = self.model.predict_from_features(window.rotations[-1:], features)
        expressive, recovered, activity = decouple_rotations(window.rotations[-1:], body, self.gain, self.exponent)
        return recovered[0], expressive[0], activity[0]
