"""No output destroys or silently corrupts a file that is not ours to replace: a device, FIFO,
socket or folder at the destination (or behind a symlink) is refused before any work and left as
it was; ``-`` and ``/dev/stdout`` stream to standard output; a symlink to a regular file is
written through; every write error names the path; nothing non-finite is written; resampling
is bounded before it allocates. Device nodes are made in tmp_path (a copy of /dev/null), so a
regression could never replace the machine's own /dev/null."""

from __future__ import annotations

import errno
import io
import os
import socket
import stat
from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap import io as em_io
from expressive_mocap.cli import main
from expressive_mocap.demo import walk_and_wave
from expressive_mocap.errors import MocapError

needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="making a device node (mknod) needs root")


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    path = tmp_path_factory.mktemp("walk") / "walk.bvh"
    em.write_bvh(walk_and_wave(seconds=1.0).walk, path)
    return path


def make(kind: str, path: Path) -> tuple[int, int]:
    """A non-regular file of ``kind`` at ``path``; its (file type, device) to check it survives."""
    if kind == "character device":
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))  # what /dev/null is
    elif kind == "FIFO":
        os.mkfifo(path)
    elif kind == "socket":
        os.chdir(path.parent)  # AF_UNIX paths are short: bind the relative name
        server = socket.socket(socket.AF_UNIX)
        server.bind(path.name)
        server.close()  # the socket file stays
    elif kind == "folder":
        path.mkdir()
    elif kind == "symlink to a character device":
        make("character device", path.with_name("device"))
        path.symlink_to("device")
    info = os.stat(path)
    return stat.S_IFMT(info.st_mode), info.st_rdev


KINDS = [pytest.param("character device", marks=needs_root), "FIFO", "socket", "folder", pytest.param("symlink to a character device", marks=needs_root)]


@pytest.mark.parametrize("kind", KINDS)
def test_write_bvh_refuses_a_destination_that_is_not_a_regular_file_and_leaves_it_be(kind, walk, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    destination = tmp_path / "out.bvh"
    before = make(kind, destination)
    with pytest.raises(MocapError) as error:
        em.write_bvh(em.read_bvh(walk), destination)
    message = str(error.value)
    assert message.startswith(f"cannot write {destination}: it is a") and kind.split()[-1] in message and "\n" not in message
    info = os.stat(destination)
    assert (stat.S_IFMT(info.st_mode), info.st_rdev) == before, "the destination was replaced"
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


@needs_root
@pytest.mark.parametrize("argv", [["convert", "{walk}", "-o", "{out}"], ["positions", "{walk}", "-o", "{out}"], ["convert", "{walk}", "--fps", "60", "-o", "{out}"]])
def test_the_cli_never_replaces_a_device_node(argv, walk, tmp_path, capsys):
    device = tmp_path / "null"
    before = make("character device", device)
    status = main([a.format(walk=walk, out=device) for a in argv])
    err = capsys.readouterr().err
    assert status == 1 and err == f"expressive-mocap: error: cannot write {device}: it is a character device, not a regular file " \
        "(outputs replace regular files only; '-' writes to standard output)\n"
    info = os.stat(device)
    assert (stat.S_IFMT(info.st_mode), info.st_rdev) == before


@pytest.mark.parametrize("command", ["convert", "positions"])
def test_the_real_dev_null_stays_a_character_device(command, walk, capsys):
    # Run only once the copies above pass: the check refuses before anything is written.
    assert main([command, str(walk), "-o", "/dev/null"]) == 1
    assert "it is a character device" in capsys.readouterr().err
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode) and os.stat("/dev/null").st_rdev == os.makedev(1, 3)


def test_a_fifo_destination_does_not_block(walk, tmp_path):
    # Opening a FIFO to write would wait for a reader for ever; it is refused from its lstat.
    fifo = tmp_path / "pipe.bvh"
    os.mkfifo(fifo)
    with pytest.raises(MocapError, match="it is a FIFO"):
        em_io.atomic_write(fifo, b"data")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


