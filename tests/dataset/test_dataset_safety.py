"""`preprocess` never loses or corrupts a dataset, and `load_dataset` reads only a dataset whose
files are the ones its manifest vouches for: concurrent runs (real processes), reruns after a kill
at each step of finishing, a source spelled another way, duplicate clip names, tampered
manifests, folders holding the user's own files, a full disk."""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
import expressive_mocap.dataset.finish as finish_module
import expressive_mocap.dataset.npy as npy_module
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.errors import ArgumentError, DatasetError
from expressive_mocap.procedural import procedural_walk

# Child processes import the package the tests import: the installed one in CI, not the sources.
PACKAGE_ROOT = str(Path(em.__file__).resolve().parent.parent)
BROKEN = b"HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 2 Xposition\n}\n"


@pytest.fixture(scope="module")
def clips(tmp_path_factory) -> Path:
    """Four walks and a broken file in a folder."""
    folder = tmp_path_factory.mktemp("safety") / "clips"
    folder.mkdir()
    for k, seconds in enumerate((2.0, 1.5, 1.0, 1.2)):
        em.write_bvh(procedural_walk(seconds=seconds, speed=0.9 + 0.1 * k), folder / f"walk_{k}.bvh")
    (folder / "broken.bvh").write_bytes(BROKEN)
    return folder


