"""Headers read from a file's beginning (``bvh.read_header``), which the Rust kernel
``clip_pipeline_many`` then reads whole, and the search for the MOTION line."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import expressive_mocap as em
from expressive_mocap import bvh
from expressive_mocap.bvh import header as bvh_header
from expressive_mocap.procedural import procedural_walk


def header_fields(header):
    return (
        header.skeleton.names,
        header.skeleton.offsets.tolist(),
        header.frames,
        header.frame_time,
        header.block_start,
        header.block_line,
    )


def padded_clip(pad: int) -> bytes:
    """A walk whose OFFSET line of the root carries ``pad`` extra spaces: moves the MOTION,
    Frames and Frame Time lines across the boundary of what read_header reads first (HEADER_PREFIX)."""
    text = em.bvh_bytes(procedural_walk(seconds=0.5))
    return text.replace(b"OFFSET", b"OFFSET" + b" " * pad, 1)


def test_read_header_takes_the_beginning_only_when_the_header_fits(tmp_path):
    base = padded_clip(0)
    motion_at = base.index(b"MOTION")
    block_at = bvh.parse_header(base, "x").block_start
    # Cuts at that boundary through the MOTION line, the Frames line, the Frame Time line
    # (number cut short: 0.0333 read as 0.03 would be wrong), its newline, and just after.
    for cut in sorted({motion_at + 3, motion_at + 12, block_at - 4, block_at - 1, block_at, block_at + 1}):
        data = padded_clip(bvh.HEADER_PREFIX - cut)
        path = tmp_path / f"cut{cut}.bvh"
        path.write_bytes(data)
        header, whole = bvh.read_header(path)
        assert header_fields(header) == header_fields(bvh.parse_header(data, str(path)))
        starts_in_beginning = header.block_start < bvh.HEADER_PREFIX
        assert (whole is None) == starts_in_beginning and (whole is None or whole == data)
    assert bvh.HEADER_PREFIX - (block_at - 1) < 1 << 20  # the cases above did cross the boundary


def test_read_header_errors_are_read_bvh_errors(tmp_path):
    big = padded_clip(bvh.HEADER_PREFIX)  # a header longer than the beginning
    path = tmp_path / "big.bvh"
    path.write_bytes(big)
    header, whole = bvh.read_header(path)
    assert whole == big and header.frames == em.read_bvh(path).n_frames
    # A clip whose frame count is only plausible for the whole file's size (frames x joints
    # above 65,536 and above a third of the beginning's bytes): read from the beginning.
    long = em.bvh_bytes(procedural_walk(seconds=120))
    path = tmp_path / "long.bvh"
    path.write_bytes(long)
    header, whole = bvh.read_header(path)
    assert whole is None and header.frames == em.read_bvh(path).n_frames
    assert header.frames * header.skeleton.n_joints > max(bvh.HEADER_PREFIX // 3, 65536)
    # Errors: a Frames count the file cannot hold (small and large files), blank beginnings.
    frames = f"Frames: {header.frames}".encode()
    claims = long.replace(frames, b"Frames: 99999999", 1)
    short = padded_clip(0)
    short = short.replace(short[short.index(b"Frames:") :].split(b"\n", 1)[0], b"Frames: 9999", 1)
    cases = (
        ("claims.bvh", claims),
        ("short.bvh", short),
        ("empty.bvh", b" " * (bvh.HEADER_PREFIX + 10)),
        ("late.bvh", b"\n" * bvh.HEADER_PREFIX + short),
    )
    for name, data in cases:
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(em.BVHError) as expected:
            em.read_bvh(path)
        with pytest.raises(em.BVHError) as got:
            bvh.read_header(path)
        assert str(got.value) == str(expected.value)
    with pytest.raises(em.BVHError, match="cannot read the file"):
        bvh.read_header(tmp_path / "missing.bvh")


@settings(max_examples=3000, deadline=None, derandomize=True)
@given(
    st.lists(
        st.sampled_from(
            [b"MOTION", b"motion", b"MoTiOn", b"MOTIONS", b" ", b"\t", b"\n", b"\r", b"\r\n", b"x", b"Mot", b"ion"]
        ),
        max_size=16,
    ),
    st.integers(0, 5000),
)
def test_the_motion_line_is_found_as_the_regex_finds_it(pieces, padding):
    # Padding moves the candidates across the first 4 KB window when there is no upper-case MOTION.
    for data in (b"".join(pieces), b"x" * padding + b"".join(pieces), b"\n" * padding + b"".join(pieces)):
        expected, found = bvh_header._MOTION.search(data), bvh_header._find_motion_line(data)
        assert (found is None) == (expected is None) and (found is None or found.span() == expected.span())


def test_finding_the_motion_line_stays_linear_on_hostile_headers():
    # Millions of candidates on one line, or one line each: each line is matched once.
    for data in (b"motion" * 600_000, b" " * 2_000_000 + b"motion" * 300_000, b"\n motion x" * 400_000):
        assert bvh_header._find_motion_line(data) is None and bvh_header._MOTION.search(data) is None
