"""`expressive-mocap preprocess`: an archive of clips into a dataset of arrays.

A small synthetic archive (procedural walks and the hand-written mixed_orders.bvh, plus a broken
file) as a folder, a .zip and a .tar.gz; values checked against the package's own per-clip
results; failures, resume and the finished-or-nothing output. One test on ~20 real Bandai clips
(Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0).
"""

import json
import os
import shutil
import tarfile
import time
import zipfile

import numpy as np
import pytest

import expressive_mocap as em
import expressive_mocap.dataset.work as work_module
from expressive_mocap.cli import main
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.decoupling.algebra import decompose
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.errors import DatasetError
from expressive_mocap.procedural import procedural_walk

BROKEN = b"HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 2 Xposition\n}\n"
KEEP = "positions,rotations,features,contacts,activity,body,expressive"


@pytest.fixture(scope="module")
def archive(tmp_path_factory):
    """The same clips as a folder (with a subfolder), a .zip and a .tar.gz."""
    root = tmp_path_factory.mktemp("archive")
    folder = root / "clips"
    (folder / "more").mkdir(parents=True)
    em.write_bvh(procedural_walk(seconds=2.0), folder / "walk_a.bvh")
    em.write_bvh(procedural_walk(seconds=1.5, speed=0.9, wave="right"), folder / "walk_b.bvh")
    (folder / "broken.bvh").write_bytes(BROKEN)
    em.write_bvh(procedural_walk(seconds=1.0, speed=1.4, wave="left"), folder / "more" / "walk_c.bvh")
    (folder / "notes.txt").write_text("not a clip")
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    with zipfile.ZipFile(root / "clips.zip", "w", zipfile.ZIP_DEFLATED) as z:
        for p in files:
            z.write(p, p.relative_to(folder).as_posix())
    with tarfile.open(root / "clips.tar.gz", "w:gz") as t:
        for p in files:
            t.add(p, p.relative_to(folder).as_posix())
    return root


def run(src, out, **kw):
    kw.setdefault("progress", False)
    return preprocess(src, out, **kw)


def test_values_equal_the_packages_own_per_clip_results(archive, tmp_path):
    summary = run(archive / "clips", tmp_path / "ds", keep=KEEP, model="")
    assert summary.finished and summary.clips_ok == 3 and summary.clips_failed == 1
    ds = load_dataset(tmp_path / "ds")
    assert ds.names == ["more/walk_c", "walk_a", "walk_b"]
    model = BodyModel.load()
    for i, name in enumerate(ds.names):
        motion = em.read_bvh(archive / "clips" / f"{name}.bvh")
        parts = decompose(motion, model)
        expected = {
            "positions": motion.positions(),
            "rotations": motion.rotations,
            "features": em.dynamic_features(motion),
            "contacts": em.foot_contacts(motion),
            "activity": parts.activity,
            "body": parts.body,
            "expressive": parts.expressive,
        }
        clip = ds.clip(name)
        assert ds.clips[i]["frames"] == motion.n_frames and ds.clips[i]["fps"] == pytest.approx(motion.fps)
        for kind, values in expected.items():
            got = clip[kind]
            assert got.dtype == (bool if kind == "contacts" else np.float32), kind
            np.testing.assert_array_equal(got, ds.arrays[kind][ds.offsets[i] : ds.offsets[i + 1]])
            if kind == "contacts":
                np.testing.assert_array_equal(got, values)
            else:  # float32 precision of values up to ~300 (cm)
                np.testing.assert_allclose(got, values.astype(np.float32), rtol=2e-7, atol=1e-6, err_msg=kind)
    assert ds.skeleton["names"] == list(em.read_bvh(archive / "clips" / "walk_a.bvh").skeleton.names)
    assert ds.manifest["options"]["keep"] == KEEP.split(",")
    assert ds.manifest["package_version"] == em.__version__
    assert isinstance(ds.positions, np.memmap)


