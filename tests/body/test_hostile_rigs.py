"""Rigs no human motion should come on: all bones of zero length, bones along one line, four legs.
Each is refused in one line (or, for four legs, mapped with a warning), and in an archive under
``preprocess --canonical`` each is that clip's failure: the run goes on, the other clips land."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.conventions import read_conventions
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.cli import main
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.errors import MocapError
from expressive_mocap.motion import Motion, Skeleton
from expressive_mocap.skeletons import synthetic_walk


def reshaped(motion: Motion, offsets: np.ndarray) -> Motion:
    """``motion`` on its skeleton with other ``offsets`` (rotations at rest, the root moving)."""
    skeleton = motion.skeleton
    shaped = Skeleton(skeleton.names, skeleton.parents, offsets, skeleton.channels, skeleton.end_sites)
    rotations = np.zeros_like(motion.rotations)
    rotations[..., 3] = 1.0
    translations = np.tile(offsets, (motion.n_frames, 1, 1))
    translations[:, 0] = motion.translations[:, 0]
    return Motion(shaped, rotations, translations, motion.frame_time)


@pytest.fixture(scope="module")
def walk() -> Motion:
    return synthetic_walk("cmu", seconds=1.0).motion


def zero_length(walk: Motion) -> Motion:
    return reshaped(walk, np.zeros_like(walk.skeleton.offsets))


def collinear(walk: Motion) -> Motion:
    """Every bone along the vertical: the legs down, the rest up (left and right at one place)."""
    skeleton = walk.skeleton
    lengths = np.linalg.norm(skeleton.offsets, axis=1)
    down = np.array([any(w in n for w in ("Leg", "Foot", "Toe", "HipJoint")) for n in skeleton.names])
    offsets = np.zeros_like(skeleton.offsets)
    offsets[:, 1] = np.where(down, -lengths, lengths)
    offsets[0] = 0.0
    return reshaped(walk, offsets)


def dog() -> Motion:
    """A four-legged rig standing still, trunk level, paws on the floor."""
    names = ("Pelvis", "Spine", "Chest", "Neck", "Head")
    names += tuple(f"{leg}_{part}" for leg in ("FL", "FR", "HL", "HR") for part in ("Upper", "Lower", "Paw"))
    parents = [-1, 0, 1, 2, 3, 2, 5, 6, 2, 8, 9, 0, 11, 12, 0, 14, 15]
    offsets = [[0, 60, 0], [0, 0, 20], [0, 0, 20], [0, 10, 15], [0, 5, 10]]
    for x in (10, -10, 10, -10):
        offsets += [[x, -5, 0], [0, -25, 0], [0, -25, 2]]
    channels = tuple(
        ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
        if p < 0
        else ("Zrotation", "Xrotation", "Yrotation")
        for p in parents
    )
    ends = tuple((j, (0.0, 0.0, 5.0)) for j in (4, 7, 10, 13, 16))
    skeleton = Skeleton(names, parents, np.array(offsets, float), channels, ends)
    rotations = np.zeros((30, len(names), 4))
    rotations[..., 3] = 1.0
    translations = np.tile(skeleton.offsets, (30, 1, 1))
    translations[:, 0, 2] = np.arange(30) * 2.0
    return Motion(skeleton, rotations, translations, 1 / 30)


def test_a_rig_of_zero_length_bones_is_refused(walk):
    with pytest.raises(MocapError, match="every bone has zero length"):
        find_joint_map(zero_length(walk).skeleton)


def test_a_rig_of_bones_along_one_line_is_refused_before_any_nan(walk):
    motion = collinear(walk)
    with pytest.raises(
        MocapError, match="left upper leg 'LeftUpLeg' and right upper leg 'RightUpLeg' are at one place"
    ):
        read_conventions(motion, find_joint_map(motion.skeleton))


def test_a_four_legged_rig_is_mapped_with_a_warning(walk):
    motion = dog()
    with pytest.warns(UserWarning, match="moves on four legs"):
        read_conventions(motion, find_joint_map(motion.skeleton))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_conventions(walk, find_joint_map(walk.skeleton))  # a walking human: no warning


def test_retarget_and_skeleton_refuse_them_in_one_line(walk, tmp_path, capsys):
    target = tmp_path / "target.bvh"
    em.write_bvh(synthetic_walk("bandai", seconds=1.0).motion, target)
    for name, motion in (("zero", zero_length(walk)), ("collinear", collinear(walk))):
        path = tmp_path / f"{name}.bvh"
        em.write_bvh(motion, path)
        for argv in (
            ["skeleton", str(path)],
            ["retarget", str(path), "--to", str(target), "-o", str(tmp_path / "o.bvh")],
        ):
            assert main(argv) == 1, argv
            err = capsys.readouterr().err.strip()
            assert len(err.splitlines()) == 1 and err.startswith("expressive-mocap: error: "), err
    assert not (tmp_path / "o.bvh").exists()


def test_canonical_archive_fails_each_bad_rig_alone(walk, tmp_path):
    """Bad rigs among good clips: each bad one fails with its own reason (never the hint to pass
    --canonical, never the bad clip's skeleton taken as the dataset's), the good ones land, and a
    rerun finds the dataset finished."""
    src = tmp_path / "src"
    src.mkdir()
    em.write_bvh(zero_length(walk), src / "a_zero.bvh")
    em.write_bvh(collinear(walk), src / "b_collinear.bvh")
    for rig in ("cmu", "bandai", "mixamo"):
        em.write_bvh(synthetic_walk(rig, seconds=1.0).motion, src / f"walk_{rig}.bvh")
    summary = preprocess(src, tmp_path / "out", canonical=True, progress=False)
    assert summary.clips_ok == 3 and summary.clips_failed == 2
    failures = {f["name"]: f["error"] for f in json.loads((tmp_path / "out" / "manifest.json").read_text())["failures"]}
    assert "every bone has zero length" in failures["a_zero"]
    assert "at one place" in failures["b_collinear"]
    assert not any("--canonical" in error for error in failures.values())
    assert len(load_dataset(tmp_path / "out")) == 3


def test_a_bug_on_one_clip_is_that_clips_failure(walk, tmp_path, monkeypatch):
    """Whatever goes wrong retargeting one clip (here a ZeroDivisionError planted for the clip of
    17 frames) fails that clip, with the error's name: the run goes on."""
    from expressive_mocap.skeletons import canonical

    real_many, real_one = canonical.many_onto_canonical, canonical.onto_canonical

    def poisoned(motion):
        if motion.n_frames == 17:
            raise ZeroDivisionError("float division by zero")

    def many(motions, user_map=None):
        for motion in motions:
            poisoned(motion)
        return real_many(motions, user_map)

    def one(motion, user_map=None, **options):
        poisoned(motion)
        return real_one(motion, user_map, **options)

    monkeypatch.setattr(canonical, "many_onto_canonical", many)
    monkeypatch.setattr(canonical, "onto_canonical", one)
    src = tmp_path / "src"
    src.mkdir()
    em.write_bvh(walk[:17], src / "short.bvh")
    em.write_bvh(walk, src / "walk.bvh")
    summary = preprocess(src, tmp_path / "out", canonical=True, progress=False)
    assert summary.clips_ok == 1 and summary.clips_failed == 1
    assert "ZeroDivisionError: float division by zero" in summary.failures[0]["error"]


