"""The package's canonical body: the skeleton everything it has learned lives on (the shipped
body-mechanics model, features and contacts tuned on Bandai-Namco captures), so a motion of any
other skeleton is retargeted onto it to be compared with them.

It is the Bandai-Namco dataset-2 skeleton (22 joints, centimetres, Y up, facing +Z, six channels a
joint in Z X Y order; the demo's, :func:`~expressive_mocap.procedural.bandai_like_skeleton`).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from ..body.body import Body
from ..body.canonical import canonical_shape, canonical_skeleton
from ..body.conventions import Conventions
from ..body.jointmap import JointMap
from ..body.take import Take
from ..errors import MocapError
from ..motion import Motion, Skeleton
from .retargeting import retarget_clips, retarget_rigs
from .rig import _IDENTITY, Rig
from .transfer import _mul, _turned, with_twists

# The toe joint sits 4.35 cm above the floor on a flat foot (measured on dataset-2's walks).
_TOE_HEIGHT_CM = 4.35


@lru_cache(maxsize=1)
def canonical_rig() -> Rig:
    """The canonical body with its joint map, conventions and floor."""
    skeleton = canonical_skeleton()
    jmap = Body.of(skeleton).joint_map
    sure = {"up": 1.0, "facing": 1.0, "unit": 1.0, "rest_pose": 1.0}
    conventions = Conventions("+Y", "+Z", "cm", 0.01, 163.07, "other", 30.0, sure)
    return Rig(skeleton, jmap, conventions, _TOE_HEIGHT_CM)


def onto_canonical(motion: Motion, user_map: dict | None = None, *, plant_feet: bool = True) -> tuple[Motion, JointMap]:
    """``motion`` retargeted onto the canonical body (at its own frame rate), and the joint map
    its skeleton was read with."""
    source = Rig.of(motion, user_map)
    target = canonical_rig()
    moved = retarget_rigs(motion, source, target, plant_feet=plant_feet)
    return stood(moved, source.skeleton, source.jmap, target), source.jmap


def many_onto_canonical(motions: list[Motion], user_map: dict | None = None) -> list[tuple[Motion, JointMap]]:
    """:func:`onto_canonical` of many clips at once (feet planted; see
    :func:`~expressive_mocap.skeletons.retargeting.retarget_clips`)."""
    target = canonical_rig()
    moved = retarget_clips(motions, target, user_map=user_map)
    return [(stood(body, motion.skeleton, jmap, target), jmap) for (body, jmap), motion in zip(moved, motions)]


def stood(body: Motion, source: Skeleton, source_map: JointMap, target: Rig) -> Motion:
    """``body`` (retargeted from ``source``, read with ``source_map``, onto ``target``) with the
    toes and foot roll its source does not show put as the canonical body stands on them
    (:mod:`.unseen`); as it is on any other target."""
    if target.skeleton.names != canonical_rig().skeleton.names:
        return body
    from .unseen import stand_unseen, unseen_toes

    return stand_unseen(body, target.jmap, unseen_toes(source, source_map))


class Carried:
    """A user's motion put on the canonical body for a model trained there (or on ``target``, a
    model's own body), and the way back.

    ``body`` is the motion retargeted onto the canonical body (feet as carried; the toes and foot
    roll the user's skeleton does not show as the canonical body stands on them unless ``stand``
    is False, :func:`stood`: with nothing edited, :meth:`back` gives the user's motion back
    exactly). :meth:`back` carries an edit of
    ``body`` onto the user's own motion as per-joint changes of world orientation: each mapped
    joint turns by what its role turned on the body; joints the body lacks keep their local
    rotations (they follow their parents), offsets stay the user's; the hips' change of place is
    scaled back by the ratio of the leg lengths.
    """

    def __init__(
        self,
        motion: Motion,
        user_map: dict | None = None,
        target: Rig | None = None,
        source: Rig | None = None,
        stand: bool = True,
    ):
        self.original = motion
        self._take = Take(motion, Body.of(motion.skeleton, user_map))  # its positions: read once
        # Given: a stream's rig, read from its first frame.
        self.source = with_twists(source or Rig.of(self._take, user_map), self._take)
        self.target = target or canonical_rig()
        self.body = retarget_rigs(self._take, self.source, self.target, plant_feet=False)
        if stand:  # a stream's frames, one at a time, cannot tell how its feet stand: as carried
            self.body = stood(self.body, self.source.skeleton, self.source.jmap, self.target)
        self._body_take = Take(self.body)
        self._limits: Any = None  # the user's HingeLimits, once needed
        self._contacts: np.ndarray | None = None  # the user's foot contacts, once needed

    def back(self, edited: Motion, hinges: bool = True, plant_feet: bool = False) -> Motion:
        """``edited`` (an edit of :attr:`body`) as a motion of the user's skeleton. An edit of
        another length (a blend into a second motion) has no frame-by-frame counterpart to turn:
        it is retargeted onto the user's skeleton instead, joints the body lacks at rest. Either
        way (unless ``hinges`` is False) the user's elbows and knees are then kept within their
        limits, about the axes the user's motion bends them about, never tighter than it has them
        itself (:func:`~expressive_mocap.body.hinges.limit_hinges`): bodies differ, so a limb the edit
        kept within limits on the body may pass straight on the user's. ``plant_feet``: then the
        stance feet are put back where the user's motion has them through its own contacts
        (:func:`~expressive_mocap.decoupling.feet.planted`, on the user's skeleton: feet planted on
        the body slid and sank once carried back onto other proportions)."""
        from ..body.hinges import hinge_limits_for, limit_hinges

        out = self._back(edited)
        same = out.n_frames == self.original.n_frames
        if hinges:
            if self._limits is None:  # the user's hinge axes, learnt once for every edit carried back
                self._limits = hinge_limits_for([self.original])
            out = limit_hinges(out, self._limits, (self.original.rotations,) if same else ())[0]
        return self._planted(out) if plant_feet and same else out

    def _planted(self, out: Motion) -> Motion:
        """``out`` with its stance feet where the user's motion has them (as it is, on a skeleton
        whose legs are not two bones from hip to ankle)."""
        from ..body.contacts import foot_contacts
        from ..body.conventions import upright
        from ..decoupling.feet import planted
        from ..errors import ArgumentError

        if self._contacts is None:  # the user's contacts, read once, Y up
            self._contacts = foot_contacts(upright(self.original))
        try:
            return planted(self._take, out, contacts=self._contacts)[0]
        except ArgumentError:
            return out

    def _back(self, edited: Motion) -> Motion:
        from ..rotations import quat

        if edited.n_frames != self.body.n_frames:
            return retarget_rigs(edited, self.target, self.source, plant_feet=False)
        before, body_positions = self._body_take.fk
        after, edited_positions = edited.fk()
        # The body's axes -> canonical -> the user's: a change of orientation D on the body is
        # user^-1 body D body^-1 user in the user's axes.
        turn = quat.mul(quat.conjugate(self.source.conventions.rotation()), self.target.conventions.rotation())
        world, positions = self._take.fk
        skeleton = self.original.skeleton
        parents = skeleton.parents
        # Each joint turns by the change of the nearest mapped joint at or above it (the root by
        # none): mapped joints by their role's change on the body, the others with their parents.
        roles = [role for role in self.target.jmap.joints if role in self.source.jmap.joints]
        mapped = {self.source.jmap[role]: k for k, role in enumerate(roles)}
        which = np.full(skeleton.n_joints, len(roles))  # the last change is none
        for j in range(skeleton.n_joints):  # parents come before their children
            which[j] = mapped.get(j, which[parents[j]] if parents[j] >= 0 else len(roles))
        bodies = [self.target.jmap[role] for role in roles]
        on_body = _mul(after[:, bodies], quat.conjugate(before[:, bodies]))  # each role's change, the body's axes
        # The user's spine segments below the chest have no role: they turn as one piece, as the
        # body's hips-to-chest line does (else they kept the hips' change only, and a lean taken
        # off the body stayed in the user's lower back: 36.9 degrees left where the body kept 23).
        hips, chest = self.target.jmap["hips"], self.target.jmap["chest"]
        lines = (
            body_positions[:, chest] - body_positions[:, hips],
            edited_positions[:, chest] - edited_positions[:, hips],
        )
        spine = _line_turn(on_body[:, roles.index("hips")], *lines)
        which[list(self.source.jmap.spine)[:-1]] = len(roles) + 1
        identity = np.broadcast_to(_IDENTITY, (len(world), 1, 4))
        change = _turned(turn, np.concatenate([on_body, identity, spine[:, None]], axis=1))  # the user's axes

        def turned(joints) -> np.ndarray:  # the joints' new world rotations
            return _mul(change[:, which[joints]], world[:, joints])

        # A joint turning with its parent keeps its local rotation: only the others are recomputed.
        rotations = self.original.rotations.copy()
        own = [
            j for j in range(skeleton.n_joints) if which[j] != (which[parents[j]] if parents[j] >= 0 else len(roles))
        ]
        inner, roots = [j for j in own if parents[j] >= 0], [j for j in own if parents[j] < 0]
        if inner:
            rotations[:, inner] = _mul(quat.conjugate(turned(parents[inner])), turned(inner))
        if roots:
            rotations[:, roots] = turned(roots)
        translations = self.original.translations.copy()
        hips_t, hips_s = self.target.jmap["hips"], self.source.jmap["hips"]
        moved = edited_positions[:, hips_t] - body_positions[:, hips_t]
        if np.abs(moved).max(initial=0.0) > 0:
            from .rig import _leg, _path_joint

            shift = quat.rotate(turn, moved) * (_leg(self.source) / _leg(self.target))
            mover = _path_joint(skeleton, hips_s)
            parent = parents[mover]
            frame = turned([parent])[:, 0] if parent >= 0 else np.broadcast_to(_IDENTITY, world[:, 0].shape)
            translations[:, mover] += quat.rotate(quat.conjugate(frame), shift)
        return Motion(skeleton, rotations, translations, self.original.frame_time)


def _line_turn(hips_change: np.ndarray, line: np.ndarray, edited_line: np.ndarray) -> np.ndarray:
    """The change of world orientation ``[F, 4]`` that takes a body's hips-to-chest ``line`` where
    the edit has it (``edited_line``): the hips' change, then the least rotation left. The user's
    spine below the chest turns by it as one piece, whatever its joints in number or rest
    directions."""
    from ..rotations import quat

    return _mul(quat.between(quat.rotate(hips_change, line), edited_line), hips_change)


def carried_for(motion: Motion, model, user_map: dict | None = None) -> Carried | None:
    """How ``motion`` reaches ``model`` (a body-mechanics or exaggeration model): None when it is
    on the model's skeleton already; else a :class:`Carried` through the model's own body when the
    model keeps its skeleton (an exaggeration model: its mean pose on its skeleton), or through
    the canonical body when the model was trained there; otherwise :class:`MocapError`."""
    joint_names = tuple(model.joint_names)
    if tuple(motion.skeleton.names) == joint_names:
        return None
    body = model.body() if hasattr(model, "body") else None
    if body is not None:
        return Carried(motion, user_map, Rig.of(body, getattr(model, "joint_map", None) or None))
    if joint_names != canonical_shape()[0]:
        raise MocapError(
            f"the model was trained on a {len(joint_names)}-joint skeleton ({', '.join(joint_names[:3])}, ...), "
            "not the canonical body: only models of the canonical body take motions of other skeletons"
        )
    return Carried(motion, user_map)


__all__ = [
    "Carried",
    "canonical_rig",
    "carried_for",
    "many_onto_canonical",
    "onto_canonical",
]