def test_a_bad_clip_is_reported_and_the_others_are_fine(archive, tmp_path):
    summary = run(archive / "clips", tmp_path / "ds")
    ds = load_dataset(tmp_path / "ds")
    assert [f["name"] for f in ds.failures] == ["broken"]
    error = ds.failures[0]["error"]
    assert "broken.bvh, line 6: unknown channel" in error
    with pytest.raises(em.BVHError) as raised:
        em.read_bvh(archive / "clips" / "broken.bvh")
    assert error == str(raised.value)
    assert summary.failures[0]["error"] == error
    assert len(ds) == 3 and len(ds.positions) == sum(c["frames"] for c in ds.clips)


def test_a_clip_that_cannot_be_read_is_a_failure_not_the_end(archive, tmp_path, monkeypatch):
    folder = tmp_path / "clips"
    shutil.copytree(archive / "clips", folder)
    os.symlink(tmp_path / "nowhere.bvh", folder / "dangling.bvh")  # listed, never readable
    summary = run(folder, tmp_path / "ds")
    errors = {f["name"]: f["error"] for f in load_dataset(tmp_path / "ds").failures}
    assert summary.finished and sorted(errors) == ["broken", "dangling"]
    assert errors["dangling"] == f"{folder / 'dangling.bvh'}: cannot read the file: No such file or directory"
    # A file that goes away after its header was read: the kernel's own read fails, that clip only.
    prepare = work_module.prepare

    def prepare_then_remove(batch, *args):
        prepared = prepare(batch, *args)
        (folder / "walk_b.bvh").unlink(missing_ok=True)
        return prepared

    monkeypatch.setattr(work_module, "prepare", prepare_then_remove)
    run(folder, tmp_path / "gone")
    gone = load_dataset(tmp_path / "gone")
    errors = {f["name"]: f["error"] for f in gone.failures}
    assert sorted(errors) == ["broken", "dangling", "walk_b"] and gone.names == ["more/walk_c", "walk_a"]
    assert errors["walk_b"] == f"{folder / 'walk_b.bvh'}: cannot read the file: No such file or directory"


def test_a_damaged_zip_member_is_a_failure_not_the_end(archive, tmp_path):
    damaged = tmp_path / "damaged.zip"
    with zipfile.ZipFile(damaged, "w", zipfile.ZIP_STORED) as z:
        for name in ("walk_a.bvh", "walk_b.bvh"):
            z.write(archive / "clips" / name, name)
    data = bytearray(damaged.read_bytes())
    at = data.index(b"HIERARCHY", data.index(b"walk_b.bvh")) + 200  # inside walk_b's stored bytes
    data[at] ^= 0x01  # its CRC no longer matches
    damaged.write_bytes(bytes(data))
    summary = run(damaged, tmp_path / "ds")
    ds = load_dataset(tmp_path / "ds")
    assert summary.finished and ds.names == ["walk_a"]
    assert ds.failures[0]["error"].startswith(f"{damaged}:walk_b.bvh: cannot read the archive member: Bad CRC-32")


def assert_same_dataset(a, b):
    assert a.names == b.names and a.manifest["skeleton"] == b.manifest["skeleton"]
    assert [c["frames"] for c in a.clips] == [c["frames"] for c in b.clips]
    assert [f["name"] for f in a.failures] == [f["name"] for f in b.failures]
    np.testing.assert_array_equal(a.offsets, b.offsets)
    assert a.arrays.keys() == b.arrays.keys()
    for kind in a.arrays:
        np.testing.assert_array_equal(a.arrays[kind], b.arrays[kind])


def test_folder_zip_and_tar_give_the_same_dataset(archive, tmp_path):
    for name in ("clips", "clips.zip", "clips.tar.gz"):
        run(archive / name, tmp_path / name)
    folder = load_dataset(tmp_path / "clips")
    for name in ("clips.zip", "clips.tar.gz"):
        other = load_dataset(tmp_path / name)
        assert_same_dataset(folder, other)
        assert other.clips[1]["source"] == f"{archive / name}:walk_a.bvh"
        assert other.failures[0]["error"].startswith(f"{archive / name}:broken.bvh, line")


