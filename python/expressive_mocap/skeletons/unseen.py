"""Rotations nothing shows, set by how a foot stands.

A rig whose toe joints end where they start (an End Site of no length: the Bandai-Namco, m21 and
many game rigs) shows nothing of its toes' rotation, nor of its foot's roll about the line to the
toes: no joint moves with them. Each rig's solver puts them somewhere of its own (m21's toes sit
36-39 degrees from their rest through a walk), retargeting carries that convention over, and on
the canonical body the body-mechanics model read it as expression: 0.68-0.87 of activity on a
neutral walk's toes, its body-mechanics file turning the actor's toes 24-35 degrees.

:func:`stand_unseen` puts them where the canonical body's own captures have them while the foot
stands: each clip's toes' mean rotation and its foot roll's median over its stance frames taken
onto the dataset-2 walks' (constants below), the motion about them kept (a toe bending at
push-off still bends).
"""

from __future__ import annotations

import numpy as np

from ..body.contacts import foot_contacts
from ..body.jointmap import JointMap
from ..motion import Motion, Skeleton
from ..rotations import quat

# The canonical body's toes (local, x y z w) and foot roll about the line to the toes (degrees)
# over the stance frames of dataset-2's neutral walks, takes 1-8 (the body-mechanics model's
# training walks): toes spread 2.6-3.4 degrees (median) about these, the roll -9 to 7 (quartiles).
STANCE_TOES = {
    "left": np.array([-0.0034, -0.1735, -0.0015, 0.9848]),
    "right": np.array([-0.0032, -0.2002, -0.0011, 0.9797]),
}
STANCE_ROLL = {"left": 1.8, "right": -4.6}
MIN_STANCE = 10  # stance frames a side needs for its median to be read


def unseen_toes(skeleton: Skeleton, jmap: JointMap) -> list[str]:
    """The sides (``left``, ``right``) whose toe joint shows nothing of its rotation: no child, and
    End Sites of no length."""
    sides = []
    for side in ("left", "right"):
        toes = jmap.joints.get(f"{side}_toes")
        if toes is None or any(p == toes for p in skeleton.parents):
            continue
        if all(np.linalg.norm(offset) <= 1e-9 for j, offset in skeleton.end_sites if j == toes):
            sides.append(side)
    return sides


def stand_unseen(motion: Motion, jmap: JointMap, sides: list[str]) -> Motion:
    """``motion`` (on the canonical body, Y up) with, for each of ``sides``, the foot's roll about
    the line to its toes and the toes' rotation turned by one constant each, so that over the
    stance frames the roll's median is :data:`STANCE_ROLL` and the toes' mean rotation
    :data:`STANCE_TOES`; the toes keep their
    world orientation through the foot's turn before their own. A side standing fewer than
    :data:`MIN_STANCE` frames is left as it is."""
    if not sides or motion.n_frames < MIN_STANCE:
        return motion
    contacts = foot_contacts(motion)
    rotations = motion.rotations.copy()
    for side in sides:
        s = 0 if side == "left" else 1
        foot, toes = jmap[f"{side}_foot"], jmap[f"{side}_toes"]
        if contacts[:, s].sum() < MIN_STANCE:
            continue
        axis = motion.skeleton.offsets[toes] / np.linalg.norm(motion.skeleton.offsets[toes])
        standing = rotations[contacts[:, s], foot]
        standing = np.where(standing[:, 3:] < 0, -standing, standing)  # one hemisphere: rolls within 180
        roll = np.degrees(np.median(2.0 * np.arctan2(standing[:, :3] @ axis, standing[:, 3])))
        turn = quat.exp(axis * np.radians(STANCE_ROLL[side] - roll))  # about the foot's own line
        rotations[:, foot] = quat.mul(rotations[:, foot], turn)
        rotations[:, toes] = quat.mul(quat.conjugate(turn), rotations[:, toes])
        typical = quat.mean_rotation(rotations[contacts[:, s], toes])
        onto = quat.mul(STANCE_TOES[side], quat.conjugate(typical))
        rotations[:, toes] = quat.mul(onto, rotations[:, toes])
    return Motion(motion.skeleton, quat.normalize(rotations), motion.translations, motion.frame_time)


__all__ = ["MIN_STANCE", "STANCE_ROLL", "STANCE_TOES", "stand_unseen", "unseen_toes"]