@pytest.fixture(scope="module")
def reference(clips, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("reference") / "ds"
    run(clips, out)
    return out


def run(src, out, **kw):
    kw.setdefault("progress", False)
    return preprocess(src, out, **kw)


def same_dataset(a: Path, b: Path) -> None:
    x, y = load_dataset(a), load_dataset(b)
    assert x.names == y.names and [f["name"] for f in x.failures] == [f["name"] for f in y.failures]
    np.testing.assert_array_equal(x.offsets, y.offsets)
    assert x.arrays.keys() == y.arrays.keys()
    for kind in x.arrays:
        np.testing.assert_array_equal(x.arrays[kind], y.arrays[kind])


def snapshot(folder: Path) -> dict:
    """Every file's bytes and mtime below ``folder``."""
    return {
        p.relative_to(folder).as_posix(): (p.read_bytes(), p.stat().st_mtime_ns)
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def cli(*args: str, **kw) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": PACKAGE_ROOT}
    return subprocess.Popen(
        [sys.executable, "-m", "expressive_mocap.cli", "preprocess", *args, "-q"],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kw,
    )


# ----------------------------------------------------------------------------- concurrent runs


@pytest.mark.parametrize(
    "state", ["idle", "starting", "moving"], ids=["idle", "holder making .partial", "holder moving files into place"]
)
def test_a_second_run_on_a_locked_folder_fails_naming_the_holder(clips, reference, tmp_path, state):
    out = tmp_path / "ds"
    out.mkdir()
    if state != "idle":  # the moment the holder has made .partial but not yet its run.json (a CI run hit it)
        (out / ".partial").mkdir()
    if state == "moving":  # a data file in place, the manifest not yet: judged alone, a foreign folder
        (out / "positions.npy").write_bytes(b"")
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time; from pathlib import Path; from expressive_mocap.dataset import FolderLock\n"
            "with FolderLock(Path(sys.argv[1])):\n    print('locked', flush=True); time.sleep(60)",
            str(out),
        ],
        env={**os.environ, "PYTHONPATH": PACKAGE_ROOT},
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        second = cli(str(clips), "-o", str(out))
        _, err = second.communicate(timeout=60)
        assert second.returncode == 1
        assert err.count("\n") == 1 and f"process {holder.pid}" in err and "being written by another run" in err
        expected = {"idle": [], "starting": [".partial"], "moving": [".partial", "positions.npy"]}[state]
        assert sorted(os.listdir(out)) == sorted([".lock", *expected])  # it touched nothing
    finally:
        holder.kill()
        holder.wait()
    if state != "moving":  # (a half-moved dataset without its process is refused: not ours to guess)
        assert cli(str(clips), "-o", str(out)).wait(timeout=120) == 0  # the lock went with its process
        same_dataset(reference, out)


def test_two_runs_started_together_leave_one_good_dataset(tmp_path):
    src = tmp_path / "many"
    src.mkdir()
    walk = procedural_walk(seconds=1.0)
    for k in range(150):
        em.write_bvh(walk[: 10 + k % 20], src / f"clip_{k:03d}.bvh")
    out = tmp_path / "ds"
    runs = [cli(str(src), "-o", str(out), "--batch-mb", "0.000001") for _ in range(2)]
    results = [(r.wait(timeout=300), r.stderr.read()) for r in runs]
    codes = sorted(code for code, _ in results)
    assert codes == [0, 1], results
    loser = next(err for code, err in results if code == 1)
    assert "being written by another run" in loser or "already holds a finished dataset" in loser
    ds = load_dataset(out)  # verified against its manifest
    assert len(ds) == 150 and ds.positions.shape[0] == sum(10 + k % 20 for k in range(150))
    np.testing.assert_array_equal(ds.clip("clip_007")["positions"], walk[:17].positions().astype(np.float32))


# ----------------------------------------------------------------------------- reruns after a kill


def test_a_rerun_after_a_kill_before_partial_was_removed_keeps_the_arrays(clips, reference, tmp_path, monkeypatch):
    out = tmp_path / "ds"

    def killed(_out):
        raise KeyboardInterrupt  # the process dies after the manifest is in place

    monkeypatch.setattr(finish_module, "remove_partial", killed)
    with pytest.raises(KeyboardInterrupt):
        run(clips, out)
    monkeypatch.undo()
    assert (out / "manifest.json").exists() and (out / ".partial" / "journal.jsonl").exists()
    before = snapshot(out)
    again = run(clips, out)
    assert again.finished and (again.clips_ok, again.clips_failed, again.clips_resumed) == (4, 1, 5)
    finished = {k: v for k, v in before.items() if not k.startswith(".")}  # the arrays, offsets, manifest
    assert {k: v for k, v in snapshot(out).items() if not k.startswith(".")} == finished  # bytes and mtimes
    assert not (out / ".partial").exists()
    same_dataset(reference, out)


def test_a_rerun_after_a_kill_during_the_final_moves_finishes_them(clips, reference, tmp_path, monkeypatch):
    out = tmp_path / "ds"
    real_replace, moved = os.replace, []

    def replace(a, b):
        if Path(a).parent.name == ".partial" and Path(a).name.endswith(".npy") and Path(b).parent == out:
            if moved:
                raise KeyboardInterrupt  # killed after moving one file
            moved.append(a)
        return real_replace(a, b)

    monkeypatch.setattr(finish_module.os, "replace", replace)
    with pytest.raises(KeyboardInterrupt):
        run(clips, out)
    monkeypatch.undo()
    assert not (out / "manifest.json").exists() and (out / ".partial" / "manifest.json").exists()
    again = run(clips, out)
    assert again.finished and (again.clips_ok, again.clips_failed) == (4, 1)
    same_dataset(reference, out)


def test_resuming_with_the_source_spelled_otherwise_does_each_clip_once(clips, reference, tmp_path, monkeypatch):
    monkeypatch.chdir(clips.parent)
    out = tmp_path / "ds"
    first = run(Path("clips"), out, batch_mb=1e-6, max_batches=2)
    assert not first.finished
    link = tmp_path / "link"
    link.symlink_to(clips)
    second = run(link, out, batch_mb=1e-6)  # absolute, through a link
    assert second.finished and second.clips_resumed == 2 and second.clips_ok + second.clips_failed == 5
    same_dataset(reference, out)


def test_a_second_clip_of_the_same_name_is_a_failure(clips, tmp_path):
    src = tmp_path / "src"
    shutil.copytree(clips, src)
    shutil.copy(src / "walk_1.bvh", src / "walk_0.BVH")  # the same name, walk_0, in another case of .bvh
    out = tmp_path / "ds"
    summary = run(src, out, batch_mb=1e-6)
    ds = load_dataset(out)
    assert ds.names.count("walk_0") == 1 and summary.clips_ok == 4
    duplicate = [f for f in ds.failures if f["name"] == "walk_0"]
    assert len(duplicate) == 1 and "already in the dataset" in duplicate[0]["error"]
    # Resumed runs keep the same rule.
    resumed = tmp_path / "resumed"
    run(src, resumed, batch_mb=1e-6, max_batches=1)
    run(src, resumed, batch_mb=1e-6)
    same_dataset(out, resumed)


# ----------------------------------------------------------------------------- what OUT may hold


def test_overwrite_deletes_only_the_formats_own_files(clips, tmp_path):
    out = tmp_path / "ds"
    run(clips, out)
    victim = tmp_path / "victim.txt"
    victim.write_text("the user's")
    (out / "notes.txt").write_text("also the user's")
    manifest = json.loads((out / "manifest.json").read_text())
    manifest["kinds"]["positions"]["file"] = "../victim.txt"
    (out / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(DatasetError, match="names a file its format does not have"):
        run(clips, out, overwrite=True)
    with pytest.raises(DatasetError, match="names a file its format does not have"):
        load_dataset(out)
    assert victim.read_text() == "the user's" and (out / "positions.npy").exists()
    manifest["kinds"]["positions"]["file"] = "positions.npy"
    (out / "manifest.json").write_text(json.dumps(manifest))
    run(clips, out, keep="positions", overwrite=True)
    assert (out / "notes.txt").read_text() == "also the user's" and not (out / "features.npy").exists()
    assert list(load_dataset(out).arrays) == ["positions"]


def test_a_folder_with_the_users_files_is_refused(clips, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    np.save(out / "features.npy", np.arange(3.0))
    np.save(out / "offsets.npy", np.arange(2))
    before = snapshot(out)
    for overwrite in (False, True):
        with pytest.raises(DatasetError, match="not empty .* holds no dataset"):
            run(clips, out, overwrite=overwrite)
    assert snapshot(out) == before
    afile = tmp_path / "afile"
    afile.write_text("x")
    with pytest.raises(DatasetError, match="not a folder"):
        run(clips, afile)
    assert afile.read_text() == "x"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    linked = tmp_path / "linked"
    linked.mkdir()
    (linked / ".partial").symlink_to(elsewhere)
    with pytest.raises(DatasetError, match="not a folder of ours"):
        run(clips, linked)
    assert list(elsewhere.iterdir()) == []


# ----------------------------------------------------------------------------- load_dataset's checks


@pytest.mark.parametrize("damage", ["longer", "header", "offsets", "touched", "missing", "symlink"])
def test_load_dataset_refuses_files_the_manifest_does_not_vouch_for(clips, tmp_path, damage):
    out = tmp_path / "ds"
    run(clips, out)
    load_dataset(out)
    positions = out / "positions.npy"
    if damage == "longer":  # what two runs appending to one file left
        with open(positions, "ab") as handle:
            handle.write(b"\0" * 12 * 22)
        expected = "the manifest says"
    elif damage == "header":  # same size, another shape
        array = np.load(positions)
        stat = positions.stat()
        np.save(positions, array.reshape(-1, 11, 6))
        os.utime(positions, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        expected = "the manifest says float32"
    elif damage == "offsets":
        offsets = np.load(out / "offsets.npy")
        stat = (out / "offsets.npy").stat()
        np.save(out / "offsets.npy", offsets[::-1].copy())
        os.utime(out / "offsets.npy", ns=(stat.st_atime_ns, stat.st_mtime_ns))
        expected = "rows differ"
    elif damage == "touched":  # same bytes count, rewritten: the zeros of an old rerun
        stat = positions.stat()
        positions.write_bytes(positions.read_bytes()[:128] + b"\0" * (stat.st_size - 128))
        expected = "modified after the dataset was written"
    elif damage == "missing":
        (out / "features.npy").unlink()
        expected = "cannot be read"
    else:
        positions.rename(tmp_path / "elsewhere.npy")
        positions.symlink_to(tmp_path / "elsewhere.npy")
        expected = "not a regular file"
    with pytest.raises(DatasetError, match=expected):
        load_dataset(out)
    if damage == "touched":  # a copy that did not keep times can opt out of the time check only
        assert load_dataset(out, check_times=False).positions.shape[0] > 0


# ----------------------------------------------------------------------------- a full disk


def test_a_full_disk_names_the_file_and_the_run_resumes(clips, reference, tmp_path, monkeypatch):
    out = tmp_path / "ds"
    real_open = open
    calls = []

    class Full:
        def __init__(self, handle):
            self.handle = handle

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.handle.close()

        def write(self, data):
            raise OSError(errno.ENOSPC, "No space left on device")

    def full_after_one_batch(path, mode="r", *args, **kw):
        handle = real_open(path, mode, *args, **kw)
        if mode == "ab" and str(path).endswith(".npy"):
            calls.append(path)
            if len(calls) > 3:
                return Full(handle)
        return handle

    monkeypatch.setattr(npy_module, "open", full_after_one_batch, raising=False)
    with pytest.raises(DatasetError, match=r"cannot write .*\.partial/\w+\.npy: No space left on device \(rerun"):
        run(clips, out, batch_mb=1e-6)
    monkeypatch.undo()
    run(clips, out, batch_mb=1e-6)
    same_dataset(reference, out)


def test_a_failed_background_flush_stops_the_run(clips, tmp_path, monkeypatch):
    def fails(_handle):
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(os, "fdatasync", fails)
    with pytest.raises(DatasetError, match=r"cannot write .*\.npy: Input/output error"):
        run(clips, tmp_path / "ds", batch_mb=1e-6)
    assert not (tmp_path / "ds" / "manifest.json").exists()


def test_a_bad_source_leaves_the_output_folder_untouched(tmp_path):
    out = tmp_path / "ds"
    for _ in range(2):  # twice: a first failed run must not change what the second says
        with pytest.raises(ArgumentError, match="no such folder or archive"):
            run(tmp_path / "nothing", out)
    assert not out.exists()


def test_nothing_read_is_a_failure_of_the_command(tmp_path, capsys):
    from expressive_mocap.cli import main

    empty = tmp_path / "empty"
    empty.mkdir()
    assert main(["preprocess", str(empty), "-o", str(tmp_path / "a"), "-q"]) == 1
    assert "holds no .bvh clips" in capsys.readouterr().err
    broken = tmp_path / "broken"
    broken.mkdir()
    for k in range(3):
        (broken / f"b{k}.bvh").write_bytes(BROKEN)
    assert main(["preprocess", str(broken), "-o", str(tmp_path / "b"), "-q"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "none of its 3 clips could be read" in err


def test_clips_of_the_same_skeleton_in_other_units_are_failures(clips, tmp_path):
    src = tmp_path / "src"
    shutil.copytree(clips, src)
    walk = em.read_bvh(src / "walk_2.bvh")
    em.write_bvh(walk.scaled(0.01), src / "walk_2_metres.bvh")  # the same walk in metres
    em.write_bvh(walk.scaled(1 / 2.54), src / "walk_2_inches.bvh")
    em.write_bvh(walk.scaled(1.3), src / "walk_2_taller.bvh")  # a taller actor: the same units
    ds = load_dataset(run(src, tmp_path / "ds").out)
    errors = {f["name"]: f["error"] for f in ds.failures}
    assert "other units?" in errors["walk_2_metres"] and "0.01x as long" in errors["walk_2_metres"]
    assert "0.394x as long" in errors["walk_2_inches"]
    assert "walk_2_taller" in ds.names and "walk_2" in ds.names


def test_a_partial_folder_without_its_run_file(clips, reference, tmp_path):
    out = tmp_path / "ds"
    (out / ".partial").mkdir(parents=True)
    (out / ".partial" / ".run.json.abc.tmp").write_text("{")  # killed while writing run.json
    run(clips, out)  # ours: the run starts there
    same_dataset(reference, out)
    other = tmp_path / "other"
    (other / ".partial").mkdir(parents=True)
    (other / ".partial" / "notes.txt").write_text("mine")
    with pytest.raises(DatasetError, match="not an unfinished run of ours"):
        run(clips, other)
    assert (other / ".partial" / "notes.txt").read_text() == "mine"


def test_a_manifest_nested_past_the_stack_is_refused_and_overwrite_keeps_the_folder(clips, tmp_path, capsys):
    """A manifest of 100,000 nested lists: load_dataset and `preprocess --overwrite` say in one line
    that it is not a readable manifest (a RecursionError before), and nothing is deleted."""
    from expressive_mocap.cli import main

    out = tmp_path / "out"
    preprocess(clips, out, progress=False)
    (out / "manifest.json").write_text('{"format": ' + "[" * 100_000 + "]" * 100_000 + "}")
    before = sorted(p.name for p in out.iterdir())
    with pytest.raises(DatasetError, match="not a readable dataset manifest"):
        load_dataset(out)
    assert main(["preprocess", str(clips), "-o", str(out), "--overwrite", "-q"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a readable dataset manifest" in err[0]
    assert sorted(p.name for p in out.iterdir()) == before


def test_a_dataset_redone_while_it_is_read_is_one_error(reference, tmp_path, monkeypatch):
    """`--overwrite` deleting the files between load_dataset's checks and its reads: a DatasetError
    saying so (a bare FileNotFoundError before)."""
    import expressive_mocap.dataset.reader as reader_module

    copy = tmp_path / "ds"
    shutil.copytree(reference, copy)
    checked = reader_module.verify

    def then_deleted(folder, manifest, check_times):
        checked(folder, manifest, check_times)
        (folder / "positions.npy").unlink()

    monkeypatch.setattr(reader_module, "verify", then_deleted)
    with pytest.raises(DatasetError, match="its files changed while it was read .*another run redoing it"):
        load_dataset(copy, check_times=False)


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"length": 10**7, "padding": "edge"}, "windows of 10,000,000 frames takes"),
        ({"length": 10**8, "padding": "edge", "batch_size": 1}, "1 windows of 100,000,000 frames takes"),
        ({"length": 30, "batch_size": 2.5}, "argument `batch_size`: a positive whole number of windows, got 2.5"),
        ({"length": 30, "batch_size": True}, "got True"),
    ],
)
def test_batches_that_cannot_be_made_are_refused_up_front(reference, options, words):
    """A padded window far longer than any clip took 2.6 GB a window and ended in a raw
    MemoryError; batch_size=2.5 in a raw TypeError."""
    from expressive_mocap.dataset import window_batches

    with pytest.raises(ArgumentError, match=words):
        window_batches(load_dataset(reference), **options)