def test_a_glob_takes_the_matching_files(archive, tmp_path):
    run(str(archive / "clips" / "walk_*.bvh"), tmp_path / "ds")
    assert load_dataset(tmp_path / "ds").names == ["walk_a", "walk_b"]


def test_mixed_orders_file_positions_and_rotations(mixed_path, tmp_path):
    folder = tmp_path / "mixed"
    folder.mkdir()
    shutil.copy(mixed_path, folder)
    # No joint roles in this skeleton: features fail with a clear error, positions do not.
    run(folder, tmp_path / "pos", keep="positions,rotations")
    ds = load_dataset(tmp_path / "pos")
    motion = em.read_bvh(mixed_path)
    np.testing.assert_allclose(ds.clip(0)["positions"], motion.positions().astype(np.float32), rtol=2e-7, atol=1e-6)
    np.testing.assert_allclose(ds.clip(0)["rotations"], motion.rotations.astype(np.float32), rtol=2e-7, atol=1e-7)
    run(folder, tmp_path / "feat", keep="features")
    assert load_dataset(tmp_path / "feat").failures[0]["name"] == "mixed_orders"


def test_batches_read_out_of_order_are_written_in_order(archive, tmp_path, monkeypatch):
    run(archive / "clips", tmp_path / "one_batch")
    prepare = work_module.prepare

    def first_batch_slow(batch, *args):
        if any(item.name == "broken" for item in batch):  # the first clip in name order
            time.sleep(0.3)  # the second header thread finishes the next batch first
        return prepare(batch, *args)

    monkeypatch.setattr(work_module, "prepare", first_batch_slow)
    run(archive / "clips", tmp_path / "one_clip_a_batch", batch_mb=1e-6)
    assert_same_dataset(load_dataset(tmp_path / "one_batch"), load_dataset(tmp_path / "one_clip_a_batch"))


def test_interrupted_run_resumes_without_redoing_finished_clips(archive, tmp_path):
    full = tmp_path / "full"
    run(archive / "clips", full, batch_mb=1e-6)  # one clip a batch
    out = tmp_path / "resumed"
    first = run(archive / "clips", out, batch_mb=1e-6, max_batches=2)
    assert not first.finished and first.batches == 2
    assert not (out / "manifest.json").exists() and (out / ".partial").is_dir()
    with pytest.raises(DatasetError, match="interrupted run"):
        load_dataset(out)
    journal = [json.loads(line) for line in (out / ".partial" / "journal.jsonl").read_text().splitlines()]
    done = [key for entry in journal for key in entry["items"]]
    assert len(done) == 2
    # A crash in the middle of the next batch: rows appended but no journal line, a torn line.
    with open(out / ".partial" / "positions.npy", "ab") as handle:
        handle.write(b"\0" * 1000)
    with open(out / ".partial" / "journal.jsonl", "ab") as handle:
        handle.write(b'{"batch": 2, "ite')
    second = run(archive / "clips", out, batch_mb=1e-6)
    assert second.finished and second.clips_resumed == 2 and second.batches == 2
    assert second.clips_ok + second.clips_failed == 4
    assert_same_dataset(load_dataset(full), load_dataset(out))
    assert not (out / ".partial").exists()


def test_resume_refuses_other_options_and_finished_output_needs_overwrite(archive, tmp_path):
    out = tmp_path / "ds"
    run(archive / "clips", out, batch_mb=1e-6, max_batches=1)
    with pytest.raises(DatasetError, match="other options"):
        run(archive / "clips", out, keep="positions")
    run(archive / "clips", out)
    with pytest.raises(DatasetError, match="--overwrite"):
        run(archive / "clips", out)
    run(archive / "clips", out, keep="positions", overwrite=True)
    ds = load_dataset(out)
    assert list(ds.arrays) == ["positions"] and not (out / "features.npy").exists()


