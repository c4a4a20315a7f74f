"""The input side of ``preprocess`` never hangs, crashes or reads unboundedly: a FIFO, a device,
a socket or a link to /dev/zero among the clips, an encrypted or damaged archive member, or a
file or member larger than ``io.MAX_INPUT_BYTES`` is that clip's failure (checked before
reading), the run goes on, and Ctrl-C stops a run promptly and leaves it resumable."""

from __future__ import annotations

import dataclasses
import errno
import os
import signal
import socket
import subprocess
import sys
import tarfile
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
import expressive_mocap.dataset.sources as sources_module
import expressive_mocap.dataset.work as work_module
from conftest import returns_within
from expressive_mocap import ops
from expressive_mocap._utils import files as em_io
from expressive_mocap.cli import main
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.procedural import procedural_walk
from pipeline_inputs import GAIT, pipeline_input

POSITIONS = ops.PipelineOutputs(positions=True)

NOT_REGULAR = "not a regular file: only regular files are read"


@pytest.fixture(scope="module")
def walk() -> bytes:
    return em.bvh_bytes(procedural_walk(seconds=1.0))


def make_fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def release(fifo: Path) -> None:
    """Let a reader that did block on ``fifo`` (a failing test) go: open its write end without waiting."""
    try:
        os.close(os.open(fifo, os.O_WRONLY | os.O_NONBLOCK))
    except OSError:
        pass


def run(src, out, **kw):
    kw.setdefault("progress", False)
    return preprocess(src, out, **kw)


def failures(out: Path) -> dict[str, str]:
    return {f["name"]: f["error"] for f in load_dataset(out).failures}


# ----------------------------------------------------------------------------- the kernel's own read


def test_the_kernel_reads_only_regular_files_within_its_bound(walk, tmp_path, backend):
    clip, parents, joints = pipeline_input(walk, walk)
    good = tmp_path / "good.bvh"
    good.write_bytes(walk)
    fifo = make_fifo(tmp_path / "pipe.bvh")
    zero = tmp_path / "zero.bvh"
    zero.symlink_to("/dev/zero")
    paths = [good, fifo, zero, tmp_path]
    try:
        results = returns_within(
            10,
            lambda: ops.clip_pipeline_many(
                [dataclasses.replace(clip, source=str(p)) for p in paths],
                parents,
                joints,
                GAIT,
                POSITIONS,
                max_bytes=len(walk),
            ),
        )
    finally:
        release(fifo)
    assert isinstance(results[0], tuple)
    for result, kind, code in zip(
        results[1:], ("a FIFO", "a character device", "a folder"), (errno.EINVAL, errno.EINVAL, errno.EISDIR)
    ):
        assert isinstance(result, OSError) and (result.errno, result.strerror) == (code, f"{kind}, {NOT_REGULAR}")
    # One byte under the file's size: refused before reading, with io.open_input's words.
    (small,) = ops.clip_pipeline_many(
        [dataclasses.replace(clip, source=str(good))], parents, joints, GAIT, POSITIONS, max_bytes=len(walk) - 1
    )
    assert isinstance(small, OSError) and small.errno == errno.EFBIG
    assert small.strerror == f"{len(walk):,} bytes, more than the {len(walk) - 1:,} bytes read at most"
    # Without max_bytes, the package's bound.
    with open(good, "r+b") as handle:  # sparse: no disk space taken
        handle.truncate(em_io.MAX_INPUT_BYTES + 1)
    (big,) = ops.clip_pipeline_many([dataclasses.replace(clip, source=str(good))], parents, joints, GAIT, POSITIONS)
    assert isinstance(big, OSError) and "more than the 536,870,912 bytes read at most" in big.strerror


