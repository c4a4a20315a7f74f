"""Archives that mix skeletons: Bandai-Namco dataset-2 clips (Bandai-Namco-Research-Motiondataset,
CC BY-NC 4.0) with CMU clips (CMU Graphics Lab Motion Capture Database). Without ``--canonical``
the dataset keeps the skeleton most clips share, whatever comes first, says once how many clips
are of others and what to do, and the command fails when most clips did."""

from __future__ import annotations

import json

import numpy as np

from expressive_mocap.cli import main
from expressive_mocap.dataset import load_dataset, preprocess
from mixed_archives import BANDAI, CMU, bandai_members, cmu_members, zip_of


def test_the_skeleton_most_clips_share_is_kept_whatever_comes_first(mixed_zip, bandai2_dir, tmp_path, capsys):
    """The 2 CMU clips come first by name, the 3 Bandai clips are most: the Bandai clips are kept;
    the summary names the count once, with --canonical; the command succeeds."""
    archive, _ = mixed_zip
    assert main(["preprocess", str(archive), "-o", str(tmp_path / "m")]) == 0
    said = capsys.readouterr()
    ds = load_dataset(tmp_path / "m")
    assert sorted(ds.names) == sorted(f"dataset-2_{c}" for c in BANDAI) and len(ds.skeleton["names"]) == 22
    assert sorted(f["name"] for f in ds.failures) == list(CMU)
    assert all(f["skeleton"] == {"joints": 31, "root": "Hips"} for f in ds.failures)
    assert all("another skeleton than the dataset's" in f["error"] for f in ds.failures)
    assert "2 of 5 clips are of other skeletons than the dataset's (22 joints" in said.out
    assert said.out.count("--canonical") == 1 and "error" not in said.err  # once, not once per clip


def test_when_most_clips_fail_the_command_says_so_and_exits_1_with_the_dataset_written(
    bandai2_dir, other_dir, tmp_path, capsys
):
    """2 Bandai clips and 3 clips of three other skeletons (the two CMU clips name their joints
    differently, an m21 rig): the Bandai clips are most, yet 3 of 5 failed: status 1, said on
    stderr, and the 2 clips that worked are still a dataset."""
    members = {**cmu_members(other_dir), **bandai_members(bandai2_dir, 2), "m21_walk.bvh": other_dir / "m21_walk.bvh"}
    archive = zip_of(tmp_path / "four.zip", members)
    assert main(["preprocess", str(archive), "-o", str(tmp_path / "t"), "-q"]) == 1
    said = capsys.readouterr()
    assert f"3 of the 5 clips of {archive} failed" in said.err
    assert f"{tmp_path / 't'} holds the 2 that worked" in said.err
    ds = load_dataset(tmp_path / "t")
    assert sorted(ds.names) == sorted(f"dataset-2_{c}" for c in BANDAI[:2]) and len(ds.failures) == 3
    assert sorted(f["skeleton"]["joints"] for f in ds.failures) == [21, 31, 31]


def test_a_tie_keeps_the_first_clips_skeleton_by_name(bandai2_dir, other_dir, tmp_path, capsys):
    """One CMU clip and one Bandai clip: no skeleton is most, the first by name is kept (as before
    the scan); half failed, not most: status 0."""
    archive = zip_of(
        tmp_path / "tie.zip", {**bandai_members(bandai2_dir, 1), "cmu_01_01.bvh": other_dir / "cmu_01_01.bvh"}
    )
    assert main(["preprocess", str(archive), "-o", str(tmp_path / "t"), "-q"]) == 0
    ds = load_dataset(tmp_path / "t")
    assert ds.names == ["cmu_01_01"] and [f["name"] for f in ds.failures] == [f"dataset-2_{BANDAI[0]}"]
    assert "1 of 2 clips are of other skeletons" in capsys.readouterr().out


def test_when_the_first_clip_is_of_the_majority_nothing_changes(bandai2_dir, other_dir, tmp_path):
    """Bandai clips first by name and most: the dataset's arrays are byte for byte those of the
    Bandai clips alone, the CMU clip a failure."""
    alone = zip_of(tmp_path / "alone.zip", bandai_members(bandai2_dir))
    mixed = zip_of(tmp_path / "mixed.zip", {**bandai_members(bandai2_dir), "zz_cmu.bvh": other_dir / "cmu_01_01.bvh"})
    preprocess(alone, tmp_path / "a", progress=False)
    summary = preprocess(mixed, tmp_path / "b", progress=False)
    assert summary.clips_ok == 3 and summary.clips_failed == 1 and summary.other_skeletons == 1
    a, b = load_dataset(tmp_path / "a"), load_dataset(tmp_path / "b")
    assert a.names == b.names and a.manifest["skeleton"] == b.manifest["skeleton"]
    for kind in a.kinds:
        assert (tmp_path / "a" / f"{kind}.npy").read_bytes() == (tmp_path / "b" / f"{kind}.npy").read_bytes()
    assert np.array_equal(a.offsets, b.offsets)


def test_an_interrupted_mixed_run_resumes_into_the_same_dataset(mixed_zip, tmp_path):
    """Stopped after the first batch (the CMU clips, failing) and resumed: the same clips and
    failures as a run straight through."""
    archive, _ = mixed_zip
    straight = preprocess(archive, tmp_path / "s", progress=False, batch_mb=0.5)
    first = preprocess(archive, tmp_path / "r", progress=False, batch_mb=0.5, max_batches=1)
    assert not first.finished
    resumed = preprocess(archive, tmp_path / "r", progress=False, batch_mb=0.5)
    assert resumed.finished and (resumed.clips_ok, resumed.clips_failed) == (straight.clips_ok, straight.clips_failed)
    s, r = (json.loads((tmp_path / d / "manifest.json").read_text()) for d in ("s", "r"))
    assert s["clips"] == r["clips"] and s["failures"] == r["failures"] and s["skeleton"] == r["skeleton"]


def test_a_tar_stream_keeps_its_first_clips_skeleton_and_says_so(bandai2_dir, other_dir, tmp_path, capsys):
    """A tar is read once, as a stream (scanning it first would decompress it twice): its first
    readable clip's skeleton is the dataset's even when most clips are of another, as the docs
    say; the others fail, most of them here, so the command exits 1 with the dataset written."""
    import tarfile

    archive = tmp_path / "mixed.tar.gz"
    with tarfile.open(archive, "w:gz") as tar:
        tar.add(other_dir / "cmu_01_01.bvh", "a_cmu_01_01.bvh")  # first in the stream
        for name, source in bandai_members(bandai2_dir).items():
            tar.add(source, name)
    assert main(["preprocess", str(archive), "-o", str(tmp_path / "t"), "-q"]) == 1
    ds = load_dataset(tmp_path / "t")
    assert ds.names == ["a_cmu_01_01"] and len(ds.skeleton["names"]) == 31
    assert sorted(f["name"] for f in ds.failures) == sorted(f"dataset-2_{c}" for c in BANDAI)
    assert "3 of the 4 clips" in capsys.readouterr().err
