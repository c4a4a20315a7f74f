"""Joint maps of any humanoid skeleton, on ground truth: the demo's walk written on synthetic
skeletons built after six conventions (Bandai, CMU, Mixamo, SMPL, a game rig, LAFAN1), each with
the map it was built with. The package must find that map on its own: by names, by topology
where names say nothing, or from a map file."""

from __future__ import annotations

import json

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.jointmap import find_joint_map, read_joint_map
from expressive_mocap.body.names import label
from expressive_mocap.body.roles import JointRoles
from expressive_mocap.skeletons.synthetic import RIGS, synthetic_walk


@pytest.fixture(scope="module")
def walks() -> dict[str, em.Motion]:
    return {rig: synthetic_walk(rig, wave="right").motion for rig in RIGS}


# -- names --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("name", "side", "roles"),
    [
        ("mixamorig:LeftUpLeg", "left", ("upper_leg",)),
        ("UpperLeg_L", "left", ("upper_leg",)),
        ("thigh_r", "right", ("upper_leg",)),
        ("Bip01 L Thigh", "left", ("upper_leg",)),
        ("left_shoulder", "left", ("clavicle", "upper_arm")),  # SMPL's upper arm, CMU's clavicle
        ("right_foot", "right", ("foot", "toes")),  # SMPL's toes
        ("LHipJoint", "left", ()),  # CMU's zero-length joint
        ("upperarm_twist_01_l", "left", ()),
        ("LeftHandIndex1", "left", ()),
        ("mixamorig:HeadTop_End", "", ()),
        ("Spine1", "", ("spine",)),
        ("pelvis", "", ("hips",)),
        ("lefthand", "left", ("hand",)),
    ],
)
def test_names_say_side_and_part(name, side, roles):
    found = label(name)
    assert (found.side, found.roles) == (side, roles)


# -- joint maps ---------------------------------------------------------------------------------


@pytest.mark.parametrize("rig", RIGS)
def test_map_is_found_by_names(walks, rig):
    truth = synthetic_walk(rig).truth
    jmap = find_joint_map(walks[rig].skeleton)
    found = {role: name for role, name in jmap.as_names().items() if role != "spine"}
    assert found == truth
    names = walks[rig].skeleton.names
    unmapped = {names[j] for j in jmap.unmapped}
    assert unmapped.isdisjoint(truth.values())
    if rig == "game":  # twist bones are reported, never an error
        assert {"upperarm_twist_01_l", "thigh_twist_01_r"} <= unmapped


@pytest.mark.parametrize("rig", RIGS)
def test_map_is_found_by_topology_where_names_say_nothing(walks, rig):
    motion = walks[rig]
    skeleton = motion.skeleton
    anonymous = em.Skeleton(
        tuple(f"j{j}" for j in range(skeleton.n_joints)),
        skeleton.parents,
        skeleton.offsets,
        skeleton.channels,
        skeleton.end_sites,
    )
    jmap = find_joint_map(anonymous, pose=motion.positions()[0])  # the pose tells left from right
    truth = synthetic_walk(rig).truth
    found = {role: skeleton.names[j] for role, j in jmap.joints.items()}
    if rig == "mixamo":  # a head-top joint with rotation channels reads as the head without its name
        assert found.pop("head") == "mixamorig:HeadTop_End"
        truth = {k: v for k, v in truth.items() if k != "head"}
    assert found == truth
    assert all(how == "topology" for how in jmap.how.values())


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_a_map_file_gives_what_names_cannot(tmp_path, suffix):
    motion = synthetic_walk("game").motion
    names = list(motion.skeleton.names)
    renamed = {"thigh_l": "bone_17", "calf_l": "bone_18", "spine_03": "torso_top"}
    skeleton = em.Skeleton(
        tuple(renamed.get(n, n) for n in names),
        motion.skeleton.parents,
        motion.skeleton.offsets,
        motion.skeleton.channels,
        motion.skeleton.end_sites,
    )
    path = tmp_path / f"map{suffix}"
    entries = {"left_upper_leg": "bone_17", "left_lower_leg": "bone_18", "chest": "torso_top"}
    if suffix == ".json":
        path.write_text(json.dumps(entries))
    else:
        path.write_text("".join(f'{k} = "{v}"\n' for k, v in entries.items()))
    jmap = find_joint_map(skeleton, read_joint_map(path))
    assert {r: skeleton.names[jmap[r]] for r in entries} == entries
    assert all(jmap.how[r] == "map" for r in entries)
    assert skeleton.names[jmap["left_foot"]] == "foot_l"


def test_bad_map_files_are_named(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"left_elbow": "x"}')
    with pytest.raises(em.MocapError, match=r"bad.json: unknown role 'left_elbow'"):
        read_joint_map(bad)
    bad.write_text("{not json")
    with pytest.raises(em.MocapError, match=r"bad.json: not a valid joint map"):
        read_joint_map(bad)
    bad.write_text('{"hips": "Nope"}')
    with pytest.raises(em.MocapError, match="no joint named 'Nope'"):
        find_joint_map(synthetic_walk("lafan").motion.skeleton, read_joint_map(bad))


def test_a_skeleton_without_legs_is_refused_with_the_joints_listed():
    skeleton = em.Skeleton(("a", "b", "c"), [-1, 0, 1], np.eye(3), (("Xrotation",),) * 3)
    with pytest.raises(em.MocapError, match="cannot tell which joint is the hips.*joints are: a, b, c"):
        find_joint_map(skeleton)


def test_feature_roles_come_from_the_map_where_names_fail(walks):
    roles = JointRoles.find(walks["smpl"].skeleton)  # SMPL's "left_foot" is a toe
    names = walks["smpl"].skeleton.names
    assert [names[j] for j in roles.feet + roles.toes] == ["left_ankle", "right_ankle", "left_foot", "right_foot"]