def test_a_file_swapped_for_a_fifo_after_its_header_was_read_fails_alone(walk, tmp_path, backend):
    # The header thread reads the file's beginning, the kernel reads the file again: swapped in
    # between for a FIFO, the kernel's read must not wait for a writer.
    for name in ("a", "b"):
        (tmp_path / f"{name}.bvh").write_bytes(walk)
    batch = sources_module.open_source(tmp_path).items
    keep = ("positions", "contacts")
    prepared = work_module.prepare(batch, keep, None)
    (tmp_path / "b.bvh").unlink()
    fifo = make_fifo(tmp_path / "b.bvh")
    try:
        outcomes, _, _ = returns_within(10, lambda: work_module.run_kernels(batch, prepared, keep, None, False))
    finally:
        release(fifo)
    assert outcomes[0].error is None and outcomes[0].frames == em.read_bvh(tmp_path / "a.bvh").n_frames
    assert outcomes[1].error == f"{fifo}: cannot read the file: a FIFO, {NOT_REGULAR}"


# ----------------------------------------------------------------------------- folders and globs


@pytest.fixture
def hostile_folder(tmp_path, walk):
    """A folder of one good clip among a FIFO, a /dev/zero link, a socket and a dangling link, all named *.bvh."""
    folder = tmp_path / "clips"
    folder.mkdir()
    (folder / "good.bvh").write_bytes(walk)
    fifo = make_fifo(folder / "pipe.bvh")
    (folder / "zero.bvh").symlink_to("/dev/zero")
    (folder / "gone.bvh").symlink_to(folder / "nowhere.bvh")
    server = socket.socket(socket.AF_UNIX)
    server.bind(str(folder / "sock.bvh"))
    yield folder
    server.close()
    release(fifo)


@pytest.mark.parametrize("pattern", [False, True], ids=["folder", "glob"])
def test_only_regular_files_are_read_from_a_folder_or_glob(hostile_folder, pattern, tmp_path, walk, backend):
    src = str(hostile_folder / "*.bvh") if pattern else hostile_folder
    summary = returns_within(30, lambda: run(src, tmp_path / "ds"))
    assert summary.finished and summary.clips_ok == 1 and load_dataset(tmp_path / "ds").names == ["good"]
    found = failures(tmp_path / "ds")
    assert sorted(found) == ["gone", "pipe", "sock", "zero"]
    for name, kind in (("pipe", "a FIFO"), ("zero", "a character device"), ("sock", "a socket")):
        assert found[name] == f"{hostile_folder / name}.bvh: cannot read the file: {kind}, {NOT_REGULAR}"
    assert found["gone"] == f"{hostile_folder / 'gone'}.bvh: cannot read the file: {os.strerror(errno.ENOENT)}"
    assert summary.bytes_read == len(walk)  # the good clip alone was read


def test_listing_a_folder_opens_nothing(hostile_folder, monkeypatch):
    # A stat per file, never an open: a FIFO opened to be listed would block.
    def no_open(*args, **kwargs):
        raise AssertionError("a file was opened while listing")

    monkeypatch.setattr(os, "open", no_open)
    items = {item.name: item.size for item in sources_module._folder(hostile_folder)}
    assert items == {"gone": 0, "good": (hostile_folder / "good.bvh").stat().st_size, "pipe": 0, "sock": 0, "zero": 0}


# ----------------------------------------------------------------------------- archives


def _central_entry(data: bytes, name: str) -> int:
    """Where the zip's central directory entry of ``name`` starts."""
    at = data.index(b"PK\x01\x02")
    while True:
        length = int.from_bytes(data[at + 28 : at + 30], "little")
        if data[at + 46 : at + 46 + length] == name.encode():
            return at
        at = data.index(b"PK\x01\x02", at + 46)


def patch_zip(
    path: Path, name: str, flags: int = 0, method: int | None = None, size: int | None = None, flip: bool = False
) -> None:
    """Damage member ``name`` in place: set flag bits, the compression method or the declared
    size (in both its local and central headers), or flip its first data byte."""
    data = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as archive:
        local = archive.getinfo(name).header_offset
    central = _central_entry(data, name)
    for at, flag_at, method_at, size_at in ((local, 6, 8, 22), (central, 8, 10, 24)):
        data[at + flag_at] |= flags
        if method is not None:
            data[at + method_at : at + method_at + 2] = method.to_bytes(2, "little")
        if size is not None:
            data[at + size_at : at + size_at + 4] = size.to_bytes(4, "little")
    if flip:
        start = (
            local
            + 30
            + int.from_bytes(data[local + 26 : local + 28], "little")
            + int.from_bytes(data[local + 28 : local + 30], "little")
        )
        data[start] ^= 0xFF
    path.write_bytes(bytes(data))