def with_long_toe(walk: Motion, joints: int) -> Motion:
    """``walk`` with a chain of ``joints`` tiny joints below its left toe (depth first)."""
    skeleton, toe = walk.skeleton, walk.skeleton.names.index("LeftToeBase")
    count = skeleton.n_joints
    new = [j if j <= toe else j + joints for j in range(count)]
    names = [""] * (count + joints)
    parents = [0] * (count + joints)
    offsets = np.zeros((count + joints, 3))
    channels: list = [("Zrotation", "Xrotation", "Yrotation")] * (count + joints)
    for j in range(count):
        names[new[j]], offsets[new[j]], channels[new[j]] = skeleton.names[j], skeleton.offsets[j], skeleton.channels[j]
        parents[new[j]] = -1 if skeleton.parents[j] < 0 else new[int(skeleton.parents[j])]
    for c in range(joints):
        names[toe + 1 + c], parents[toe + 1 + c], offsets[toe + 1 + c] = f"LeftToe{c}", toe + c, (0.0, 0.0, 0.001)
    ends = sorted([(new[j], o) for j, o in skeleton.end_sites if j != toe] + [(toe + joints, (0.0, 0.0, 0.001))])
    long = Skeleton(tuple(names), parents, offsets, tuple(channels), tuple(ends))
    rotations = np.tile([0.0, 0.0, 0.0, 1.0], (walk.n_frames, count + joints, 1))
    translations = np.tile(offsets, (walk.n_frames, 1, 1))
    rotations[:, new], translations[:, new] = walk.rotations, walk.translations
    return Motion(long, rotations, translations, walk.frame_time)


def test_a_humanoid_with_a_toe_chain_of_1500_joints_is_mapped(walk, tmp_path, capsys):
    """Mapping walked the limb's chain recursively: RecursionError at about 1,000 joints."""
    motion = with_long_toe(walk, 1500)
    jmap = find_joint_map(motion.skeleton)
    assert motion.skeleton.names[jmap["left_toes"]] == "LeftToeBase"
    assert jmap.as_names() == {**find_joint_map(walk.skeleton).as_names()}
    path = tmp_path / "long.bvh"
    em.write_bvh(motion, path)
    assert main(["skeleton", str(path)]) == 0
    out = capsys.readouterr().out
    assert "unmapped (1509): " in out and "... (1469 more)" in out  # a line of 40 names, not 1509


def test_clips_of_no_frame_and_one_are_retargeted_without_a_word(walk):
    """The per-clip readings (conventions, map checks, twists) of a clip with no frame read
    nothing and warn of nothing (a median of no frames refused it as a body of no height)."""
    from expressive_mocap.skeletons.canonical import many_onto_canonical

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = many_onto_canonical([walk, walk[:0], walk[:1]])
    assert [motion.n_frames for motion, _ in out] == [walk.n_frames, 0, 1]
