"""Hostile BVH files: small files with absurd claims, and hierarchies at and beyond the reader's
limits. Run as a script (``python hostile_files.py BACKEND``) it reads each one and prints, as
JSON, what happened and how much the peak RSS grew while reading it (reset between files).
``tests/bvh/test_reader_limits.py`` runs it in a fresh process; the fuzz harness seeds its corpus
with them.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROTATION = b"CHANNELS 3 Zrotation Xrotation Yrotation"
GOOD = (Path(__file__).parent / "data" / "mixed_orders.bvh").read_bytes()


def motion(frames: int, lines: list[bytes], frame_time: bytes = b"0.04") -> bytes:
    return b"MOTION\nFrames: %d\nFrame Time: %s\n" % (frames, frame_time) + b"\n".join(lines) + b"\n"


def chain(joints: int, channels: bytes = ROTATION) -> bytes:
    """A hierarchy of ``joints`` joints, each the child of the previous one (depth = joints)."""
    opened = [b"HIERARCHY\nROOT j0\n{\nOFFSET 0 1 0\n%s\n" % channels]
    opened += [b"JOINT j%d\n{\nOFFSET 0 1 0\n%s\n" % (j, channels) for j in range(1, joints)]
    return b"".join(opened) + b"}\n" * joints


def star(joints: int, root_channels: bytes = b"CHANNELS 1 Xrotation") -> bytes:
    """A root with ``joints - 1`` children without channels."""
    children = b"".join(b"JOINT j%d\n{\nOFFSET 0 1 0\nCHANNELS 0\n}\n" % j for j in range(1, joints))
    return b"HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\n%s\n%s}\n" % (root_channels, children)


def cases() -> dict[str, tuple[bytes, str]]:
    """name -> (file, "ok" or words the BVHError must contain)."""
    one = b"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n}\n"
    return {
        "claims 10^9 frames": (GOOD.replace(b"Frames: 4", b"Frames: 1000000000"), "more than the"),
        "claims 10^18 - 1 frames": (GOOD.replace(b"Frames: 4", b"Frames: " + b"9" * 18), "more than the"),
        "a 19-digit frame count": (GOOD.replace(b"Frames: 4", b"Frames: " + b"9" * 19), "at most 18 digits"),
        "a 5000-digit frame count": (GOOD.replace(b"Frames: 4", b"Frames: " + b"9" * 5000), "at most 18 digits"),
        "a superscript frame count": (GOOD.replace(b"Frames: 4", "Frames: ²".encode()), "whole number"),
        "a superscript channel count": (GOOD.replace(b"CHANNELS 2", "CHANNELS ²".encode()), "channel count"),
        "a huge channel count": (GOOD.replace(b"CHANNELS 2", b"CHANNELS 99999999999999999999"), "channel count"),
        "values of 1e308": (one + motion(2, [b"1e308 -1e308 1.7976931348623157e308"] * 2), "ok"),
        "offsets of 1e308": (one.replace(b"OFFSET 0 0 0", b"OFFSET 1e308 -1e308 1e308") + motion(1, [b"0 0 0"]), "ok"),
        "a value of 1e309": (one + motion(1, [b"1e309 0 0"]), "finite"),
        "an offset of 1e309": (one.replace(b"OFFSET 0 0 0", b"OFFSET 1e309 0 0") + motion(1, [b"0 0 0"]), "finite"),
        "a frame time of 1e-300": (one + motion(1, [b"0 0 0"], b"1e-300"), "ok"),
        "no channels, 10^17 frames": (star(3, b"CHANNELS 0") + motion(10**17, []), "more than the"),
        "duplicate joint names": (GOOD.replace(b"JOINT Head", b"JOINT Chest"), "more than once"),
        # At the limits: the largest files the reader accepts must still be cheap.
        "10^4 joints deep (the limits)": (chain(10_000) + motion(2, [b" ".join([b"0"] * 30_000)] * 2), "ok"),
        "330,000 frames without channels": (star(1, b"CHANNELS 0") + motion(330_000, [b""] * 999_000)[:-1], "ok"),
        "9000 joints decoded from one channel": (star(9_000) + motion(23, [b"1"] * 23 + [b" " * 640_000]), "ok"),
        # Beyond them.
        "10^4 + 1 joints": (star(10_001, b"CHANNELS 0") + motion(1, [b""]), "more than 10000 joints"),
        "10^6 joints (42 MB)": (star(1_000_000) + motion(1, [b"0"]), "longer than"),
        "10^5 deep (7 MB)": (chain(100_000) + motion(1, [b"0 0 0" * 100_000]), "longer than"),
        "a 1 MB header of tokens": (one[:-2] + b"ab\n" * 340_000 + b"}\n" + motion(1, [b"0 0 0"]), "expected OFFSET"),
        "a 1 MB header of braces": (one[:-2] + b"{\n" * 500_000 + motion(1, [b"0 0 0"]), "expected OFFSET"),
    }


def peak_mb() -> float:
    return int(Path("/proc/self/status").read_text().split("VmHWM:")[1].split()[0]) / 1024


def main(backend: str) -> None:
    import ctypes
    import gc

    import expressive_mocap as em

    trim = ctypes.CDLL("libc.so.6").malloc_trim
    report = {}
    for name, (data, _) in cases().items():
        gc.collect()
        trim(0)  # give freed memory back to the system, so the next file's peak counts in full
        Path("/proc/self/clear_refs").write_text("5")  # reset the peak RSS to the current RSS
        before = peak_mb()
        try:
            with em.use_backend(backend):
                motion = em.read_bvh(data)
            outcome = f"ok: {motion.skeleton.n_joints} joints, {motion.n_frames} frames"
            del motion
        except em.BVHError as error:
            outcome = f"error: {error}"
        report[name] = {"bytes": len(data), "outcome": outcome[:300], "grown_mb": peak_mb() - before}
    print(json.dumps(report))


if __name__ == "__main__":
    main(sys.argv[1])
