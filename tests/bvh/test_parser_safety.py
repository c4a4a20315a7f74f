"""Hostile inputs to the reader and the kernels: arrays written by another thread during a call,
odd bytes in bool arrays, one number grammar for the whole file, byte-order marks and old Mac
line endings, and huge tokens echoed in error messages."""

import importlib
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import expressive_mocap as em
from conftest import REPO
from expressive_mocap import bvh, reference

needs_rust = pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")

# Run in a subprocess, so that the panic messages a kernel might print on stderr can be checked.
# One thread flips one entry of `parents` (or of a layout) between valid and invalid values while
# the main thread calls a kernel in a loop; every call must give a clean ValueError or exactly
# the result of one of the valid values.
HAMMER = textwrap.dedent(
    """
    import json, sys, threading, time
    import numpy as np
    from expressive_mocap import _core, bvh, ops, procedural
    from expressive_mocap.body import Body
    from expressive_mocap.body.contacts import FLOOR_PERCENTILE, HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD

    GAIT = ops.GaitSettings(HEIGHT_THRESHOLD, SPEED_THRESHOLD, MIN_DURATION, FLOOR_PERCENTILE)

    def fk_kernels():
        rng = np.random.default_rng(0)
        q = rng.normal(size=(4000, 8, 4))
        q /= np.linalg.norm(q, axis=-1, keepdims=True)
        t = rng.normal(size=(4000, 8, 3))
        parents = np.arange(-1, 7, dtype=np.int64)
        yield "forward_kinematics", parents, 5, [0, 2, 4], lambda: _core.forward_kinematics(q, t, parents)
        yield (
            "forward_kinematics_many",
            parents,
            5,
            [0, 2, 4],
            lambda: _core.forward_kinematics_many([(q, t, parents)] * 3),
        )

    def pipeline():
        data = bvh.bvh_bytes(procedural.procedural_walk(seconds=4.0))
        header = bvh.parse_header(data, "walk")
        skeleton = header.skeleton
        body = Body.of(skeleton)
        roles = body.roles
        clip = ops.ClipInput.of(data, header, body.actor_height, body.hips_rest_height)
        outputs = ops.PipelineOutputs(positions=True, features=(ops.FeatureRequest(0.0),), contacts=True)
        parents = np.array(skeleton.parents, dtype=np.int64)  # the skeleton's own is read-only
        joint = skeleton.n_joints - 1
        valid = sorted({int(parents[joint]), 0, joint - 1})
        call = lambda: _core.clip_pipeline_many([clip] * 2, parents, roles.gait_joints, gait=GAIT, outputs=outputs)
        yield "clip_pipeline_many", parents, joint, valid, call

    def flat(result):
        out = []
        for item in result if isinstance(result, (list, tuple)) else [result]:
            if isinstance(item, np.ndarray):
                out.append(item)
            elif isinstance(item, (list, tuple)):
                out += flat(item)
            elif item is not None:
                raise AssertionError(f"unexpected result item {item!r}")
        return out

    def same(a, b):
        return len(a) == len(b) and all(x.shape == y.shape and np.array_equal(x, y) for x, y in zip(a, b))

    report = {}
    sys.setswitchinterval(1e-4)
    for name, parents, joint, valid, call in [*fk_kernels(), *pipeline()]:
        expected = []
        for value in valid:
            parents[joint] = value
            expected.append(flat(call()))
        stop, writes = threading.Event(), [0]

        def hammer():
            # Valid, then the joint itself, a later joint, out of range, negative.
            values = valid + [joint, joint + 1, len(parents), 1 << 40, 1 << 62, -2, -(1 << 40)]
            while not stop.is_set():
                parents[joint] = values[writes[0] % len(values)]
                writes[0] += 1

        counts = {"calls": 0, "refused": 0, "valid": 0, "wrong": 0, "other": []}
        thread = threading.Thread(target=hammer)
        thread.start()
        start = time.perf_counter()
        try:
            while counts["calls"] < 20 or time.perf_counter() - start < 1.5:
                counts["calls"] += 1
                try:
                    got = flat(call())
                except ValueError as error:
                    counts["refused"] += 1
                    if "parents" not in str(error):
                        counts["other"].append(str(error)[:200])
                    continue
                except BaseException as error:  # PanicException is a BaseException
                    counts["other"].append(f"{type(error).__name__}: {str(error)[:200]}")
                    continue
                counts["valid" if any(same(got, e) for e in expected) else "wrong"] += 1
        finally:
            stop.set()
            thread.join()
        counts["writes"] = writes[0]
        report[name] = counts
    print(json.dumps(report))
    """
)