@pytest.mark.parametrize("name", ["-", "/dev/stdout"])
def test_dash_and_dev_stdout_stream_the_bvh_and_reports_go_to_stderr(name, walk, tmp_path, capfdbinary, monkeypatch):
    monkeypatch.chdir(tmp_path)  # were "-" taken for a file name, it would land here
    assert main(["convert", str(walk), "--fps", "60", "-o", str(tmp_path / "file.bvh")]) == 0
    capfdbinary.readouterr()
    link = os.lstat("/dev/stdout")
    assert main(["convert", str(walk), "--fps", "60", "-o", name]) == 0
    out, err = capfdbinary.readouterr()
    assert out == (tmp_path / "file.bvh").read_bytes()  # the data alone, byte for byte
    assert err.startswith(f"wrote {name}: ".encode())
    assert os.lstat("/dev/stdout").st_ino == link.st_ino, "/dev/stdout was replaced"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.bvh"]


def test_positions_stream_an_npz(walk, tmp_path, capfdbinary, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["positions", str(walk), "-o", "-"]) == 0
    out, _ = capfdbinary.readouterr()
    with np.load(io.BytesIO(out)) as arrays:
        assert arrays["positions"].shape == (em.read_bvh(walk).n_frames, 22, 3)


@pytest.mark.parametrize("argv", [["render", "{walk}", "-o", "-"], ["decouple", "{walk}", "-o", "-"], ["footsteps", "{walk}", "--plot", "-"],
                                  ["demo", "-o", "-"], ["render", "{walk}", "-o", "/dev/stdout"]])
def test_commands_that_cannot_stream_refuse_standard_output(argv, walk, tmp_path, capfd, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status = main([a.format(walk=walk) for a in argv])
    out, err = capfd.readouterr()
    assert status == 1 and out == "" and err.count("\n") == 1 and "does not write to standard output" in err, err
    assert list(tmp_path.iterdir()) == []  # no file called "-" or "-_body.bvh" either


def test_a_symlink_to_a_regular_file_is_written_through(walk, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    target = elsewhere / "take.bvh"
    target.write_text("old")
    link = tmp_path / "latest.bvh"
    link.symlink_to(target)
    assert main(["convert", str(walk), "--scale", "2", "-o", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(target), "the link was replaced"
    assert em.read_bvh(target).skeleton.offsets == pytest.approx(2 * em.read_bvh(walk).skeleton.offsets)
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["elsewhere", "latest.bvh", "take.bvh"]  # no temporary left


@pytest.mark.parametrize("link_to", ["missing.bvh", "itself"])
def test_a_broken_symlink_is_refused(link_to, walk, tmp_path):
    link = tmp_path / "out.bvh"
    link.symlink_to(link if link_to == "itself" else tmp_path / link_to)
    with pytest.raises(MocapError, match="does not exist" if link_to == "missing.bvh" else "leads back to itself"):
        em.write_bvh(em.read_bvh(walk), link)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bvh"] and link.is_symlink()


class _FullDisk:
    """A file whose write stops halfway with ENOSPC, as a full disk does."""

    def __init__(self, handle):
        self.handle = handle

    def write(self, data):
        self.handle.write(data[: len(data) // 2])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.handle.close()


def test_a_full_disk_names_the_file_removes_the_temporary_and_keeps_the_old_file(walk, tmp_path, monkeypatch):
    destination = tmp_path / "out.bvh"
    destination.write_bytes(b"the user's file")
    motion, real_fdopen = em.read_bvh(walk), os.fdopen
    monkeypatch.setattr(em_io.os, "fdopen", lambda fd, mode: _FullDisk(real_fdopen(fd, mode)))
    with pytest.raises(MocapError) as error:
        em.write_bvh(motion, destination)
    assert str(error.value) == f"cannot write {destination}: No space left on device"
    assert [p.name for p in tmp_path.iterdir()] == ["out.bvh"] and destination.read_bytes() == b"the user's file"


def test_a_failed_rename_names_the_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    def failing_replace(source, target):
        raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))

    monkeypatch.setattr(em_io.os, "replace", failing_replace)
    with pytest.raises(MocapError, match=f"^cannot write {tmp_path / 'a.csv'}: Invalid cross-device link$"):
        em_io.atomic_write_all({tmp_path / "a.csv": b"1", tmp_path / "b.csv": b"2"})
    assert list(tmp_path.iterdir()) == []


def test_a_full_standard_output_is_named(monkeypatch):
    monkeypatch.setattr(em_io.os, "write", lambda fd, data: (_ for _ in ()).throw(OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))))
    with pytest.raises(MocapError, match="^cannot write to standard output: No space left on device$"):
        em_io.atomic_write("-", b"data")
