"""Resource bounds of the reader: hostile files (tests/hostile_files.py) give a Motion or a
BVHError naming the limit, and no file under 1 MB makes the reader's peak memory grow by more
than 100 MB. Each backend reads every file in one fresh process, its peak RSS reset between files."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import expressive_mocap as em
from conftest import BACKENDS
from hostile_files import cases

SCRIPT = Path(__file__).parents[1] / "hostile_files.py"
CASES = cases()


@pytest.fixture(scope="module", params=BACKENDS)
def report(request):
    env = {**os.environ, "PYTHONPATH": str(Path(em.__file__).parent.parent)}
    done = subprocess.run(
        [sys.executable, str(SCRIPT), request.param], capture_output=True, text=True, env=env, timeout=600
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.mark.parametrize("case", list(CASES))
def test_hostile_file_is_read_or_refused_within_bounds(report, case):
    result, expected = report[case], CASES[case][1]
    if expected == "ok":
        assert result["outcome"].startswith("ok"), result
    else:
        assert result["outcome"].startswith("error") and expected in result["outcome"], result
    assert result["grown_mb"] < 100, result


def test_the_cases_are_small_files_except_the_huge_hierarchies():
    small = [name for name, (data, _) in CASES.items() if len(data) < 1 << 20]
    assert len(small) >= len(CASES) - 2


def test_the_largest_skeleton_we_write_reads_back():
    # A chain of MAX_JOINTS joints: the writer's indentation stops growing, so the header stays
    # under MAX_HEADER_BYTES and what we write at the limits we read.
    import numpy as np

    from expressive_mocap.bvh import MAX_HEADER_BYTES, MAX_JOINTS

    joints = MAX_JOINTS
    skeleton = em.Skeleton(
        names=tuple(f"j{j}" for j in range(joints)),
        parents=np.arange(-1, joints - 1),
        offsets=np.tile([0.0, 1.0, 0.0], (joints, 1)),
        channels=(("Zrotation", "Xrotation", "Yrotation"),) * joints,
    )
    rotations = np.tile([0.0, 0.0, 0.0, 1.0], (1, joints, 1))
    data = em.bvh_bytes(em.Motion(skeleton, rotations, np.broadcast_to(skeleton.offsets, (1, joints, 3)).copy(), 0.04))
    assert data.index(b"MOTION") < MAX_HEADER_BYTES
    again = em.read_bvh(data)
    assert again.skeleton.n_joints == joints and again.skeleton.parents[-1] == joints - 2
