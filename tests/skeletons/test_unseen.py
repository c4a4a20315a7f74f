"""Toes and foot rolls nothing shows (skeletons.unseen): put where the canonical body stands on
them, every joint's position unchanged, carried back to the user's skeleton exactly; and on a
real walk of another rig, no longer read as expression."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body import Body
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.decoupling import BodyModel, decompose
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.canonical import Carried
from expressive_mocap.skeletons.unseen import STANCE_ROLL, STANCE_TOES, stand_unseen, unseen_toes


def test_toes_ending_where_they_start_are_unseen():
    for rig, sides in (("cmu", ["left", "right"]), ("game", ["left", "right"]), ("mixamo", [])):
        motion = synthetic_walk(rig).motion  # mixamo's toes end 8 cm on: they show
        assert unseen_toes(motion.skeleton, Body.of(motion.skeleton).joint_map) == sides, rig


def _stance_roll(motion, jmap, side, contacts):
    s = 0 if side == "left" else 1
    foot, toes = jmap[f"{side}_foot"], jmap[f"{side}_toes"]
    axis = motion.skeleton.offsets[toes] / np.linalg.norm(motion.skeleton.offsets[toes])
    q = motion.rotations[contacts[:, s], foot]
    q = np.where(q[:, 3:] < 0, -q, q)
    return np.degrees(np.median(2 * np.arctan2(q[:, :3] @ axis, q[:, 3])))


def test_the_canonical_body_stands_on_its_stance_values_and_nothing_moves():
    walk = synthetic_walk("cmu").motion
    body = Carried(walk, stand=False).body  # on the canonical body, as retargeting carries it
    jmap = Body.of(body.skeleton).joint_map
    stood = stand_unseen(body, jmap, ["left", "right"])
    contacts = foot_contacts(body)
    for s, side in enumerate(("left", "right")):
        toes = jmap[f"{side}_toes"]
        mean = quat.mean_rotation(stood.rotations[contacts[:, s], toes])
        assert np.degrees(quat.angle(quat.mul(quat.conjugate(STANCE_TOES[side]), mean))) < 1e-6
        assert abs(_stance_roll(stood, jmap, side, contacts) - STANCE_ROLL[side]) < 1e-6
    # Nothing shows them: every joint stands where it stood, to rounding.
    assert np.abs(stood.positions() - body.positions()).max() < 1e-9 * np.abs(body.positions()).max()
    # The toes move as they did about their stance (one constant turn each).
    for side in ("left", "right"):
        toes = jmap[f"{side}_toes"]
        step = quat.mul(quat.conjugate(body.rotations[:-1, toes]), body.rotations[1:, toes])
        stood_step = quat.mul(quat.conjugate(stood.rotations[:-1, toes]), stood.rotations[1:, toes])
        np.testing.assert_allclose(quat.angle(step), quat.angle(stood_step), atol=1e-6)


def test_carried_back_unedited_is_the_users_motion():
    walk = synthetic_walk("game").motion
    carried = Carried(walk)
    back = carried.back(carried.body, hinges=False)
    assert np.abs(quat.angle(quat.mul(quat.conjugate(back.rotations), walk.rotations))).max() < 1e-9


def _feet_and_toes(walk, model, stand: bool) -> tuple[np.ndarray, np.ndarray]:
    """Uncalibrated decoupling of ``walk`` through the canonical body: the mean activity of the
    feet and toes, and how far the body mechanics turn the actor's toes (mean degrees, per side)."""
    carried = Carried(walk, stand=stand)
    parts = decompose(carried.body, model)
    names = model.joint_names
    activity = parts.activity[:, [names.index(j) for j in ("Foot_L", "Foot_R", "Toes_L", "Toes_R")]].mean(axis=0)
    body = carried.back(parts.body_motion())
    jmap = Body.of(walk.skeleton).joint_map
    turned = []
    for side in ("left", "right"):
        toes = jmap[f"{side}_toes"]
        turn = quat.mul(quat.conjugate(walk.rotations[:, toes]), body.rotations[:, toes])
        turned.append(np.degrees(quat.angle(turn)).mean())
    return activity, np.array(turned)


@pytest.mark.parametrize("name", ["m21_walk.bvh", "m21_female-walk.bvh"])
def test_a_neutral_walk_of_another_rig_keeps_its_own_toes(other_dir, name):
    """m21's toes sit 36-39 degrees from their rest through a walk, which nothing shows: read as
    expression, the feet and toes of its two neutral walks had activity 0.27-0.87 (uncalibrated)
    and the body mechanics turned the actor's toes 19-60 degrees on average."""
    model = BodyModel.load()
    walk = em.read_bvh(other_dir / name)
    before, turned_before = _feet_and_toes(walk, model, stand=False)
    after, turned_after = _feet_and_toes(walk, model, stand=True)
    assert (after < before).all(), (before, after)  # measured 0.27-0.87 -> 0.05-0.45
    assert turned_after.mean() < 0.7 * turned_before.mean(), (turned_before, turned_after)
    if name == "m21_walk.bvh":  # measured: activity 0.05-0.12, toes turned 1.6-2.6 degrees
        assert after.max() < 0.2 and turned_after.max() < 5.0, (after, turned_after)