@needs_rust
def test_index_arrays_written_by_another_thread_never_reach_a_kernel():
    # Found by review: the bindings read `parents` from NumPy's memory after releasing the GIL,
    # so a parent checked in range could be out of range when used: a PanicException (a
    # BaseException) and tens of MB of panic messages on stderr.
    env = dict(
        os.environ,
        PYTHONPATH=str(Path(em.__file__).resolve().parent.parent),
        EXPRESSIVE_MOCAP_BACKEND="rust",
        RUST_BACKTRACE="0",
    )
    done = subprocess.run([sys.executable, "-c", HAMMER], capture_output=True, text=True, env=env, timeout=600)
    assert "panicked" not in done.stderr, done.stderr[:2000]
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout)
    assert set(report) == {"forward_kinematics", "forward_kinematics_many", "clip_pipeline_many"}
    for name, counts in report.items():
        assert counts["other"] == [] and counts["wrong"] == 0, (name, counts)
        assert (
            counts["calls"] >= 20 and counts["refused"] + counts["valid"] == counts["calls"] and counts["writes"] > 0
        ), (name, counts)


@needs_rust
@pytest.mark.parametrize("kernel", ["air_time", "dynamic_features"])
def test_a_bool_array_holding_other_bytes_reads_them_as_numpy_does(kernel):
    # NumPy lets a bool array hold any byte (a view of uint8 data); NumPy reads non-zero as
    # True, and Rust must not read such a byte as a `bool` (undefined behaviour).
    from expressive_mocap import _core

    flags = np.array([[0, 0], [2, 1], [0, 255], [0, 0], [128, 0]], dtype=np.uint8)
    odd, plain = flags.view(bool), flags != 0
    if kernel == "air_time":
        args = lambda contacts: (contacts, 0.1)  # noqa: E731
    else:
        rng = np.random.default_rng(1)
        points, thighs = rng.normal(size=(5, 3, 3)), rng.normal(size=(5, 2, 4))
        reference_quats = np.tile([0.0, 0.0, 0.0, 1.0], (2, 1))
        args = lambda contacts: (points, thighs, contacts, reference_quats, 0.1, 170.0, 90.0, 0.0, 3)  # noqa: E731
    expected = getattr(_core, kernel)(*args(plain))
    np.testing.assert_allclose(expected, getattr(reference, kernel)(*args(plain)), atol=1e-12)
    np.testing.assert_array_equal(getattr(_core, kernel)(*args(odd)), expected)


# --- One number grammar for the whole file -------------------------------------------------


def one_joint_file(offset: str, frame_time: str = "0.04", frame: str = "0") -> bytes:
    return (
        f"HIERARCHY\nROOT Hips\n{{\n\tOFFSET {offset} 0 0\n\tCHANNELS 1 Xrotation\n}}\n"
        f"MOTION\nFrames: 1\nFrame Time: {frame_time}\n{frame}\n"
    ).encode()


def header_number(token: str) -> float | None:
    """The OFFSET value the header reads for ``token``, or None when it refuses it."""
    try:
        return float(bvh.parse_header(one_joint_file(token), "t").skeleton.offsets[0, 0])
    except em.BVHError as error:
        assert "OFFSET value" in error.reason, error
        return None


def block_outcomes(token: str) -> list:
    """Per backend, the value the MOTION block parser reads for ``token`` or its message."""
    data = token.encode("utf-8") + b"\n"
    outcomes = []
    for module in [reference] + ([importlib.import_module("expressive_mocap._core")] if em.rust_available() else []):
        try:
            outcomes.append(float(module.parse_motion_block(data, 0, 1, 1)[0, 0]))
        except em.errors.ParseError as error:
            outcomes.append(error.args)
    return outcomes


# Python's float() takes all of these; the Rust MOTION parser none.
LENIENT = ["1_000", "0.0_3", "\u0661\u0662", "\uff11", "\u0967.5", "1e1_0", "١"]
TOKENS = st.one_of(
    st.text(alphabet="0123456789+-.eE", min_size=1, max_size=10),
    st.text(alphabet="0123456789+-.eE_xnaifINFAty\u0661\uff11\u00a0\x0b\u2003", min_size=1, max_size=10),
    st.sampled_from(
        LENIENT
        + [
            "nan",
            "-NaN",
            "+inf",
            "Infinity",
            "infinit",
            "1e999",
            "-1e-999",
            "5.",
            ".5",
            "+.5e-3",
            ".",
            "+",
            "1e",
            "1e+",
        ]
    ),
)