def member_zip(path: Path, walk: bytes, names, compression=zipfile.ZIP_DEFLATED) -> Path:
    with zipfile.ZipFile(path, "w", compression) as archive:
        for name in names:
            archive.writestr(name, walk)
    return path


def test_a_damaged_or_encrypted_zip_member_fails_alone(walk, tmp_path, backend):
    path = member_zip(tmp_path / "clips.zip", walk, ["good.bvh", "secret.bvh", "method.bvh"])
    member_zip(tmp_path / "stored.zip", walk, ["crc.bvh"], zipfile.ZIP_STORED)
    patch_zip(path, "secret.bvh", flags=0x1)
    patch_zip(path, "method.bvh", method=99)
    summary = run(path, tmp_path / "ds")
    assert summary.finished and load_dataset(tmp_path / "ds").names == ["good"]
    assert failures(tmp_path / "ds") == {
        "method": f"{path}:method.bvh: cannot read the archive member: That compression method is not supported",
        "secret": f"{path}:secret.bvh: cannot read the archive member: encrypted: members are read without a password",
    }
    stored = tmp_path / "stored.zip"
    patch_zip(stored, "crc.bvh", flip=True)
    run(stored, tmp_path / "crc")
    assert failures(tmp_path / "crc") == {
        "crc": f"{stored}:crc.bvh: cannot read the archive member: Bad CRC-32 for file 'crc.bvh'"
    }


def test_a_zip_member_declared_over_the_real_bound_is_refused_unread(walk, tmp_path):
    # The declared size alone decides: this member's real bytes are a good clip.
    path = member_zip(tmp_path / "clips.zip", walk, ["good.bvh", "claims.bvh"])
    patch_zip(path, "claims.bvh", size=em_io.MAX_INPUT_BYTES + 1)
    summary = run(path, tmp_path / "ds")
    assert summary.finished and load_dataset(tmp_path / "ds").names == ["good"]
    assert failures(tmp_path / "ds") == {
        "claims": (
            f"{path}:claims.bvh: cannot read the archive member: "
            "536,870,913 bytes, more than the 536,870,912 bytes read at most"
        )
    }
    assert summary.bytes_read == len(walk)  # not the 537 MB claimed: what was read


@pytest.fixture
def small_bound(monkeypatch):
    """io.MAX_INPUT_BYTES at 1 MiB: members over the bound cost little to make."""
    monkeypatch.setattr(em_io, "MAX_INPUT_BYTES", 1 << 20)
    return 1 << 20


def test_zip_members_over_the_bound_are_not_decompressed(walk, tmp_path, small_bound):
    import tracemalloc

    path = tmp_path / "bomb.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("good.bvh", walk)
        archive.writestr("over.bvh", walk + b" " * (small_bound + 1 - len(walk)))  # one byte over
        archive.writestr("huge.bvh", bytes(64 << 20))  # 64 MiB of zeros in 64 KB
        archive.writestr("lies.bvh", bytes(64 << 20))
    patch_zip(path, "lies.bvh", size=small_bound)  # declares the bound, holds 64 MiB
    assert path.stat().st_size < 1 << 20
    # Listed for batching and the progress bar: a member refused unread counts 0, not its claim.
    listed = {item.name: item.size for item in sources_module.open_source(path).items}
    assert listed == {"good": len(walk), "huge": 0, "lies": small_bound, "over": 0}
    tracemalloc.start()
    try:
        summary = run(path, tmp_path / "ds")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    found = failures(tmp_path / "ds")
    assert (
        summary.finished
        and load_dataset(tmp_path / "ds").names == ["good"]
        and sorted(found) == ["huge", "lies", "over"]
    )
    assert found["over"].endswith(f"{small_bound + 1:,} bytes, more than the {small_bound:,} bytes read at most")
    assert found["huge"].endswith(f"{64 << 20:,} bytes, more than the {small_bound:,} bytes read at most")
    assert found["lies"] == f"{path}:lies.bvh: cannot read the archive member: Bad CRC-32 for file 'lies.bvh'"
    # Never more than a member of the bound held (before: the 64 MiB members were read whole).
    assert peak < 16 << 20, f"peak {peak / 1e6:.1f} MB"
    assert summary.bytes_read == len(walk)  # not the 129 MB declared


