"""A joint map is checked as a whole: a map that puts two roles on one joint, breaks a chain of
the hierarchy, crosses the sides or turns the body upside down is refused with one line naming
the role and the joint, whether it comes from a map file, the Python API or a command; every map
the package finds on real and synthetic rigs passes."""

from __future__ import annotations

import json

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.conventions import read_conventions
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.cli import main
from expressive_mocap.errors import MocapError
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.synthetic import RIGS

ARM = ("Shoulder", "Arm", "ForeArm", "Hand")
LEG = ("UpLeg", "Leg", "Foot", "ToeBase")
ARM_ROLES = ("clavicle", "upper_arm", "forearm", "hand")
LEG_ROLES = ("upper_leg", "lower_leg", "foot", "toes")


def swapped(parts: tuple, roles: tuple) -> dict:
    """A map giving each left role of a limb the right joint, and the other way round (CMU names)."""
    out = {}
    for side, other in (("left", "Right"), ("right", "Left")):
        out.update({f"{side}_{role}": f"{other}{part}" for role, part in zip(roles, parts)})
    return out


@pytest.fixture(scope="module")
def cmu_walk() -> em.Motion:
    return synthetic_walk("cmu", seconds=2.0).motion


# Maps refused by the hierarchy alone (find_joint_map), and what the one line must name.
STRUCTURAL = [
    ({"neck": "Head"}, ["'Head' plays two roles", "neck", "head"]),
    ({"head": "Hips"}, ["'Hips' plays two roles", "hips", "head"]),
    ({"chest": "LeftToeBase"}, ["'LeftToeBase' plays two roles, chest and left_toes"]),
    ({"chest": "LThumb"}, ["the neck 'Neck' does not hang below the chest 'LThumb'"]),
    ({"spine": ["Hips", "Spine1"]}, ["the spine's joint 'Hips' does not hang below the hips"]),
    (
        {"left_upper_arm": "RThumb"},
        ["the left upper arm 'RThumb' does not hang below the left clavicle 'LeftShoulder'"],
    ),
    ({"left_hand": "RightFingerBase"}, ["the left hand 'RightFingerBase' does not hang below the left forearm"]),
    ({"head": "LeftFingerBase"}, ["the head 'LeftFingerBase' does not hang below the neck 'Neck'"]),
    ({"left_upper_arm": "RightArm"}, ["'RightArm' plays two roles"]),
]


@pytest.mark.parametrize(("given", "named"), STRUCTURAL)
def test_a_map_that_breaks_the_hierarchy_is_refused_naming_role_and_joint(given, named, cmu_walk):
    with pytest.raises(MocapError) as refused:
        find_joint_map(cmu_walk.skeleton, given)
    message = str(refused.value)
    assert message.startswith("joint map refused: ") and "\n" not in message
    for words in named:
        assert words in message, message


@pytest.mark.parametrize(
    ("given", "named"),
    [
        (swapped(ARM, ARM_ROLES), "left and right disagree: the left upper arm 'RightArm'"),
        ({**swapped(ARM, ARM_ROLES), **swapped(LEG, LEG_ROLES)}, "left and right look swapped"),
    ],
)
def test_a_map_whose_sides_disagree_with_the_motion_is_refused(given, named, cmu_walk):
    """Whole limbs swapped keep the hierarchy whole: the motion's frames tell (a rest pose may
    not: Bandai-Namco's lays every bone along X)."""
    jmap = find_joint_map(cmu_walk.skeleton, given)
    with pytest.raises(MocapError, match=named):
        read_conventions(cmu_walk, jmap)


def test_a_map_that_puts_the_feet_above_the_hips_is_refused(cmu_walk):
    """A body read upside down: the head's role on a foot's chain is caught by the hierarchy, so
    the feet above the hips are checked on a motion turned over, its map found by names."""
    flipped = cmu_walk.positions() * np.array([1.0, -1.0, 1.0])
    jmap = find_joint_map(cmu_walk.skeleton)
    from expressive_mocap.body.mapcheck import check_posed_map

    check_posed_map(jmap, cmu_walk.positions())  # upright: fine
    swap_head = dict(jmap.joints, head=jmap["left_toes"])
    with pytest.raises(MocapError, match="the left foot 'LeftFoot' is on the head's side of the hips 'Hips'"):
        check_posed_map(type(jmap)(jmap.names, swap_head, jmap.spine, jmap.how), flipped)


