"""``preprocess --canonical``: an archive mixing skeletons into one dataset on the canonical body."""

from __future__ import annotations

import json

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.canonical import canonical_skeleton
from expressive_mocap.cli import main
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.skeletons import synthetic_walk

RIGS = ("bandai", "smpl", "game", "mixamo")


@pytest.fixture(scope="module")
def mixed(tmp_path_factory):
    folder = tmp_path_factory.mktemp("mixed")
    for rig in RIGS:
        em.write_bvh(synthetic_walk(rig).motion, folder / f"walk_{rig}.bvh")
    return folder


def test_without_canonical_one_skeleton_and_a_message_that_says_why(mixed, tmp_path, capsys):
    summary = preprocess(mixed, tmp_path / "one", progress=False)
    assert summary.clips_ok == 1 and summary.clips_failed == 3
    errors = [f["error"] for f in json.loads((tmp_path / "one" / "manifest.json").read_text())["failures"]]
    assert all("another skeleton than the dataset's" in e and "--canonical" not in e for e in errors)
    # What to do is said once, with the count, not once per clip.
    said = "\n".join(summary.lines())
    assert said.count("--canonical") == 1 and "3 of 4 clips are of other skeletons" in said
    assert any("24 joints against 22; joint 0 is 'pelvis' where the dataset has 'joint_Root'" in e for e in errors)


def test_canonical_puts_every_skeleton_on_one_body(mixed, tmp_path):
    summary = preprocess(mixed, tmp_path / "all", canonical=True, progress=False)
    assert summary.clips_ok == len(RIGS) and summary.clips_failed == 0
    ds = load_dataset(tmp_path / "all")
    assert ds.skeleton["names"] == list(canonical_skeleton().names)
    records = {c["name"]: c for c in ds.manifest["clips"]}
    assert "source_skeleton" not in records["walk_bandai"]  # already on the canonical body
    smpl = records["walk_smpl"]["source_skeleton"]
    assert smpl["joints"] == 24 and smpl["map"]["left_toes"] == "left_foot" and smpl["fps"] == pytest.approx(60)
    assert ds.manifest["options"]["canonical"] is True
    # The same walk on four skeletons: comparable positions (cm, Y up) and contacts at the same times.
    frames = {c["name"]: (c["start"], c["frames"], c["fps"]) for c in ds.manifest["clips"]}

    def at_30fps(name, kind):
        start, count, fps = frames[name]
        step = int(round(fps / 30))
        return ds.arrays[kind][start : start + count][::step][:121]

    hips = canonical_skeleton().names.index("Hips")
    reference = at_30fps("walk_bandai", "positions")
    for rig in RIGS[1:]:
        positions = at_30fps(f"walk_{rig}", "positions")
        assert np.abs(positions[:, hips] - reference[:, hips]).max() < 1.0, rig  # cm
        contacts = at_30fps(f"walk_{rig}", "contacts")
        agree = np.mean(contacts == at_30fps("walk_bandai", "contacts"))
        assert agree > 0.95, rig


def test_the_model_on_another_skeleton_without_canonical_says_to_give_it(tmp_path, capsys):
    """An archive of one skeleton other than the model's, with --model alone: each clip fails
    naming the model's skeleton, and the message says that --canonical takes them."""
    folder = tmp_path / "game"
    folder.mkdir()
    em.write_bvh(synthetic_walk("game", seconds=1.0).motion, folder / "walk.bvh")
    assert main(["preprocess", str(folder), "-o", str(tmp_path / "m"), "--model"]) == 1
    said = capsys.readouterr()
    assert "this body model was trained on a 22-joint skeleton" in said.out + said.err
    assert "--canonical retargets" in said.out + said.err


def test_canonical_from_the_command_line_with_the_model(mixed, tmp_path, capsys):
    assert main(["preprocess", str(mixed), "-o", str(tmp_path / "m"), "--canonical", "--model", "-q"]) == 0
    ds = load_dataset(tmp_path / "m")
    assert len(ds.manifest["clips"]) == len(RIGS) and "activity" in ds.arrays


