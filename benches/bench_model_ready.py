#!/usr/bin/env python
"""Benchmark ``expressive-mocap preprocess`` writing model-ready arrays on the whole Bandai-Namco
dataset-2 archive (2,902 clips).

    python benches/bench_model_ready.py [--data DIR] [--rounds R] [--out benches/RESULTS.md]

Configurations, each run a fresh child process (its peak RSS its own, from ``wait4``), alternated
round by round (machines here drift by +-30 %: compare within a run):

- plain: ``preprocess DIR -o OUT`` (positions, features, contacts as stored by the Rust pipeline);
- model-ready: ``--rotations 6d --keep rotations,velocities,root_velocity,contacts --positions
  heading --mirror`` (the target: under 5 s on the 2-core machine);
- the same without ``--mirror``, and with ``--fps 15`` instead, for where the time goes.

The load average at the start and end is reported: other jobs on the machine slow every figure.
Each run's dataset is checked before its time counts (benches/harness.py; a failed check raises):
it holds every clip of ``--data`` (twice with ``--mirror``: each and its mirror image).

Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
The repository never contains it.
"""

from __future__ import annotations

import argparse
import datetime
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_preprocess import DEFAULT_DATA, machine
from harness import Stopwatch, check_equal, rotated
from results import write_section  # benches/results.py: this script rewrites only its own section

REPO = Path(__file__).resolve().parent.parent
TITLE = "Model-ready arrays: `preprocess --rotations --positions --mirror`"
READY = ["--rotations", "6d", "--keep", "rotations,velocities,root_velocity,contacts", "--positions", "heading"]
CONFIGS = {
    "plain (positions, features, contacts)": [],
    "model-ready + --mirror (the target)": [*READY, "--mirror"],
    "model-ready, no mirror": READY,
    "model-ready + --fps 15": [*READY, "--fps", "15"],
}
TARGET = "model-ready + --mirror (the target)"
TARGET_S = 5.0


def run_once(data: Path, args: list[str], out: Path) -> tuple[float, int, int]:
    """(wall seconds, peak RSS bytes, output bytes) of one preprocess run in a child process, its
    dataset checked to hold every clip (and every mirror image with ``--mirror``)."""
    from expressive_mocap.dataset import load_dataset

    shutil.rmtree(out, ignore_errors=True)
    command = [sys.executable, "-m", "expressive_mocap.cli", "preprocess", str(data), "-o", str(out), "-q", *args]
    env = {**os.environ, "PYTHONPATH": str(REPO / "python")}
    with Stopwatch() as watch:
        child = subprocess.Popen(command, env=env, stdout=subprocess.DEVNULL)
        _, status, usage = os.wait4(child.pid, 0)
    seconds = watch.seconds
    if status != 0:
        raise SystemExit(f"{' '.join(command)} failed with status {status}")
    clips = len(list(data.glob("*.bvh"))) * (2 if "--mirror" in args else 1)
    check_equal(len(load_dataset(out).names), clips, f"clips in the dataset of `{' '.join(args) or '(defaults)'}`")
    size = sum(p.stat().st_size for p in out.iterdir() if p.is_file())
    return seconds, usage.ru_maxrss * 1024, size


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA, help="the unpacked dataset-2 folder")
    parser.add_argument("--rounds", type=int, default=3, help="rounds (default 3)")
    parser.add_argument("--out", type=Path, help="write the section into this RESULTS.md")
    args = parser.parse_args()
    started, info = datetime.datetime.now(), machine()  # its load average: at the start
    times: dict[str, list[float]] = {name: [] for name in CONFIGS}
    peaks: dict[str, int] = dict.fromkeys(CONFIGS, 0)
    sizes: dict[str, int] = {}
    names = list(CONFIGS)
    with tempfile.TemporaryDirectory(prefix="bench-model-ready-") as scratch:
        for round_number in range(args.rounds):
            for name in rotated(names, round_number):
                seconds, peak, size = run_once(args.data, CONFIGS[name], Path(scratch) / "out")
                times[name].append(seconds)
                peaks[name], sizes[name] = max(peaks[name], peak), size
                print(f"{name}: {seconds:.2f} s, peak {peak / 1e6:.0f} MB", flush=True)
    end_load = os.getloadavg()
    rows = [
        f"| {name} | `{' '.join(CONFIGS[name]) or '(defaults)'}` | {len(times[name])} | "
        f"{statistics.median(times[name]):.2f} | {min(times[name]):.2f} | {peaks[name] / 1e6:.0f} MB | "
        f"{sizes[name] / 1e6:.0f} MB |"
        for name in CONFIGS
    ]
    target = statistics.median(times[TARGET])
    text = "\n".join(
        [
            f"- date: {started:%Y-%m-%d %H:%M}",
            f"- machine: {info}, at the end {end_load[0]:.1f}, {end_load[1]:.1f}, {end_load[2]:.1f} "
            "(other jobs share the cores)",
            f"- command: `python benches/bench_model_ready.py --rounds {args.rounds}`; each run "
            "`expressive-mocap preprocess DATA -o OUT -q ARGS` in a fresh child process, order rotated each round",
            "- Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), "
            "licensed CC BY-NC 4.0: 2,902 clips, 514.6 MB, 384,931 frames (769,862 with --mirror).",
            "",
            "| configuration | ARGS | runs | wall s (median) | best s | peak RSS | output |",
            "|---|---|---|---|---|---|---|",
            *rows,
            "",
            f"Target: the model-ready run with --mirror under {TARGET_S:g} s: {target:.2f} s, "
            f"**{'pass' if target < TARGET_S else 'FAIL'}**.",
        ]
    )
    print(text)
    if args.out:
        write_section(TITLE, text, args.out)


if __name__ == "__main__":
    main()
