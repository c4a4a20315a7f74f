"""Joint roles and actor height: Bandai, CMU and Mixamo names, roles given by hand, candidates
settled by the topology, heights by hand and of a real Bandai-Namco actor."""

import numpy as np
import pytest

import expressive_mocap as em
from conftest import stick_walker, straight_walker
from expressive_mocap.body import actor_height
from expressive_mocap.body.canonical import bandai_like_skeleton
from expressive_mocap.body.roles import JointRoles, rest_heights


def test_roles_of_bandai_cmu_and_mixamo_names():
    bandai = JointRoles.find(bandai_like_skeleton())
    assert bandai.names(bandai_like_skeleton()) == {
        "hips": "Hips",
        "head": "Head",
        "left_upper_leg": "UpperLeg_L",
        "right_upper_leg": "UpperLeg_R",
        "left_foot": "Foot_L",
        "right_foot": "Foot_R",
        "left_toe": "Toes_L",
        "right_toe": "Toes_R",
    }
    assert [bandai_like_skeleton().names[j] for j in bandai.spine] == ["Hips", "Spine", "Chest", "Neck", "Head"]
    walker = straight_walker(frames=2)
    for prefix in ["", "mixamorig:"]:
        skeleton = stick_walker(*(walker.positions()[:, j] for j in (0, 4, 7)), prefix=prefix).skeleton
        roles = JointRoles.find(skeleton)
        assert (roles.hips, roles.head, roles.spine, roles.upper_legs, roles.feet, roles.toes) == (
            0,
            2,
            (0, 1, 2),
            (3, 6),
            (4, 7),
            (5, 8),
        )


def test_roles_can_be_given_and_missing_ones_are_named(mixed_path):
    skeleton = bandai_like_skeleton()
    roles = JointRoles.find(skeleton, {"left_toe": "Foot_L", "right_toe": 20})
    assert roles.toes == (16, 20)
    with pytest.raises(em.MocapError, match="no joint named 'Nope'"):
        JointRoles.find(skeleton, {"head": "Nope"})
    with pytest.raises(em.MocapError, match="unknown joint role.*left_hand"):
        JointRoles.find(skeleton, {"left_hand": "Hand_L"})
    with pytest.raises(em.MocapError, match="out of range"):
        JointRoles.find(skeleton, {"hips": 99})
    hand_written = em.read_bvh(mixed_path).skeleton
    with pytest.raises(
        em.MocapError,
        match="cannot tell which joint is the left_upper_leg; right_upper_leg; left_foot; left_toe: pass it by name",
    ) as error:
        JointRoles.find(hand_written)
    assert "joints are: mixamorig:Hips, Spine Lower" in str(error.value)


def test_two_candidates_for_a_role_are_settled_by_the_topology():
    skeleton = bandai_like_skeleton()
    names = list(skeleton.names)
    names[names.index("Shoulder_L")] = "LeftUpLeg"  # a second left upper leg, on the arm
    twin = em.Skeleton(tuple(names), skeleton.parents, skeleton.offsets, skeleton.channels)
    assert twin.names[JointRoles.find(twin).upper_legs[0]] == "UpperLeg_L"
    with pytest.raises(em.MocapError, match="left_upper_leg \\(several candidates: LeftUpLeg, UpperLeg_L\\)"):
        JointRoles.find(twin, {"head": "Head"})  # roles given: names only, so the clash is reported


def test_actor_height_by_hand():
    skeleton = straight_walker(frames=2).skeleton
    roles = JointRoles.find(skeleton)
    assert rest_heights(skeleton, roles)[0] == pytest.approx(90.0)
    assert rest_heights(skeleton, roles)[1] == pytest.approx(140.0)
    # Rest pose hanging from the origin (CMU style): the leg's length stands in for the hips' height.
    offsets = skeleton.offsets.copy()
    offsets[0] = 0.0
    hanging = skeleton.with_offsets(offsets, [])
    assert rest_heights(hanging, roles)[0] == pytest.approx(np.hypot(10, 5) + 80)


@pytest.mark.real_data
def test_bandai_actor_is_141_cm(bandai2_dir):
    skeleton = em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh").skeleton
    roles = JointRoles.find(skeleton)
    assert rest_heights(skeleton, roles)[0] == pytest.approx(93.31, abs=0.01)
    assert actor_height(skeleton) == pytest.approx(140.9, abs=0.1)