def test_tar_members_over_the_bound_or_not_regular_fail_alone(walk, tmp_path, small_bound):
    folder = tmp_path / "clips"
    folder.mkdir()
    (folder / "good.bvh").write_bytes(walk)
    (folder / "over.bvh").write_bytes(walk + b" " * (small_bound + 1 - len(walk)))
    (folder / "link.bvh").symlink_to("/dev/zero")
    fifo = make_fifo(folder / "pipe.bvh")
    path = tmp_path / "clips.tar.gz"
    with tarfile.open(path, "w:gz") as archive:
        for name in ("good.bvh", "over.bvh", "link.bvh", "pipe.bvh"):
            archive.add(folder / name, name)
    release(fifo)
    summary = run(path, tmp_path / "ds")
    assert summary.finished and load_dataset(tmp_path / "ds").names == ["good"]
    member = "cannot read the archive member"
    assert failures(tmp_path / "ds") == {
        "over": (
            f"{path}:over.bvh: {member}: {small_bound + 1:,} bytes, more than the {small_bound:,} bytes read at most"
        ),
        "link": f"{path}:link.bvh: {member}: a symbolic link, {NOT_REGULAR}",
        "pipe": f"{path}:pipe.bvh: {member}: a FIFO, {NOT_REGULAR}",
    }
    assert summary.bytes_read == len(walk)


def test_an_unreadable_zip_directory_or_a_fifo_source_is_a_one_line_error(walk, tmp_path, capsys):
    path = member_zip(tmp_path / "clips.zip", walk, ["a.bvh", "b.bvh"])
    data = bytearray(path.read_bytes())
    data[_central_entry(data, "b.bvh") + 1] = 0  # the central directory's second entry, damaged
    path.write_bytes(bytes(data))
    fifo = make_fifo(tmp_path / "pipe.bvh")
    try:
        for src, message in (
            (path, f"{path}: cannot read the zip archive (BadZipFile: Bad magic number for central directory)"),
            (fifo, f"{fifo}: a FIFO, not a folder, .zip or .tar(.gz/.xz) archive of BVH files"),
        ):
            code = returns_within(
                20, lambda src=src: main(["preprocess", str(src), "-o", str(tmp_path / f"{src.name}.out"), "-q"])
            )
            assert (code, capsys.readouterr().err) == (1, f"expressive-mocap: error: {message}\n")
    finally:
        release(fifo)


# ----------------------------------------------------------------------------- Ctrl-C


def _start(args: list[str], cwd: Path) -> subprocess.Popen:
    """A child Python taking SIGINT as a terminal's Ctrl-C (default handling restored: a shell's
    background job would inherit it ignored)."""
    env = dict(os.environ, PYTHONPATH=str(Path(em.__file__).parent.parent))
    return subprocess.Popen(
        [sys.executable, *args],
        cwd=cwd,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )


def _wait_for(condition, seconds: float, what: str) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, f"no {what} after {seconds} s"
        time.sleep(0.01)


def _interrupt(process: subprocess.Popen, seconds: float = 5.0) -> str:
    """Send Ctrl-C; the child must exit within ``seconds`` with status 130 and no traceback. Its stderr."""
    process.send_signal(signal.SIGINT)
    try:
        _, err = process.communicate(timeout=seconds)
    except subprocess.TimeoutExpired:
        process.kill()
        process.communicate()
        pytest.fail(f"still running {seconds} s after Ctrl-C")
    err = err.decode()
    assert (
        process.returncode == 130 and "Traceback" not in err and err.strip().endswith("expressive-mocap: interrupted")
    ), err
    return err


