"""`expressive-mocap preprocess` alone against the same run on a Dask scheduler and workers.

    python benches/bench_cluster.py [--data DIR] [--workers 2] [--rounds 3] [--write-results]

Starts `dask scheduler` and WORKERS `dask worker --nthreads 1` on 127.0.0.1 (as docs/cluster.md
says to start them on each machine), then runs the command on dataset-2 alone and with
``--dask ADDRESS``, with and without ``--model``, the four alternated round after round, each a
fresh child process (wall time of the process, Dask already running; medians). Also counts the
bytes that crossed the loopback interface during each cluster run (other traffic on it counts
too; each byte is seen once sent and once received, halved here). On one machine the workers
share the command's cores: this measures the cost of the transfers, not a speed-up. Each run's
dataset is checked before its time counts (benches/harness.py; a failed check raises): every clip
of ``--data``, and the same frames in every run.
Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_pybvh_ml import DATA
from harness import Stopwatch, check_equal, commit, cpu_name, memory_gib, rotated

RESULTS = Path(__file__).parent / "RESULTS.md"
SECTION = "Preprocessing on a Dask scheduler and workers: `benches/bench_cluster.py`"

CHILD = r"""
import sys, time
from expressive_mocap.cli import main
assert main(["preprocess", *sys.argv[1:], "-q"]) == 0
with open("/proc/self/status") as status:
    print(next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmHWM:")))
"""


def loopback_bytes() -> int:
    with open("/proc/net/dev") as dev:
        for line in dev:
            name, _, counters = line.partition(":")
            if name.strip() == "lo":
                fields = counters.split()
                return int(fields[0]) + int(fields[8])
    return 0


def start_cluster(folder: Path, workers: int) -> tuple[str, list[subprocess.Popen]]:
    """A scheduler and its workers on free ports of 127.0.0.1, each its own process group."""
    logs = open(folder / "dask.log", "w")
    processes: list[subprocess.Popen] = []

    def start(*args: str) -> None:
        processes.append(
            subprocess.Popen(
                [sys.executable, "-m", "dask", *args], stdout=logs, stderr=subprocess.STDOUT, start_new_session=True
            )
        )

    scheduler_file = folder / "scheduler.json"
    start("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard", "--dashboard-address", "127.0.0.1:0",
          "--scheduler-file", str(scheduler_file))  # fmt: skip
    deadline = time.monotonic() + 60
    while not scheduler_file.exists():
        if time.monotonic() > deadline:
            stop(processes)
            raise SystemExit(f"the scheduler did not start: {(folder / 'dask.log').read_text()}")
        time.sleep(0.1)
    address = json.loads(scheduler_file.read_text())["address"]
    for n in range(workers):
        start("worker", address, "--nthreads", "1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0",
              "--host", "127.0.0.1", "--local-directory", str(folder / f"w{n}"))  # fmt: skip
    from distributed import Client

    with Client(address, timeout=60) as client:
        client.wait_for_workers(workers, timeout=120)
    return address, processes


def stop(processes: list[subprocess.Popen]) -> None:
    for process in processes:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGTERM)
    for process in processes:
        try:
            process.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)


def run(data: Path, out: Path, options: list[str]) -> dict:
    """One preprocess run in a child process: wall, the child's peak RSS, bytes over loopback, and
    the clips and frames of its dataset (checked: every clip of ``data``)."""
    from expressive_mocap.dataset import load_dataset

    shutil.rmtree(out, ignore_errors=True)
    before = loopback_bytes()
    with Stopwatch() as watch:
        result = subprocess.run(
            [sys.executable, "-c", CHILD, str(data), "-o", str(out), *options], capture_output=True, text=True
        )
    if result.returncode != 0:
        raise SystemExit(f"preprocess {' '.join(options)} failed:\n{result.stderr[-3000:]}")
    peak = int(result.stdout.strip().splitlines()[-1])
    moved = (loopback_bytes() - before) / 2
    dataset = load_dataset(out)
    check_equal(len(dataset.names), len(list(data.glob("*.bvh"))), f"clips written by `{' '.join(options)}`")
    return {"wall": watch.seconds, "peak": peak, "moved": moved, "frames": int(dataset.offsets[-1])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--write-results", action="store_true", help=f"rewrite the section {SECTION!r}")
    args = parser.parse_args()

    work = Path(tempfile.mkdtemp(prefix="bench_cluster_"))
    load = os.getloadavg()
    address, processes = start_cluster(work, args.workers)
    configs = {
        "this machine": [],
        f"scheduler + {args.workers} workers": ["--dask", address],
        "this machine, `--model`": ["--model"],
        f"scheduler + {args.workers} workers, `--model`": ["--model", "--dask", address],
    }
    times: dict[str, list[dict]] = {name: [] for name in configs}
    watch = Stopwatch()
    try:
        for round_ in range(args.rounds):
            for name in rotated(list(configs), round_):
                times[name].append(run(args.data, work / "out", configs[name]))
                print(f"round {round_ + 1}: {name}: {times[name][-1]['wall']:.2f} s", flush=True)
    finally:
        stop(processes)
    frames = {r["frames"] for records in times.values() for r in records}
    check_equal(len(frames), 1, f"distinct frame counts of the runs {sorted(frames)}")
    size = sum(p.stat().st_size for p in (work / "out").iterdir()) / 1e6
    shutil.rmtree(work, ignore_errors=True)
    clips = len(list(args.data.glob("*.bvh")))
    mb = sum(p.stat().st_size for p in args.data.glob("*.bvh")) / 1e6
    lines = [
        f"- date: {time.strftime('%Y-%m-%d %H:%M')} (the run took {watch.elapsed() / 60:.1f} min)",
        f"- machine: {cpu_name()}, {os.cpu_count()} cores, {memory_gib():.1f} GiB RAM; commit {commit()}; load "
        f"average at the start {load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}, at the end "
        f"{', '.join(f'{x:.1f}' for x in os.getloadavg())}",
        f"- command: `python benches/bench_cluster.py --workers {args.workers} --rounds {args.rounds} "
        "--write-results`: `dask scheduler` and `dask worker --nthreads 1` on 127.0.0.1 (the same cores as the "
        "command), then `expressive-mocap preprocess DATA -o OUT -q [--model] [--dask ADDRESS]`, the four "
        "alternated round after round, each a fresh process, Dask already running; medians",
        f"- data: dataset-2, {clips} clips, {mb:.1f} MB, the folder form (the last dataset written: {size:.0f} MB); "
        "Bandai-Namco-Research-Motiondataset (Bandai Namco Research Inc., 2022), CC BY-NC 4.0",
        "",
        "| run | runs | wall s | command's peak RSS | moved over loopback |",
        "|---|---|---|---|---|",
    ]
    for name, records in times.items():
        moved = statistics.median(r["moved"] for r in records) / 1e6
        lines.append(
            f"| {name} | {len(records)} | {statistics.median(r['wall'] for r in records):.2f} | "
            f"{statistics.median(r['peak'] for r in records) / 1e6:.0f} MB | "
            f"{f'{moved:.0f} MB' if '--dask' in configs[name] else ''} |"
        )
    print("\n".join(lines))
    if args.write_results:
        from results import write_section

        write_section(SECTION, "\n".join(lines), RESULTS)


if __name__ == "__main__":
    main()
