"""The Rust kernels release the GIL: other Python threads run meanwhile, and kernels called
from several threads at once give the same results as serial calls."""

import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from kernel_cases import CORE

pytestmark = pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")


def big_motion_arrays(frames=40_000, joints=22):
    rng = np.random.default_rng(0)
    rotations = Rotation.random(frames * joints, random_state=1).as_quat().reshape(frames, joints, 4)
    translations = rng.normal(size=(frames, joints, 3))
    parents = np.array([-1] + [int(rng.integers(0, j)) for j in range(1, joints)])
    return rotations, translations, parents


def test_python_threads_run_inside_a_kernel_call():
    from expressive_mocap import _core

    rotations, translations, parents = big_motion_arrays(frames=100_000)
    calls = []  # (start, end) of each kernel call, timed in the worker
    done = threading.Event()

    def worker():
        for _ in range(3):
            start = time.perf_counter()
            _core.forward_kinematics(rotations, translations, parents)
            calls.append((start, time.perf_counter()))
        done.set()

    previous = sys.getswitchinterval()
    sys.setswitchinterval(1e-3)
    try:
        thread = threading.Thread(target=worker)
        thread.start()
        ticks = []
        while not done.is_set():
            ticks.append(time.perf_counter())  # the main thread can only do this holding the GIL
        thread.join()
    finally:
        sys.setswitchinterval(previous)
    ticks = np.array(ticks)
    # Near a call's ends the worker may be waiting for the GIL (a few switch intervals); inside,
    # a kernel that held the GIL would leave no tick at all (checked with builtin sum(): 0).
    margin = 0.005
    inside = [np.count_nonzero((ticks > a + margin) & (ticks < b - margin)) for a, b in calls if b - a > 4 * margin]
    assert inside and min(inside) > 0, (inside, [b - a for a, b in calls])


def test_concurrent_calls_match_serial_calls(mixed_path):
    rotations, translations, parents = big_motion_arrays(frames=3000)
    with em.use_backend("rust"):
        serial = em.forward_kinematics(rotations, translations, parents)
        text = mixed_path.read_bytes()
        serial_read = em.read_bvh(text)
        with ThreadPoolExecutor(4) as pool:
            fks = list(pool.map(lambda _: em.forward_kinematics(rotations, translations, parents), range(8)))
            reads = list(pool.map(lambda _: em.read_bvh(text), range(8)))
    for world_rot, world_pos in fks:
        np.testing.assert_array_equal(world_rot, serial[0])
        np.testing.assert_array_equal(world_pos, serial[1])
    for motion in reads:
        np.testing.assert_array_equal(motion.rotations, serial_read.rotations)


# Frames per call: enough for each kernel's parallel path (16,384 joint-frames; a MOTION block
# over 1 MB), so Python threads and rayon threads run at once.
BIG = {"parse_motion_block": 200_000, "read_motion_blocks": 200_000, "format_motion_block": 20_000}


def _leaves(result):
    if isinstance(result, (tuple, list)):
        return [leaf for item in result for leaf in _leaves(item)]
    return [result]


@pytest.mark.parametrize("name", sorted(CORE))
def test_every_kernel_gives_serial_results_from_concurrent_threads(name):
    from expressive_mocap import _core

    args = CORE[name][0](BIG.get(name, 6000))
    kernel = getattr(_core, name)
    serial = _leaves(kernel(*args))
    with ThreadPoolExecutor(4) as pool:
        concurrent = list(pool.map(lambda _: _leaves(kernel(*args)), range(8)))
    for leaves in concurrent:
        assert len(leaves) == len(serial)
        for got, want in zip(leaves, serial):
            if isinstance(want, bytes):
                assert got == want
            else:
                np.testing.assert_array_equal(got, want)


def test_the_interpreter_exits_only_once_no_thread_is_in_a_kernel(tmp_path):
    """A daemon thread still in a kernel when Python finalised came back to a dying interpreter
    and aborted the process ("FATAL: exception not rethrown", exit 134: 5 runs in 40 of
    `preprocess --max-batches 1 --fps 24 --mirror --canonical` on dataset-2). Every call through
    backend.kernels() is counted and the exit waits for it: here a kernel that takes 0.5 s and
    then leaves a mark, called from a daemon thread as the main thread ends."""
    import subprocess

    marker = tmp_path / "finished"
    script = f"""
import threading, time, types
from expressive_mocap import backend

def slow_kernel():
    time.sleep(0.5)
    with open({str(marker)!r}, "w") as out:
        out.write("done")

backend._counted = backend._InRust(types.SimpleNamespace(slow_kernel=slow_kernel))
calling = threading.Event()

def work():
    calling.set()
    backend.kernels().slow_kernel()

threading.Thread(target=work, daemon=True).start()
calling.wait()
"""
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, timeout=60)
    assert done.returncode == 0, done.stderr.decode()
    assert marker.read_text() == "done"  # the exit waited for the call under way


def test_kernel_calls_are_counted_while_they_run():
    from expressive_mocap import backend

    with em.use_backend("rust"):
        kernels = backend.kernels()
        assert kernels.forward_kinematics.__name__ == "forward_kinematics"
        inside, release = threading.Event(), threading.Event()
        counted = backend._InRust(type("Fake", (), {"wait": staticmethod(lambda: (inside.set(), release.wait()))}))
        thread = threading.Thread(target=counted.wait)
        thread.start()
        inside.wait()
        assert not counted.wait_idle(0.05)  # a call under way
        release.set()
        assert counted.wait_idle(10)
        thread.join()
