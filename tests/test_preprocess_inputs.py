"""The input side of ``preprocess`` never hangs, crashes or reads unboundedly: a FIFO, a device,
a socket or a link to /dev/zero among the clips, an encrypted or damaged archive member, or a
file or member larger than ``io.MAX_INPUT_BYTES`` is that clip's failure (checked before
reading), the run goes on, and Ctrl-C stops a run promptly and leaves it resumable."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

import expressive_mocap as em
import expressive_mocap.preprocess as preprocess_module
from expressive_mocap import io as em_io
from expressive_mocap.backend import kernels
from expressive_mocap.demo import procedural_walk
from expressive_mocap.preprocess import load_dataset, preprocess

from test_clip_pipeline import GAIT, pipeline_input
from test_inputs import _returns_within

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
        results = _returns_within(10, lambda: kernels().clip_pipeline_many(
            [(str(p), *clip[1:]) for p in paths], parents, joints, *GAIT, True, False, [], False, False, max_bytes=len(walk)))
    finally:
        release(fifo)
    assert isinstance(results[0], tuple)
    for result, kind, code in zip(results[1:], ("a FIFO", "a character device", "a folder"), (errno.EINVAL, errno.EINVAL, errno.EISDIR)):
        assert isinstance(result, OSError) and (result.errno, result.strerror) == (code, f"{kind}, {NOT_REGULAR}")
    # One byte under the file's size: refused before reading, with io.open_input's words.
    (small,) = kernels().clip_pipeline_many([(str(good), *clip[1:])], parents, joints, *GAIT, True, False, [], False, False,
                                            max_bytes=len(walk) - 1)
    assert isinstance(small, OSError) and small.errno == errno.EFBIG
    assert small.strerror == f"{len(walk):,} bytes, more than the {len(walk) - 1:,} bytes read at most"
    # Without max_bytes, the package's bound.
    with open(good, "r+b") as handle:  # sparse: no disk space taken
        handle.truncate(em_io.MAX_INPUT_BYTES + 1)
    (big,) = kernels().clip_pipeline_many([(str(good), *clip[1:])], parents, joints, *GAIT, True, False, [], False, False)
    assert isinstance(big, OSError) and "more than the 536,870,912 bytes read at most" in big.strerror


def test_a_file_swapped_for_a_fifo_after_its_header_was_read_fails_alone(walk, tmp_path, backend):
    # The header thread reads the file's beginning, the kernel reads the file again: swapped in
    # between for a FIFO, the kernel's read must not wait for a writer.
    for name in ("a", "b"):
        (tmp_path / f"{name}.bvh").write_bytes(walk)
    batch = preprocess_module.open_source(tmp_path).items
    keep = ("positions", "contacts")
    prepared = preprocess_module._prepare(batch, keep, None)
    (tmp_path / "b.bvh").unlink()
    fifo = make_fifo(tmp_path / "b.bvh")
    try:
        outcomes, _, _ = _returns_within(10, lambda: preprocess_module._kernels(batch, prepared, keep, None, False))
    finally:
        release(fifo)
    assert "error" not in outcomes[0] and outcomes[0]["frames"] == em.read_bvh(tmp_path / "a.bvh").n_frames
    assert outcomes[1]["error"] == f"{fifo}: cannot read the file: a FIFO, {NOT_REGULAR}"
