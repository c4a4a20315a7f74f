"""Mirroring a motion left for right: twice is the identity; joints take their partners' places."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body import find_joint_map
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.body.conventions import read_conventions
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.mirror import mirror, partners
from expressive_mocap.skeletons.synthetic import RIGS


def reflected_partners(motion: em.Motion) -> tuple[np.ndarray, np.ndarray, float]:
    """(the motion's positions with each joint at its partner's place reflected across the sagittal
    plane, the mirrored motion's positions), both in canonical axes, and the actor's height."""
    jmap = find_joint_map(motion.skeleton)
    conventions = read_conventions(motion, jmap)
    turn = conventions.rotation()
    mine = quat.rotate(turn, motion.positions())[:, partners(motion.skeleton, jmap)] * np.array([-1.0, 1.0, 1.0])
    return mine, quat.rotate(turn, mirror(motion).positions()), conventions.height


@pytest.mark.parametrize("rig", RIGS)
def test_mirroring_twice_is_the_identity_and_partners_swap(rig):
    motion = synthetic_walk(rig, wave="left", seconds=2.0).motion
    twice = mirror(mirror(motion))
    np.testing.assert_allclose(np.abs(np.sum(twice.rotations * motion.rotations, axis=-1)), 1.0, atol=1e-12)
    np.testing.assert_allclose(twice.translations, motion.translations, atol=1e-9 * np.abs(motion.translations).max())
    # Built from one symmetric T-pose (the Bandai rig from its symmetric average pose): every joint
    # lands where its partner was, reflected.
    expected, mirrored, height = reflected_partners(motion)
    assert np.abs(mirrored - expected).max() / height < (0.03 if rig == "bandai" else 1e-9), rig


def test_partners_by_role_and_by_name():
    skeleton = synthetic_walk("game", seconds=1.0).motion.skeleton
    partner = partners(skeleton, find_joint_map(skeleton))
    pairs = {skeleton.names[j]: skeleton.names[k] for j, k in enumerate(partner)}
    assert pairs["thigh_l"] == "thigh_r" and pairs["upperarm_twist_01_r"] == "upperarm_twist_01_l"
    assert pairs["spine_02"] == "spine_02" and pairs["head"] == "head"
    assert all(partner[partner] == np.arange(len(partner)))  # an involution


@pytest.mark.real_data
def test_a_mirrored_left_hand_wave_waves_the_right_hand(bandai2_dir, other_dir):
    """A dataset-2 left-hand wave mirrored: the shipped model finds the wave on the right arm (its
    activity swaps sides), the feet's contacts swap, and the CMU file (lhand/rhand named in one
    word) mirrors onto its partners within 3% of the actor's height."""
    from expressive_mocap.decoupling import BodyModel, decompose

    wave = em.read_bvh(bandai2_dir / "dataset-2_wave-left-hand_normal_001.bvh")
    mirrored = mirror(wave)
    model, names = BodyModel.load(), wave.skeleton.names
    before, after = (decompose(m, model).activity.mean(axis=0) for m in (wave, mirrored))
    left, right = names.index("UpperArm_L"), names.index("UpperArm_R")
    assert before[left] > 0.5 > 0.1 > before[right]
    assert after[right] > 0.5 > 0.1 > after[left]
    contacts, swapped = foot_contacts(wave), foot_contacts(mirrored)
    assert np.mean(contacts[:, 0] == swapped[:, 1]) > 0.95 and np.mean(contacts[:, 1] == swapped[:, 0]) > 0.95
    cmu = em.read_bvh(other_dir / "cmu_scaled_131_03.bvh")
    expected, mirrored_cmu, height = reflected_partners(cmu)
    assert np.abs(mirrored_cmu - expected).max() / height < 0.03