def test_cli(archive, tmp_path, capsys):
    assert (
        main(
            ["preprocess", str(archive / "clips.zip"), "-o", str(tmp_path / "ds"), "--keep", "positions,contacts", "-q"]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "3 clips ok, 1 failed" in out and "headers" in out and "failed: " in out
    assert main(["preprocess", str(archive / "nothing"), "-o", str(tmp_path / "x")]) == 1
    assert "no such folder or archive" in capsys.readouterr().err
    assert main(["preprocess", str(archive / "clips"), "-o", str(tmp_path / "y"), "--keep", "activity"]) == 1
    assert "needs a body-mechanics model" in capsys.readouterr().err
    assert main(["preprocess", str(archive / "clips"), "-o", str(tmp_path / "y"), "--keep", "velocity"]) == 1
    err = capsys.readouterr().err
    assert "unknown kinds" in err and len(err.strip().splitlines()) == 1


@pytest.mark.real_data
def test_twenty_bandai_clips(bandai2_dir, tmp_path):
    paths = sorted(bandai2_dir.glob("*.bvh"))[::145][:20]
    folder = tmp_path / "bandai"
    folder.mkdir()
    for p in paths:
        os.symlink(p, folder / p.name)
    summary = run(folder, tmp_path / "ds", model="", batch_mb=2.0)
    assert summary.finished and summary.clips_ok == 20 and summary.batches > 1
    ds = load_dataset(tmp_path / "ds")
    model = BodyModel.load()
    for k in (0, 7, 19):
        motion = em.read_bvh(paths[k])
        clip = ds.clip(paths[k].stem)
        np.testing.assert_allclose(clip["positions"], motion.positions().astype(np.float32), rtol=2e-7, atol=2e-5)
        np.testing.assert_allclose(
            clip["features"], em.dynamic_features(motion).astype(np.float32), rtol=2e-7, atol=1e-6
        )
        np.testing.assert_array_equal(clip["contacts"], em.foot_contacts(motion))
        np.testing.assert_allclose(
            clip["activity"], decompose(motion, model).activity.astype(np.float32), rtol=2e-7, atol=1e-6
        )


def test_model_in_float32_stays_close_to_float64(archive, tmp_path):
    run(archive / "clips", tmp_path / "f64", keep="activity,body", model="")
    run(archive / "clips", tmp_path / "f32", keep="activity,body", model="", model_float32=True)
    a, b = load_dataset(tmp_path / "f64"), load_dataset(tmp_path / "f32")
    assert b.manifest["options"]["model_float32"] and a.names == b.names
    np.testing.assert_allclose(b.activity, a.activity, atol=1e-4)
    np.testing.assert_allclose(b.body, a.body, atol=1e-5)


def test_a_dask_cluster_writes_the_single_machine_dataset(archive, tmp_path):
    distributed = pytest.importorskip("distributed", reason="the [distributed] extra (Dask) is not installed")
    run(archive / "clips.zip", tmp_path / "single", model="", batch_mb=1e-6)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            summary = run(archive / "clips.zip", tmp_path / "dask", model="", batch_mb=1e-6, cluster=client)
    assert summary.finished and summary.clips_ok == 3 and summary.clips_failed == 1
    single, dask = load_dataset(tmp_path / "single"), load_dataset(tmp_path / "dask")
    assert_same_dataset(single, dask)
    assert [f["error"] for f in single.failures] == [f["error"] for f in dask.failures]


def test_the_manifest_reads_back_with_a_clip_a_line():
    from expressive_mocap.dataset.finish import manifest_text

    manifest = {
        "format": "x",
        "options": {"keep": ["positions"], "canonical": True},
        "clips": [{"name": f"c{k}", "frames": k, "source_skeleton": {"map": {"spine": ["a", "b"]}}} for k in range(3)],
        "failures": [],
        "feature_names": None,
    }
    text = manifest_text(manifest)
    assert json.loads(text) == manifest
    assert sum(line.lstrip().startswith('{"name"') for line in text.splitlines()) == 3
