"""Joint maps, conventions and retargeting on real files: the CMU and Xia-style files beside the
archives and Bandai-Namco clips of both datasets, with no mapping file."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.conventions import read_conventions
from expressive_mocap.body.jointmap import REQUIRED, find_joint_map
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons.retargeting import retarget

pytestmark = pytest.mark.real_data

_LIMB = [("upper_leg", "lower_leg"), ("lower_leg", "foot"), ("foot", "toes")]
_LIMB += [("clavicle", "upper_arm"), ("upper_arm", "forearm"), ("forearm", "hand")]
BONES = [(f"{s}_{a}", f"{s}_{b}") for s in ("left", "right") for a, b in _LIMB] + [("neck", "head")]
ROUND_TRIP_DEG = 2.0


def directions(motion: em.Motion) -> np.ndarray:
    jmap = find_joint_map(motion.skeleton)
    p = motion.positions()
    v = np.stack([p[:, jmap[b]] - p[:, jmap[a]] for a, b in BONES], axis=1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def worst_angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1, 1))).max())


@pytest.fixture(scope="module")
def others(other_dir) -> dict[str, em.Motion]:
    return {path.name: em.read_bvh(path) for path in sorted(other_dir.glob("*.bvh"))}


def test_other_skeletons_are_mapped_without_a_map_file(others):
    assert len(others) >= 6  # the folder has grown: CMU, Xia-style, the 21-joint walks, ...
    for name, motion in others.items():
        jmap = find_joint_map(motion.skeleton)
        assert set(REQUIRED) <= set(jmap.joints), name
        assert all(f"{s}_{r}" in jmap for s in ("left", "right") for r in ("clavicle", "upper_arm", "forearm", "hand"))
        unmapped = {motion.skeleton.names[j] for j in jmap.unmapped}
        hip_joints = {"LHipJoint", "RHipJoint"} & set(motion.skeleton.names)  # CMU's, of zero length
        assert hip_joints <= unmapped, name  # reported, not roles
        read = read_conventions(motion, jmap)
        assert (read.up, read.facing) == ("+Y", "+Z"), name
    cmu = read_conventions(others["cmu_scaled_131_03.bvh"], find_joint_map(others["cmu_scaled_131_03.bvh"].skeleton))
    assert cmu.unit == "m" and cmu.fps == pytest.approx(120, rel=1e-3)
    xia = read_conventions(others["dme_rest.bvh"], find_joint_map(others["dme_rest.bvh"].skeleton))
    assert xia.unit == "cmu" and xia.height * xia.metres_per_unit == pytest.approx(1.70, abs=0.05)


def test_bandai_clips_of_both_datasets_are_mapped(bandai1_dir, bandai2_dir):
    paths = sorted(bandai1_dir.glob("*.bvh"))[::20] + sorted(bandai2_dir.glob("*.bvh"))[::100]
    for path in paths:
        skeleton = em.read_bvh(path).skeleton
        jmap = find_joint_map(skeleton)
        assert jmap.as_names()["left_upper_leg"] == "UpperLeg_L" and jmap.as_names()["spine"] == ["Spine", "Chest"]
        assert jmap.confidence() == 1.0  # every role found by its name and the topology alike


def test_round_trips_between_real_skeletons_hold(others, bandai1_dir, bandai2_dir):
    motions = {
        "bandai2 walk": em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh"),
        "bandai1 bye": em.read_bvh(bandai1_dir / "dataset-1_bye_normal_001.bvh"),
        **{k: v for k, v in others.items() if v.n_frames > 1},
    }
    for (a, source), (b, target) in itertools.permutations(motions.items(), 2):
        there = retarget(source, target, plant_feet=False)
        back = retarget(there, source, plant_feet=False)
        assert worst_angle(directions(back), directions(source)) < ROUND_TRIP_DEG, (a, b)
        assert worst_angle(directions(there), directions(source)) < 1e-6 or a != b


def test_a_bandai_walk_on_the_cmu_skeleton_keeps_its_feet_and_its_unit(others, bandai2_dir):
    walk = em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh")
    cmu = others["cmu_scaled_131_03.bvh"]
    there = retarget(walk, cmu)
    jmap = find_joint_map(cmu.skeleton)
    hips = there.positions()[:, jmap["hips"]]
    walk_hips = walk.positions()[:, find_joint_map(walk.skeleton)["hips"]]
    # Metres now, on legs of another length: the hips as high, for their legs, as the walk's.
    ratio = np.median(hips[:, 1]) / np.median(walk_hips[:, 1])
    assert 0.005 < ratio < 0.015
    travelled = np.linalg.norm(hips[-1, [0, 2]] - hips[0, [0, 2]]) / np.linalg.norm(
        walk_hips[-1, [0, 2]] - walk_hips[0, [0, 2]]
    )
    assert travelled == pytest.approx(ratio, rel=0.1)


def test_the_cmu_clip_on_the_canonical_body_twists_its_bones_as_bandai_captures_do(others, bandai2_dir):
    """Positions do not show how a thigh or a spine segment is twisted about itself, but a model of
    the canonical body reads its local rotations. The CMU clip carried onto the canonical body has
    its spine and legs turned as a real dataset-2 walk's are (mean local rotation within 30
    degrees; measured 4-25), so the shipped model reads its legs and spine, joint by joint, as body
    mechanics (activity under 0.5; measured 0.01-0.41; the trunk's lean read as one chain is this
    dance's own, tests/decoupling/test_trunk_lean.py). Before the twists were aligned through each
    body's reference pose: 55-174 degrees off, activity 1.0 on the spine and the right leg."""
    from expressive_mocap.decoupling import BodyModel, decompose
    from expressive_mocap.rotations import quat
    from expressive_mocap.skeletons.canonical import onto_canonical

    walk = em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh")
    body, _ = onto_canonical(others["cmu_scaled_131_03.bvh"], plant_feet=False)
    names = ("Spine", "Chest", "UpperLeg_L", "LowerLeg_L", "UpperLeg_R", "LowerLeg_R")
    joints = [walk.skeleton.index(n) for n in names]
    for j in joints:
        ours, theirs = (quat.mean_rotation(m.rotations[:, j]) for m in (body, walk))
        offset = quat.mul(ours, quat.conjugate(theirs))
        assert np.degrees(quat.angle(offset)) < 30, walk.skeleton.names[j]
    joint_by_joint = replace(BodyModel.load(None), trunk=None)
    activity = decompose(body, joint_by_joint).activity[:, joints].mean(axis=0)
    assert activity.max() < 0.5, activity


def _twist_degrees(rotations: np.ndarray, bone: np.ndarray) -> np.ndarray:
    """The angle of each rotation's twist about ``bone`` (its swing-twist decomposition)."""
    axis = bone / np.linalg.norm(bone)
    along = (rotations[:, :3] @ axis)[:, None] * axis
    return np.degrees(2 * np.arctan2(np.linalg.norm(along, axis=1), np.abs(rotations[:, 3])))


def test_the_xia_style_walks_twisted_arbitrarily_are_read_from_their_positions(others):
    """The Xia-style files (a style-transfer network's output) twist spine segments, thighs and
    upper arms 50-170 degrees about themselves and back at the next joint; their hips and chest
    have every child at the joint. Read from the positions instead, their walks' chest and thighs
    are body mechanics to the shipped model joint by joint (mean activity over the four walks
    under 0.35; measured 0.15-0.22), and what the model reads off the spine, chest and thighs is
    hardly a twist about the bone (under 35 degrees on average in each walk; measured 2-30, the
    most where the walk leans 37-42 degrees, its lean being its style). Taken from the rotations:
    activity 1.0 on every one."""
    from expressive_mocap.body.canonical import canonical_skeleton
    from expressive_mocap.decoupling import BodyModel, decompose
    from expressive_mocap.skeletons.canonical import onto_canonical
    from expressive_mocap.skeletons.rig import Rig
    from expressive_mocap.skeletons.transfer import with_twists

    skeleton = canonical_skeleton()
    bones = {n: skeleton.index(c) for n, c in (("Spine", "Chest"), ("Chest", "Neck"))}
    bones |= {f"UpperLeg_{s}": skeleton.index(f"LowerLeg_{s}") for s in "LR"}
    joints = [skeleton.index(n) for n in ("Chest", "UpperLeg_L", "UpperLeg_R")]
    walks = [others[f"{n}.bvh"] for n in ("dme_demo_3d_1", "dme_demo_3d_2", "dme_comp_3d_2", "dme_demo_video_2")]
    model = replace(BodyModel.load(None), trunk=None)
    activity = []
    for walk in walks:
        assert {"hips", "chest", "left_upper_leg", "left_upper_arm"} <= with_twists(Rig.of(walk), walk).untrusted
        body, _ = onto_canonical(walk, plant_feet=False)
        activity.append(decompose(body, model).activity[:, joints].mean(axis=0))
        predicted = model.predict(body)
        for name, child in bones.items():
            j = skeleton.index(name)
            twist = _twist_degrees(
                quat.mul(quat.conjugate(predicted[:, j]), body.rotations[:, j]), skeleton.offsets[child]
            )
            assert twist.mean() < 35.0, (name, twist.mean())
    assert np.mean(activity, axis=0).max() < 0.35, np.mean(activity, axis=0)
    cmu = others["cmu_scaled_131_03.bvh"]
    assert with_twists(Rig.of(cmu), cmu).untrusted == frozenset()  # a real capture's twists stand


def test_skeleton_reports_the_twists_read_from_positions(other_dir, capsys):
    import json

    from expressive_mocap.cli import main

    assert (
        main(["skeleton", str(other_dir / "dme_demo_3d_1.bvh"), str(other_dir / "cmu_scaled_131_03.bvh"), "--json"])
        == 0
    )
    xia, cmu = (json.loads(line) for line in capsys.readouterr().out.splitlines())
    assert {"hips", "chest", "left_upper_leg", "right_upper_arm"} <= set(xia["twists_from_positions"])
    assert cmu["twists_from_positions"] == []