def test_ctrl_c_stops_a_real_run_promptly_and_the_rerun_completes_it(bandai2_dir, tmp_path):
    clips = tmp_path / "clips"
    clips.mkdir()
    # All of dataset-2 (515 MB, about 65 batches of 8 MB): the run must still be going when the
    # Ctrl-C lands. With 900 clips (20 batches), runs became fast enough to finish first now and then.
    for path in sorted(bandai2_dir.glob("*.bvh")):
        (clips / path.name).symlink_to(path)
    reference = run(clips, tmp_path / "reference", batch_mb=8)
    out = tmp_path / "ds"
    command = ["-m", "expressive_mocap.cli", "preprocess", str(clips), "-o", str(out), "--batch-mb", "8", "-q"]
    journal = out / ".partial" / "journal.jsonl"
    process = _start(command, tmp_path)
    _wait_for(lambda: journal.exists() and journal.read_bytes().count(b"\n") >= 2, 60, "second journal line")
    _interrupt(process)
    assert not (out / "manifest.json").exists() and 2 <= journal.read_bytes().count(b"\n") < reference.batches

    process = _start(command, tmp_path)
    _, err = process.communicate(timeout=300)
    assert process.returncode == 0, err.decode()
    ds, expected = load_dataset(out), load_dataset(tmp_path / "reference")
    assert ds.names == expected.names and len(ds) == len(list(clips.iterdir())) and not ds.failures
    np.testing.assert_array_equal(ds.offsets, expected.offsets)
    assert set(ds.arrays) == set(expected.arrays)
    for kind in expected.arrays:
        np.testing.assert_array_equal(ds.arrays[kind], expected[kind])


def test_a_blocked_thread_does_not_keep_an_interrupted_run_alive(walk, tmp_path):
    # The second batch's header read never returns (as a FIFO's open did): Ctrl-C must still end
    # the process (a ThreadPoolExecutor would wait for it, then join its thread at exit).
    clips = tmp_path / "clips"
    clips.mkdir()
    for number in range(12):
        (clips / f"walk_{number:02d}.bvh").write_bytes(walk)
    marker = tmp_path / "blocked"
    script = f"""
import sys, threading
import expressive_mocap.dataset.work as p
from expressive_mocap.cli import main
prepare, calls = p.prepare, []
def blocking(*args):
    calls.append(1)
    if len(calls) == 2:
        open({str(marker)!r}, "w").close()
        threading.Event().wait()
    return prepare(*args)
p.prepare = blocking
sys.exit(main(["preprocess", {str(clips)!r}, "-o", {str(tmp_path / "ds")!r}, "--batch-mb", "0.1", "-q"]))
"""
    process = _start(["-c", script], tmp_path)
    _wait_for(marker.exists, 60, "blocked header read")
    _interrupt(process)


def test_a_stuck_background_flush_does_not_keep_an_interrupted_run_alive(walk, tmp_path):
    # The thread that syncs finished rows to disk never returns (a Ctrl-C that lands while the
    # main thread holds its task's lock left it so): the process must still end on Ctrl-C (a
    # ThreadPoolExecutor's worker is joined at interpreter exit, for ever).
    clips = tmp_path / "clips"
    clips.mkdir()
    for number in range(12):
        (clips / f"walk_{number:02d}.bvh").write_bytes(walk)
    marker = tmp_path / "flushing"
    script = f"""
import sys, threading
import expressive_mocap.dataset.run as run
from expressive_mocap.cli import main
def stuck(paths):
    open({str(marker)!r}, "w").close()
    threading.Event().wait()
run.flush = stuck
sys.exit(main(["preprocess", {str(clips)!r}, "-o", {str(tmp_path / "ds")!r}, "--batch-mb", "0.1", "-q"]))
"""
    process = _start(["-c", script], tmp_path)
    _wait_for(marker.exists, 60, "background flush")
    _interrupt(process)
