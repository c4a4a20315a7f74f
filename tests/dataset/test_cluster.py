"""`expressive-mocap preprocess --dask ADDRESS` against a real `dask scheduler` and `dask worker`
processes on 127.0.0.1, as one would start them on several machines: the dataset equals a local
run's bit for bit, with all workers alive, with one killed mid-run, and after losing the scheduler
or every worker (the run stops with one clear line and the same command resumes it).

A worker preload (written below) marks each batch a worker ran, and holds (sleeps in) the first
batch holding a named clip, so a test can kill a process while a batch is certainly in flight.
Real clips: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from contextlib import contextmanager
from pathlib import Path

import pytest

import expressive_mocap as em
import expressive_mocap.dataset.cluster as cluster_module
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.errors import DatasetError

distributed = pytest.importorskip("distributed", reason="the [distributed] extra (Dask) is not installed")

pytestmark = pytest.mark.real_data

PACKAGE_ROOT = str(Path(em.__file__).resolve().parent.parent)
OPTIONS = ["--keep", "positions,rotations,features,contacts,activity", "--model", "--batch-mb", "0.25", "-q"]
STARTUP_S = 90  # a process that has not started by then fails the test instead of hanging it

PRELOAD = '''
"""Test preload: each batch leaves its clip names in MARKS/<pid>.jsonl; the first batch holding
the clip named in MARKS/hold sleeps once its worker's pid is in MARKS/held."""
import json, os, time
import expressive_mocap.dataset.cluster as cluster

# The worker may import this file twice (from its copy too): wrap the package's function once.
_run = cluster.__dict__.setdefault("_unwrapped_remote_batch", cluster.remote_batch)
MARKS = os.environ["EXPRESSIVE_MOCAP_TEST_MARKS"]


