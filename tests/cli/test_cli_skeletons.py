"""``skeleton`` and ``retarget`` as a user runs them, on synthetic rigs written to BVH files."""

from __future__ import annotations

import json

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap._utils.tokens import listed
from expressive_mocap.body import find_joint_map
from expressive_mocap.cli import main
from expressive_mocap.skeletons import synthetic_walk


@pytest.fixture(scope="module")
def rig_files(tmp_path_factory) -> dict:
    folder = tmp_path_factory.mktemp("rigs")
    files = {}
    for rig in ("bandai", "smpl", "game", "cmu"):
        path = folder / f"{rig}.bvh"
        em.write_bvh(synthetic_walk(rig, wave="left").motion, path)
        files[rig] = path
    return files


def test_skeleton_reports_the_map_and_conventions_of_each_file(rig_files, capsys):
    assert main(["skeleton", "--json", *map(str, rig_files.values())]) == 0
    reports = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["file"] for r in reports] == [str(p) for p in rig_files.values()]
    for rig, report in zip(rig_files, reports):
        truth = synthetic_walk(rig).truth
        assert {k: v for k, v in report["map"].items() if k in truth} == truth
        built = synthetic_walk(rig).conventions
        assert (report["up"], report["facing"], report["unit"]) == (built.up, built.facing, built.unit)
        assert report["stature_m"] == pytest.approx(1.63, abs=0.05)  # what tells the unit
        # The actor height is the one every other step reads: the skeleton's Body's.
        assert report["actor_height"] == pytest.approx(em.actor_height(em.read_bvh(rig_files[rig]).skeleton), abs=1e-6)
    game = reports[2]
    assert "upperarm_twist_01_l" in game["unmapped"] and game["rest_pose"] == "A"


def test_skeleton_text_and_overrides(rig_files, capsys):
    assert main(["skeleton", str(rig_files["smpl"]), "--up", "y", "--facing", "z", "--unit", "cm"]) == 0
    out = capsys.readouterr().out
    assert "up +Y (sure 1.00)" in out and "unit cm (1.00)" in out
    assert "left_foot        left_ankle" in out and "left_toes        left_foot" in out  # SMPL's naming


def test_skeleton_takes_a_map_file_and_names_a_bad_one(rig_files, tmp_path, capsys):
    good = tmp_path / "map.toml"
    good.write_text('chest = "spine_02"\n')
    assert main(["skeleton", "--json", "--map", str(good), str(rig_files["game"])]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["map"]["chest"] == "spine_02" and report["how"]["chest"] == "map"
    bad = tmp_path / "bad.json"
    bad.write_text('{"elbow_l": "lowerarm_l"}')
    assert main(["skeleton", "--map", str(bad), str(rig_files["game"])]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bad.json: unknown role 'elbow_l'" in err


def test_retarget_writes_the_motion_on_the_target_skeleton(rig_files, tmp_path, capsys):
    out = tmp_path / "walk_on_smpl.bvh"
    assert main(["retarget", str(rig_files["bandai"]), "--to", str(rig_files["smpl"]), "-o", str(out)]) == 0
    assert "roles carried" in capsys.readouterr().out
    moved = em.read_bvh(out)
    smpl = em.read_bvh(rig_files["smpl"])
    assert moved.skeleton.names == smpl.skeleton.names
    np.testing.assert_allclose(moved.skeleton.offsets, smpl.skeleton.offsets, atol=1e-5)
    assert moved.fps == pytest.approx(30.0) and moved.n_frames == 121
    # The wave is on the left arm of the result: the left hand well above the right one.
    jmap = find_joint_map(moved.skeleton)
    hands = moved.positions()[:, [jmap["left_hand"], jmap["right_hand"]], 2]  # Z is up on this rig
    assert np.median(hands[:, 0] - hands[:, 1]) > 0.3


def test_retarget_refuses_a_target_it_cannot_map(rig_files, tmp_path, capsys):
    stick = tmp_path / "stick.bvh"
    stick.write_text(
        "HIERARCHY\nROOT a\n{\n OFFSET 0 0 0\n CHANNELS 3 Xposition Yposition Zposition\n JOINT b\n {\n"
        "  OFFSET 0 1 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\n"
        "MOTION\nFrames: 1\nFrame Time: 0.0333333\n0 0 0 0 0 0\n"
    )
    out = tmp_path / "never.bvh"
    assert main(["retarget", str(rig_files["bandai"]), "--to", str(stick), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot tell which joint is the hips" in err
    assert not out.exists()


def test_footsteps_of_a_z_up_rig_with_a_map(rig_files, tmp_path, capsys):
    map_file = tmp_path / "map.json"
    map_file.write_text('{"left_foot": "left_ankle", "right_foot": "right_ankle"}')
    assert main(["footsteps", str(rig_files["smpl"]), "--map", str(map_file)]) == 0
    out = capsys.readouterr().out
    # The demo's 4 s walk at 1.8 steps a second, Z up in metres: read upright, as on the Bandai rig.
    assert main(["footsteps", str(rig_files["bandai"])]) == 0
    bandai = capsys.readouterr().out
    summary = [line for line in out.splitlines() if line.startswith("summary")]
    assert summary == [line for line in bandai.splitlines() if line.startswith("summary")]
    assert "7 steps" in summary[0] and "cadence 1.8" in summary[0], summary


def test_retarget_can_take_the_targets_frame_rate(rig_files, tmp_path):
    out = tmp_path / "at_120.bvh"
    assert (
        main(["retarget", str(rig_files["bandai"]), "--to", str(rig_files["cmu"]), "--fps", "120", "-o", str(out)]) == 0
    )
    moved = em.read_bvh(out)
    assert moved.fps == pytest.approx(120) and moved.n_frames == 481  # 4 s, every 1/120 s
    jmap = find_joint_map(moved.skeleton)
    same = em.read_bvh(rig_files["cmu"])  # the same walk written at 120 fps on that rig
    np.testing.assert_allclose(
        moved.positions()[::4, jmap["head"]],
        same.positions()[::4, jmap["head"]],
        atol=0.5,  # inches
    )


@pytest.mark.parametrize("source, target", [("bandai", "cmu"), ("cmu", "game"), ("smpl", "bandai")])
def test_retarget_names_the_joints_without_counterpart(rig_files, source, target, tmp_path, capsys):
    from expressive_mocap.body import Body
    from expressive_mocap.skeletons.rig import Rig
    from expressive_mocap.skeletons.transfer import matched_chains, without_counterpart

    a, b = em.read_bvh(rig_files[source]), em.read_bvh(rig_files[target])
    held, shared = without_counterpart(Rig.of(a), Rig.of(b))
    matched = {b.skeleton.names[j] for j, _, _, _ in matched_chains(Rig.of(a), Rig.of(b))}
    ours, theirs = Body.of(a.skeleton).joint_map, Body.of(b.skeleton).joint_map
    carried = {b.skeleton.names[theirs[role]] for role in theirs.joints if role in ours.joints}
    assert not set(held) & set(shared) and not (set(held) | set(shared)) & (carried | matched)
    # Every joint is carried (by role or as its counterpart's), held or shared: none left out.
    assert carried | matched | set(held) | set(shared) == set(b.skeleton.names)
    out_file = str(tmp_path / "o.bvh")
    assert main(["retarget", str(rig_files[source]), "--to", str(rig_files[target]), "-o", out_file]) == 0
    out = capsys.readouterr().out
    assert (f"held at rest with their parents: {listed(held)}" in out) == bool(held)
    assert (f"sharing the turn from the hips to the chest: {listed(shared)}" in out) == bool(shared)
