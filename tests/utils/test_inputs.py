"""Every input the package opens is a regular file of a bounded size, checked before reading:
a FIFO, a device or a folder in place of a BVH or a model file is a one-line error, never a hang
or a read until memory runs out, and so is a file larger than the stated bound."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import expressive_mocap as em
from conftest import returns_within
from expressive_mocap._utils import files as em_io
from expressive_mocap.bvh import read_header
from expressive_mocap.cli import main
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.errors import MocapError


@pytest.fixture
def fifo(tmp_path) -> Path:
    path = tmp_path / "pipe.bvh"
    os.mkfifo(path)
    yield path
    # Let a reader that did block (a failing test) go: open the write end without waiting.
    try:
        os.close(os.open(path, os.O_WRONLY | os.O_NONBLOCK))
    except OSError:
        pass


@pytest.fixture
def zero_link(tmp_path) -> Path:
    path = tmp_path / "zero.bvh"
    path.symlink_to("/dev/zero")
    return path


@pytest.mark.parametrize("reader", [em.read_bvh, read_header], ids=["read_bvh", "read_header"])
def test_bvh_reader_refuses_fifo_and_devices(reader, fifo, zero_link, tmp_path):
    for path, kind in ((fifo, "a FIFO"), (zero_link, "a character device"), (tmp_path, "a folder")):
        with pytest.raises(em.BVHError, match=f"{kind}, not a regular file"):
            returns_within(10, lambda path=path: reader(path))


@pytest.mark.parametrize("reader", [em.read_bvh, read_header], ids=["read_bvh", "read_header"])
def test_bvh_reader_refuses_files_over_the_bound_before_reading(reader, tmp_path, monkeypatch):
    path = tmp_path / "big.bvh"
    with open(path, "wb") as handle:  # sparse: no disk space taken
        handle.truncate(em_io.MAX_INPUT_BYTES + 1)
    with pytest.raises(em.BVHError, match=r"big.bvh: .*more than the 536,870,912 bytes read at most"):
        reader(path)


def test_model_loaders_refuse_fifo_and_devices(fifo, zero_link):
    from expressive_mocap.exaggeration import ExaggerationModel

    for path in (fifo, zero_link):
        for load in (BodyModel.load, ExaggerationModel.load):
            with pytest.raises(MocapError, match="not a regular file"):
                returns_within(10, lambda load=load, path=path: load(path))


def test_cli_model_fifo_is_one_line_error(fifo, mixed_path, tmp_path, capsys):
    code = returns_within(
        20, lambda: main(["decouple", str(mixed_path), "--model", str(fifo), "-o", str(tmp_path / "out")])
    )
    assert code == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "a FIFO, not a regular file" in err and str(fifo) in err


def test_reading_a_small_file_reserves_its_size_not_the_bound(tmp_path):
    import tracemalloc

    path = tmp_path / "small.bvh"
    path.write_bytes(b"x" * 1000)
    tracemalloc.start()
    try:
        assert len(em_io.read_input(path)) == 1000
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20  # read(bound + 1) reserved the whole 512 MiB bound
