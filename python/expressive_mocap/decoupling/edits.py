"""Applications of the decoupling method (Boehs et al.): modulation (scaling the expressive
component), source mixing (one motion's body mechanics with another's expressiveness) and
asynchronous blending (body mechanics and expressiveness over different windows).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..body.hinges import hinge_limits_for, limit_hinges
from ..body.roles import JointRoles, facing_yaw, path_joint
from ..body.take import Take
from ..errors import ArgumentError
from ..motion import Motion
from ..ops import compose_rotations, forward_kinematics
from ..rotations import quat
from .algebra import EXPONENT, GAIN, BodyMechanicsModel, Decomposition, decompose
from .feet import chosen_joints, planted

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def modulate(
    motion: Motion | Take,
    scale: float,
    model: BodyMechanicsModel,
    gain: float = GAIN,
    exponent: float = EXPONENT,
    plant_feet: bool = True,
    hinges: bool = True,
    parts: Decomposition | None = None,
) -> Motion:
    """The motion with its expressiveness scaled: ``O_s = E*^s B'`` (1 = unchanged, 0 = body
    mechanics only); elbows and knees kept within their limits (``hinges``, see :func:`_limited`).
    ``plant_feet``: the stance feet kept where ``motion`` has them during its contacts
    (:func:`~expressive_mocap.decoupling.feet.planted`). ``parts``: the motion's decomposition
    by ``model``, when the caller has made it already (its ``original`` must be ``motion``)."""
    take = Take.of(motion)
    motion = take.motion
    if parts is not None and parts.original is not motion:
        raise ArgumentError("argument `parts`: a decomposition of another motion than `motion`")
    out = (parts if parts is not None else decompose(take, model, gain, exponent)).recompose(scale)
    out = _limited(out, [motion], [motion.rotations], hinges)
    return planted(take, out)[0] if plant_feet else out


def _limited(out: Motion, sources: list[Motion], allow: list[np.ndarray], hinges: bool) -> Motion:
    """``out`` with every elbow and knee kept from straight to the most the body shows (plus a
    margin), never tighter than the inputs' rotations ``allow`` (on ``out``'s timeline) have it:
    the limits of :func:`~expressive_mocap.body.hinges.hinge_limits_for` the ``sources``."""
    if not hinges:
        return out
    return limit_hinges(out, hinge_limits_for(sources), allow)[0]


def _check_same_skeleton(a: Motion, b: Motion, what: str) -> None:
    if a.skeleton.names != b.skeleton.names:
        raise ArgumentError(
            f"{what}: the two motions have different skeletons "
            f"({a.skeleton.n_joints} and {b.skeleton.n_joints} joints, or other names)"
        )


ALIGNS = ("time", "index", "resample")
# Two frame rates this close are one: files round the frame time (0.0333333 s for 30 fps).
SAME_RATE = 1e-4


def at_rate_of(motion: Motion, other: Motion, align: str = "time") -> Motion:
    """``motion`` at ``other``'s frame rate when ``align`` is ``"time"`` and the rates differ
    (:meth:`Motion.resample`: slerp for rotations), so that frame ``k`` of each is at the same
    time; else ``motion`` as it is (``"index"`` pairs frames by number, whatever their rates)."""
    if align not in ALIGNS:
        raise ArgumentError(f"align must be one of {', '.join(ALIGNS)}, got {align!r}")
    if align != "time" or abs(motion.frame_time - other.frame_time) <= SAME_RATE * other.frame_time:
        return motion
    return motion.resample(fps=other.fps)


def _at_rate_of(take: Take, other: Motion, align: str) -> Take:
    """:func:`at_rate_of` of a take: the take itself where its motion is kept."""
    motion = at_rate_of(take.motion, other, align)
    return take if motion is take.motion else Take(motion, take.body)


def _aligned(rotations: np.ndarray, frames: int, align: str, offset: int) -> np.ndarray:
    """``rotations [F, J, 4]`` on a timeline of ``frames`` frames: frame by frame from ``offset``
    (holding the last frame), or resampled (slerp) to that length."""
    if align in ("time", "index"):  # "time": the rates were made one (at_rate_of)
        index = np.clip(np.arange(frames) + offset, 0, len(rotations) - 1)
        return rotations[index]
    if align == "resample":
        if len(rotations) < 2 or frames < 2:
            return rotations[np.zeros(frames, dtype=int)]
        return quat.resample(rotations, quat.spanning_positions(len(rotations), frames))
    raise ArgumentError(f"align must be one of {', '.join(ALIGNS)}, got {align!r}")


def mix(
    body_source: Motion | Take,
    expressive_source: Motion | Take,
    model: BodyMechanicsModel,
    align: str = "time",
    offset: int = 0,
    gain: float = GAIN,
    exponent: float = EXPONENT,
    joints=None,
    plant_feet: bool = True,
    hinges: bool = True,
) -> Motion:
    """The body mechanics (and root trajectory) of ``body_source`` with the expressive component
    of ``expressive_source``: ``E*_Y B'_X``. The expressive source is aligned to the body source
    in time (``align="time"``: resampled to the body source's frame rate, then frame by frame
    from ``offset``, holding its last frame), frame by frame whatever the rates (``"index"``), or
    stretched to the body source's length (``"resample"``).
    ``joints``: the joints that take ``expressive_source``'s expression (group names such as
    ``"arms"``, or a mask; default :func:`~expressive_mocap.decoupling.feet.default_mask`); the
    others keep ``body_source``'s rotations exactly. ``plant_feet``: the stance feet kept where
    ``body_source`` has them during its contacts. Elbows and knees are kept within their limits
    (``hinges``), never tighter than either source has them."""
    body_take = Take.of(body_source)
    body_source = body_take.motion
    _check_same_skeleton(body_source, Take.of(expressive_source).motion, "mix")
    expressive_take = _at_rate_of(Take.of(expressive_source), body_source, align)
    expressive_source = expressive_take.motion
    mask = chosen_joints(joints, body_take, expressive_take)
    body = decompose(body_take, model, gain, exponent)
    expressive = decompose(expressive_take, model, gain, exponent).expressive
    rotations = compose_rotations(_aligned(expressive, body_source.n_frames, align, offset), body.body)
    rotations = np.where(mask[None, :, None], rotations, body_source.rotations)
    out = Motion(body_source.skeleton, rotations, body_source.translations, body_source.frame_time)
    allow = [body_source.rotations, _aligned(expressive_source.rotations, body_source.n_frames, align, offset)]
    out = _limited(out, [body_source, expressive_source], allow, hinges)
    return planted(body_take, out)[0] if plant_feet else out


def _weights(frames: int, window: tuple[int, int]) -> np.ndarray:
    """Smoothstep from 0 before ``window[0]`` to 1 from ``window[1]`` on; an empty window is a step."""
    start, end = window
    if end < start:
        raise ArgumentError(f"a window must not end before it starts, got {start}:{end}")
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
        parent_rotation, parent_position = (
            np.broadcast_to(IDENTITY, (motion.n_frames, 4)),
            np.zeros((motion.n_frames, 3)),
        )
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


def blend_alignment(
    first: Motion | Take,
    second: Motion | Take,
    body_window: tuple[int, int],
    expressive_window: tuple[int, int] | None = None,
    align: str = "time",
) -> BlendAlignment:
    """The placement of ``second`` that :func:`blend` uses with these windows (and ``align``)."""
    first_take = Take.of(first)
    first = first_take.motion
    second_take = _at_rate_of(Take.of(second), first, align)
    second = second_take.motion
    roles = first_take.body.roles
    start = _second_start(body_window, expressive_window)
    frames = start + second.n_frames
    anchor = min(body_window[0], frames - 1)
    i, j = _on_timeline(first, 0, frames)[anchor], _on_timeline(second, start, frames)[anchor]
    joint = min(path_joint(m.translations, m.skeleton, roles) for m in (first, second))  # the higher on the chain
    a, b = first_take.positions, second_take.positions
    turn = _facing_at(a, roles, i, first.fps) - _facing_at(b, roles, j, second.fps)
    turn = (turn + 180.0) % 360.0 - 180.0
    return BlendAlignment(
        joint, int(anchor), float(turn), b[j, joint].copy(), (a[i, joint] - b[j, joint]) * [1.0, 0.0, 1.0]
    )


def blend(
    first: Motion | Take,
    second: Motion | Take,
    model: BodyMechanicsModel | None,
    body_window: tuple[int, int],
    expressive_window: tuple[int, int] | None = None,
    gain: float = GAIN,
    exponent: float = EXPONENT,
    joints=None,
    plant_feet: bool = True,
    hinges: bool = True,
    align: str = "time",
) -> Motion:
    """Blend from ``first`` to ``second``, body mechanics over ``body_window`` and the expressive
    component over ``expressive_window`` (output frames ``(start, end)``, at ``first``'s frame
    rate; slerp with smoothstep weights). ``second`` is first resampled to ``first``'s frame rate
    (``align="time"``; ``"index"`` takes its frames as they are, whatever the rates) and starts at
    the earlier window's start. At the start of the body window
    (the anchor) it is turned about the vertical to face where ``first`` faces (the facing from the
    upper legs, averaged over a second around the anchor) and moved on the floor plane to where
    ``first``'s path is; both applied to the joint that carries the path (:func:`path_joint`: the
    hips on Bandai-Namco files, whose root never moves). In the body window the path follows the
    blend of both motions' steps, so it never moves faster than either (:func:`blend_alignment`
    tells the turn and the move). Without a model (or without an expressive window) this is the
    naive blend: whole poses over ``body_window``. ``joints``: the joints whose expressive
    component goes over ``expressive_window`` (as in :func:`mix`); the others' goes with their body
    mechanics. ``plant_feet``: the stance feet kept where the naive blend (whose feet are the
    first's before the body window and the second's after it) has them during its contacts.
    Elbows and knees are kept within their limits (``hinges``), never tighter than the two motions
    have them."""
    first_take = Take.of(first)
    first = first_take.motion
    _check_same_skeleton(first, Take.of(second).motion, "blend")
    if align == "resample":
        raise ArgumentError("blend: align must be 'time' or 'index' (a blend keeps each motion's own length)")
    second_take = _at_rate_of(Take.of(second), first, align)
    second = second_take.motion
    start = _second_start(body_window, expressive_window)
    frames = start + second.n_frames
    i, j = _on_timeline(first, 0, frames), _on_timeline(second, start, frames)
    body_weights = _weights(frames, body_window)

    first_positions = first_take.positions
    alignment = blend_alignment(first_take, second_take, body_window, expressive_window)
    carrier = alignment.joint
    second = _turned(second, carrier, alignment.turn, alignment.pivot, alignment.pivot + alignment.shift)

    if model is None or expressive_window is None:
        rotations = quat.slerp(first.rotations[i], second.rotations[j], body_weights[:, None])
    else:
        turned = Take(second, second_take.body)
        a, b = decompose(first_take, model, gain, exponent), decompose(turned, model, gain, exponent)
        body = quat.slerp(a.body[i], b.body[j], body_weights[:, None])
        mask = chosen_joints(joints, first_take, turned)[None, :]
        weights = np.where(mask, _weights(frames, expressive_window)[:, None], body_weights[:, None])
        expressive = quat.slerp(a.expressive[i], b.expressive[j], weights)
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
    out = Motion(first.skeleton, rotations, translations, first.frame_time)
    out = _limited(out, [first, second], [first.rotations[i], second.rotations[j]], hinges)
    if plant_feet and model is not None and expressive_window is not None:
        naive = blend(first_take, second_take, None, body_window, expressive_window, plant_feet=False)
        out = planted(naive, out)[0]
    return out


__all__ = ["ALIGNS", "BlendAlignment", "at_rate_of", "blend", "blend_alignment", "mix", "modulate"]
