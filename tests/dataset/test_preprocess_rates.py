"""Archives that mix frame rates: Bandai-Namco dataset-2 clips (30 fps;
Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0) with CMU clips (120 fps; CMU Graphics Lab
Motion Capture Database). With ``--canonical`` every clip is stored at one rate, its own kept in
its record; without it each keeps its own and the manifest names no one rate."""

from __future__ import annotations

import math

import pytest

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.dataset import load_dataset, preprocess
from mixed_archives import BANDAI, source_rates


def test_canonical_stores_every_clip_at_the_rate_most_share_keeping_durations(mixed_zip, tmp_path, capsys):
    archive, members = mixed_zip
    assert main(["preprocess", str(archive), "-o", str(tmp_path / "one"), "--canonical", "-q"]) == 0
    manifest = load_dataset(tmp_path / "one").manifest
    assert manifest["fps"] == 30.0 and manifest["options"]["fps"] == 30.0  # 3 clips at 30 fps, 2 at 120
    source = source_rates(members)
    assert {c["name"] for c in manifest["clips"]} == set(source) and not manifest["failures"]
    for clip in manifest["clips"]:
        frames, rate = source[clip["name"]]
        assert clip["source_fps"] == pytest.approx(rate, rel=1e-9), clip["name"]  # its own rate, recorded
        assert clip["fps"] == 30.0 and clip["frame_time"] == pytest.approx(1 / 30)
        # The duration is kept: as many frames as the clip's seconds hold at 30 fps (to one frame).
        assert clip["frames"] == math.ceil(frames * 30.0 / rate - 1e-6), clip["name"]
        assert abs(clip["frames"] / 30.0 - frames / rate) < 1 / 30
    cmu = next(c for c in manifest["clips"] if c["name"] == "cmu_01_01")
    assert cmu["source_skeleton"]["fps"] == pytest.approx(120, rel=1e-4) and cmu["frames"] == 2752 // 4


def test_canonical_with_fps_given_takes_that_rate(mixed_zip, tmp_path):
    archive, members = mixed_zip
    assert main(["preprocess", str(archive), "-o", str(tmp_path / "f"), "--canonical", "--fps", "60", "-q"]) == 0
    manifest = load_dataset(tmp_path / "f").manifest
    source = source_rates(members)
    assert manifest["fps"] == 60.0 and {c["fps"] for c in manifest["clips"]} == {60.0}
    for clip in manifest["clips"]:
        frames, rate = source[clip["name"]]
        assert abs(clip["frames"] / 60.0 - frames / rate) < 1 / 60, clip["name"]


def test_without_canonical_clips_of_several_rates_keep_their_own_and_the_manifest_names_none(
    bandai2_dir, tmp_path, capsys
):
    """One skeleton at 30 and 60 fps: each clip stored at its own rate; the manifest's fps is null,
    never one rate for clips of several, and the summary says so with what to do."""
    folder = tmp_path / "rates"
    folder.mkdir()
    clip = em.read_bvh(bandai2_dir / f"dataset-2_{BANDAI[0]}.bvh")
    em.write_bvh(clip, folder / "a.bvh")
    em.write_bvh(clip.resample(fps=60.0), folder / "b.bvh")
    assert main(["preprocess", str(folder), "-o", str(tmp_path / "out"), "-q"]) == 0
    said = capsys.readouterr().out
    manifest = load_dataset(tmp_path / "out").manifest
    assert manifest["fps"] is None and manifest["options"]["fps"] is None
    assert [round(c["fps"]) for c in manifest["clips"]] == [30, 60]
    assert "clips at 2 frame rates (1 at 30 fps, 1 at 60 fps)" in said and "--fps F" in said
    # One rate: the manifest names it.
    assert preprocess(str(folder / "a*.bvh"), tmp_path / "single", progress=False).clips_ok == 1
    assert load_dataset(tmp_path / "single").manifest["fps"] == 30.0