@pytest.mark.real_data
def test_canonical_takes_real_files_of_other_sources_beside_bandai(other_dir, bandai2_dir, tmp_path):
    folder = tmp_path / "src"
    folder.mkdir()
    others = list(other_dir.glob("*.bvh"))
    for path in others:
        (folder / path.name).symlink_to(path)
    for path in sorted(bandai2_dir.glob("dataset-2_walk_normal_*.bvh"))[:3]:
        (folder / path.name).symlink_to(path)
    summary = preprocess(folder, tmp_path / "out", canonical=True, progress=False)
    assert summary.clips_failed == 0 and summary.clips_ok == len(others) + 3
    ds = load_dataset(tmp_path / "out")
    cmu = next(c for c in ds.manifest["clips"] if c["name"] == "cmu_scaled_131_03")
    assert cmu["source_skeleton"]["joints"] == 31 and cmu["source_fps"] == pytest.approx(120, rel=1e-3)
    # Clips of 24 to 120 fps, stored at the rate most of them share, each its own rate recorded.
    assert ds.manifest["fps"] == 30.0 and {c["fps"] for c in ds.manifest["clips"]} == {30.0}
    assert {round(c["source_fps"]) for c in ds.manifest["clips"]} >= {30, 60, 120}
    # Real CMU walking, now in the canonical body's centimetres: the hips about a metre up.
    hips = ds.arrays["positions"][cmu["start"] : cmu["start"] + cmu["frames"], 1]
    assert 70 < np.median(hips[:, 1]) < 110


def test_a_map_file_reaches_every_clip_and_needs_canonical(mixed, tmp_path, capsys):
    from expressive_mocap.errors import ArgumentError

    game_only = tmp_path / "game"
    game_only.mkdir()
    (game_only / "walk_game.bvh").symlink_to(mixed / "walk_game.bvh")
    map_file = tmp_path / "map.toml"
    map_file.write_text('chest = "spine_02"\n')
    argv = ["preprocess", str(game_only), "-o", str(tmp_path / "m"), "--canonical", "--map", str(map_file), "-q"]
    assert main(argv) == 0
    record = load_dataset(tmp_path / "m").manifest["clips"][0]
    assert record["source_skeleton"]["map"]["chest"] == "spine_02"
    with pytest.raises(ArgumentError, match="give canonical=True too"):
        preprocess(game_only, tmp_path / "n", joint_map={"chest": "spine_02"}, progress=False)


@pytest.mark.parametrize(("keep", "model"), [(None, None), ("rotations,features,activity,body,expressive", "")])
def test_retargeted_clips_skip_the_text_and_store_what_the_text_gave(mixed, tmp_path, monkeypatch, keep, model):
    """The clips retargeted by ``--canonical`` reach the kernels as arrays: stored as the same
    clips written as BVH text on the canonical body and preprocessed from that text, every kind
    kept (the model's too), to float32 rounding, contacts alike. Clips of 30 and 60 fps: both runs
    store them at 30 fps (``--canonical`` takes the rate most clips share)."""
    import expressive_mocap.bvh as bvh
    from expressive_mocap.skeletons.canonical import many_onto_canonical

    foreign = [f"walk_{rig}" for rig in RIGS[1:]]
    moved = many_onto_canonical([em.read_bvh(mixed / f"{name}.bvh") for name in foreign])
    as_text = tmp_path / "as_text"
    as_text.mkdir()
    for name, (motion, _) in zip(foreign, moved):
        (as_text / f"{name}.bvh").write_bytes(bvh.bvh_bytes(motion))
    expected = load_dataset(
        preprocess(as_text, tmp_path / "expected", keep=keep, model=model, fps=30.0, progress=False).out
    )

    def no_text(*args, **kwargs):
        raise AssertionError("a retargeted clip was written as BVH text")

    monkeypatch.setattr(bvh, "bvh_bytes", no_text)
    summary = preprocess(mixed, tmp_path / "got", keep=keep, model=model, canonical=True, progress=False)
    got = load_dataset(summary.out)
    clips = {c["name"]: c for c in got.manifest["clips"]}
    for record in expected.manifest["clips"]:
        mine = clips[record["name"]]
        assert (mine["frames"], mine["fps"], mine["source_fps"]) == (record["frames"], 30.0, record["source_fps"])
        for kind in expected.arrays:
            want = expected.arrays[kind][record["start"] : record["start"] + record["frames"]]
            have = got.arrays[kind][mine["start"] : mine["start"] + mine["frames"]]
            if kind == "contacts":
                assert np.array_equal(have, want), record["name"]
            else:
                np.testing.assert_allclose(have, want, rtol=1e-5, atol=1e-4, err_msg=f"{record['name']} {kind}")