def remote_batch(batch, *args):
    names = [item.name for item in batch]
    hold = os.path.join(MARKS, "hold")
    if os.path.exists(hold) and open(hold).read() in names:
        try:
            os.close(os.open(os.path.join(MARKS, "claimed"), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
        except FileExistsError:  # held once already: this is the batch run again elsewhere
            pass
        else:
            with open(os.path.join(MARKS, "held.tmp"), "w") as held:
                held.write(str(os.getpid()))
            os.rename(os.path.join(MARKS, "held.tmp"), os.path.join(MARKS, "held"))
            time.sleep(600)
    result = _run(batch, *args)
    with open(os.path.join(MARKS, f"{os.getpid()}.jsonl"), "a") as marks:
        marks.write(json.dumps(names) + "\\n")
    return result


cluster.remote_batch = remote_batch
'''


@pytest.fixture(scope="module")
def clips(bandai2_dir, tmp_path_factory) -> Path:
    """12 clips of dataset-2, linked into a folder."""
    folder = tmp_path_factory.mktemp("cluster") / "clips"
    folder.mkdir()
    for path in sorted(bandai2_dir.glob("*.bvh"))[::241][:12]:
        os.symlink(path, folder / path.name)
    return folder


@pytest.fixture(scope="module")
def local(clips, tmp_path_factory):
    """The dataset a run on this machine writes (the CLI, no cluster)."""
    out = tmp_path_factory.mktemp("local") / "ds"
    result = subprocess.run(cli(clips, out), capture_output=True, text=True, timeout=120, env=env_for(None))
    assert result.returncode == 0, result.stderr
    return load_dataset(out)


def cli(src: Path, out: Path, *extra: str) -> list[str]:
    return [sys.executable, "-m", "expressive_mocap.cli", "preprocess", str(src), "-o", str(out), *OPTIONS, *extra]


def env_for(marks: Path | None) -> dict:
    env = {**os.environ, "PYTHONPATH": PACKAGE_ROOT}
    if marks is not None:
        env["EXPRESSIVE_MOCAP_TEST_MARKS"] = str(marks)
    return env


class Cluster:
    """A scheduler and its workers, each a process group of its own."""

    def __init__(self, address: str, scheduler: subprocess.Popen, workers: list[subprocess.Popen], marks: Path):
        self.address, self.scheduler, self.workers, self.marks = address, scheduler, workers, marks

    def held_pid(self) -> int:
        """The pid of the worker holding the batch named in ``marks/hold``, once it holds it."""
        held = self.marks / "held"
        deadline = time.monotonic() + STARTUP_S
        while not held.exists():
            assert time.monotonic() < deadline, "no worker took the batch to hold"
            time.sleep(0.05)
        return int(held.read_text())

    def batches_by_worker(self) -> dict[int, list[list[str]]]:
        return {
            int(p.stem): [json.loads(line) for line in p.read_text().splitlines()] for p in self.marks.glob("*.jsonl")
        }


@contextmanager
def dask_cluster(folder: Path, workers: int = 2):
    """`dask scheduler` and ``workers`` `dask worker` processes on free ports of 127.0.0.1 (one
    thread each, no nanny, no dashboard), killed on the way out whatever happened."""
    marks = folder / "marks"
    marks.mkdir(parents=True)
    env, logs, processes = env_for(marks), open(folder / "dask.log", "w"), []

    def start(*args: str) -> subprocess.Popen:
        process = subprocess.Popen(
            [sys.executable, "-m", "dask", *args],
            env=env,
            stdout=logs,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # its own process group, killed as one
        )
        processes.append(process)
        return process

    try:
        scheduler_file = folder / "scheduler.json"
        scheduler = start(
            "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--dashboard-address",
            "127.0.0.1:0", "--scheduler-file", str(scheduler_file), "--idle-timeout", "600",
        )  # fmt: skip
        deadline = time.monotonic() + STARTUP_S
        address = None
        while address is None:  # Dask writes the file in place: it may exist empty or half written a moment
            assert scheduler.poll() is None and time.monotonic() < deadline, (folder / "dask.log").read_text()
            try:
                address = json.loads(scheduler_file.read_text())["address"]
            except (FileNotFoundError, json.JSONDecodeError, KeyError):
                time.sleep(0.1)
        preload = folder / "preload_marks.py"
        preload.write_text(PRELOAD)
        started = [
            start(
                "worker",
                address,
                "--nthreads",
                "1",
                "--no-nanny",
                "--no-dashboard",
                "--dashboard-address",
                "127.0.0.1:0",
                "--host",
                "127.0.0.1",
                "--name",
                f"w{n}",
                "--preload",
                str(preload),
                "--death-timeout",
                "60",
                "--local-directory",
                str(folder / f"w{n}"),
            )  # fmt: skip
            for n in range(workers)
        ]
        if workers:
            with distributed.Client(address, timeout=STARTUP_S) as client:
                client.wait_for_workers(workers, timeout=STARTUP_S)
        yield Cluster(address, scheduler, started, marks)
    finally:
        for process in processes:
            if process.poll() is None:
                os.killpg(process.pid, signal.SIGKILL)
        for process in processes:
            process.wait(timeout=60)
        logs.close()


def assert_same_dataset(a, b) -> None:
    """Same clips in the same order, same skeleton and offsets, every kind equal bit for bit."""
    assert a.names == b.names and a.manifest["skeleton"] == b.manifest["skeleton"]
    assert a.manifest["options"] == b.manifest["options"]
    assert [c["frames"] for c in a.clips] == [c["frames"] for c in b.clips]
    assert a.offsets.tobytes() == b.offsets.tobytes()
    assert a.arrays.keys() == b.arrays.keys()
    for kind in a.arrays:
        assert a.arrays[kind].dtype == b.arrays[kind].dtype and a.arrays[kind].shape == b.arrays[kind].shape, kind
        assert a.arrays[kind].tobytes() == b.arrays[kind].tobytes(), kind


def test_workers_write_the_local_dataset_and_survive_one_killed(clips, local, tmp_path):
    with dask_cluster(tmp_path / "dask") as cluster:
        run = subprocess.run(
            cli(clips, tmp_path / "all", "--dask", cluster.address),
            capture_output=True, text=True, timeout=120, env=env_for(None),
        )  # fmt: skip
        assert run.returncode == 0, run.stderr
        assert "12 clips ok, 0 failed" in run.stdout
        assert_same_dataset(local, load_dataset(tmp_path / "all"))
        done = cluster.batches_by_worker()
        assert len(done) == 2  # both workers ran batches
        assert sorted(n for batches in done.values() for batch in batches for n in batch) == local.names

        # Now kill the worker holding the batch of the 6th clip while the run waits for it.
        (cluster.marks / "hold").write_text(local.names[5])
        for marks in cluster.marks.glob("*.jsonl"):
            marks.unlink()
        running = subprocess.Popen(
            cli(clips, tmp_path / "one_killed", "--dask", cluster.address),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env_for(None),
        )  # fmt: skip
        try:
            victim = cluster.held_pid()
            os.killpg(victim, signal.SIGKILL)
            out, err = running.communicate(timeout=120)
        finally:
            running.kill()
        assert running.returncode == 0, err
        assert_same_dataset(local, load_dataset(tmp_path / "one_killed"))
        done = cluster.batches_by_worker()
        (survivor,) = set(done) - {victim}
        assert any(local.names[5] in batch for batch in done[survivor])  # the held batch, run again


def test_losing_the_scheduler_stops_the_run_with_one_line_and_it_resumes(clips, local, tmp_path):
    out = tmp_path / "ds"
    with dask_cluster(tmp_path / "dask") as cluster:
        (cluster.marks / "hold").write_text(local.names[7])
        running = subprocess.Popen(
            cli(clips, out, "--dask", cluster.address),
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env_for(None),
        )  # fmt: skip
        try:
            cluster.held_pid()
            os.killpg(cluster.scheduler.pid, signal.SIGKILL)
            _, err = running.communicate(timeout=120)
        finally:
            running.kill()
    assert running.returncode == 1
    last = err.strip().splitlines()[-1]
    assert last.startswith("expressive-mocap: error: lost the Dask scheduler at tcp://127.0.0.1:"), err
    assert "run the same command again to resume" in last
    assert (out / ".partial").is_dir() and not (out / "manifest.json").exists()
    # Resumed on this machine: where the batches ran is not part of a run's options.
    resumed = subprocess.run(cli(clips, out), capture_output=True, text=True, timeout=120, env=env_for(None))
    assert resumed.returncode == 0, resumed.stderr
    assert "12 clips ok" in resumed.stdout
    assert_same_dataset(local, load_dataset(out))


def bounded(call, *args, **kw):
    """``call(*args, **kw)`` in a thread: its result or its exception, or a failure after 120 s
    (a run that waits for ever must fail the test, not hang it)."""
    outcome: dict = {}

    def target() -> None:
        try:
            outcome["result"] = call(*args, **kw)
        except BaseException as error:  # handed to the test
            outcome["error"] = error

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(timeout=120)
    assert not thread.is_alive(), f"{call.__name__} still running after 120 s"
    if "error" in outcome:
        raise outcome["error"]
    return outcome["result"]


def test_a_cluster_without_workers_stops_the_run_and_it_resumes(clips, local, tmp_path, monkeypatch):
    monkeypatch.setattr(cluster_module, "WAIT_FOR_WORKERS", 2.0)
    kw = dict(keep="positions,rotations,features,contacts,activity", model="", batch_mb=0.25, progress=False)
    out = tmp_path / "ds"
    with dask_cluster(tmp_path / "none", workers=0) as cluster:
        client, close = cluster_module.client_for(cluster.address)
        try:  # results come from the workers, not relayed by the scheduler (twice the traffic)
            assert client.direct_to_workers is True
        finally:
            close()
        with pytest.raises(DatasetError, match="has no workers .waited 2 s.: start some with `dask worker"):
            bounded(preprocess, clips, out, cluster=cluster.address, **kw)
    with dask_cluster(tmp_path / "one", workers=1) as cluster:
        (cluster.marks / "hold").write_text(local.names[3])
        # The only worker killed while it holds the batch of the 4th clip.
        threading.Thread(target=lambda: os.killpg(cluster.held_pid(), signal.SIGKILL), daemon=True).start()
        with pytest.raises(DatasetError, match="every worker of the Dask cluster at .* has gone .none for 2 s."):
            bounded(preprocess, clips, out, cluster=cluster.address, **kw)
    summary = preprocess(clips, out, **kw)
    assert summary.finished and 0 < summary.clips_resumed < 12
    assert_same_dataset(local, load_dataset(out))