@settings(max_examples=600, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(TOKENS)
def test_the_header_and_the_motion_block_accept_the_same_numbers(token):
    header = header_number(token)
    outcomes = block_outcomes(token)
    if header is None:
        assert all(isinstance(o, tuple) for o in outcomes), (token, outcomes)
    else:
        assert outcomes == [header] * len(outcomes), (token, header, outcomes)
    assert len(set(map(repr, outcomes))) == 1, (token, outcomes)  # the same value, or message and line
    # Frame Time: the same numbers, positive.
    try:
        frame_time = bvh.parse_header(one_joint_file("0", frame_time=token), "t").frame_time
    except em.BVHError:
        frame_time = None
    assert frame_time == (header if header is not None and header > 0 else None), (token, frame_time)


@pytest.mark.parametrize("token", LENIENT)
def test_numbers_python_alone_would_read_are_refused_in_the_header(token):
    # Found by review: OFFSET and Frame Time went through float(), which takes these.
    with pytest.raises(em.BVHError, match="OFFSET value"):
        em.read_bvh(one_joint_file(token))
    with pytest.raises(em.BVHError, match="Frame Time"):
        em.read_bvh(one_joint_file("0", frame_time=token))


# --- Tokens echoed in error messages ---------------------------------------------------------

HUGE = "7" * (1 << 20)
GOOD = one_joint_file("0")
ECHOES = {
    # where a 1 MB token goes: the file
    "OFFSET value": one_joint_file(HUGE + "x"),
    "joint name": GOOD.replace(b"ROOT Hips\n{\n\tOFFSET 0 0 0\n", b"ROOT " + HUGE.encode() + b"\n{\n"),
    "keyword": GOOD.replace(b"\tCHANNELS", HUGE.encode() + b" CHANNELS"),
    "channel count": GOOD.replace(b"CHANNELS 1", b"CHANNELS " + HUGE.encode()),
    "channel name": GOOD.replace(b"Xrotation", b"X" + HUGE.encode()),
    "after the hierarchy": GOOD.replace(b"}\nMOTION", b"}\n" + HUGE.encode() + b"\nMOTION"),
    "Frames line": GOOD.replace(b"Frames: 1", HUGE.encode()),
    "Frames value": GOOD.replace(b"Frames: 1", b"Frames: " + HUGE.encode()),
    "Frame Time value": GOOD.replace(b"Frame Time: 0.04", b"Frame Time: " + HUGE.encode() + b"x"),
    "first line": HUGE.encode() + b"\n" + GOOD,
    "MOTION block": one_joint_file("0", frame=HUGE + "x"),
}


@pytest.mark.parametrize("case", sorted(ECHOES))
def test_a_huge_token_is_echoed_cut_with_its_length(case, backend):
    # Found by review: a 1 MB OFFSET token made a 1 MB error line.
    with pytest.raises(em.BVHError) as caught:
        em.read_bvh(ECHOES[case])
    message = str(caught.value)
    assert len(message) < 300 and "\n" not in message, message[:500]
    assert (
        "'7777777777777777777777777777777777777777'... (10485" in message
        or "'X777777777777777777777777777777777777777'... (10485" in message
    ), message


def test_control_characters_in_an_echoed_token_are_escaped_the_same_in_both_backends():
    token = "a\x0bb\x1b\x85\u2028\u00e9\u0661"
    outcomes = block_outcomes(token)
    assert outcomes[0] == ("'a\\x0bb\\x1b\\x85\\u2028\u00e9\u0661' is not a number", 0)
    assert len(set(outcomes)) == 1, outcomes
    with pytest.raises(em.BVHError, match=r"found 'a\\x0bb\\x1b\\x85\\u2028\u00e9\u0661'$"):
        em.read_bvh(one_joint_file(token))


# --- Byte-order marks and line endings -----------------------------------------------------

MIXED = (REPO / "tests" / "data" / "mixed_orders.bvh").read_bytes()
BOM = b"\xef\xbb\xbf"


def test_a_utf8_byte_order_mark_is_read_with_the_same_lines_and_offsets(backend, tmp_path):
    # Found by review: "expected 'HIERARCHY' ..., found '\ufeffHIERARCHY'" (exporters write it).
    plain, marked = em.read_bvh(MIXED), em.read_bvh(BOM + MIXED)
    np.testing.assert_array_equal(marked.rotations, plain.rotations)
    np.testing.assert_array_equal(marked.translations, plain.translations)
    assert marked.skeleton.names == plain.skeleton.names
    # Lines named in errors, header and MOTION block, are those of the file without the mark.
    lines = MIXED.split(b"\n")
    for number, broken in ((12, b"\t\tOFFSET 0.0 twelve 0.0"), (len(lines) - 2, lines[-2].replace(b" ", b" x ", 1))):
        assert lines[number - 1].strip() and broken != lines[number - 1]
        bad = b"\n".join(lines[: number - 1] + [broken] + lines[number:])
        for data in (bad, BOM + bad):
            with pytest.raises(em.BVHError) as caught:
                em.read_bvh(data)
            assert caught.value.line == number, caught.value
    # The header read from a file's beginning gives the Rust kernel byte offsets into the file.
    path = tmp_path / "marked.bvh"
    path.write_bytes(BOM + MIXED)
    header, _ = bvh.read_header(path)
    assert header.block_start == bvh.parse_header(MIXED, "plain").block_start + len(BOM)


def test_cr_only_line_endings_are_refused_with_how_to_convert(backend):
    # Found by review: "expected MOTION after the hierarchy, found 'MOTION'".
    for data in (MIXED.replace(b"\n", b"\r"), BOM + MIXED.replace(b"\n", b"\r")):
        with pytest.raises(em.BVHError, match=r"line 1: CR-only line endings .* tr '\\r' '\\n'") as caught:
            em.read_bvh(data)
        assert "\n" not in str(caught.value) and "\r" not in str(caught.value)
    # CRLF, and CRCRLF (CRLF converted twice), are still read.
    for ending in (b"\r\n", b"\r\r\n"):
        np.testing.assert_array_equal(em.read_bvh(MIXED.replace(b"\n", ending)).rotations, em.read_bvh(MIXED).rotations)
