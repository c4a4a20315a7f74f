"""The embedded default: a procedurally generated walk, so everything runs with no download.

The skeleton has the 22 joints of the Bandai-Namco datasets (same names, hierarchy, bone
lengths and BVH channel layout: six channels a joint, Z X Y rotation order), in an upright
rest pose (T-pose, facing +Z, Y up, centimetres). Arm swing and step length follow the speed.
"""

from __future__ import annotations

import numpy as np

from . import quat
from .motion import Motion, Skeleton

BANDAI_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")

# name, parent, rest offset (cm). Bone lengths measured on the Bandai-Namco skeleton.
_JOINTS = [
    ("joint_Root", None, (0.0, 0.0, 0.0)),
    ("Hips", "joint_Root", (0.0, 89.4, 0.0)),
    ("Spine", "Hips", (0.0, 15.7, 0.0)),
    ("Chest", "Spine", (0.0, 9.0, 0.0)),
    ("Neck", "Chest", (0.0, 16.4, 1.0)),
    ("Head", "Neck", (0.0, 6.5, 0.5)),
    ("Shoulder_L", "Chest", (5.0, 13.0, 0.5)),
    ("UpperArm_L", "Shoulder_L", (5.3, 0.0, 0.0)),
    ("LowerArm_L", "UpperArm_L", (24.3, 0.0, 0.0)),
    ("Hand_L", "LowerArm_L", (22.3, 0.0, 0.0)),
    ("Shoulder_R", "Chest", (-5.0, 13.0, 0.5)),
    ("UpperArm_R", "Shoulder_R", (-5.3, 0.0, 0.0)),
    ("LowerArm_R", "UpperArm_R", (-24.3, 0.0, 0.0)),
    ("Hand_R", "LowerArm_R", (-22.3, 0.0, 0.0)),
    ("UpperLeg_L", "Hips", (6.4, -2.2, 0.0)),
    ("LowerLeg_L", "UpperLeg_L", (0.0, -39.1, 0.0)),
    ("Foot_L", "LowerLeg_L", (0.0, -41.0, 0.0)),
    ("Toes_L", "Foot_L", (0.0, -7.1, 9.3)),
    ("UpperLeg_R", "Hips", (-6.4, -2.2, 0.0)),
    ("LowerLeg_R", "UpperLeg_R", (0.0, -39.1, 0.0)),
    ("Foot_R", "LowerLeg_R", (0.0, -41.0, 0.0)),
    ("Toes_R", "Foot_R", (0.0, -7.1, 9.3)),
]
_END_SITES = {"Head": (0.0, 16.0, 1.0), "Hand_L": (9.0, 0.0, 0.0), "Hand_R": (-9.0, 0.0, 0.0), "Toes_L": (0.0, 0.0, 5.0), "Toes_R": (0.0, 0.0, 5.0)}


def bandai_like_skeleton() -> Skeleton:
    """The demo skeleton: Bandai-Namco joint names and layout, upright rest pose."""
    names = [n for n, _, _ in _JOINTS]
    return Skeleton(
        names=tuple(names),
        parents=[-1 if p is None else names.index(p) for _, p, _ in _JOINTS],
        offsets=[o for _, _, o in _JOINTS],
        channels=(BANDAI_CHANNELS,) * len(_JOINTS),
        end_sites=tuple((names.index(n), o) for n, o in _END_SITES.items()),
    )


def procedural_walk(seconds: float = 4.0, fps: float = 30.0, speed: float = 1.2) -> Motion:
    """A straight walk at ``speed`` metres a second along +Z, feet on the floor (y = 0).

    Step frequency, stride, arm swing and hip bob grow with speed (walking, not running).
    """
    skeleton = bandai_like_skeleton()
    frames = int(round(seconds * fps)) + 1
    t = np.arange(frames) / fps
    cadence = 0.75 + 0.35 * speed  # strides (two steps) per second
    phase = 2 * np.pi * cadence * t
    swing = 10.0 + 12.0 * speed  # hip flexion amplitude, degrees

    index = {n: i for i, n in enumerate(skeleton.names)}
    rotations = np.zeros((frames, skeleton.n_joints, 4))
    rotations[..., 3] = 1.0

    def set_rotation(name: str, q: np.ndarray) -> None:
        rotations[:, index[name]] = q

    hips_yaw = 4.0 * speed * np.sin(phase)
    set_rotation("Hips", quat.mul(quat.about("Y", hips_yaw), quat.about("Z", 2.0 * np.sin(phase))))
    set_rotation("Spine", quat.about("Y", -0.6 * hips_yaw))
    set_rotation("Chest", quat.about("Y", -0.4 * hips_yaw))
    for side, shift, sign in (("L", 0.0, 1.0), ("R", np.pi, -1.0)):
        p = phase + shift
        # Hip flexion brings the foot forward (negative X rotation); the knee bends most mid-swing.
        set_rotation(f"UpperLeg_{side}", quat.about("X", -swing * np.sin(p)))
        set_rotation(f"LowerLeg_{side}", quat.about("X", 5.0 + 45.0 * np.clip(np.cos(p + 0.4), 0, None) ** 2))
        set_rotation(f"Foot_{side}", quat.about("X", -8.0 * np.sin(p)))
        # Arms hang down (about Z) and swing against the leg of their side (about X, outermost).
        arm_swing = (8.0 + 14.0 * speed) * np.sin(p)
        set_rotation(f"UpperArm_{side}", quat.mul(quat.about("X", arm_swing), quat.about("Z", np.full(frames, -sign * 78.0))))
        set_rotation(f"LowerArm_{side}", quat.about("Y", -sign * (15.0 + 10.0 * np.clip(np.sin(p), 0, None))))

    translations = np.broadcast_to(skeleton.offsets, (frames, skeleton.n_joints, 3)).copy()
    translations[:, index["joint_Root"]] = np.stack([1.5 * np.sin(phase), np.zeros(frames), 100.0 * speed * t], axis=1)
    translations[:, index["Hips"], 1] += 1.0 * speed * np.cos(2 * phase)
    motion = Motion(skeleton, rotations, translations, 1.0 / fps)

    # Put the lower foot of every frame on the floor.
    positions = motion.positions()
    feet = [index[n] for n in ("Foot_L", "Toes_L", "Foot_R", "Toes_R")]
    translations[:, index["joint_Root"], 1] -= positions[:, feet, 1].min(axis=1) - 2.0
    return Motion(skeleton, rotations, translations, 1.0 / fps)
