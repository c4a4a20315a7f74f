"""Every kind of malformed file raises BVHError naming the file, the line and what was
expected, with both kernel backends (the Rust parser must never panic)."""

import pytest

import expressive_mocap as em
from conftest import DATA
from expressive_mocap.bvh import read_summary

GOOD = (DATA / "mixed_orders.bvh").read_bytes()
LINES = GOOD.split(b"\n")
FIRST_FRAME_LINE = LINES.index(b"Frame Time: 0.0333333") + 2  # 1-based


def replace_line(number: int, text: bytes) -> bytes:
    lines = list(LINES)
    lines[number - 1] = text
    return b"\n".join(lines)


def frame_line(k: int) -> int:
    return FIRST_FRAME_LINE + k


CASES = {
    # name: (file bytes, expected line or None, words the message must contain)
    "truncated block": (b"\n".join(LINES[: frame_line(2) - 1]) + b"\n", frame_line(1), "truncated"),
    "truncated mid-line": (GOOD[: GOOD.rindex(b"-81.0")], frame_line(3), "expected 27 values"),
    "too few values": (
        replace_line(frame_line(1), LINES[frame_line(1) - 1].rsplit(b" ", 1)[0]),
        frame_line(1),
        "expected 27 values",
    ),
    "too many values": (replace_line(frame_line(2), LINES[frame_line(2) - 1] + b" 1.0"), frame_line(2), "found 28"),
    "non-numeric token": (
        replace_line(frame_line(2), LINES[frame_line(2) - 1].replace(b"93.0", b"9x3")),
        frame_line(2),
        "not a number",
    ),
    "nan": (replace_line(frame_line(0), LINES[frame_line(0) - 1].replace(b"91.0", b"nan")), frame_line(0), "finite"),
    "inf": (replace_line(frame_line(3), LINES[frame_line(3) - 1].replace(b"94.0", b"-inf")), frame_line(3), "finite"),
    "more frames than declared": (GOOD.replace(b"Frames: 4", b"Frames: 3"), frame_line(3), "more frame lines"),
    "missing Frames": (GOOD.replace(b"Frames: 4\n", b""), FIRST_FRAME_LINE - 2, "Frames"),
    "missing Frame Time": (GOOD.replace(b"Frame Time: 0.0333333\n", b""), FIRST_FRAME_LINE - 1, "Frame Time"),
    "negative frame count": (GOOD.replace(b"Frames: 4", b"Frames: -4"), FIRST_FRAME_LINE - 2, "whole number"),
    "zero frame time": (GOOD.replace(b"Frame Time: 0.0333333", b"Frame Time: 0"), FIRST_FRAME_LINE - 1, "positive"),
    "missing closing brace": (GOOD.replace(b"\t}\n}\nMOTION", b"\t}\nMOTION"), None, "never closed"),
    "extra closing brace": (GOOD.replace(b"}\nMOTION", b"}\n}\nMOTION"), LINES.index(b"MOTION") + 1, "closes nothing"),
    "several roots": (
        GOOD.replace(b"}\nMOTION", b"}\nROOT Other\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION"),
        LINES.index(b"MOTION") + 1,
        "several ROOT",
    ),
    "unknown channel": (
        GOOD.replace(b"Yrotation Zrotation Xrotation", b"Yrotation Zrot Xrotation"),
        13,
        "unknown channel",
    ),
    "channel count too large": (
        GOOD.replace(b"CHANNELS 2 Yposition", b"CHANNELS 3 Yposition"),
        None,
        "unknown channel 'JOINT'",
    ),
    "missing OFFSET": (GOOD.replace(b"\t\tOFFSET 0.0 12.0 0.0\n", b""), None, "no OFFSET"),
    "non-numeric OFFSET": (GOOD.replace(b"OFFSET 0.0 12.0 0.0", b"OFFSET 0.0 twelve 0.0"), 12, "OFFSET value"),
    "header ends early": (GOOD[: GOOD.index(b"JOINT Leg_R")], None, "never closed"),
    "header ends mid-OFFSET": (GOOD[: GOOD.index(b" 12.0 0.0")], None, "end of the header"),
    "no MOTION": (GOOD[: GOOD.index(b"MOTION")], None, "MOTION"),
    "empty file": (b"", None, "empty"),
    "blank file": (b"  \n\r\n\t\n", None, "empty"),
    "not BVH text": (b"hello world\n", 1, "HIERARCHY"),
    "binary file": (bytes(range(256)) * 4, None, "binary"),
    "gzip file": (b"\x1f\x8b\x08\x00" + bytes(100), None, "binary"),
    # Found by tools/fuzz_bvh.py: the same channel in two spellings escaped as a MocapError.
    "channel twice in two cases": (
        GOOD.replace(b"Yrotation Zrotation Xrotation", b"Yrotation Zrotation ZROTATION"),
        13,
        "lists a channel twice",
    ),
    "Latin-1 header": (GOOD.replace(b"Spine Lower", b"Spine \xe9"), 6, "not UTF-8"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_malformed_file_names_file_line_and_expectation(tmp_path, backend, case):
    data, line, words = CASES[case]
    path = tmp_path / "broken.bvh"
    path.write_bytes(data)
    with pytest.raises(em.BVHError) as caught:
        em.read_bvh(path)
    error = caught.value
    assert error.source == str(path)
    assert str(error).startswith(str(path))
    if line is not None:
        assert error.line == line, str(error)
        assert f"line {line}:" in str(error)
    assert words in str(error), str(error)
    # `info`'s reader, which checks the number block without keeping it, refuses it alike.
    with pytest.raises(em.BVHError) as summarised:
        read_summary(path)
    assert str(summarised.value) == str(error)


def test_a_summary_says_what_a_whole_read_says(backend, mixed_path):
    header, motion = read_summary(mixed_path), em.read_bvh(mixed_path)
    skeleton = motion.skeleton
    assert (header.frames, header.frame_time) == (motion.n_frames, motion.frame_time)
    assert header.skeleton.names == skeleton.names and list(header.skeleton.parents) == skeleton.parents.tolist()
    assert header.skeleton.offsets == tuple(map(tuple, skeleton.offsets.tolist()))
    assert header.skeleton.channels == skeleton.channels and header.skeleton.end_sites == skeleton.end_sites


def test_missing_file(tmp_path):
    with pytest.raises(em.BVHError, match="cannot read"):
        em.read_bvh(tmp_path / "absent.bvh")


def test_bvh_error_is_a_value_error_of_the_package():
    assert issubclass(em.BVHError, em.MocapError) and issubclass(em.MocapError, ValueError)


def test_the_hierarchy_cache_never_accepts_a_broken_hierarchy():
    # Found by tools/fuzz_bvh.py: after a valid file with a brace glued to its OFFSET, the same
    # hierarchy without that brace was taken from the cache of known shapes and read.
    em.read_bvh(b"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0}\nMOTION\nFrames: 1\nFrame Time: .09\n\n")
    with pytest.raises(em.BVHError, match="never closed"):
        em.read_bvh(b"HIERARCHY\nROOT a\n{\nOFFSET 1 0 0\nMOTION\nFrames: 1\nFrame Time: .09\n\n")


# Huge claims (10^9 frames, 10^6 joints, ...) and their memory: tests/bvh/test_reader_limits.py.


def test_a_deep_hierarchy_is_read_without_recursion(tmp_path):
    depth = 5000  # far beyond Python's recursion limit
    lines = ["HIERARCHY"]
    for j in range(depth):
        lines += [
            ("ROOT" if j == 0 else "JOINT") + f" j{j}",
            "{",
            "OFFSET 0 1 0",
            "CHANNELS 3 Zrotation Xrotation Yrotation",
        ]
    lines += ["}"] * depth + ["MOTION", "Frames: 1", "Frame Time: 0.04", " ".join(["1.0"] * 3 * depth)]
    motion = em.read_bvh("\n".join(lines).encode())
    assert motion.skeleton.n_joints == depth
    assert em.read_bvh(em.bvh_bytes(motion)).skeleton.parents[-1] == depth - 2