def test_legs_hanging_from_the_chest_and_limbs_crossing_sides_are_refused(cmu_walk):
    from expressive_mocap.body.mapcheck import check_joint_map

    skeleton, jmap = cmu_walk.skeleton, find_joint_map(cmu_walk.skeleton)
    arms_as_legs = dict(jmap.joints)
    for role, arm in zip(("upper_leg", "lower_leg", "foot"), ("upper_arm", "forearm", "hand")):
        arms_as_legs[f"left_{role}"] = jmap[f"right_{arm}"]
        del arms_as_legs[f"right_{arm}"]
    del arms_as_legs["left_toes"]
    with pytest.raises(MocapError, match="hangs below the right clavicle 'RightShoulder', on the other side"):
        check_joint_map(skeleton, arms_as_legs, jmap.spine)
    del arms_as_legs["right_clavicle"]
    with pytest.raises(MocapError, match="the left upper leg 'RightArm' hangs below the chest 'Spine1'"):
        check_joint_map(skeleton, arms_as_legs, jmap.spine)


def test_found_maps_of_every_synthetic_rig_pass(cmu_walk):
    for rig in RIGS:
        motion = synthetic_walk(rig, seconds=1.0).motion
        read_conventions(motion, find_joint_map(motion.skeleton))  # raises if refused


@pytest.mark.real_data
def test_found_maps_of_every_real_clip_pass(bandai1_dir, bandai2_dir, other_dir):
    """Every clip of both Bandai-Namco datasets (every 10th: the skeletons repeat) and every file
    on other rigs: the map found is checked as a whole, and passes."""
    paths = sorted(other_dir.glob("*.bvh")) + sorted(bandai1_dir.glob("*.bvh"))[::10]
    paths += sorted(bandai2_dir.glob("*.bvh"))[::10]
    for path in paths:
        motion = em.read_bvh(path)
        read_conventions(motion, find_joint_map(motion.skeleton))


@pytest.mark.parametrize(("given", "named"), STRUCTURAL[:4])
def test_commands_refuse_a_bad_map_file_in_one_line(given, named, cmu_walk, tmp_path, capsys):
    walk, target, map_file = tmp_path / "walk.bvh", tmp_path / "target.bvh", tmp_path / "map.json"
    em.write_bvh(cmu_walk, walk)
    em.write_bvh(synthetic_walk("bandai", seconds=1.0).motion, target)
    map_file.write_text(json.dumps(given))
    for argv in (
        ["skeleton", str(walk), "--map", str(map_file)],
        ["retarget", str(walk), "--to", str(target), "--map", str(map_file), "-o", str(tmp_path / "out.bvh")],
    ):
        assert main(argv) == 1
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "joint map refused" in err and named[0] in err, err
    assert not (tmp_path / "out.bvh").exists()


def test_a_spine_that_ends_on_a_toe_is_one_line(cmu_walk):
    with pytest.raises(MocapError, match="the spine given ends at 'LeftToeBase', where no neck leaves"):
        find_joint_map(cmu_walk.skeleton, {"spine": ["LeftToeBase"]})


def test_a_huge_unknown_joint_name_is_shown_cut(cmu_walk, tmp_path, capsys):
    """A map naming a joint of 5 MB: the message shows its first 40 bytes and its length."""
    walk, map_file = tmp_path / "walk.bvh", tmp_path / "map.json"
    em.write_bvh(cmu_walk, walk)
    map_file.write_text(json.dumps({"hips": "x" * 5_000_000}))
    assert main(["skeleton", str(walk), "--map", str(map_file)]) == 1
    err = capsys.readouterr().err
    assert f"no joint named '{'x' * 40}'... (5000000 bytes)" in err and len(err) < 1000


@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_a_map_file_nested_past_the_stack_is_one_line(suffix, cmu_walk, tmp_path, capsys):
    walk, map_file = tmp_path / "walk.bvh", tmp_path / f"map{suffix}"
    em.write_bvh(cmu_walk, walk)
    nested = "[" * 100_000 + "]" * 100_000
    map_file.write_text(f'{{"hips": {nested}}}' if suffix == ".json" else f"hips = {nested}")
    assert main(["skeleton", str(walk), "--map", str(map_file)]) == 1
    err = capsys.readouterr().err.strip()
    assert err == f"expressive-mocap: error: {map_file}: not a valid joint map (nested too deeply)"
