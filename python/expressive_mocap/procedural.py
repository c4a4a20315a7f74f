"""Motion made up, so everything runs with no download (the demo's embedded default): a
procedurally generated walk on the canonical body's skeleton
(:mod:`expressive_mocap.body.canonical`, the Bandai-Namco dataset-2 one), optionally with a wave
laid on one arm, and the same walk with a load carried. That skeleton's rest pose is not
upright (each bone lies along its joint's local X axis), so the walk is made in three steps:

1. an upright generator gives every joint a WORLD rotation ``R_j(t)``; its standing pose ``U_j``
   has every swing at zero and the arms down (pelvis sway, trunk counter-rotation, arm swing,
   foot pitch; the thighs and shins only follow the pelvis);
2. the retarget ``R'_j = R_j U_j^-1 W_j`` lays those changes on ``W_j``, the world rotations of
   a real Bandai neutral walk's average pose, which brings the dataset's own twist conventions;
3. a footstep plan (a planted stance foot rolling over heel and toe, swing arcs between
   footprints) places the hips and the ankles, and two-bone IK swings each thigh and shin so the
   ankle lands where the plan puts it.

A wave is a world rotation laid on one arm in step 1, before the retarget: it changes that arm's
upper arm, forearm and hand and nothing else.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .body.canonical import bandai_like_skeleton, bandai_standing_pose
from .body.ik import two_bone_ik
from .errors import MocapError
from .motion import Motion
from .rotations import quat

_SKELETON = bandai_like_skeleton()
_NAMES = _SKELETON.names
_J = {n: j for j, n in enumerate(_NAMES)}
_PARENTS = _SKELETON.parents
_STANDING = bandai_standing_pose()  # W_j

# Measured on the same clip: the toe joint sits inside the foot, 4.35 cm above the floor when the
# foot is flat; the ankles are 13.2 cm apart; the hips are 90.4 cm high on average (1.5 cm std).
_TOE_HEIGHT = 4.35
_ANKLE_LATERAL = 6.6
_HIPS_HEIGHT = 90.4

# The gait cycle of one foot, in fractions of a stride from its heel strike.
_HEEL_ROCKER_END = 0.08  # heel strike: the foot rolls down onto the sole
_TOE_ROCKER_START = 0.34  # the heel lifts, the foot rolls over the toes
_TOE_OFF = 0.6  # swing begins
_MID_STANCE = 0.28  # the hips pass over the ankle
_HEEL_STRIKE_PITCH = 12.0  # degrees, toes up
_TOE_OFF_PITCH = 35.0  # degrees, heel up
_LIFT = 12.0  # cm, extra ankle height in the swing: highest 30% of the way, gone at 80% (the leg reaches out low)

_REACH = 0.9995  # of the leg's length: IK stays clear of a fully straight knee

WAVE_RAISE = 125.0  # degrees the upper arm turns up from hanging, out to the side
WAVE_BEND = 30.0  # degrees the forearm turns further up (the elbow bends)


def strides_per_second(speed: float) -> float:
    """Strides (two steps) a second at ``speed`` m/s: 1.8 steps/s at 1.1 m/s, as the Bandai
    neutral walks, growing with speed."""
    return (1.2 + 0.55 * speed) / 2


class WalkAndWave(NamedTuple):
    """The same walk twice: ``walk`` without the wave, ``waving`` with it (identical but for
    the waving arm's upper arm, forearm and hand)."""

    walk: Motion
    waving: Motion


def procedural_walk(
    seconds: float = 4.0,
    fps: float = 30.0,
    speed: float = 1.2,
    *,
    wave: str | None = None,
    wave_frequency: float = 2.0,
    wave_amplitude: float = 30.0,
) -> Motion:
    """A straight walk at ``speed`` m/s along +Z on the Bandai-Namco skeleton, feet on the floor
    at y = 0 (the toe joints, inside the feet, touch down 4.35 cm above it, as in the real
    files), optionally waving the ``"left"`` or ``"right"`` arm (the upper arm raised, the
    forearm and hand swinging ``wave_amplitude`` degrees either way ``wave_frequency`` times a
    second). Cadence, stride, arm swing, pelvis turn and hip bob grow with speed."""
    # Both walks come from one call, so the walk is the same with or without a wave.
    pair = walk_and_wave(seconds, fps, speed, wave or "right", wave_frequency, wave_amplitude)
    return pair.waving if wave else pair.walk


def walk_and_wave(
    seconds: float = 4.0,
    fps: float = 30.0,
    speed: float = 1.2,
    side: str = "right",
    frequency: float = 2.0,
    amplitude: float = 30.0,
) -> WalkAndWave:
    """The procedural walk with and without a wave of the ``side`` arm (see :func:`procedural_walk`)."""
    if side not in ("left", "right"):
        raise MocapError(f"wave: expected 'left', 'right' or None, got {side!r}")
    for name, value in (("seconds", seconds), ("fps", fps), ("speed", speed), ("wave_frequency", frequency)):
        if not (np.isfinite(value) and value > 0):
            raise MocapError(f"procedural_walk: {name} must be positive, got {value}")
    t = np.arange(int(round(seconds * fps)) + 1) / fps
    upright = _upright_world(t, speed)
    standing = _upright_world(t[:1], speed, amplitude=0.0)[0]  # U_j
    hips = _hips_path(t, speed)
    ankles, pitches = _footsteps(t, speed)
    upright[:, [_J["Foot_L"], _J["Foot_R"]]] = quat.about("X", -pitches[..., 0])
    upright[:, [_J["Toes_L"], _J["Toes_R"]]] = quat.about("X", -pitches[..., 1])
    waved = upright.copy()
    letter = side[0].upper()
    for name, q in zip(("UpperArm", "LowerArm", "Hand"), _wave(t, side, frequency, amplitude)):
        waved[:, _J[f"{name}_{letter}"]] = quat.mul(q, waved[:, _J[f"{name}_{letter}"]])
    motions = [_on_bandai(world, standing, hips, ankles, 1.0 / fps) for world in (upright, waved)]
    return WalkAndWave(*motions)


# -- step 1: the upright generator ---------------------------------------------------------


def _upright_world(t: np.ndarray, speed: float, amplitude: float = 1.0) -> np.ndarray:
    """World rotations ``[F, J, 4]`` of the upright walk (facing +Z, left is +X); ``amplitude``
    scales every swing (0: the standing pose U, arms hanging, elbows a little bent)."""
    u = strides_per_second(speed) * t  # strides since the left heel strike at t = 0
    local = np.zeros((len(t), len(_NAMES), 4))
    local[..., 3] = 1.0
    # The pelvis turns the forward-swinging leg's hip forward and drops on the swing side.
    yaw = -amplitude * 4.0 * speed * np.cos(2 * np.pi * u)
    roll = amplitude * 2.5 * np.sin(2 * np.pi * u)
    local[:, _J["Hips"]] = quat.mul(quat.about("Y", yaw), quat.about("Z", roll))
    # The trunk turns against the pelvis and keeps the shoulders level.
    for name in ("Spine", "Chest"):
        local[:, _J[name]] = quat.mul(quat.about("Y", -0.7 * yaw), quat.about("Z", -0.5 * roll))
    for side, shift, sign in (("L", 0.0, 1.0), ("R", 0.5, -1.0)):
        cycle = np.cos(2 * np.pi * (u + shift))  # -1 when this side's arm is furthest forward
        # Arms hang down (about Z) and swing against the leg of their side (about X, outermost);
        # the elbow bends more on the forward swing.
        swing = amplitude * (8.0 + 12.0 * speed) * cycle
        local[:, _J[f"UpperArm_{side}"]] = quat.mul(
            quat.about("X", swing), quat.about("Z", np.full(len(t), -sign * 78.0))
        )
        local[:, _J[f"LowerArm_{side}"]] = quat.about("Y", -sign * (15.0 + amplitude * 12.0 * np.clip(-cycle, 0, None)))
    return _world(local)


def _world(local: np.ndarray) -> np.ndarray:
    world = local.copy()
    for j in range(1, len(_NAMES)):
        world[:, j] = quat.mul(world[:, _PARENTS[j]], local[:, j])
    return world


def _wave(t: np.ndarray, side: str, frequency: float, amplitude: float) -> list[np.ndarray]:
    """World rotations laid on the upper arm, forearm and hand: the arm raised out to the side
    (about the walking direction), the forearm bent further up and swinging, the hand lagging."""
    sign = 1.0 if side == "left" else -1.0
    angle = 2 * np.pi * frequency * t
    raise_arm = quat.about("Z", np.full(len(t), sign * WAVE_RAISE))
    forearm = quat.mul(raise_arm, quat.about("Z", sign * (WAVE_BEND + amplitude * np.sin(angle))))
    hand = quat.mul(forearm, quat.about("Z", sign * 0.3 * amplitude * np.sin(angle - 1.0)))
    return [raise_arm, forearm, hand]


# -- step 3's plan: hips path and footsteps ------------------------------------------------


def _smooth(x: np.ndarray) -> np.ndarray:
    """0 -> 1 with zero slope at both ends."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def _hips_path(t: np.ndarray, speed: float) -> np.ndarray:
    """Hips positions ``[F, 3]``: constant speed forward, swaying over the stance foot, highest
    at mid-stance (twice a stride)."""
    u = strides_per_second(speed) * t - _MID_STANCE
    sway = 1.5 * np.cos(2 * np.pi * u)
    bob = (1.0 + 1.0 * speed) * np.cos(4 * np.pi * u)
    return np.stack([sway, _HIPS_HEIGHT + bob, 100.0 * speed * t], axis=1)


def _foot_geometry(side: str) -> tuple[np.ndarray, np.ndarray, float]:
    """The flat foot of ``side`` ("L", "R"), relative to its ankle: ball (the toe joint) and
    heel, and the ankle's height above the floor."""
    ball = quat.rotate(_STANDING[_J[f"Foot_{side}"]], _SKELETON.offsets[_J[f"Toes_{side}"]])
    ankle_height = _TOE_HEIGHT - ball[1]
    heel = np.array([0.0, -ankle_height + 2.0, -4.0])
    return ball, heel, ankle_height


def _footsteps(t: np.ndarray, speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Planned ankle positions ``[F, 2, 3]`` and pitches ``[F, 2, 2]`` (foot, toes; degrees,
    toes up) of the left and right feet."""
    stride = 100.0 * speed / strides_per_second(speed)
    ankles, pitches = [], []
    for side, shift, lateral in (("L", 0.0, _ANKLE_LATERAL), ("R", 0.5, -_ANKLE_LATERAL)):
        ball, heel, ankle_height = _foot_geometry(side)
        u = strides_per_second(speed) * t + shift
        n = np.floor(u)
        p = u - n

        # The flat ankle of stride k: under the hips at mid-stance (this side's values bound now).
        def footprint(k, lateral=lateral, ankle_height=ankle_height, shift=shift):
            return np.stack(
                [np.full_like(k, lateral), np.full_like(k, ankle_height), stride * (k + _MID_STANCE - shift)], axis=1
            )

        def rolled(k, pitch, pivot):  # the ankle when the foot turns about a point of its sole
            turn = quat.about("X", -pitch)
            return footprint(k) + pivot - quat.rotate(turn, np.broadcast_to(pivot, (len(k), 3)))

        heel_pitch = _HEEL_STRIKE_PITCH * (1 - _smooth(p / _HEEL_ROCKER_END))
        toe_pitch = -_TOE_OFF_PITCH * _smooth((p - _TOE_ROCKER_START) / (_TOE_OFF - _TOE_ROCKER_START))
        swing = _smooth((p - _TOE_OFF) / (1 - _TOE_OFF))
        lift = _LIFT * np.sin(np.pi * np.clip((p - _TOE_OFF) / (0.8 * (1 - _TOE_OFF)), 0, 1) ** 0.7) ** 2
        take_off = rolled(n, np.full_like(p, -_TOE_OFF_PITCH), ball)
        landing = rolled(n + 1, np.full_like(p, _HEEL_STRIKE_PITCH), heel)
        in_swing = (p >= _TOE_OFF)[:, None]
        stance = np.where((p < _TOE_ROCKER_START)[:, None], rolled(n, heel_pitch, heel), rolled(n, toe_pitch, ball))
        ankle = np.where(in_swing, take_off + swing[:, None] * (landing - take_off) + np.outer(lift, [0, 1, 0]), stance)
        pitch = np.where(
            p < _TOE_ROCKER_START,
            heel_pitch,
            np.where(p < _TOE_OFF, toe_pitch, -_TOE_OFF_PITCH + swing * (_HEEL_STRIKE_PITCH + _TOE_OFF_PITCH)),
        )
        # The toes bend (stay flatter than the foot) while the heel is up, and catch up in the swing.
        toes = np.where(p < _TOE_ROCKER_START, pitch, np.where(p < _TOE_OFF, 0.4 * pitch, (0.4 + 0.6 * swing) * pitch))
        ankles.append(ankle)
        pitches.append(np.stack([pitch, toes], axis=1))
    return np.stack(ankles, axis=1), np.stack(pitches, axis=1)


# -- steps 2 and 3: retarget onto the Bandai skeleton, then plant the feet ---------------------


def _on_bandai(
    upright: np.ndarray, standing: np.ndarray, hips: np.ndarray, ankles: np.ndarray, frame_time: float
) -> Motion:
    skeleton = bandai_like_skeleton()
    world = quat.mul(quat.mul(upright, quat.conjugate(standing)), _STANDING)  # R U^-1 W
    world[:, 0] = [0.0, 0.0, 0.0, 1.0]  # joint_Root stays on the floor, unturned, as in the files
    hips = _within_reach(world, hips, ankles, skeleton.offsets)
    offsets = skeleton.offsets
    for side, target in zip("LR", np.moveaxis(ankles, 1, 0)):
        hip, knee, ankle = (_J[f"{n}_{side}"] for n in ("UpperLeg", "LowerLeg", "Foot"))
        root = hips + quat.rotate(world[:, 1], offsets[hip])
        # The foot's world rotation is kept: only the thigh and shin swing.
        world[:, hip], world[:, knee] = two_bone_ik(
            root, world[:, hip], world[:, knee], offsets[knee], offsets[ankle], target
        )
    rotations = world.copy()
    rotations[:, 1:] = quat.mul(quat.conjugate(world[:, _PARENTS[1:]]), world[:, 1:])
    translations = np.broadcast_to(skeleton.offsets, world.shape[:2] + (3,)).copy()
    translations[:, _J["Hips"]] = hips
    return Motion(skeleton, rotations, translations, frame_time)


def _within_reach(world: np.ndarray, hips: np.ndarray, ankles: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """The hips path lowered wherever a leg, nearly straight, could not reach its planned ankle
    (long strides of fast walks)."""
    hips = hips.copy()
    for side, target in zip("LR", np.moveaxis(ankles, 1, 0)):
        leg = _REACH * sum(np.linalg.norm(offsets[_J[f"{n}_{side}"]]) for n in ("LowerLeg", "Foot"))
        joint = quat.rotate(world[:, 1], offsets[_J[f"UpperLeg_{side}"]])  # the hip joint, from the hips
        gap = target - hips - joint
        highest = target[:, 1] + np.sqrt(np.maximum(leg**2 - gap[:, 0] ** 2 - gap[:, 2] ** 2, 0.0)) - joint[:, 1]
        hips[:, 1] = np.minimum(hips[:, 1], highest)
    return hips


LOADED_JOINTS = ("Spine", "Chest", "UpperArm_L", "UpperArm_R", "LowerArm_L", "LowerArm_R")


def loaded_walk(
    intensity: float,
    seconds: float = 3.0,
    *,
    lean: float = 4.0,
    stiffness: float = 0.2,
    wobble: float = 0.0,
    seed: int = 0,
) -> Motion:
    """The procedural walk as if carrying a load of ``intensity`` (a synthetic intensity series
    whose changing joints are known, so a ranking can be checked against them): the
    spine and chest each lean ``lean`` x intensity degrees further forward, and the upper arms
    and forearms swing less (their deviation from their mean rotation scaled by
    ``1 - stiffness (intensity - 1)``). Only :data:`LOADED_JOINTS` change with the intensity.
    ``wobble`` > 0 adds a slow random rotation (up to ``wobble`` degrees; ``seed`` picks it) to
    every joint but the root, like a performer who never repeats a walk exactly."""
    from .rotations.quat import mean_rotation

    motion = procedural_walk(seconds)
    rotations = motion.rotations.copy()
    names = motion.skeleton.names
    for name in ("Spine", "Chest"):
        j = names.index(name)
        rotations[:, j] = quat.mul(rotations[:, j], quat.about("Z", -lean * intensity))  # bones lie along local X
    for name in ("UpperArm_L", "UpperArm_R", "LowerArm_L", "LowerArm_R"):
        j = names.index(name)
        mean = mean_rotation(rotations[:, j])
        swing = quat.mul(quat.conjugate(mean), rotations[:, j])
        rotations[:, j] = quat.mul(mean, quat.power(swing, 1.0 - stiffness * (intensity - 1.0)))
    if wobble > 0:
        rng = np.random.default_rng(seed)
        t = np.arange(motion.n_frames)[:, None, None] * motion.frame_time
        amplitude = np.radians(wobble) * rng.uniform(0.3, 1.0, (1, len(names), 3))
        frequency, phase = rng.uniform(0.1, 0.4, (1, len(names), 3)), rng.uniform(0, 2 * np.pi, (1, len(names), 3))
        vectors = amplitude * np.sin(2 * np.pi * frequency * t + phase)
        vectors[:, 0] = 0.0  # the root stays put: its rotation would tilt the whole figure
        angle = np.linalg.norm(vectors, axis=-1, keepdims=True)
        axis = vectors / np.maximum(angle, 1e-15)
        rotations = quat.mul(rotations, np.concatenate([axis * np.sin(angle / 2), np.cos(angle / 2)], axis=-1))
    return Motion(motion.skeleton, rotations, motion.translations, motion.frame_time)


__all__ = [
    "LOADED_JOINTS",
    "WAVE_BEND",
    "WAVE_RAISE",
    "WalkAndWave",
    "loaded_walk",
    "procedural_walk",
    "strides_per_second",
    "walk_and_wave",
]
