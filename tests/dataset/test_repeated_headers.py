"""Headers read ahead for a batch (``heads.headers_ahead``, the ``repeated_headers`` kernel): a
file that repeats another's header gets the header the full reader gives it, field for field;
anything else, the full reader's own result or error. Both backends, and whole preprocess runs
with and without reading ahead."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.bvh.header import Header
from expressive_mocap.dataset import heads, load_dataset, preprocess
from expressive_mocap.dataset import work as work_module
from expressive_mocap.dataset.sources import open_source
from expressive_mocap.errors import BVHError
from expressive_mocap.procedural import procedural_walk


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    """A walk of more than 16 KB written many ways: its header repeated (other frame counts and
    times, blanks, CRLF), or changed so that the full reader reads or refuses it."""
    root = tmp_path_factory.mktemp("heads")
    text = em.bvh_bytes(procedural_walk(seconds=3.0))
    assert len(text) > 1 << 14
    frames = int(text.split(b"Frames:", 1)[1].split(b"\n", 1)[0])
    block = text.split(b"Frame Time:", 1)[1].split(b"\n", 1)[1]
    rows = block.split(b"\n")
    head = text[: text.index(b"Frames:")]
    variants = {
        "a_first": text,
        "same": text,
        "fewer_frames": head + b"Frames: %d\nFrame Time: 0.04\n" % (frames - 5) + b"\n".join(rows[5:]),
        "blanks": head + b"Frames:\t%d \r\nFrame Time:  0.0333333\t\n" % frames + block,
        "blank_line": head + b"\nFrames: %d\nFrame Time: 0.0333333\n" % frames + block,
        "exponent": head + b"Frames: %d\nFrame Time: 3.33333e-2\n" % frames + block,
        "zero_time": head + b"Frames: %d\nFrame Time: 0\n" % frames + block,
        "too_many": head + b"Frames: 99999999\nFrame Time: 0.0333333\n" + block,
        "nul": head + b"Frames: %d\nFrame Time: 0.0333333\n\0" % frames + block,
        "lower_case": head + b"frames: %d\nframe time: 0.0333333\n" % frames + block,
        "other_hierarchy": text.replace(b"OFFSET", b"OFFSET ", 1),
        # another actor's header again (matched to the one above, not parsed again)
        "other_repeated": head.replace(b"OFFSET", b"OFFSET ", 1)
        + b"Frames: %d\nFrame Time: 0.04\n" % (frames - 5)
        + b"\n".join(rows[5:]),
        "short": head + b"Frames: 1\nFrame Time: 0.0333333\n" + rows[0] + b"\n",
        "truncated": text[: len(text) // 2],
    }
    for name, data in variants.items():
        (root / f"{name}.bvh").write_bytes(data)
    return root


def full_reader(item):
    """The header (fields), the kernel's text kind, and bytes counted, or the error, read alone."""
    return _read(item, None)


def _read(item, known):
    outcome = work_module.Outcome()
    try:
        header, text = item.header(outcome, known)
    except BVHError as error:
        return str(error)
    skeleton = header.skeleton
    fields = (skeleton.names, tuple(skeleton.parents), skeleton.offsets.tobytes(), header.frames)
    return (*fields, header.frame_time, header.block_start, header.block_line, type(text).__name__, outcome.bytes)


def test_a_repeated_header_is_the_full_readers_and_anything_else_is_read_by_it(folder, backend):
    batch = open_source(folder).items
    known = heads.headers_ahead(batch)
    fast = {batch[k].name for k, v in known.items() if isinstance(v, Header)}
    # The repeats were read ahead (else this test would compare the full reader with itself) ...
    assert fast == {"same", "fewer_frames", "blanks", "truncated", "other_repeated"}
    for k, item in enumerate(batch):
        # ... and every file, read ahead or not, is what the full reader makes of it.
        assert _read(item, known.get(k)) == full_reader(item), item.name


def test_a_batch_whose_first_header_is_not_plain_reads_every_file_in_full(folder, tmp_path):
    (tmp_path / "a.bvh").write_bytes((folder / "blank_line.bvh").read_bytes())
    (tmp_path / "b.bvh").write_bytes((folder / "same.bvh").read_bytes())
    assert heads.headers_ahead(open_source(tmp_path).items) == {}


def test_a_preprocess_run_is_the_same_with_and_without_reading_ahead(folder, tmp_path, monkeypatch, backend):
    keep = "rotations,velocities,contacts"
    preprocess(folder, tmp_path / "ahead", keep=keep, rotations="6d", progress=False)
    monkeypatch.setattr(work_module, "headers_ahead", lambda batch: {})
    preprocess(folder, tmp_path / "alone", keep=keep, rotations="6d", progress=False)
    ahead, alone = load_dataset(tmp_path / "ahead"), load_dataset(tmp_path / "alone")
    assert ahead.manifest["clips"] == alone.manifest["clips"]
    assert ahead.manifest["failures"] == alone.manifest["failures"]
    failed = {failure["name"] for failure in ahead.manifest["failures"]}
    assert failed == {"zero_time", "too_many", "nul", "truncated"}
    for kind in keep.split(","):
        np.testing.assert_array_equal(ahead.arrays[kind], alone.arrays[kind])


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built: nothing to compare")
def test_the_kernel_and_its_twin_read_the_same_and_refuse_the_same(folder, tmp_path):
    from expressive_mocap import ops
    from expressive_mocap._utils.files import read_beginning
    from expressive_mocap.bvh.header import header_template, parse_header
    from expressive_mocap.bvh.reader import HEADER_PREFIX

    data, size = read_beginning(folder / "a_first.bvh", HEADER_PREFIX)
    header = parse_header(data, "a_first", size)
    template = header_template(data, size, header)
    assert template is not None and template.endswith(b"MOTION\n")
    (tmp_path / "folder.bvh").mkdir()
    paths = [*sorted(folder.glob("*.bvh")), tmp_path / "folder.bvh", tmp_path / "missing.bvh"]
    results = {}
    for name in ("rust", "numpy"):
        with em.use_backend(name):
            found = ops.repeated_headers(paths, template, header.skeleton.n_joints, HEADER_PREFIX)
        results[name] = [(type(r).__name__, r.errno, r.strerror) if isinstance(r, OSError) else r for r in found]
    assert results["rust"] == results["numpy"]
    assert sum(isinstance(r, tuple) and isinstance(r[0], int) for r in results["rust"]) == 5  # a_first too
